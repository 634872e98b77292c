//! Anti-aliasing on whole frames of `tests/scenes/aa_edges.toml` (rotated
//! high-contrast squares, sub-pixel poles, a fence of sub-pixel bars):
//! - edges: 128x128 against a 16x16-supersampled render (2048x2048 box
//!   filtered in linear light), RMSE in sRGB ordered none > smaa > hraa;
//! - temporal stability: 32 frames of slow sideways camera motion, per-pixel
//!   temporal standard deviation of hraa against none.

mod common;

use common::renderer;
use glam::Vec3;
use himal::passes::aa::AaMode;
use himal::passes::aa::smaa::reference::{linear_to_srgb, srgb_to_linear};
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer};

const N: u32 = 128;
const SS: u32 = 16;

fn load() -> (Scene, Camera) {
    common::scene_and_camera("aa_edges", "main")
}

fn settings(scene: &Scene, size: u32, aa: AaMode) -> FrameSettings {
    let mut s = FrameSettings::new(size, size, scene.sun.clone());
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.bloom.enabled = false;
    s.adaptation.enabled = false;
    s.aa = aa;
    s
}

/// sRGB values (0..1), row-major.
fn render(r: &mut Renderer, camera: &Camera, s: &FrameSettings) -> Vec<[f32; 3]> {
    let frame = r.render(camera, s).expect("frame");
    let px = frame.image.to_rgba_f32().expect("rgba");
    px.iter().map(|p| [p[0], p[1], p[2]]).collect()
}

fn rmse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    let sum: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (0..3).map(|c| (x[c] - y[c]).powi(2)).sum::<f32>())
        .sum();
    (sum / (3 * a.len()) as f32).sqrt()
}

/// The converged image of `mode` from a static camera (temporal modes: 8 frames).
fn converged(r: &mut Renderer, camera: &Camera, s: &FrameSettings) -> Vec<[f32; 3]> {
    r.reset_history();
    let frames = if s.aa.temporal() { 8 } else { 1 };
    let mut img = Vec::new();
    for _ in 0..frames {
        img = render(r, camera, s);
    }
    img
}

/// docs/images/A1-crops.png: the 56x56 pixels at (8, 20) of each image, 4x
/// nearest zoom, side by side with 4-pixel white gaps.
fn crop_strip(images: &[Vec<[f32; 3]>]) -> image::RgbImage {
    const CROP: u32 = 56;
    const ZOOM: u32 = 4;
    const GAP: u32 = 4;
    let panel = CROP * ZOOM;
    let n = images.len() as u32;
    let mut out =
        image::RgbImage::from_pixel(n * panel + (n - 1) * GAP, panel, image::Rgb([255; 3]));
    for (k, img) in images.iter().enumerate() {
        for y in 0..panel {
            for x in 0..panel {
                let p = img[((20 + y / ZOOM) * N + 8 + x / ZOOM) as usize];
                let rgb = p.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8);
                out.put_pixel(k as u32 * (panel + GAP) + x, y, image::Rgb(rgb));
            }
        }
    }
    out
}

#[test]
fn edge_error_is_ordered_none_smaa_hraa() {
    let (scene, camera) = load();
    let mut r = renderer(&scene);
    // Reference: 16x16 samples per pixel, averaged in linear light.
    let big = render(&mut r, &camera, &settings(&scene, N * SS, AaMode::None));
    let mut reference = vec![[0.0f32; 3]; (N * N) as usize];
    for y in 0..N * SS {
        for x in 0..N * SS {
            let p = big[(y * N * SS + x) as usize];
            let t = &mut reference[((y / SS) * N + x / SS) as usize];
            for c in 0..3 {
                t[c] += srgb_to_linear(p[c]) / (SS * SS) as f32;
            }
        }
    }
    for t in &mut reference {
        *t = t.map(linear_to_srgb);
    }
    let mut errors = Vec::new();
    // none, smaa, hraa, reference: the crops of docs/images/A1-crops.png.
    let mut crops = Vec::new();
    for mode in [
        AaMode::None,
        AaMode::Smaa,
        AaMode::Tfq,
        AaMode::Taa,
        AaMode::SmaaT2x,
        AaMode::Hraa,
    ] {
        let img = converged(&mut r, &camera, &settings(&scene, N, mode));
        let e = rmse(&img, &reference);
        println!("edges: {:9} RMSE {e:.4}", mode.name());
        errors.push((mode, e));
        if matches!(mode, AaMode::None | AaMode::Smaa | AaMode::Hraa) {
            crops.push(img);
        }
    }
    crops.push(reference.clone());
    if let Some(dir) = std::env::var_os("HIMAL_PLOT_DIR") {
        let path = std::path::Path::new(&dir).join("A1-crops.png");
        crop_strip(&crops).save(&path).expect("write A1-crops.png");
        eprintln!("wrote {}", path.display());
    }
    let e = |m: AaMode| {
        errors
            .iter()
            .find(|(k, _)| *k == m)
            .map_or(f32::NAN, |x| x.1)
    };
    let (none, smaa, hraa) = (e(AaMode::None), e(AaMode::Smaa), e(AaMode::Hraa));
    // Measured 2026-11-22: none 0.0807, smaa 0.0679, tfq 0.0398, taa 0.0624,
    // smaa-t2x 0.0447, hraa 0.0394 (hraa/smaa 0.58; before SMAA's diagonal and
    // corner detection smaa 0.0674, smaa-t2x 0.0502, hraa 0.0430); thresholds 0.95 and 0.8.
    assert!(smaa < 0.95 * none, "smaa {smaa} vs none {none}");
    assert!(hraa < 0.8 * smaa, "hraa {hraa} vs smaa {smaa}");
}

