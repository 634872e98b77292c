//! glTF sample models rendered at 256x256 against goldens reviewed by eye
//! next to the Khronos screenshots (docs/gltf.md). Set
//! `HIMAL_UPDATE_GOLDENS=1` to rewrite them after a deliberate change.

mod common;

use std::path::{Path, PathBuf};

use himal::FrameSettings;
use himal::scene::Scene;

const MODELS: [&str; 9] = [
    "AlphaBlendModeTest",
    "AnisotropyRotationTest",
    "AnisotropyStrengthTest",
    "DamagedHelmet",
    "MetalRoughSpheresNoTextures",
    "NormalTangentMirrorTest",
    "NormalTangentTest",
    "OrientationTest",
    "TextureSettingsTest",
];

fn golden_path(model: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/goldens/gltf"))
        .join(format!("{model}.png"))
}

/// RGB of the final frame, 8-bit sRGB as written to PNG.
fn render(model: &str) -> (u32, u32, Vec<u8>) {
    let scene = Scene::from_gltf(&common::gltf_sample(model)).expect("model");
    let camera = scene.camera("default").expect("auto-framed camera").clone();
    let settings = FrameSettings::new(256, 256, scene.sun.clone());
    let mut r = common::renderer(&scene);
    let frame = r.render(&camera, &settings).expect("frame").image;
    let rgba = frame.to_rgba_f32().expect("rgba");
    let rgb = rgba
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]])
        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    (frame.width, frame.height, rgb)
}

/// Root-mean-square difference in 8-bit steps over all channels.
fn rmse(a: &[u8], b: &[u8]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum();
    (sum / a.len() as f64).sqrt()
}

