//! Screen-space AO (TECHNIQUES O1-O4): GPU passes against their CPU twins
//! (`passes/ao/reference.rs`) on small frames, blurred HBAO against
//! ray-traced AO (`himal_reference::ao`) on analytic scenes, and the O4
//! directional term and reflection occlusion against ray-traced visibility.

mod common;

use common::{pixel_ray_from, render_rgba as render, renderer};
use glam::{IVec2, Vec2, Vec3};
use himal::gpu::testing::run_compute;
use himal::passes::ao::reference::{self as twin, Image, StfView};
use himal::passes::ao::{AoMode, AoSettings, AoUniform, AoView};
use himal::passes::debug::DebugView;
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer, ViewBuffer};
use himal_reference::ao::{Shape, ambient_occlusion, directional_visibility, trace};

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

/// The blurred AO (no temporal filter) on the GPU, and its twin.
fn blurred(adaptive: bool, compute: bool, size: (u32, u32)) -> (Vec<[f32; 4]>, Image<[f32; 2]>) {
    let (scene, camera) = load("ao_sphere_on_plane");
    let mut r = renderer(&scene);
    let ao = AoSettings {
        adaptive_blur: adaptive,
        compute_blur: compute,
        ..ao_settings(AoMode::Hbao)
    };
    let mut s = frame_settings(&scene, size, ao, ViewBuffer::Ao(AoView::Raw));
    let depth = depth_image(&mut r, &camera, &s);
    let raw_full: Image<[f32; 4]> = channel(&render(&mut r, &camera, &s), size);
    s.view = ViewBuffer::Ao(AoView::Ao);
    let gpu = render(&mut r, &camera, &s);
    let p = uniform(&s, &camera);
    let (aw, ah) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    let raw = Image::from_fn(aw, ah, |q| {
        let v = raw_full.get(q * 2);
        [v[0], v[1]]
    });
    let packed = twin::pack(&p, &depth, &raw);
    let bx = twin::blur(&p, &packed, IVec2::X);
    (gpu, twin::blur(&p, &bx, IVec2::Y))
}

fn check_blur(adaptive: bool) -> (f32, f32) {
    let (gpu, cpu) = blurred(adaptive, false, (96, 64));
    diff_stats(cpu.data.iter().zip(&gpu).map(|(c, g)| (c[0], g[0])))
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

/// `--ao-blur-pass compute`: 288 pixels wide, so rows span three
/// workgroup tiles (128 pixels), the last one partial.
#[test]
fn compute_blur_matches_the_cpu_twin_and_the_fragment_blur() {
    let size = (288, 48);
    for adaptive in [true, false] {
        let (compute, cpu) = blurred(adaptive, true, size);
        let (mean, p99) = diff_stats(cpu.data.iter().zip(&compute).map(|(c, g)| (c[0], g[0])));
        eprintln!("compute blur, adaptive {adaptive}: twin mean {mean:.2e}, p99 {p99:.2e}");
        // Measured 2026-12-06 (lavapipe): mean 4.8e-4, p99 8.6e-4 both ways
        // (the tile keeps the packed values in f32); the fragment blur's thresholds.
        assert!(
            mean < 1.5e-3 && p99 < 4e-3,
            "adaptive {adaptive}: mean {mean}, p99 {p99}"
        );
        let (fragment, _) = blurred(adaptive, false, size);
        let max = fragment
            .iter()
            .zip(&compute)
            .map(|(f, c)| (f[0] - c[0]).abs())
            .fold(0.0f32, f32::max);
        eprintln!("compute vs fragment blur, adaptive {adaptive}: max |AO difference| {max:.2e}");
        // Measured 2026-12-06 (lavapipe): 4.9e-4 both ways, one f16 step at
        // AO 0.5: the fragment path rounds the packed (AO, Z) to f16, the
        // tile does not (with the packed texture kept: 0.0). Margin: one step at AO 1.
        assert!(max < 1e-3, "adaptive {adaptive}: max {max}");
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
    // (0.043); the issue's threshold 0.08 over all pixels with geometry.
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

// ---- O4: screen-space directional occlusion (docs/techniques/O4.md) ----

/// The analytic shapes of `scenes/ao_doorway.toml` (boxes from size and centre).
fn doorway_shapes() -> Vec<Shape> {
    let boxes = [
        ([2.4, 1.6, 0.2], [0.0, 0.8, -2.1]),
        ([0.2, 1.6, 2.2], [-1.1, 0.8, -1.0]),
        ([0.2, 1.6, 2.2], [1.1, 0.8, -1.0]),
        ([2.4, 0.2, 2.4], [0.0, 1.5, -1.0]),
        ([0.7, 1.4, 0.2], [-0.85, 0.7, 0.0]),
        ([0.7, 1.4, 0.2], [0.85, 0.7, 0.0]),
        ([1.0, 0.3, 0.2], [0.0, 1.25, 0.0]),
    ];
    let mut shapes = vec![Shape::Plane {
        normal: Vec3::Y,
        offset: 0.0,
    }];
    shapes.extend(boxes.iter().map(|&(size, centre)| {
        let (h, c) = (Vec3::from(size) * 0.5, Vec3::from(centre));
        Shape::Box {
            min: c - h,
            max: c + h,
        }
    }));
    shapes
}

const SSDO_KERNEL: &str = r#"
#import ao
struct In { p: vec4f, n: vec4f, l: vec4f, c: vec4f }
@group(0) @binding(0) var<storage, read> input: array<In>;
@group(0) @binding(1) var<storage, read_write> output: array<vec2f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&input)) { return; }
    let x = input[id.x];
    output[id.x] = vec2f(
        ssdo_visibility(x.p.xyz, x.n.xyz, x.l.xyz, x.c.yz, x.c.x * 8.0, x.c.w),
        specular_occlusion_lagarde(x.p.w, x.n.w, x.l.w));
}
"#;

