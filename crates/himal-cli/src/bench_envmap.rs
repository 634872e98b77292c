//! `himal bench --compare-envmap`: the cost of the environment map (L3, L4)
//! for a 128x128x6 Rgba16Float cube in the talk's three parts (PS4: lighting
//! 0.066, mips 0.044, filtering 0.275 ms), as ratios.
//!
//! Relighting is the sum of the per-face passes' GPU timestamps
//! (`envmap.probeN.faceF.*`: lighting, sky, mirror) in frames that relight
//! the nearest probe every frame. Mips and filter are timed alone by wall
//! clock (submitted and waited for): encoder timestamps do not bracket
//! lavapipe's compute passes (they read about 0.03 ms there).

use anyhow::{Result, bail};
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer};

use crate::GpuArgs;
use crate::bench::median;

pub fn run(
    gpu: &GpuArgs,
    scene: &Scene,
    camera: &Camera,
    base: &FrameSettings,
    frames: u32,
) -> Result<()> {
    if scene.probes.is_empty() {
        bail!("--compare-envmap needs a scene with [[probe]] entries (the demo has two)");
    }
    let mut settings = base.clone();
    settings.envmap_every_frame = true;
    settings.environment_probes = true;
    let mut renderer = Renderer::new(gpu.context()?, scene)?;
    renderer.render(camera, &settings)?; // warm-up and the probe's G-buffer capture
    let (mut relight, mut frame) = (Vec::new(), Vec::new());
    for _ in 0..frames {
        let timings = renderer.render(camera, &settings)?.timings;
        if timings.is_empty() {
            bail!("this adapter has no timestamp queries");
        }
        let face = |id: &str| id.starts_with("envmap.probe") && id.contains(".face");
        relight.push(
            timings
                .iter()
                .filter(|t| face(&t.id))
                .map(|t| t.gpu_ms)
                .sum(),
        );
        frame.push(
            timings
                .iter()
                .filter(|t| !face(&t.id))
                .map(|t| t.gpu_ms)
                .sum(),
        );
    }
    let repeats = frames.max(3);
    let (mips, filter) = renderer
        .envmap()
        .time_mips_and_filter(renderer.context(), repeats)?;
    let (relight, frame) = (median(&mut relight), median(&mut frame));
    println!(
        "environment map, 128x128x6 Rgba16Float, camera frame {}x{}:",
        base.width, base.height
    );
    println!(
        "  relight, 6 faces (lighting, sky, mirror; timestamps, median of {frames}) {relight:9.2} ms"
    );
    println!(
        "  mips   (wall clock alone, median of {repeats})                        {mips:9.2} ms"
    );
    println!(
        "  filter (wall clock alone, median of {repeats})                        {filter:9.2} ms"
    );
    println!("  rest of the frame (timestamps)                                   {frame:9.2} ms");
    let talk = (0.066, 0.044, 0.275);
    println!(
        "lighting : mips : filter = {:.2} : {:.2} : 1   (talk, PS4: {:.2} : {:.2} : 1)",
        relight / filter,
        mips / filter,
        talk.0 / talk.2,
        talk.1 / talk.2
    );
    Ok(())
}
