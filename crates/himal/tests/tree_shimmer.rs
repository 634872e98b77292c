//! Issue #18's temporal-stability must-show: foliage shimmer (the temporal
//! standard deviation of the displayed image over a tree, static camera,
//! light wind moving branches and leaves through V2/V5) with HRAA on
//! against AA off. `tests/scenes/tree_approach.toml`, one tree on a meadow.
//! The bar (HRAA at most a third of AA off) is NOT met: HRAA's
//! jitter alone, at rest, shimmers as much as AA off does in this wind.
//! The test measures and holds today's standing. Figures, analysis and
//! command: `docs/techniques/V1.md` "Shimmer".

mod common;

use glam::Vec3;
use himal::FrameSettings;
use himal::passes::aa::AaMode;
use himal::passes::vegetation::VegetationMotion;
use himal::scene::tree::Species;
use himal::scene::{Camera, Scene};

/// Light wind (Beaufort 2, "light breeze": 1.6-3.3 m/s), across the view.
const WIND: Vec3 = Vec3::new(3.0, 0.0, 0.0);
/// Frames measured, at 30 Hz, after [`WARM_UP`] frames that fill the
/// temporal history.
const FRAMES: usize = 32;
const WARM_UP: usize = 8;

fn tree_scene(species: Species) -> Scene {
    let to = format!("species = \"{}\"", species.name());
    common::scene_with("tree_approach", &[("species = \"larch\"", &to)])
}

fn luma(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Mean over `pixels` of the temporal standard deviation of the displayed
/// luma of `frames` (display-encoded values in [0, 1]).
fn shimmer(frames: &[Vec<[f32; 4]>], pixels: &[usize]) -> f64 {
    let n = frames.len() as f64;
    let sum: f64 = pixels
        .iter()
        .map(|&i| {
            let v: Vec<f64> = frames.iter().map(|f| f64::from(luma(f[i]))).collect();
            let mean = v.iter().sum::<f64>() / n;
            (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt()
        })
        .sum();
    sum / pixels.len().max(1) as f64
}

#[test]
fn foliage_shimmer_in_light_wind_with_hraa_against_aa_off() {
    let size = (256u32, 144u32);
    let mut results = Vec::new();
    for species in Species::ALL {
        let scene = tree_scene(species);
        let leaves = (scene.objects.iter().find(|o| o.name == "tree/leaves"))
            .expect("tree/leaves")
            .mesh;
        let bounds = scene.meshes[leaves].bounds;
        let target = Vec3::new(0.0, 0.5 * bounds.max.y, 0.0);
        for distance in [60.0f32, 140.0] {
            let camera = Camera::look_at(target + Vec3::new(0.0, 0.0, distance), target, 45.0);
            let pixels: Vec<usize> = (0..size.0 * size.1)
                .filter(|&i| {
                    let d = common::pixel_ray(&camera, size, i % size.0, i / size.0);
                    let (lo, hi) = (bounds.min, bounds.max);
                    common::hits_box(camera.position, d, (lo, hi), f32::INFINITY)
                })
                .map(|i| i as usize)
                .collect();
            let run = |aa: AaMode| -> f64 {
                let mut s = FrameSettings::new(size.0, size.1, scene.sun.clone());
                s.aa = aa;
                s.lod_threshold_px = 4.0;
                s.vegetation_motion = VegetationMotion::On;
                s.wind = Some(WIND);
                let mut r = common::renderer(&scene);
                let frames: Vec<Vec<[f32; 4]>> = (0..WARM_UP + FRAMES)
                    .map(|k| {
                        s.time_s = k as f32 / 30.0;
                        common::render_rgba(&mut r, &camera, &s)
                    })
                    .skip(WARM_UP)
                    .collect();
                shimmer(&frames, &pixels)
            };
            let (off, hraa) = (run(AaMode::None), run(AaMode::Hraa));
            eprintln!(
                "{} at {distance} m ({} px): shimmer AA off {off:.5}, HRAA {hraa:.5}, ratio {:.3}",
                species.name(),
                pixels.len(),
                hraa / off
            );
            results.push((species, distance, off, hraa));
        }
    }
    for (species, distance, off, hraa) in results {
        // Measured 2026-12-07 (256 x 144, 3 m/s, 32 frames at 30 Hz after 8,
        // lavapipe): HRAA / AA off = 1.56 (larch, 60 m), 3.75 (larch,
        // 140 m), 1.92 and 1.78 (rosewood); AA off 0.0015-0.0041. The
        // issue's bar is 1/3; this holds the standing against regressions.
        assert!(
            off > 0.001,
            "{} at {distance} m: the wind moved nothing",
            species.name()
        );
        assert!(
            hraa <= 4.0 * off,
            "{} at {distance} m: HRAA {hraa} against AA off {off}",
            species.name()
        );
    }
}