#[test]
fn ssdo_lookups_match_the_cpu_twin() {
    let mut rng = common::Lcg(4);
    let mut r = move |lo: f32, hi: f32| lo + (hi - lo) * rng.next();
    let count = 4096;
    let mut input: Vec<[f32; 16]> = Vec::new();
    for _ in 0..count {
        let p = Vec3::new(r(-3.0, 3.0), r(-2.0, 2.0), r(-12.0, -0.5));
        let mut n = Vec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)).normalize();
        if n.dot(-p) < 0.0 {
            n = -n;
        }
        let l = Vec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0)).normalize();
        let c = Vec3::new(r(-0.1, 0.7), r(-0.6, 0.6), r(-0.6, 0.6));
        let (n_o_v, ao, rough, soft) = (r(0.0, 1.0), r(0.0, 1.0), r(0.0, 1.0), r(0.05, 0.6));
        input.push([
            p.x, p.y, p.z, n_o_v, n.x, n.y, n.z, ao, l.x, l.y, l.z, rough, c.x, c.y, c.z, soft,
        ]);
    }
    let out = run_compute(
        SSDO_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        (count * 8) as u64,
        [(count as u32).div_ceil(64), 1, 1],
    )
    .expect("kernel");
    let gpu: &[[f32; 2]] = bytemuck::cast_slice(&out);
    let (mut worst_v, mut worst_s) = (0.0f32, 0.0f32);
    for (x, g) in input.iter().zip(gpu) {
        let v3 = |i: usize| Vec3::new(x[i], x[i + 1], x[i + 2]);
        let v = twin::ssdo_visibility(
            v3(0),
            v3(4),
            v3(8),
            Vec2::new(x[13], x[14]),
            x[12] * 8.0,
            x[15],
        );
        let s = twin::specular_occlusion_lagarde(x[3], x[7], x[11]);
        worst_v = worst_v.max((v - g[0]).abs());
        worst_s = worst_s.max((s - g[1]).abs());
    }
    eprintln!("ssdo_visibility max |GPU - CPU| {worst_v:.2e}, Lagarde {worst_s:.2e}");
    // Measured 2026-12-05 (lavapipe): see docs/techniques/O4.md; f32 rounding
    // through a division by the penumbra width (>= 0.05).
    assert!(worst_v < 1e-3 && worst_s < 1e-4, "{worst_v} {worst_s}");
}

fn ssdo_settings() -> AoSettings {
    ao_settings(AoMode::Ssdo)
}

