//! Screen-space AO (TECHNIQUES O1-O3): GPU passes against their CPU twins
//! (`passes/ao/reference.rs`) on small frames, and blurred HBAO against
//! ray-traced AO (`himal_reference::ao`) on analytic scenes.

mod common;

use common::{pixel_ray_from, render_rgba as render, renderer};
use glam::{IVec2, Vec3};
use himal::passes::ao::reference::{self as twin, Image, StfView};
use himal::passes::ao::{AoMode, AoSettings, AoUniform, AoView};
use himal::passes::debug::DebugView;
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer, ViewBuffer};
use himal_reference::ao::{Shape, ambient_occlusion, trace};

/// The analytic shapes of `scenes/ao_sphere_on_plane.toml`.
fn sphere_shapes() -> Vec<Shape> {
    vec![
        Shape::Plane {
            normal: Vec3::Y,
            offset: 0.0,
        },
        Shape::Sphere {
            centre: Vec3::new(0.0, 0.5, 0.0),
            radius: 0.5,
        },
    ]
}

/// The analytic shapes of `scenes/ao_box_corner.toml`.
fn box_shapes() -> Vec<Shape> {
    vec![
        Shape::Plane {
            normal: Vec3::Y,
            offset: 0.0,
        },
        Shape::Box {
            min: Vec3::new(-1.0, 0.0, -1.0),
            max: Vec3::new(1.0, 1.0, 1.0),
        },
    ]
}

/// `scenes/<name>.toml` and its camera `main`.
fn load(name: &str) -> (Scene, Camera) {
    common::scene_and_camera(name, "main")
}

fn ao_settings(mode: AoMode) -> AoSettings {
    AoSettings {
        mode,
        radius: 1.0,
        ..AoSettings::default()
    }
}

fn frame_settings(
    scene: &Scene,
    size: (u32, u32),
    ao: AoSettings,
    view: ViewBuffer,
) -> FrameSettings {
    let mut s = FrameSettings::new(size.0, size.1, scene.sun.clone());
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.ao = ao;
    s.view = view;
    s.raw = true;
    s
}

fn uniform(s: &FrameSettings, camera: &Camera) -> AoUniform {
    let aspect = s.width as f32 / s.height as f32;
    AoUniform::new(
        &s.ao,
        camera.projection(aspect),
        camera.near,
        (s.width, s.height),
    )
}

fn channel<const N: usize>(img: &[[f32; 4]], size: (u32, u32)) -> Image<[f32; N]> {
    Image::new(
        size.0,
        size.1,
        img.iter().map(|p| std::array::from_fn(|c| p[c])).collect(),
    )
}

fn depth_image(r: &mut Renderer, camera: &Camera, s: &FrameSettings) -> Image<f32> {
    let mut d = s.clone();
    d.view = ViewBuffer::Debug(DebugView::Depth);
    let img = render(r, camera, &d);
    Image::new(s.width, s.height, img.iter().map(|p| p[0]).collect())
}

/// Mean and 99th percentile of |a - b| over paired values.
fn diff_stats(pairs: impl Iterator<Item = (f32, f32)>) -> (f32, f32) {
    let mut d: Vec<f32> = pairs.map(|(a, b)| (a - b).abs()).collect();
    d.sort_by(f32::total_cmp);
    let mean = d.iter().sum::<f32>() / d.len().max(1) as f32;
    (mean, d[(d.len() * 99 / 100).min(d.len() - 1)])
}

