//! Environment-map filtering (TECHNIQUES L4) and the M4 reflection normal:
//! the GPU DFG table against `dfg_reference.txt` and its CPU twin, the GGX
//! filtered mips of a cube made from `venice_sunset_1k.hdr` against a
//! brute-force 16k-sample reference and against the CPU twin, and M4 on
//! the GPU against the CPU.

mod common;

use glam::{Vec2, Vec3};
use himal::gpu::testing::{run_compute, shared_context};
use himal::passes::envmap::reference::{
    CubeMip, box_mips, cube_face_direction, dfg, filter_fis, filter_reference,
    m4_reflection_normal, mip_alpha,
};
use himal::passes::envmap::{DFG_SIZE, ENVMAP_SIZE, EnvMapPass, FILTER_SAMPLES, FILTERED_LEVELS};

const VENICE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/assets/env/venice_sunset_1k.hdr"
);
const DFG_REFERENCE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../../shared/assets/reference/dfg_reference.txt"
);

#[test]
fn dfg_table_matches_cpu_twin_and_reference() {
    let ctx = shared_context().expect("GPU");
    let env = EnvMapPass::new(ctx, 32).expect("envmap");
    let gpu = common::read_rgb(ctx, &env.dfg, 0, 0);
    let n = DFG_SIZE as usize;
    let mut worst_twin = 0.0f32;
    for y in (0..n).step_by(7) {
        for x in (0..n).step_by(7) {
            let uv = (Vec2::new(x as f32, y as f32) + 0.5) / n as f32;
            let cpu = dfg(uv.x, uv.y, 512);
            worst_twin = worst_twin.max((gpu[y * n + x].truncate() - cpu).abs().max_element());
        }
    }
    // Measured 2026-11-22: 4.8e-4 (fp16 storage of values up to 1); threshold 2e-3.
    eprintln!("DFG GPU vs CPU twin: max |error| {worst_twin:.2e}");
    assert!(worst_twin < 2e-3, "{worst_twin}");

    // The converged table (2^21 samples), looked up bilinearly like the lighting pass.
    let text = std::fs::read_to_string(DFG_REFERENCE).expect(DFG_REFERENCE);
    let table = himal::passes::lighting::reference::EnvironmentSpecular {
        filtered: Vec::new(),
        dfg: gpu.iter().map(|t| t.truncate()).collect(),
        dfg_size: n,
    };
    let mut worst = 0.0f32;
    let mut rows = 0;
    for line in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
    {
        let c: Vec<f32> = line
            .split_whitespace()
            .map(|v| v.parse().expect("number"))
            .collect();
        let (roughness, n_o_v, ab) = (c[0], c[2], Vec2::new(c[3], c[4]));
        worst = worst.max((table.dfg_at(n_o_v, roughness) - ab).abs().max_element());
        rows += 1;
    }
    eprintln!("DFG table vs dfg_reference.txt ({rows} rows): max |error| {worst:.4}");
    // Measured 2026-11-22: 0.0111, at n.v = 0.05 where the 64-texel table
    // interpolates the steepest part of the curve (the reference's own 1024-sample
    // column differs from its converged one by up to 0.0088); threshold 0.02.
    assert_eq!(rows, 30);
    assert!(worst < 0.02, "{worst}");
}

/// `size`² cube faces sampled (bilinear) from an equirectangular HDR image.
fn cube_from_equirect(path: &str, size: usize) -> CubeMip {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{path}: {e}"))
        .into_rgb32f();
    let (w, h) = (img.width() as f32, img.height() as f32);
    let texel = |x: i64, y: i64| {
        let x = x.rem_euclid(img.width() as i64) as u32;
        let y = y.clamp(0, img.height() as i64 - 1) as u32;
        let p = img.get_pixel(x, y).0;
        Vec3::new(p[0], p[1], p[2])
    };
    CubeMip::from_fn(size, |d| {
        // +Y up; longitude from +X toward -Z, so -Z (face 5) sits a quarter turn from +X.
        let u = 0.5 + d.z.atan2(d.x) / std::f32::consts::TAU;
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        let p = Vec2::new(u * w, v * h) - 0.5;
        let p0 = p.floor();
        let f = p - p0;
        let (x0, y0) = (p0.x as i64, p0.y as i64);
        let top = texel(x0, y0).lerp(texel(x0 + 1, y0), f.x);
        let bottom = texel(x0, y0 + 1).lerp(texel(x0 + 1, y0 + 1), f.x);
        top.lerp(bottom, f.y)
    })
}