/// `--ao ssdo --ao-blur-pass compute`: the tile carries the O4
/// coefficients (c1, c2) with the AO's weights, as the fragment blur.
#[test]
fn compute_blur_carries_the_ssdo_coefficients() {
    let (scene, camera) = load("ao_box_corner");
    let size = (160, 64);
    let ao = AoSettings {
        compute_blur: true,
        ..ssdo_settings()
    };
    let view = |v| frame_settings(&scene, size, ao.clone(), v);
    let mut r = renderer(&scene);
    let depth = depth_image(&mut r, &camera, &view(ViewBuffer::Final));
    let p = uniform(&view(ViewBuffer::Final), &camera);
    r.reset_history();
    let raw_full: Image<[f32; 4]> = channel(
        &render(&mut r, &camera, &view(ViewBuffer::Ao(AoView::Raw))),
        size,
    );
    let raw = Image::from_fn(p.ao_size[0] as u32, p.ao_size[1] as u32, |q| {
        raw_full.get(q * 2)
    });
    // The first frame: no history, the STF passes the blur through.
    r.reset_history();
    let gpu: Image<[f32; 4]> = channel(
        &render(&mut r, &camera, &view(ViewBuffer::Ao(AoView::Directional))),
        size,
    );
    let packed = twin::pack_ssdo(&p, &depth, &raw);
    let cpu = twin::blur(&p, &twin::blur(&p, &packed, IVec2::X), IVec2::Y);
    let pairs = cpu
        .data
        .iter()
        .zip(&gpu.data)
        .flat_map(|(c, g)| [(c[0], g[0]), (c[2], g[1]), (c[3], g[2])]);
    let (mean, p99) = diff_stats(pairs);
    eprintln!("ssdo compute blur: mean {mean:.2e}, p99 {p99:.2e}");
    // Measured 2026-12-06 (lavapipe): mean 1.8e-4, p99 7.8e-4; the fragment
    // path's thresholds (ssdo_passes_match_the_cpu_twin).
    assert!(mean < 1.5e-3 && p99 < 4e-3, "{mean} {p99}");
}