#[test]
fn hbao_and_continuity_match_the_cpu_twin() {
    let (scene, camera) = load("ao_sphere_on_plane");
    let mut r = renderer(&scene);
    let size = (96, 64);
    let s = frame_settings(
        &scene,
        size,
        ao_settings(AoMode::Hbao),
        ViewBuffer::Ao(AoView::Raw),
    );
    let depth = depth_image(&mut r, &camera, &s);
    let p = uniform(&s, &camera);
    let cpu = twin::hbao(&p, &depth);
    let gpu: Image<[f32; 2]> = channel(&render(&mut r, &camera, &s), size);
    // ao-raw is shown at full resolution: AO texel q at pixel 2q.
    let gpu_at = |q: IVec2| gpu.get(q * 2);
    let (mean, p99) = diff_stats(
        (0..cpu.height as i32)
            .flat_map(|y| (0..cpu.width as i32).map(move |x| IVec2::new(x, y)))
            .map(|q| (cpu.get(q)[0], gpu_at(q)[0])),
    );
    // Measured 2026-11-22 (lavapipe): mean 1.7e-4, p99 4.9e-4 (Rg16Float storage).
    assert!(
        mean < 1e-3 && p99 < 3e-3,
        "HBAO GPU vs CPU: mean {mean}, p99 {p99}"
    );
    let agree = cpu
        .data
        .iter()
        .enumerate()
        .filter(|(i, c)| {
            let q = IVec2::new(*i as i32 % cpu.width as i32, *i as i32 / cpu.width as i32);
            c[1] == gpu_at(q)[1]
        })
        .count() as f32
        / cpu.data.len() as f32;
    // Measured: 1.0 (the classification is exact).
    assert!(agree > 0.995, "continuity mask agreement {agree}");
    // The open ground far from the ball is unoccluded (not self-occluded).
    let corner = cpu.get(IVec2::new(2, cpu.height as i32 - 3))[0];
    assert!(corner > 0.97, "flat ground AO {corner}");
}

#[test]
fn stability_mask_is_the_dilated_continuity_mask() {
    let (scene, camera) = load("ao_sphere_on_plane");
    let mut r = renderer(&scene);
    let size = (96, 64);
    let mut s = frame_settings(
        &scene,
        size,
        ao_settings(AoMode::HbaoStf),
        ViewBuffer::Ao(AoView::Raw),
    );
    let raw: Image<[f32; 4]> = channel(&render(&mut r, &camera, &s), size);
    s.view = ViewBuffer::Ao(AoView::Stability);
    let gpu: Image<[f32; 4]> = channel(&render(&mut r, &camera, &s), size);
    let p = uniform(&s, &camera);
    let (aw, ah) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    let continuity = Image::from_fn(aw, ah, |q| [1.0, raw.get(q * 2)[1]]);
    let cpu = twin::dilate_stability(&continuity);
    let mismatches = (0..ah as i32)
        .flat_map(|y| (0..aw as i32).map(move |x| IVec2::new(x, y)))
        .filter(|&q| cpu.get(q) != gpu.get(q * 2)[0])
        .count();
    // A min over exact 0/1 values: no tolerance needed.
    assert_eq!(mismatches, 0);
    // The ball's silhouette against the far ground is discontinuous, so some
    // pixels must be unstable, and the open ground near the camera stable.
    let unstable = cpu.data.iter().filter(|&&v| v < 0.5).count();
    assert!(unstable > 20, "{unstable} unstable texels");
    assert_eq!(cpu.get(IVec2::new(4, ah as i32 - 4)), 1.0);
}

fn check_blur(adaptive: bool) -> (f32, f32) {
    let (scene, camera) = load("ao_sphere_on_plane");
    let mut r = renderer(&scene);
    let size = (96, 64);
    let ao = AoSettings {
        adaptive_blur: adaptive,
        ..ao_settings(AoMode::Hbao)
    };
    let mut s = frame_settings(&scene, size, ao, ViewBuffer::Ao(AoView::Raw));
    let depth = depth_image(&mut r, &camera, &s);
    let raw_full: Image<[f32; 4]> = channel(&render(&mut r, &camera, &s), size);
    s.view = ViewBuffer::Ao(AoView::Ao);
    let gpu: Image<[f32; 4]> = channel(&render(&mut r, &camera, &s), size);
    let p = uniform(&s, &camera);
    let (aw, ah) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    let raw = Image::from_fn(aw, ah, |q| {
        let v = raw_full.get(q * 2);
        [v[0], v[1]]
    });
    let packed = twin::pack(&p, &depth, &raw);
    let bx = twin::blur(&p, &packed, IVec2::X);
    let cpu = twin::blur(&p, &bx, IVec2::Y);
    diff_stats(cpu.data.iter().zip(&gpu.data).map(|(c, g)| (c[0], g[0])))
}