#[test]
fn filtered_mips_match_brute_force_reference() {
    let ctx = shared_context().expect("GPU");
    let size = 32u32;
    let level0 = cube_from_equirect(VENICE, size as usize);
    let env = EnvMapPass::new(ctx, size).expect("envmap");
    let faces = std::array::from_fn(|f| level0.faces[f].iter().map(|c| c.to_array()).collect());
    env.filter_faces(ctx, &faces).expect("filter");
    let chain = box_mips(level0.clone());
    const REFERENCE_SAMPLES: u32 = 16384;
    eprintln!(
        "taps per texel: {FILTER_SAMPLES} filtered importance samples vs {REFERENCE_SAMPLES} ({}x fewer)",
        REFERENCE_SAMPLES / FILTER_SAMPLES
    );
    for mip in 1..FILTERED_LEVELS {
        let alpha = mip_alpha(mip, FILTERED_LEVELS);
        let s = (size >> mip) as usize;
        let (mut err_ref, mut err_twin, mut energy) = (0.0f64, 0.0f64, 0.0f64);
        for face in 0..6 {
            let gpu = common::read_rgb(ctx, env.filtered(), mip, face as u32);
            for (i, g) in gpu.iter().enumerate() {
                let uv = (Vec2::new((i % s) as f32, (i / s) as f32) + 0.5) / s as f32;
                let n = cube_face_direction(face, uv);
                let reference = filter_reference(&level0, n, alpha, REFERENCE_SAMPLES);
                let twin = filter_fis(&chain, n, alpha, FILTER_SAMPLES);
                err_ref += f64::from((*g - reference).length_squared());
                err_twin += f64::from((*g - twin).length_squared());
                energy += f64::from(reference.length_squared());
            }
        }
        let rel_ref = (err_ref / energy).sqrt();
        let rel_twin = (err_twin / energy).sqrt();
        eprintln!(
            "mip {mip} ({s}x{s}, alpha {alpha:.3}): relative RMSE vs brute force {rel_ref:.4}, vs CPU twin {rel_twin:.4}"
        );
        // The issue: relative RMSE <= 3% with <= 1/16 of the reference's taps.
        // Measured 2026-11-22 with 128 taps (1/128): mips 1..5 0.0053, 0.0070,
        // 0.0091, 0.0150, 0.0196 (64 taps: up to 0.0299, too close to 3%).
        assert!(rel_ref <= 0.03, "mip {mip}: {rel_ref}");
        // Twin: same samples and lods; the CPU clamps bilinear taps at face
        // edges where the GPU filters across seams. Measured 0.0017..0.0098.
        assert!(rel_twin <= 0.02, "mip {mip}: {rel_twin}");
    }
}