#[test]
fn ssdo_passes_match_the_cpu_twin() {
    let (scene, camera1) = load("ao_box_corner");
    let size = (96, 64);
    let view = |v| frame_settings(&scene, size, ssdo_settings(), v);
    let mut r = renderer(&scene);
    let depth = depth_image(&mut r, &camera1, &view(ViewBuffer::Final));
    let p = uniform(&view(ViewBuffer::Final), &camera1);
    // ao.hbao's SSDO permutation.
    r.reset_history();
    let raw_full: Image<[f32; 4]> = channel(
        &render(&mut r, &camera1, &view(ViewBuffer::Ao(AoView::Raw))),
        size,
    );
    let (aw, ah) = (p.ao_size[0] as u32, p.ao_size[1] as u32);
    let raw = Image::from_fn(aw, ah, |q| raw_full.get(q * 2));
    let cpu_raw = twin::hbao_ssdo(&p, &depth);
    let pairs = |c: usize| {
        cpu_raw
            .data
            .iter()
            .zip(&raw.data)
            .map(move |(a, b)| (a[c], b[c]))
    };
    let (m1, p1) = diff_stats(pairs(2).chain(pairs(3)));
    let (m0, _) = diff_stats(pairs(0));
    eprintln!("hbao ssdo: AO mean {m0:.2e}; c1, c2 mean {m1:.2e}, p99 {p1:.2e}");
    // Measured 2026-12-05 (lavapipe), see O4.md: the AO as O1's test; the
    // coefficients sum the same per-direction occlusions (Rgba16Float).
    assert!(m0 < 1e-3 && m1 < 1.5e-3 && p1 < 6e-3, "{m0} {m1} {p1}");
    // pack + blur_x + blur_y on the first frame (no history: the STF passes it through).
    r.reset_history();
    let first: Image<[f32; 4]> = channel(
        &render(&mut r, &camera1, &view(ViewBuffer::Ao(AoView::Directional))),
        size,
    );
    let packed = twin::pack_ssdo(&p, &depth, &raw);
    let cpu = twin::blur(&p, &twin::blur(&p, &packed, IVec2::X), IVec2::Y);
    let dir_pairs = cpu
        .data
        .iter()
        .zip(&first.data)
        .flat_map(|(c, g)| [(c[0], g[0]), (c[2], g[1]), (c[3], g[2])]);
    let (mb, pb) = diff_stats(dir_pairs);
    eprintln!("ssdo pack + blur: mean {mb:.2e}, p99 {pb:.2e}");
    // Measured 2026-12-05: as the AO blur test (f16 between passes).
    assert!(mb < 1.5e-3 && pb < 4e-3, "{mb} {pb}");
    // The temporal filter of the coefficients: frame 2 from a moved camera.
    let mut camera2 = camera1.clone();
    camera2.position += Vec3::new(0.03, 0.0, -0.02);
    let mut a = renderer(&scene);
    render(&mut a, &camera1, &view(ViewBuffer::Ao(AoView::Ao)));
    let gpu_ao: Image<[f32; 4]> = channel(
        &render(&mut a, &camera2, &view(ViewBuffer::Ao(AoView::Ao))),
        size,
    );
    let mut b = renderer(&scene);
    let history: Image<[f32; 4]> = channel(
        &render(&mut b, &camera1, &view(ViewBuffer::Ao(AoView::Ao))),
        size,
    );
    let gpu_dir: Image<[f32; 4]> = channel(
        &render(&mut b, &camera2, &view(ViewBuffer::Ao(AoView::Directional))),
        size,
    );
    let history_dir = Image::from_fn(size.0, size.1, |q| {
        let v = first.get(q);
        [v[1], v[2]]
    });
    let mut c = renderer(&scene);
    let blurred: Image<[f32; 4]> = channel(
        &render(&mut c, &camera2, &view(ViewBuffer::Ao(AoView::Directional))),
        size,
    );
    let depth2 = depth_image(&mut c, &camera2, &view(ViewBuffer::Final));
    let stab: Image<[f32; 4]> = channel(
        &render(&mut c, &camera2, &view(ViewBuffer::Ao(AoView::Stability))),
        size,
    );
    let p2 = uniform(&view(ViewBuffer::Final), &camera2);
    let blurred = Image::from_fn(size.0, size.1, |q| {
        let v = blurred.get(q);
        [v[0], twin::linear_depth(&p2, depth2.get(q)), v[1], v[2]]
    });
    let stability = Image::from_fn(aw, ah, |q| stab.get(q * 2)[0]);
    let aspect = size.0 as f32 / size.1 as f32;
    let stf_view = StfView {
        inv_view_proj: camera2.view_projection(aspect).inverse(),
        prev_view_proj: camera1.view_projection(aspect),
    };
    let (cpu_ao, cpu_dir) = twin::temporal_filter_ssdo(
        &p2,
        &stf_view,
        &blurred,
        &depth2,
        &stability,
        &history,
        &history_dir,
    );
    let ao_pairs = cpu_ao
        .data
        .iter()
        .zip(&gpu_ao.data)
        .map(|(c, g)| (c[0], g[0]));
    let (ma, _) = diff_stats(ao_pairs);
    let d_pairs = cpu_dir
        .data
        .iter()
        .zip(&gpu_dir.data)
        .flat_map(|(c, g)| [(c[0], g[1]), (c[1], g[2])]);
    let (md, pd) = diff_stats(d_pairs);
    eprintln!("ssdo STF: AO mean {ma:.2e}; c1, c2 mean {md:.2e}, p99 {pd:.2e}");
    // Measured 2026-12-05: see O4.md (the AO STF test's thresholds).
    assert!(ma < 1e-3 && md < 1e-3 && pd < 4e-3, "{ma} {md} {pd}");
    let filtered = cpu_ao.data.iter().filter(|v| v[2] == 2.0).count();
    assert!(filtered > 100, "{filtered} pixels filtered");
}

/// Test light directions: 8 azimuths at elevations 15, 35 and 60 degrees.
fn light_directions() -> Vec<Vec3> {
    let mut v = Vec::new();
    for e in [15.0f32, 35.0, 60.0] {
        for k in 0..8 {
            let a = (k as f32 * 45.0 + 10.0).to_radians();
            let e = e.to_radians();
            v.push(Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin()));
        }
    }
    v
}