#[test]
fn pack_and_blur_match_the_cpu_twin() {
    for adaptive in [true, false] {
        let (mean, p99) = check_blur(adaptive);
        // Measured 2026-11-22 (lavapipe): adaptive mean 5.7e-4 p99 9.7e-4,
        // brute force the same to 2 digits (f16 intermediates between passes).
        assert!(
            mean < 1.5e-3 && p99 < 4e-3,
            "adaptive {adaptive}: mean {mean}, p99 {p99}"
        );
    }
}

#[test]
fn temporal_filter_matches_the_cpu_twin() {
    let (scene, camera1) = load("ao_sphere_on_plane");
    let size = (96, 64);
    let mut camera2 = camera1.clone();
    camera2.position += Vec3::new(0.03, 0.0, -0.02);
    let stf = ao_settings(AoMode::HbaoStf);
    let view = |v| frame_settings(&scene, size, stf.clone(), v);
    // The filter's result over two frames.
    let mut a = renderer(&scene);
    let history1: Image<[f32; 4]> = channel(
        &render(&mut a, &camera1, &view(ViewBuffer::Ao(AoView::Ao))),
        size,
    );
    let gpu: Image<[f32; 4]> = channel(
        &render(&mut a, &camera2, &view(ViewBuffer::Ao(AoView::Ao))),
        size,
    );
    // Frame 2's inputs, from renderers that run the same deterministic passes.
    let mut b = renderer(&scene);
    let hbao_only = frame_settings(
        &scene,
        size,
        ao_settings(AoMode::Hbao),
        ViewBuffer::Ao(AoView::Ao),
    );
    let blurred: Image<[f32; 4]> = channel(&render(&mut b, &camera2, &hbao_only), size);
    let blurred = Image::from_fn(size.0, size.1, |q| {
        let v = blurred.get(q);
        [v[0], v[1]]
    });
    let depth = depth_image(&mut b, &camera2, &view(ViewBuffer::Final));
    let stab: Image<[f32; 4]> = channel(
        &render(&mut b, &camera2, &view(ViewBuffer::Ao(AoView::Stability))),
        size,
    );
    let p = uniform(&view(ViewBuffer::Final), &camera2);
    let (aw, ah) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    let stability = Image::from_fn(aw, ah, |q| stab.get(q * 2)[0]);
    let aspect = size.0 as f32 / size.1 as f32;
    let stf_view = StfView {
        inv_view_proj: camera2.view_projection(aspect).inverse(),
        prev_view_proj: camera1.view_projection(aspect),
    };
    let cpu = twin::temporal_filter(&p, &stf_view, &blurred, &depth, &stability, &history1);
    let (mean, p99) = diff_stats(cpu.data.iter().zip(&gpu.data).map(|(c, g)| (c[0], g[0])));
    // Measured 2026-11-22 (lavapipe): mean 1.3e-4, p99 4.4e-4.
    assert!(
        mean < 1e-3 && p99 < 4e-3,
        "STF GPU vs CPU: mean {mean}, p99 {p99}"
    );
    let n_agree = cpu
        .data
        .iter()
        .zip(&gpu.data)
        .filter(|(c, g)| c[2] == g[2])
        .count() as f32
        / cpu.data.len() as f32;
    // Measured: 1.0; a reprojection landing on a texel border could flip one.
    assert!(n_agree > 0.99, "N agreement {n_agree}");
    // Some pixels were filtered (N = 2) and some were not (stable ground: N = 1).
    assert!(gpu.data.iter().any(|g| g[2] == 2.0) && gpu.data.iter().any(|g| g[2] == 1.0));
}

#[test]
fn camera_cut_clears_the_history() {
    let (scene, camera) = load("ao_sphere_on_plane");
    let mut r = renderer(&scene);
    let s = frame_settings(
        &scene,
        (64, 48),
        ao_settings(AoMode::HbaoStf),
        ViewBuffer::Ao(AoView::Ao),
    );
    for _ in 0..3 {
        render(&mut r, &camera, &s);
    }
    let before = render(&mut r, &camera, &s);
    assert!(before.iter().any(|p| p[2] > 3.0), "history accumulates");
    r.reset_history();
    let after = render(&mut r, &camera, &s);
    assert!(after.iter().all(|p| p[2] == 1.0), "cut: N = 1 everywhere");
}