#[test]
fn m4_reflection_normal_gpu_matches_cpu() {
    let source = r#"
#import envmap
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= arrayLength(&output)) { return; }
    let n = input[3u * i].xyz;
    let b = input[3u * i + 1u].xyz;
    let v = input[3u * i + 2u].xyz;
    output[i] = vec4f(m4_reflection_normal(n, b, v, input[3u * i].w), 0.0);
}
"#;
    let mut rng = himal::math::sampling::Pcg32::new(7);
    let mut cases = Vec::new();
    for k in 0..256 {
        let n = himal::math::sampling::uniform_sample_sphere(rng.next_vec2());
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let mut v = himal::math::sampling::uniform_sample_sphere(rng.next_vec2());
        if v.dot(n) < 0.05 {
            v = (v - 2.0 * v.dot(n) * n + 0.1 * n).normalize();
        }
        let anisotropy = if k % 4 == 0 { 0.0 } else { rng.next_f32() };
        cases.push((n, b, v, anisotropy));
    }
    let input: Vec<[f32; 4]> = cases
        .iter()
        .flat_map(|(n, b, v, a)| {
            [
                n.extend(*a).to_array(),
                b.extend(0.0).to_array(),
                v.extend(0.0).to_array(),
            ]
        })
        .collect();
    let out = run_compute(
        source,
        "main",
        bytemuck::cast_slice(&input),
        (cases.len() * 16) as u64,
        [4, 1, 1],
    )
    .expect("kernel");
    let out: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = 0.0f32;
    for ((n, b, v, a), g) in cases.iter().zip(out) {
        let cpu = m4_reflection_normal(*n, *b, *v, *a);
        let g = Vec3::new(g[0], g[1], g[2]);
        worst = worst.max((g - cpu).abs().max_element());
        if *a == 0.0 {
            // With anisotropy 0 the reflection normal is the normal (the issue's check).
            assert!((g - *n).abs().max_element() < 1e-6, "{g} vs {n}");
        } else {
            // Bent toward the viewer's side, never past it: still in front of v.
            assert!(
                g.dot(*v) > -1e-4 || n.dot(*v) < 0.0,
                "{g} behind the viewer"
            );
        }
    }
    // Measured 2026-11-22: 6.0e-8; threshold 1e-5.
    eprintln!("M4 GPU vs CPU: max |error| {worst:.2e}");
    assert!(worst < 1e-5, "{worst}");
}

#[test]
fn relit_probe_faces_equal_the_lighting_pass_seen_from_the_probe() {
    use himal::passes::envmap::probe::face_camera;
    use himal::{FrameSettings, ViewBuffer};
    let scene = common::scene("envmap_probe");
    let new_renderer = || common::renderer(&scene);
    let size = 128u32;
    let base = |w, h| {
        let mut s = FrameSettings::new(w, h, scene.sun.clone());
        s.shadow_resolution = 0;
        s.aerial_extinction = 0.0;
        s.ao.mode = himal::passes::ao::AoMode::Off;
        s.environment_specular = false;
        s
    };
    // Frame 1 captures the probe's G-buffer cube and relights it.
    let mut r = new_renderer();
    r.render(scene.camera("main").expect("camera"), &base(64, 64))
        .expect("frame");
    let probe = scene.probes[0];
    let mut worst = 0.0f32;
    let mut texels = 0usize;
    // Side faces: the noon sun (and its disk, which the probe leaves out) is in +Y.
    for face in [0usize, 1, 4, 5] {
        let relit = common::read_rgb(r.context(), r.envmap().source(), 0, face as u32);
        // The same lighting permutation, rendered directly from the probe.
        let mut direct_renderer = new_renderer();
        let mut s = base(size, size);
        s.view = "lighting".parse::<ViewBuffer>().expect("view");
        s.raw = true;
        s.environment_probes = false;
        let direct = common::render_rgba(&mut direct_renderer, &face_camera(probe, face), &s);
        let n = size as usize;
        for y in 0..n {
            for x in 0..n {
                // Cube faces are seen from inside: mirrored in x.
                let d = direct[y * n + (n - 1 - x)];
                let d = Vec3::new(d[0], d[1], d[2]);
                let c = relit[y * n + x];
                worst = worst.max(((c - d).abs() / d.max(Vec3::splat(1e-2))).max_element());
                texels += 1;
            }
        }
    }
    eprintln!("relit probe vs direct lighting: {texels} texels, worst relative error {worst:.2e}");
    assert_eq!(texels, 4 * 128 * 128);
    // Same pipeline, same rasterisation, sky without a sun in view: measured
    // 2026-11-22: 0 (bit-identical). Compared without the x mirror: 11.5.
    assert!(worst < 1e-3, "{worst}");
}

