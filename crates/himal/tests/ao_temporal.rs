//! The selective temporal filter over frame sequences (TECHNIQUES O2), on the
//! two cases of the talk: thin, nearly static alpha-tested grass under slow
//! camera motion (flicker) and an object moving over flat ground (trailing).
//! Scenes: `tests/scenes/grass_patch.toml`, `tests/scenes/moving_sphere.toml`.

mod common;

use common::{pixel_ray, renderer, scene_and_camera};
use glam::Vec3;
use himal::passes::ao::{AoMode, AoSettings, AoView};
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, ViewBuffer};
use himal_reference::ao::{Shape, ambient_occlusion, trace};

const FPS: f32 = 30.0;

fn settings(scene: &Scene, size: (u32, u32), ao: AoSettings) -> FrameSettings {
    let mut s = FrameSettings::new(size.0, size.1, scene.sun.clone());
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.ao = ao;
    s.view = ViewBuffer::Ao(AoView::Ao);
    s.raw = true;
    s
}

/// Renders `frames` frames of the AO view (AO, Z, N) from `camera_at(i)` at time i / FPS.
fn sequence(
    scene: &Scene,
    size: (u32, u32),
    ao: AoSettings,
    frames: u32,
    camera_at: impl Fn(u32) -> Camera,
) -> Vec<Vec<[f32; 4]>> {
    let mut r = renderer(scene);
    let mut s = settings(scene, size, ao);
    (0..frames)
        .map(|i| {
            s.time_s = i as f32 / FPS;
            common::render_rgba(&mut r, &camera_at(i), &s)
        })
        .collect()
}

/// Mean over `pixels` of the temporal standard deviation of AO.
fn mean_temporal_std(frames: &[Vec<[f32; 4]>], pixels: &[usize]) -> f32 {
    // The first N_max frames fill the cleared history; flicker is measured after.
    common::mean_temporal_std(&frames[8..], pixels)
}

#[test]
fn selective_filter_removes_grass_flicker() {
    let (scene, mut camera) = scene_and_camera("grass_patch", "main");
    // Twice the scene camera's distance: blades of 1-2 pixels and less, the talk's flicker case.
    camera.position -= camera.forward * camera.position.length();
    let size = (400, 250);
    let frames = 32;
    // Slow sideways dolly: 0.15 pixel per frame at the patch centre.
    let h = size.1 as f32;
    let distance = camera.position.length();
    let pixel = 2.0 * distance * (camera.fov_y_deg.to_radians() * 0.5).tan() / h;
    let right = camera.forward.cross(Vec3::Y).normalize();
    let camera_at = |i: u32| {
        let mut c = camera.clone();
        c.position += right * (0.25 * pixel * i as f32);
        c
    };
    let without = sequence(
        &scene,
        size,
        AoSettings {
            mode: AoMode::Hbao,
            ..AoSettings::default()
        },
        frames,
        camera_at,
    );
    let with = sequence(&scene, size, AoSettings::default(), frames, camera_at);
    // Grass pixels: closer than the ground plane behind them by more than 2 cm in every frame.
    let grass: Vec<usize> = (0..(size.0 * size.1) as usize)
        .filter(|&i| {
            let (x, y) = ((i as u32) % size.0, (i as u32) / size.0);
            without.iter().enumerate().all(|(f, img)| {
                let c = camera_at(f as u32);
                let dir = pixel_ray(&c, size, x, y);
                if dir.y >= -1e-4 {
                    return false;
                }
                let ground_z = (-c.position.y / dir.y) * dir.dot(c.forward);
                img[i][1] < ground_z - 0.02
            })
        })
        .collect();
    assert!(grass.len() > 500, "{} grass pixels", grass.len());
    let std_without = mean_temporal_std(&without, &grass);
    let std_with = mean_temporal_std(&with, &grass);
    eprintln!(
        "grass flicker over {frames} frames, {} px: temporal std {std_without:.4} without STF, {std_with:.4} with ({:.2}x)",
        grass.len(),
        std_with / std_without
    );
    if let Some(dir) = std::env::var_os("HIMAL_PLOT_DIR") {
        let path = std::path::Path::new(&dir).join("O2-flicker.svg");
        std::fs::write(&path, flicker_plot(&without, &with, &grass)).expect("write the plot");
        eprintln!("wrote {}", path.display());
    }
    // Measured 2026-11-22 (lavapipe): 0.0217 without, 0.0050 with (0.23x) on 652 grass
    // pixels (2 cm sway); the issue asks for at most 1/3. At the scene camera's own 4 m the
    // dense patch reads as continuous with L = 0.1 m (3 cm texels), so half its
    // pixels are classified stable and left unfiltered: 0.37x there.
    assert!(std_with <= std_without / 3.0, "{std_with} vs {std_without}");
}