/// Mean |blurred HBAO - ray-traced AO| over the pixels with geometry, and
/// the same over the occluded pixels (reference AO < 0.95).
fn accuracy(name: &str, shapes: &[Shape], orthographic: bool) -> (f32, f32, usize) {
    let (scene, mut camera) = load(name);
    if orthographic {
        // The same view through a parallel projection framing the scene's
        // centre as the perspective one does at its distance.
        let d = camera.position.length();
        camera.orthographic = Some(himal::scene::Orthographic {
            half_height: d * (camera.fov_y_deg.to_radians() * 0.5).tan(),
            far: 4.0 * d,
        });
    }
    let mut r = renderer(&scene);
    let size = (128, 128);
    let s = frame_settings(
        &scene,
        size,
        ao_settings(AoMode::Hbao),
        ViewBuffer::Ao(AoView::Ao),
    );
    let gpu = render(&mut r, &camera, &s);
    let (mut sum, mut n, mut sum_occ, mut n_occ) = (0.0, 0usize, 0.0, 0usize);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let (origin, dir) = pixel_ray_from(&camera, size, x, y);
            let Some(hit) = trace(shapes, origin, dir, 0.0) else {
                continue;
            };
            let p = origin + dir * hit.t;
            let reference = ambient_occlusion(shapes, p, hit.normal, s.ao.radius, 256);
            let e = (gpu[(y * size.0 + x) as usize][0] - reference).abs();
            sum += e;
            n += 1;
            if reference < 0.95 {
                sum_occ += e;
                n_occ += 1;
            }
        }
    }
    (sum / n as f32, sum_occ / n_occ.max(1) as f32, n_occ)
}

#[test]
fn blurred_hbao_is_close_to_ray_traced_ao() {
    let (sphere, sphere_occ, n1) = accuracy("ao_sphere_on_plane", &sphere_shapes(), false);
    let (corner, corner_occ, n2) = accuracy("ao_box_corner", &box_shapes(), false);
    eprintln!(
        "MAE sphere {sphere:.4} (occluded {sphere_occ:.4}, {n1} px), box {corner:.4} (occluded {corner_occ:.4}, {n2} px)"
    );
    // Measured 2026-11-22: sphere 0.030 (0.055 on occluded pixels), box 0.026
    // (0.043); the threshold 0.08 over all pixels with geometry.
    assert!(
        sphere <= 0.08 && corner <= 0.08,
        "sphere {sphere}, box {corner}"
    );
}

/// HBAO under an orthographic camera (glTF's): view positions come from
/// the projection's depth rows, not from `near / depth`, so the same scenes
/// match the ray-traced AO as the perspective views do. Before the fix the
/// linear depth and positions were the perspective ones.
#[test]
fn orthographic_hbao_is_close_to_ray_traced_ao() {
    let (sphere, sphere_occ, n1) = accuracy("ao_sphere_on_plane", &sphere_shapes(), true);
    let (corner, corner_occ, n2) = accuracy("ao_box_corner", &box_shapes(), true);
    eprintln!(
        "orthographic MAE sphere {sphere:.4} (occluded {sphere_occ:.4}, {n1} px), box {corner:.4} (occluded {corner_occ:.4}, {n2} px)"
    );
    // Measured 2026-12-03 (lavapipe): sphere 0.026 (0.072 on occluded
    // pixels), box 0.040 (0.056); with the perspective reconstruction the
    // occluded pixels were off by 0.205 and 0.204. Thresholds: the
    // perspective test's 0.08 overall, 0.10 on the occluded pixels.
    assert!(
        sphere <= 0.08 && corner <= 0.08 && n1 > 100 && n2 > 100,
        "sphere {sphere} ({n1} px), box {corner} ({n2} px)"
    );
    assert!(
        sphere_occ <= 0.10 && corner_occ <= 0.10,
        "occluded: sphere {sphere_occ}, box {corner_occ}"
    );
}
