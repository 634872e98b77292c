//! Load a glTF model, view it as `himal render --gltf` does (the built-in
//! studio light, a three-quarter orbit framing its bounds) with the Khronos
//! PBR Neutral tone mapper, and save a PNG.
//!
//! ```sh
//! cargo run --release --example render_gltf -- [MODEL.gltf|.glb] [OUT.png]
//! ```
//! Without a model it renders the built-in helmet (`builtin:DamagedHelmet.glb`).

use std::path::{Path, PathBuf};

use himal::gpu::{GpuContext, GpuOptions};
use himal::passes::post::Tonemapper;
use himal::scene::{EnvironmentDesc, STUDIO, Scene, gltf};
use himal::{FrameSettings, Renderer};

fn main() {
    // Display, not Debug: the library's errors name the file and the problem.
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let model = args
        .next()
        .unwrap_or_else(|| "builtin:DamagedHelmet.glb".into());
    let out = PathBuf::from(args.next().unwrap_or_else(|| "out/render_gltf.png".into()));

    // Meshes, materials, textures, cameras and lights of the file.
    let mut scene = Scene::from_gltf(Path::new(&model))?;
    scene.environment = Some(EnvironmentDesc::new(STUDIO));
    // 35 degrees to the right of the front (+Z), 20 above, framing the bounds.
    let camera = gltf::orbit_camera(&scene.bounds, 35.0, 20.0, None, 40.0);

    let mut settings = FrameSettings::new(768, 768, scene.sun.clone());
    settings.tonemapper = Tonemapper::Neutral;

    let mut renderer = Renderer::new(GpuContext::new(&GpuOptions::default())?, &scene)?;
    let frame = renderer.render(&camera, &settings)?;
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    himal::image_io::save(&out, &frame.image)?;
    println!(
        "wrote {} ({} triangles, {:.2} ms on the GPU)",
        out.display(),
        scene.triangle_count(),
        frame.timings.iter().map(|t| t.gpu_ms).sum::<f64>()
    );
    Ok(())
}