/// `--view env-mirror` and `--view env-probe` (raw) against the CPU lookup
/// of the filtered cube: along -v on the sky, along the reflection of -v
/// about the G-buffer normal at the roughness mip on surfaces (anisotropy 0
/// in this scene, so the M4 normal is n).
#[test]
fn environment_views_read_the_filtered_cube_like_lighting() {
    use glam::{Mat4, Vec4};
    use himal::math::brdf::perceptual_roughness_from_glossiness;
    use himal::passes::envmap::reference::sample_lod;
    let (scene, camera) = common::scene_and_camera("envmap_probe", "main");
    let camera = &camera;
    let mut r = common::renderer(&scene);
    let (w, h) = (64u32, 48u32);
    let mut raw = |name: &str| {
        let mut s = common::raw_settings(&scene, (w, h), name);
        s.shadow_resolution = 0;
        s.ao.mode = himal::passes::ao::AoMode::Off;
        common::render_rgba(&mut r, camera, &s)
    };
    let (mirror, probe) = (raw("env-mirror"), raw("env-probe"));
    let (normal, depth, gloss, aniso) = (
        raw("normal"),
        raw("depth"),
        raw("glossiness"),
        raw("anisotropy"),
    );
    let chain: Vec<CubeMip> = (0..FILTERED_LEVELS)
        .map(|mip| {
            let size = (ENVMAP_SIZE >> mip) as usize;
            CubeMip {
                size,
                faces: std::array::from_fn(|f| {
                    common::read_rgb(r.context(), r.envmap().filtered(), mip, f as u32)
                }),
            }
        })
        .collect();
    let inv = (camera.projection(w as f32 / h as f32) * camera.view()).inverse();
    let (mut err_mirror, mut err_probe, mut n) = (0.0f32, 0.0f32, 0usize);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let d = depth[i][0];
            if aniso[i][0] != 0.0 {
                continue;
            }
            let ndc = Vec4::new(
                (x as f32 + 0.5) / w as f32 * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h as f32 * 2.0,
                if d > 0.0 { d } else { 1.0 },
                1.0,
            );
            let p = Mat4::mul_vec4(&inv, ndc);
            let v = (camera.position - p.truncate() / p.w).normalize();
            let (want_mirror, want_probe) = if d <= 0.0 {
                let c = sample_lod(&chain, -v, 0.0);
                (c, c)
            } else {
                let nrm = Vec3::new(normal[i][0], normal[i][1], normal[i][2]).normalize();
                let refl = -v - 2.0 * (-v).dot(nrm) * nrm;
                let lod = perceptual_roughness_from_glossiness(gloss[i][0])
                    * (FILTERED_LEVELS - 1) as f32;
                (sample_lod(&chain, refl, 0.0), sample_lod(&chain, refl, lod))
            };
            let rel = |got: [f32; 4], want: Vec3| {
                ((Vec3::new(got[0], got[1], got[2]) - want).abs() / want.max(Vec3::splat(1e-2)))
                    .max_element()
            };
            err_mirror += rel(mirror[i], want_mirror);
            err_probe += rel(probe[i], want_probe);
            n += 1;
        }
    }
    let (err_mirror, err_probe) = (err_mirror / n as f32, err_probe / n as f32);
    eprintln!(
        "env views vs CPU lookup over {n} pixels: mirror mean {err_mirror:.2e}, probe mean {err_probe:.2e}"
    );
    assert!(n > (w * h / 2) as usize, "{n}");
    // Measured 2026-11-22 (lavapipe): 6.8e-7 for both (float precision; the
    // CPU clamps at face edges where the GPU filters across them, and these
    // pixels barely reach them). Threshold 1e-3.
    assert!(
        err_mirror < 1e-3 && err_probe < 1e-3,
        "{err_mirror} {err_probe}"
    );
}
