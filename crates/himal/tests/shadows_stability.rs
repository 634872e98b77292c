//! S1 texel snapping: a camera translating by sub-texel steps over 32 frames
//! must not make the shadow mask crawl. The camera looks straight down on a
//! box on a plane and moves one pixel footprint per frame, so pixel x of
//! frame k sees the ground point of pixel x + 1 of frame k - 1; flicker is
//! the mean change of the mask at the same ground point between frames.

mod common;

use common::{pixel_ray, raw_settings, renderer, scene_and_camera};
use glam::Vec3;
use himal::scene::Camera;

const SIZE: u32 = 96;
const FRAMES: usize = 32;

/// Does the ray from `p` toward `d` hit the box of `scenes/shadow_stability.toml`?
fn hits_box(p: Vec3, d: Vec3) -> bool {
    let box_ = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 6.0, 1.0));
    common::hits_box(p, d, box_, f32::INFINITY)
}

/// Mean |Δmask| at the same ground point between consecutive frames over
/// the pixels on shadow edges, and
/// the cascade texel (m) and camera step (m).
fn flicker(snap: bool) -> (f64, f32, f32) {
    let (scene, camera0) = scene_and_camera("shadow_stability", "top");
    let mut r = renderer(&scene);
    let mut s = raw_settings(&scene, (SIZE, SIZE), "shadow-mask");
    // Coarse cascades so that one pixel (0.29 m) is about half a texel.
    s.shadow_resolution = 128;
    s.shadows.snap = snap;
    s.shadows.hero_resolution = 0;
    let step =
        2.0 * camera0.position.y * (camera0.fov_y_deg.to_radians() * 0.5).tan() / SIZE as f32;
    let mut prev: Option<(Vec<[f32; 4]>, Camera)> = None;
    let (mut sum, mut n) = (0.0f64, 0usize);
    let mut texel = 0.0;
    for k in 0..FRAMES {
        let mut cam = camera0.clone();
        cam.position.x += step * k as f32;
        let frame = r.render(&cam, &s).expect("frame");
        texel = frame.shadows.fits.get(1).map_or(0.0, |f| f.texel_world);
        let mask = frame.image.to_rgba_f32().expect("f32");
        if let Some((before, cam_before)) = &prev {
            for y in 0..SIZE {
                for x in 0..SIZE - 1 {
                    if hits_box(cam.position, pixel_ray(&cam, (SIZE, SIZE), x, y))
                        || hits_box(
                            cam_before.position,
                            pixel_ray(cam_before, (SIZE, SIZE), x + 1, y),
                        )
                    {
                        continue;
                    }
                    let a = mask[(y * SIZE + x) as usize][0];
                    let b = before[(y * SIZE + x + 1) as usize][0];
                    // Only edge pixels can flicker: count those (penumbra in
                    // either frame), not the flat lit and shadowed areas.
                    let edge = |v: f32| v > 0.01 && v < 0.99;
                    if edge(a) || edge(b) || (a - b).abs() > 0.01 {
                        sum += (a - b).abs() as f64;
                        n += 1;
                    }
                }
            }
        }
        prev = Some((mask, cam));
    }
    (sum / n.max(1) as f64, texel, step)
}

#[test]
fn snapped_cascades_do_not_crawl() {
    let (snapped, texel, step) = flicker(true);
    let (free, _, _) = flicker(false);
    eprintln!(
        "camera step {step:.3} m = {:.2} texels of cascade 1 ({texel:.3} m); flicker per frame: snapped {snapped:.5}, unsnapped {free:.5}",
        step / texel
    );
    assert!(step < texel, "steps must be sub-texel ({step} vs {texel})");
    // The unsnapped mask must flicker measurably, else the test proves nothing.
    // Measured 2026-11-22 on lavapipe (step 0.62 texel): snapped 0.00000,
    // unsnapped 0.0290 per edge pixel and frame; issue #6 asks <= 1/4.
    assert!(free > 1e-3, "unsnapped flicker {free} too small to compare");
    assert!(
        snapped <= 0.25 * free,
        "snapped {snapped} vs unsnapped {free}"
    );
}