/// Per frame: mean |AO_t - AO_(t-1)| over `pixels`.
fn frame_to_frame_change(frames: &[Vec<[f32; 4]>], pixels: &[usize]) -> Vec<f32> {
    frames
        .windows(2)
        .map(|w| {
            let sum: f32 = pixels
                .iter()
                .map(|&i| (w[1][i][0] - w[0][i][0]).abs())
                .sum();
            sum / pixels.len().max(1) as f32
        })
        .collect()
}

/// SVG of the flicker over frames (docs/images/O2-flicker.svg): the mean
/// frame-to-frame AO change on grass pixels, and the AO of one grass pixel
/// (the one whose unfiltered flicker is the median), without and with STF.
fn flicker_plot(without: &[Vec<[f32; 4]>], with: &[Vec<[f32; 4]>], grass: &[usize]) -> String {
    let mut by_flicker: Vec<(f32, usize)> = grass
        .iter()
        .map(|&i| (mean_temporal_std(without, &[i]), i))
        .collect();
    by_flicker.sort_by(|a, b| a.0.total_cmp(&b.0));
    let pixel = by_flicker[by_flicker.len() / 2].1;
    let trace = |frames: &[Vec<[f32; 4]>]| frames.iter().map(|f| f[pixel][0]).collect::<Vec<_>>();
    let (w, h, pad) = (640.0, 220.0, 40.0);
    let n = without.len() as f32;
    let line = |values: &[f32], first: usize, lo: f32, hi: f32, colour: &str, top: f32| {
        let points: Vec<String> = values
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let x = pad + (first + k) as f32 / (n - 1.0) * (w - 2.0 * pad);
                let y = top + h - pad - (v - lo) / (hi - lo) * (h - 2.0 * pad);
                format!("{x:.1},{y:.1}")
            })
            .collect();
        format!(
            "<polyline fill='none' stroke='{colour}' stroke-width='2' points='{}'/>\n",
            points.join(" ")
        )
    };
    let change = [
        frame_to_frame_change(without, grass),
        frame_to_frame_change(with, grass),
    ];
    let change_max = change.iter().flatten().fold(1e-6f32, |m, &v| m.max(v));
    let traces = [trace(without), trace(with)];
    let (ao_lo, ao_hi) = traces
        .iter()
        .flatten()
        .fold((1.0f32, 0.0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut svg = format!(
        "<svg xmlns='http://www.w3.org/2000/svg' width='{w}' height='{}' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n",
        2.0 * h
    );
    for (top, title) in [
        (
            0.0,
            format!(
                "mean |AO(t) - AO(t-1)| on {} grass pixels (0 .. {change_max:.3})",
                grass.len()
            ),
        ),
        (
            h,
            format!("AO of one grass pixel ({ao_lo:.2} .. {ao_hi:.2})"),
        ),
    ] {
        svg += &format!(
            "<rect x='{pad}' y='{}' width='{}' height='{}' fill='none' stroke='#999'/>\n<text x='{pad}' y='{}'>{title}</text>\n",
            top + pad,
            w - 2.0 * pad,
            h - 2.0 * pad,
            top + pad - 6.0
        );
    }
    svg += &line(&change[0], 1, 0.0, change_max, "#d62728", 0.0);
    svg += &line(&change[1], 1, 0.0, change_max, "#1f77b4", 0.0);
    svg += &line(&traces[0], 0, ao_lo, ao_hi, "#d62728", h);
    svg += &line(&traces[1], 0, ao_lo, ao_hi, "#1f77b4", h);
    svg += &format!(
        "<text x='{pad}' y='{}' fill='#d62728'>HBAO + blur (--ao hbao)</text><text x='{}' y='{}' fill='#1f77b4'>with the selective temporal filter (--ao hbao+stf)</text><text x='{}' y='{}'>frame 0 .. {}</text>\n</svg>\n",
        2.0 * h - 12.0,
        pad + 190.0,
        2.0 * h - 12.0,
        w - pad - 80.0,
        2.0 * h - 12.0,
        without.len() - 1
    );
    svg
}

/// Centre of the moving sphere at time t (the scene's orbit: radius 2, period 12 s).
fn sphere_centre(t: f32) -> Vec3 {
    let a = std::f32::consts::TAU * t / 12.0;
    Vec3::new(2.0 * a.cos(), 0.5, -2.0 * a.sin())
}

#[test]
fn selective_filter_does_not_trail_behind_moving_objects() {
    let (scene, camera) = scene_and_camera("moving_sphere", "main");
    // The talk's L = 0.1 m classifies the ground as continuous only where
    // neighbouring AO texels are closer than 10 cm: 640 px wide here.
    let size = (640, 480);
    let frames = 32;
    let radius = AoSettings::default().radius;
    let selective = sequence(&scene, size, AoSettings::default(), frames, |_| {
        camera.clone()
    });
    // The non-selective filter of the talk's "epsilon = +Inf" video: every pixel, no disocclusion test.
    let everywhere = AoSettings {
        selective: false,
        epsilon: 1e9,
        ..AoSettings::default()
    };
    let plain = sequence(&scene, size, everywhere, frames, |_| camera.clone());
    // Error against ray-traced AO of the current frame on the ground the
    // sphere has just left: up to 1.2 m behind it along the path.
    let mut errors = [0.0f32; 2];
    let mut count = 0usize;
    for f in frames / 2..frames {
        let t = f as f32 / FPS;
        let centre = sphere_centre(t);
        let heading = (sphere_centre(t + 0.01) - centre).normalize();
        let shapes = [
            Shape::Plane {
                normal: Vec3::Y,
                offset: 0.0,
            },
            Shape::Sphere {
                centre,
                radius: 0.5,
            },
        ];
        for y in 0..size.1 {
            for x in 0..size.0 {
                let dir = pixel_ray(&camera, size, x, y);
                let Some(hit) = trace(&shapes, camera.position, dir, 0.0) else {
                    continue;
                };
                if hit.normal.y < 0.999 {
                    continue; // the sphere itself
                }
                let p = camera.position + dir * hit.t;
                let back = (centre - p).with_y(0.0);
                let along = back.dot(heading);
                if !(0.6..1.6).contains(&along) || (back - heading * along).length() > 0.6 {
                    continue;
                }
                let reference = ambient_occlusion(&shapes, p, hit.normal, radius, 128);
                let i = (y * size.0 + x) as usize;
                errors[0] += (selective[f as usize][i][0] - reference).abs();
                errors[1] += (plain[f as usize][i][0] - reference).abs();
                count += 1;
            }
        }
    }
    let [e_selective, e_plain] = errors.map(|e| e / count.max(1) as f32);
    eprintln!(
        "trailing: mean AO error behind the sphere over {count} pixel-frames: selective {e_selective:.4}, non-selective {e_plain:.4} ({:.2}x)",
        e_selective / e_plain
    );
    assert!(count > 500, "{count} pixel-frames behind the sphere");
    // Measured 2026-11-22 (lavapipe): selective 0.0093, non-selective 0.0412
    // (0.23x) over 95897 pixel-frames; the issue asks for at most 1/3.
    assert!(e_selective <= e_plain / 3.0, "{e_selective} vs {e_plain}");
}