#[test]
fn hraa_is_temporally_stable_under_slow_motion() {
    let (scene, camera) = load();
    let mut r = renderer(&scene);
    let mut stddev = Vec::new();
    for mode in [AaMode::None, AaMode::Smaa, AaMode::Taa, AaMode::Hraa] {
        let s = settings(&scene, N, mode);
        r.reset_history();
        let (mut sum, mut sum2) = (
            vec![0.0f64; (N * N) as usize],
            vec![0.0f64; (N * N) as usize],
        );
        let frames = 32;
        // Warm-up frames fill the history; then 32 measured frames.
        for i in 0..frames + 8 {
            // 0.1 pixel per frame sideways (34 mm per pixel at 6 m).
            let mut cam = camera.clone();
            cam.position += Vec3::new(0.0034 * i as f32, 0.0, 0.0);
            let img = render(&mut r, &cam, &s);
            if i < 8 {
                continue;
            }
            for (k, p) in img.iter().enumerate() {
                let l = (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64;
                sum[k] += l;
                sum2[k] += l * l;
            }
        }
        let n = frames as f64;
        let mean_sd: f64 = sum
            .iter()
            .zip(&sum2)
            .map(|(s, s2)| (s2 / n - (s / n).powi(2)).max(0.0).sqrt())
            .sum::<f64>()
            / sum.len() as f64;
        println!(
            "stability: {:9} mean temporal std-dev {mean_sd:.5}",
            mode.name()
        );
        stddev.push((mode, mean_sd));
    }
    let sd = |m: AaMode| {
        stddev
            .iter()
            .find(|(k, _)| *k == m)
            .map_or(f64::NAN, |x| x.1)
    };
    // Issue #4: hraa <= 1/3 of none. Measured 2026-11-22: none 0.0491,
    // smaa 0.0384, taa 0.0185, hraa 0.0126 (0.26 of none).
    assert!(
        sd(AaMode::Hraa) <= sd(AaMode::None) / 3.0,
        "hraa {} vs none {}",
        sd(AaMode::Hraa),
        sd(AaMode::None)
    );
}

/// Trail energy of hraa with `tuning`: mean |luma − none render| over the
/// ball's trail (pixels it covered in the previous 8 frames but not now),
/// minus the same mean over floor the ball never touched (the two images
/// differ there by their anti-aliasing alone). Returns (energy, trail pixels).
fn trail_energy(tuning: himal::passes::aa::TemporalTuning) -> (f32, f32) {
    let (scene, camera) = common::scene_and_camera("aa_ghosting", "main");
    let mut r = renderer(&scene);
    let frames = 16;
    // 0.1 s per frame: the ball moves 10 cm (about 2 px) per frame.
    let run = |r: &mut Renderer, aa: AaMode| {
        let mut s = settings(&scene, N, aa);
        s.aa_tuning = tuning;
        r.reset_history();
        (0..=frames)
            .map(|i| {
                s.time_s = i as f32 * 0.1;
                render(r, &camera, &s)
            })
            .collect::<Vec<_>>()
    };
    let none = run(&mut r, AaMode::None);
    let hraa = run(&mut r, AaMode::Hraa);
    let red = |p: [f32; 3]| p[0] > 0.15 && p[0] > 1.6 * p[1];
    let last = frames as usize;
    let luma = |p: [f32; 3]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let (mut sum, mut n, mut base, mut nb) = (0.0, 0, 0.0, 0);
    for k in 0..none[last].len() {
        let d = (luma(hraa[last][k]) - luma(none[last][k])).abs();
        let trail = (last - 8..last).any(|f| red(none[f][k])) && !red(none[last][k]);
        if trail {
            sum += d;
            n += 1;
        } else if !(0..=last).any(|f| red(none[f][k])) {
            base += d;
            nb += 1;
        }
    }
    let energy = sum / n.max(1) as f32 - base / nb.max(1) as f32;
    (energy.max(0.0), n as f32)
}

#[test]
fn colour_box_rejection_cuts_the_ghosting_trail() {
    use himal::passes::aa::TemporalTuning;
    let with = trail_energy(TemporalTuning::default());
    let no_colour = trail_energy(TemporalTuning {
        colour_tolerance: f32::INFINITY,
        ..Default::default()
    });
    let colour_only = trail_energy(TemporalTuning {
        motion_tolerance_px: f32::INFINITY,
        ..Default::default()
    });
    let no_rejection = trail_energy(TemporalTuning {
        colour_tolerance: f32::INFINITY,
        motion_tolerance_px: f32::INFINITY,
        ..Default::default()
    });
    println!(
        "ghosting (trail energy, trail pixels): both tests {with:?}, \
         motion only {no_colour:?}, colour box only {colour_only:?}, neither {no_rejection:?}"
    );
    assert!(with.1 > 50.0, "trail mask too small ({})", with.1);
    // Issue #4: colour-box rejection at most half the trail of no rejection.
    // Measured 2026-11-22: both 0.016, motion only 0.018, colour box only
    // 0.061, neither 0.131 (ratios 0.12 and 0.46); threshold 0.5.
    assert!(
        colour_only.0 <= 0.5 * no_rejection.0,
        "colour box {colour_only:?} vs none {no_rejection:?}"
    );
    assert!(
        with.0 <= 0.5 * no_rejection.0,
        "with {with:?} vs without {no_rejection:?}"
    );
}