/// The O4 directional term of `scene` against ray-traced visibility. Returns
/// (lights: MAE of SSDO, of 1 (no directional term), of AO (constant term),
/// then the same along the reflection vector), each over the pixel-direction
/// pairs facing the surface.
fn directional_accuracy(name: &str, shapes: &[Shape]) -> [f32; 6] {
    let (scene, camera) = load(name);
    let mut r = renderer(&scene);
    let size = (128, 128);
    let s = frame_settings(
        &scene,
        size,
        ssdo_settings(),
        ViewBuffer::Ao(AoView::Directional),
    );
    let gpu = render(&mut r, &camera, &s);
    let view = camera.view();
    let lights = light_directions();
    let (soft, gain) = (s.ao.ssdo_softness, s.ao.ssdo_gain);
    let mut sums = [0.0f64; 6];
    let mut counts = [0usize; 2];
    for y in 0..size.1 {
        for x in 0..size.0 {
            let (origin, dir) = pixel_ray_from(&camera, size, x, y);
            let Some(hit) = trace(shapes, origin, dir, 0.0) else {
                continue;
            };
            let p = origin + dir * hit.t;
            let n = hit.normal;
            let g = gpu[(y * size.0 + x) as usize];
            let c = Vec2::new(g[1], g[2]);
            let (p_v, n_v) = (view.transform_point3(p), view.transform_vector3(n));
            let mut add = |set: usize, l: Vec3, soft: f32, cone: f32| {
                if n.dot(l) < 0.05 {
                    return;
                }
                let v_ssdo =
                    twin::ssdo_visibility(p_v, n_v, view.transform_vector3(l), c, gain, soft);
                let reference = directional_visibility(shapes, p, n, l, s.ao.radius, cone, 16);
                sums[set * 3] += (v_ssdo - reference).abs() as f64;
                sums[set * 3 + 1] += (1.0 - reference).abs() as f64;
                sums[set * 3 + 2] += (g[0] - reference).abs() as f64;
                counts[set] += 1;
            };
            for &l in &lights {
                add(0, l, soft, 0.0);
            }
            // A glossy lobe (perceptual roughness 0.15) around the mirror direction.
            let refl = dir - 2.0 * dir.dot(n) * n;
            let rough = 0.15;
            add(1, refl, soft + s.ao.ssdo_roughness_softness * rough, 0.15);
        }
    }
    std::array::from_fn(|i| (sums[i] / counts[i / 3].max(1) as f64) as f32)
}

#[test]
fn ssdo_directional_term_is_close_to_ray_traced_visibility() {
    let scenes: [(&str, Vec<Shape>); 3] = [
        ("ao_box_corner", box_shapes()),
        ("ao_sphere_on_plane", sphere_shapes()),
        ("ao_doorway", doorway_shapes()),
    ];
    for (name, shapes) in scenes {
        let e = directional_accuracy(name, &shapes);
        eprintln!(
            "{name}: lights MAE ssdo {:.4} (none {:.4}, AO {:.4}); reflection ssdo {:.4} (none {:.4}, AO {:.4})",
            e[0], e[1], e[2], e[3], e[4], e[5]
        );
        // Measured 2026-12-05 (lavapipe, gain 1.5, penumbra 0.4), lights /
        // reflection MAE: box 0.0213 (none 0.0215, AO 0.0552) / 0.0802 (none
        // 0.0841, AO 0.0782); sphere 0.0384 (0.0396, 0.0748) / 0.0781 (0.0926,
        // 0.0924); doorway 0.1682 (0.1688, 0.2122) / 0.2390 (0.2442, 0.2224).
        // The directional term must beat no term along both, and the constant
        // term along the lights.
        assert!(e[0] < e[1] && e[0] < e[2], "{name}: lights {e:?}");
        assert!(e[3] < e[4], "{name}: reflection {e:?}");
    }
}

/// Reflection occlusion (O4) in `scenes/ao_doorway.toml`: the ambient
/// specular of the metal floor inside the room (the sun's illuminance set to
/// 0, so the floor's radiance is its ambient specular alone) against the open
/// render times the ray-traced visibility of a 0.15 rad cone around the
/// mirror direction. Returns the relative mean error with reflection
/// occlusion on (SSDO), off (times AO, as before) and on without SSDO
/// (Lagarde's formula from AO), and the floor pixels counted.
fn doorway_reflection_errors() -> (f32, f32, f32, usize) {
    let (scene, camera) = load("ao_doorway");
    let shapes = doorway_shapes();
    let mut r = renderer(&scene);
    let size = (128, 96);
    let frame = |mode: AoMode, ro: bool| {
        let ao = AoSettings {
            mode,
            reflection_occlusion: ro,
            ..AoSettings::default()
        };
        let mut s = frame_settings(&scene, size, ao, ViewBuffer::Debug(DebugView::Lighting));
        s.sun.light = Some(himal::scene::SunLight {
            to_light: Vec3::new(0.4, 0.6, 0.7).normalize(),
            illuminance_klux: Vec3::ZERO,
        });
        s
    };
    let mut shot = |s: &FrameSettings| {
        r.reset_history();
        render(&mut r, &camera, s)
    };
    let open = shot(&frame(AoMode::Off, false));
    let on = shot(&frame(AoMode::Ssdo, true));
    let off = shot(&frame(AoMode::Ssdo, false));
    let lagarde = shot(&frame(AoMode::HbaoStf, true));
    let radius = AoSettings::default().radius;
    let (mut e_on, mut e_off, mut e_lag, mut total, mut n) = (0.0f64, 0.0, 0.0, 0.0, 0usize);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let (origin, dir) = pixel_ray_from(&camera, size, x, y);
            let Some(hit) = trace(&shapes, origin, dir, 0.0) else {
                continue;
            };
            let p = origin + dir * hit.t;
            // The floor inside the room.
            let inside = p.y < 1e-3 && p.x.abs() < 1.0 && p.z < -0.1 && p.z > -2.0;
            if !inside {
                continue;
            }
            let refl = dir - 2.0 * dir.dot(hit.normal) * hit.normal;
            let vis = directional_visibility(&shapes, p, hit.normal, refl, radius, 0.15, 32);
            let i = (y * size.0 + x) as usize;
            let lum = |c: [f32; 4]| (c[0] + c[1] + c[2]) as f64 / 3.0;
            let reference = lum(open[i]) * vis as f64;
            e_on += (lum(on[i]) - reference).abs();
            e_off += (lum(off[i]) - reference).abs();
            e_lag += (lum(lagarde[i]) - reference).abs();
            total += reference;
            n += 1;
        }
    }
    let t = total.max(1e-9);
    ((e_on / t) as f32, (e_off / t) as f32, (e_lag / t) as f32, n)
}