#[test]
fn sample_models_match_their_goldens() {
    let update = std::env::var_os("HIMAL_UPDATE_GOLDENS").is_some();
    let mut report = Vec::new();
    for model in MODELS {
        let (w, h, rgb) = render(model);
        let path = golden_path(model);
        if update {
            image::RgbImage::from_raw(w, h, rgb.clone())
                .expect("size")
                .save(&path)
                .expect("write golden");
        }
        let golden = image::open(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .into_rgb8();
        assert_eq!(golden.dimensions(), (w, h), "{model}");
        let e = rmse(&rgb, golden.as_raw());
        report.push(format!("{model} {e:.3}"));
        // measured 0.000 for every model (same machine, lavapipe) on 2026-11-22;
        // threshold 2.0 steps RMSE leaves room for other drivers' rounding,
        // while a lost texture, a wrong colour space or flipped normals moves
        // these images by 10+ steps (measured: sRGB as linear on the helmet: see docs/gltf.md).
        assert!(e < 2.0, "{model}: RMSE {e:.3} against {}", path.display());
    }
    eprintln!("gltf goldens RMSE: {}", report.join(", "));
}

/// A2: under temporal anti-aliasing textured materials sample with mip bias
/// -0.5, so the albedo the G-buffer stores keeps more texture detail.
#[test]
fn temporal_aa_biases_texture_mips() {
    let scene = Scene::from_gltf(&common::gltf_sample("DamagedHelmet")).expect("model");
    let camera = scene.camera("default").expect("camera").clone();
    let mut r = common::renderer(&scene);
    let mut detail = |aa| {
        let mut s = FrameSettings::new(128, 128, scene.sun.clone());
        s.view = "albedo".parse().expect("view");
        s.raw = true;
        s.aa = aa;
        let img = r.render(&camera, &s).expect("frame").image;
        let px = img.to_rgba_f32().expect("rgba");
        let w = img.width as usize;
        // Mean absolute horizontal difference of green: texture detail.
        let sum: f32 = px
            .chunks(w)
            .flat_map(|row| row.windows(2).map(|p| (p[1][1] - p[0][1]).abs()))
            .sum();
        sum / px.len() as f32
    };
    let plain = detail(himal::passes::aa::AaMode::None);
    let biased = detail(himal::passes::aa::AaMode::Tfq);
    eprintln!("albedo detail: mip bias 0 {plain:.5}, -0.5 {biased:.5}");
    // Measured 2026-11-22: 0.01671 without, 0.01754 with the bias (+5.0%);
    // without the permutation the two are equal.
    assert!(biased > plain * 1.03, "{biased} vs {plain}");
}

/// Orthographic cameras rendered as 40° perspective ones. The Cameras
/// sample's second camera is orthographic (ymag 1, zfar 100) at (0.5, 0.5, 3)
/// looking at a unit square tilted 45° about X: in parallel projection the
/// square covers exactly 1 m by cos 45° m, 128 x 90.5 px of a 256 px image
/// 2 m tall, wherever it lies in depth (AO under orthographic cameras:
/// tests/ao.rs::orthographic_hbao_is_close_to_ray_traced_ao).
#[test]
fn orthographic_cameras_project_in_parallel() {
    let scene = Scene::from_gltf(&common::gltf_sample("Cameras")).expect("model");
    let ortho = scene
        .cameras
        .iter()
        .find(|c| c.camera.orthographic.is_some())
        .expect("an orthographic camera");
    let o = ortho.camera.orthographic.unwrap();
    assert_eq!((o.half_height, o.far), (1.0, 100.0));
    let mut r = common::renderer(&scene);
    let mut settings = FrameSettings::new(256, 256, scene.sun.clone());
    settings.view = "albedo".parse().expect("view");
    let albedo = r.render(&ortho.camera, &settings).expect("frame").image;
    let px = albedo.to_rgba_f32().expect("rgba");
    // The square's albedo is the default material's white; the sky is black.
    let on = |x: u32, y: u32| px[(y * 256 + x) as usize][0] > 0.5;
    let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
    for y in 0..256 {
        for x in 0..256 {
            if on(x, y) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    let (w, h) = (x1 + 1 - x0, y1 + 1 - y0);
    eprintln!("orthographic square: {w} x {h} px at ({x0}, {y0})");
    // Parallel projection: top and bottom edges equally wide (a perspective
    // camera shows the tilted square as a trapezoid), 128 x 90.5 px.
    let row = |y: u32| (0..256).filter(|&x| on(x, y)).count() as i32;
    assert!(
        (row(y0 + 2) - row(y1 - 2)).abs() <= 1,
        "{} vs {}",
        row(y0 + 2),
        row(y1 - 2)
    );
    assert!(
        (w as i32 - 128).abs() <= 1 && (h as i32 - 90).abs() <= 1,
        "{w} x {h}"
    );
    assert!(
        (x0 as i32 - 64).abs() <= 1,
        "centred under the camera: x0 {x0}"
    );
}

/// KHR_texture_transform was ignored: TextureTransformTest's top row showed
/// its yellow "not supported" image three times. With the offsets applied
/// the three quads show the green U, blue V and cyan UV checks (the
/// README's "correct" look); albedo seen straight on.
#[test]
fn texture_transforms_show_the_samples_checks() {
    let scene = Scene::from_gltf(&common::gltf_sample("TextureTransformTest")).expect("model");
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let mut settings = FrameSettings::new(256, 256, scene.sun.clone());
    settings.view = "albedo".parse().expect("view");
    let mut r = common::renderer(&scene);
    let img = r.render(&camera, &settings).expect("frame").image;
    let px = img.to_rgba_f32().expect("rgba");
    // The top row's quads (measured on the render: x 38..93, 100..155,
    // 162..217; y 67..122), 6 px inside their edges.
    let quads = [(44, 87), (106, 149), (168, 211)];
    let expected = ["green U", "blue V", "cyan UV"];
    for (k, (x0, x1)) in quads.into_iter().enumerate() {
        let (mut yellow, mut hit, mut n) = (0, 0, 0);
        for y in 73..116u32 {
            for x in x0..x1 {
                let [r, g, b, _] = px[(y * 256 + x) as usize];
                n += 1;
                if r > 0.3 && g > 0.3 && b < 0.1 {
                    yellow += 1;
                }
                let is = match k {
                    0 => g > 0.2 && r < 0.05 && b < 0.05,
                    1 => b > 0.3 && r < 0.05 && g < 0.05,
                    _ => g > 0.2 && b > 0.2 && r < 0.05,
                };
                hit += is as u32;
            }
        }
        eprintln!("quad {k}: {hit}/{n} {}, {yellow} yellow", expected[k]);
        // Measured 2026-12-03: 0 yellow, 77-81 % the check's colour (the
        // rest its white mark); before, the yellow not-supported image.
        assert_eq!(yellow, 0, "quad {k}: the not-supported image shows");
        assert!(hit * 2 > n, "quad {k}: {hit}/{n} pixels {}", expected[k]);
    }
}
