//! HDR environments (issue #8): loading, SH9 irradiance against numerical
//! integration, the background drawn by the sky pass against the CPU lookup,
//! the scene file's `[environment]` and the errors.

mod common;

use std::path::Path;

use glam::Vec3;
use himal::scene::{EnvironmentDesc, EnvironmentImage, Scene};

const VENICE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/assets/env/venice_sunset_1k.hdr"
);

#[test]
fn sh9_irradiance_matches_numerical_integration() {
    let env = EnvironmentImage::load(&EnvironmentDesc::new(VENICE)).expect("venice");
    assert_eq!((env.width, env.height), (1024, 512));
    let sh = env.radiance_sh();
    // E(n) = integral of L(w) max(0, n.w) dw by a 256 x 512 midpoint rule.
    let irradiance = |n: Vec3| {
        let (rows, cols) = (256, 512);
        let mut e = Vec3::ZERO;
        for i in 0..rows {
            let theta = (i as f32 + 0.5) / rows as f32 * std::f32::consts::PI;
            let d_omega = theta.sin()
                * (std::f32::consts::PI / rows as f32)
                * (std::f32::consts::TAU / cols as f32);
            for j in 0..cols {
                let phi = (j as f32 + 0.5) / cols as f32 * std::f32::consts::TAU;
                let w = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                e += env.sample(w) * n.dot(w).max(0.0) * d_omega;
            }
        }
        e
    };
    let mut worst = 0.0f32;
    for n in [
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::X,
        Vec3::NEG_Z,
        Vec3::new(1.0, 1.0, 1.0).normalize(),
    ] {
        let reference = irradiance(n);
        let e = sh.irradiance(n);
        let rel = (e - reference).length() / reference.length();
        eprintln!("  n = {n}: SH9 {e}, integrated {reference}, relative {rel:.4}");
        worst = worst.max(rel);
    }
    eprintln!("venice SH9 irradiance vs integration: worst relative error {worst:.4}");
    // Measured 2026-11-22: up 0.014, down 0.082, +X 0.078, -Z 0.078,
    // diagonal 0.0045. SH9 keeps the cosine lobe's first three bands; the
    // rest is the low, bright sunset sun (red channel, 12% toward it), the
    // known truncation error of SH9 irradiance; threshold 0.10.
    assert!(worst < 0.10, "{worst}");
}

#[test]
fn background_is_the_environment_image() {
    let text = format!(
        r#"
[environment]
file = "{VENICE}"
intensity = 2.0
rotation = 30

[[camera]]
name = "main"
position = [0, 1, 0]
target = [1, 1.3, -2]
fov_y = 70
"#
    );
    let scene = Scene::from_toml_str(&text, "env.toml", Path::new(".")).expect("scene");
    let desc = scene.environment.clone().expect("environment");
    assert_eq!((desc.intensity, desc.rotation_deg), (2.0, 30.0));
    let env = EnvironmentImage::load(&desc).expect("load");
    let camera = scene.camera("main").expect("camera").clone();
    let size = (96u32, 64u32);
    let s = common::raw_settings(&scene, size, "lighting");
    let mut r = common::renderer(&scene);
    let img = common::render_rgba(&mut r, &camera, &s);
    let mut worst = 0.0f32;
    let mut sum = 0.0f32;
    for y in 0..size.1 {
        for x in 0..size.0 {
            let dir = common::pixel_ray(&camera, size, x, y);
            let cpu = env.sample(dir);
            let g = img[(y * size.0 + x) as usize];
            let rel = ((Vec3::new(g[0], g[1], g[2]) - cpu).abs() / cpu.max(Vec3::splat(1e-2)))
                .max_element();
            worst = worst.max(rel);
            sum += rel;
        }
    }
    let mean = sum / (size.0 * size.1) as f32;
    eprintln!("environment background GPU vs CPU: mean {mean:.5}, worst {worst:.4}");
    // fp16 texels and bilinear weights in 8-bit fixed point on the GPU.
    // Measured 2026-11-22: mean 0.0021, worst 0.077 (at the sun's edge);
    // thresholds 0.005, 0.12.
    assert!(mean < 0.005 && worst < 0.12, "mean {mean}, worst {worst}");
}

#[test]
fn bad_environments_name_the_file() {
    let err = |desc: EnvironmentDesc| {
        EnvironmentImage::load(&desc)
            .expect_err("must fail")
            .to_string()
    };
    let missing = err(EnvironmentDesc::new("/nowhere/sky.hdr"));
    assert!(missing.contains("/nowhere/sky.hdr"), "{missing}");
    let png = err(EnvironmentDesc::new("sky.png"));
    assert!(
        png.contains("sky.png") && png.contains(".hdr or .exr"),
        "{png}"
    );
    let text = "[environment]\nfile = \"x.hdr\"\nintensity = -1\n";
    let e = Scene::from_toml_str(text, "bad.toml", Path::new("."))
        .expect_err("negative intensity")
        .to_string();
    assert!(e.starts_with("bad.toml:3:"), "{e}");
}

/// The built-in studio (`--env studio`, the default for a bare `--gltf`):
/// neutral white light, a key softbox front-right brighter than the fill
/// front-left, a floor darker than the ceiling, scaled by the intensity.
#[test]
fn the_studio_environment_is_neutral_and_keyed_front_right() {
    use himal::scene::STUDIO;
    let studio = EnvironmentImage::load(&EnvironmentDesc::new(STUDIO)).expect("generated");
    assert_eq!((studio.width, studio.height), (512, 256));
    assert!(
        studio
            .texels
            .iter()
            .all(|t| t.is_finite() && t.x == t.y && t.y == t.z)
    );
    let at = |d: glam::Vec3| studio.sample(d.normalize()).x;
    let (key, fill) = (
        at(glam::Vec3::new(0.7, 0.55, 0.6)),
        at(glam::Vec3::new(-0.8, 0.25, 0.55)),
    );
    let (floor, ceiling) = (at(glam::Vec3::NEG_Y), at(glam::Vec3::Y));
    eprintln!("studio: key {key}, fill {fill}, floor {floor}, ceiling {ceiling}");
    assert!(
        key > 3.0 * fill && fill > 2.0 * ceiling && ceiling > floor,
        "{key} {fill} {ceiling} {floor}"
    );
    let mut brighter = EnvironmentDesc::new(STUDIO);
    brighter.intensity = 2.0;
    let twice = EnvironmentImage::load(&brighter).expect("generated");
    assert!((twice.sample(glam::Vec3::Y).x - 2.0 * ceiling).abs() < 1e-4);
}