#[test]
fn reflection_occlusion_in_a_doorway_is_closer_to_ray_traced() {
    let (on, off, lagarde, n) = doorway_reflection_errors();
    // Measured 2026-12-05 (lavapipe): on 0.509, off 0.576, Lagarde 0.560
    // (1366 px). Off and Lagarde alone must stay larger; on within 10% of its
    // measurement.
    assert!(n > 300, "{n} floor pixels inside");
    assert!(
        on < 0.95 * off && on < lagarde && on < 0.56,
        "on {on}, off {off}, Lagarde {lagarde}"
    );
}

/// The directional term multiplies the sun's visibility (shadow mask R): in
/// the box scene under a low sun with shadow maps, pixels the mask already
/// shadows do not change (nothing left to darken: no double darkening), and
/// in the map's light few change: the box's contact shadows fall where
/// the map already shadows. `--ssdo-strength` 0 vs 1.
#[test]
fn ssdo_darkens_only_what_the_shadow_map_leaves_lit() {
    let (scene, camera) = load("ao_box_corner");
    let mut r = renderer(&scene);
    let size = (128, 96);
    let frame = |strength: f32, view: ViewBuffer| {
        let ao = AoSettings {
            ssdo_strength: strength,
            ..ssdo_settings()
        };
        let mut s = frame_settings(&scene, size, ao, view);
        s.shadow_resolution = 1024;
        s.sun.time_hours = 18.5;
        s
    };
    let mut shot = |s: &FrameSettings| {
        r.reset_history();
        render(&mut r, &camera, s)
    };
    let lit = ViewBuffer::Debug(DebugView::Lighting);
    let full = shot(&frame(1.0, lit));
    let none = shot(&frame(0.0, lit));
    let mask = shot(&frame(
        1.0,
        ViewBuffer::Shadow(himal::passes::shadows::ShadowView::Mask),
    ));
    let lum = |c: [f32; 4]| (c[0] + c[1] + c[2]) / 3.0;
    let (mut shadowed_change, mut n_shadowed) = (0.0f32, 0usize);
    let (mut contact, mut n_lit) = (0usize, 0usize);
    for i in 0..full.len() {
        let (a, b) = (lum(full[i]), lum(none[i]));
        if b <= 0.0 {
            continue;
        }
        let m = mask[i][0];
        if m < 0.02 {
            shadowed_change = shadowed_change.max(1.0 - a / b);
            n_shadowed += 1;
        } else if m > 0.98 {
            n_lit += 1;
            if a < 0.98 * b {
                contact += 1;
            }
        }
    }
    eprintln!(
        "ssdo under shadow maps: {n_shadowed} shadowed px, largest darkening {shadowed_change:.2e}; {contact} of {n_lit} sunlit px darkened > 2%"
    );
    // Measured 2026-12-05 (lavapipe): 3919 shadowed px, largest darkening
    // 5.3e-4 (in the map's shadow the sun term is already 0: the product
    // changes nothing but rounding); sunlit: see O4.md.
    assert!(
        n_shadowed > 200 && shadowed_change < 2e-3,
        "{shadowed_change}"
    );
    assert!(contact < n_lit / 20, "{contact} of {n_lit}");
}
