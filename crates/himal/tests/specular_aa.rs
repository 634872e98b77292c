//! E3 specular anti-aliasing (Toksvig): normal-map mips with the normal
//! variance in alpha (`gpu_scene/normal_mipmap.wgsl`) against their CPU twin
//! `next_normal_mip_reference`, the variance of known maps, and the shared
//! WGSL functions (`brdf.wgsl` `toksvig_roughness`, `normal_variance_*`)
//! against `math::brdf`. docs/techniques/E3.md.
//! Measured numbers: `cargo test --release -p himal --test specular_aa -- --nocapture`.

mod common;

use glam::Vec3;
use himal::FrameSettings;
use himal::gpu::read_texture;
use himal::gpu::testing::{run_compute, shared_context};
use himal::gpu_scene::textures::{MaterialTextures, mip_count, next_normal_mip_reference};
use himal::math::brdf::{normal_variance_decode, normal_variance_encode, toksvig_roughness};
use himal::math::sampling::Pcg32;
use himal::scene::gltf::{ImageData, PbrMaterial, PbrSet, SamplerDesc, TextureRef, TextureSlot};
use himal::scene::{Camera, Scene, SunLight};

/// A tangent-space normal as glTF stores it (RGB = n / 2 + 1/2), alpha `a`.
fn encode(n: Vec3, a: u8) -> [u8; 4] {
    let c = |v: f32| ((v * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0).round() as u8;
    [c(n.x), c(n.y), c(n.z), a]
}

/// One material with `image` as its normal texture, uploaded; returns the
/// upload and the texture index of the normal slot.
fn upload_normal_map(image: &ImageData) -> (MaterialTextures, usize) {
    let gpu = common::upload_one_image_material(image, |m, t| m.normal_texture = Some(t));
    let index = gpu.materials[0].slots[2].0;
    (gpu, index)
}

/// The largest per-channel difference of RGB and of alpha between two RGBA8 images.
fn worst(a: &[u8], b: &[u8]) -> (i32, i32) {
    let (mut rgb, mut alpha) = (0, 0);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let d = (*x as i32 - *y as i32).abs();
        if i % 4 == 3 {
            alpha = alpha.max(d);
        } else {
            rgb = rgb.max(d);
        }
    }
    (rgb, alpha)
}

#[test]
fn gpu_normal_mips_match_the_cpu_twin() {
    // 67 x 45: odd both ways (levels 33x22, 16x11, 8x5, 4x2, 2x1, 1x1), random
    // normals within 60 degrees of +z, random alpha (the upload zeroes it).
    let (w, h) = (67u32, 45u32);
    let mut rng = Pcg32::new(67);
    let mut rgba8 = Vec::new();
    for _ in 0..w * h {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let cos = 1.0 - u * 0.5;
        let sin = (1.0 - cos * cos).sqrt();
        let phi = v * std::f32::consts::TAU;
        let n = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
        rgba8.extend(encode(n, (rng.next_u32() & 255) as u8));
    }
    let image = ImageData {
        name: "random normals".into(),
        width: w,
        height: h,
        rgba8,
    };
    let (gpu, index) = upload_normal_map(&image);
    let ctx = shared_context().expect("GPU");
    let t = &gpu.textures[index];
    assert_eq!(t.mip_level_count(), mip_count(w, h));
    let level0 = read_texture(ctx, t, 0, 0).expect("read back");
    assert!(
        level0.bytes.chunks_exact(4).all(|p| p[3] == 0),
        "level 0 carries no variance"
    );
    let mut prev = level0.bytes.clone();
    let mut chain = (w, h, level0.bytes);
    let (mut pw, mut ph) = (w, h);
    let mut report = Vec::new();
    let (mut step_rgb, mut step_a, mut chain_rgb, mut chain_a) = (0, 0, 0, 0);
    for level in 1..t.mip_level_count() {
        let got = read_texture(ctx, t, level, 0).expect("read back");
        let (sw, sh, step) = next_normal_mip_reference(pw, ph, &prev, level == 1);
        chain = next_normal_mip_reference(chain.0, chain.1, &chain.2, level == 1);
        assert_eq!((got.width, got.height), (sw, sh), "level {level}");
        let (r, a) = worst(&step, &got.bytes);
        let (cr, ca) = worst(&chain.2, &got.bytes);
        let mean_a = got.bytes.chunks_exact(4).map(|p| p[3] as f32).sum::<f32>()
            / (got.bytes.len() / 4) as f32;
        report.push(format!(
            "level {level} {sw}x{sh}: step RGB {r} alpha {a}, chain RGB {cr} alpha {ca} (8-bit steps); mean alpha {mean_a:.1} = sigma^2 {:.3}",
            normal_variance_decode(mean_a / 255.0)
        ));
        (step_rgb, step_a) = (step_rgb.max(r), step_a.max(a));
        (chain_rgb, chain_a) = (chain_rgb.max(cr), chain_a.max(ca));
        (prev, pw, ph) = (got.bytes, sw, sh);
    }
    eprintln!("{}", report.join("\n"));
    // Measured on lavapipe on 2026-12-05: every level equal to the twin's,
    // one step from the GPU's previous level and the whole chain from level
    // 0 (0 steps in RGB and alpha; both compute in f32 and round to
    // nearest). Threshold 1 step for other drivers' rounding at .5 ties; a
    // wrong parent or a missed normalisation moves random normals by tens
    // of steps.
    assert!(step_rgb <= 1 && step_a <= 1, "{}", report.join("\n"));
    assert!(chain_rgb <= 1 && chain_a <= 1, "{}", report.join("\n"));
}

#[test]
fn a_flat_map_has_no_variance_and_a_checkerboard_has_toksvigs() {
    let ctx = shared_context().expect("GPU");
    // Flat: sigma^2 exactly 0 (alpha 0) at every level, RGB stays (128, 128, 255).
    let (w, h) = (40u32, 24u32);
    let flat = ImageData {
        name: "flat".into(),
        width: w,
        height: h,
        rgba8: [128u8, 128, 255, 255].repeat((w * h) as usize),
    };
    let (gpu, index) = upload_normal_map(&flat);
    let t = &gpu.textures[index];
    for level in 0..t.mip_level_count() {
        let got = read_texture(ctx, t, level, 0).expect("read back");
        assert!(
            got.bytes.chunks_exact(4).all(|p| p == [128, 128, 255, 0]),
            "level {level} of a flat map: {:?}",
            &got.bytes[..4]
        );
    }
    // Checkerboard of (+-sin t, 0, cos t): level 1's RGB averages one of
    // each twice (+z). Its variance is that of level 0's bilinear field over
    // the footprint, where the checker's weights leave (1 - 2 tx)(1 - 2 ty)
    // of the slope: the texels' own spread (1 - cos t) / cos t would count
    // the alternation the sampler blurs away. Expected: the field's mean
    // unit normal on a fine 64 x 64 grid over a cell (the footprint holds
    // whole periods).
    for degrees in [5.0f32, 15.0, 30.0, 45.0] {
        let theta = degrees.to_radians();
        let (s, c) = theta.sin_cos();
        let mut rgba8 = Vec::new();
        for y in 0..16u32 {
            for x in 0..16u32 {
                let sign = if (x + y) % 2 == 0 { 1.0 } else { -1.0 };
                rgba8.extend(encode(Vec3::new(sign * s, 0.0, c), 255));
            }
        }
        let image = ImageData {
            name: "checker".into(),
            width: 16,
            height: 16,
            rgba8,
        };
        // The 8-bit texels as the sampler decodes them (what the GPU sees).
        let decode =
            |q: [u8; 4]| Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / 255.0 * 2.0 - 1.0;
        let (plus, minus) = (
            decode(encode(Vec3::new(s, 0.0, c), 0)),
            decode(encode(Vec3::new(-s, 0.0, c), 0)),
        );
        let grid = |i: u32| (i as f32 + 0.5) / 64.0;
        let m = (0..64 * 64)
            .map(|i| {
                let (tx, ty) = (grid(i % 64), grid(i / 64));
                let w = (1.0 - tx) * (1.0 - ty) + tx * ty;
                (plus * w + minus * (1.0 - w)).normalize()
            })
            .sum::<Vec3>()
            / 4096.0;
        let expected = (1.0 - m.length()) / m.length();
        let texels = (1.0 - plus.normalize().dot(Vec3::Z)) / plus.normalize().dot(Vec3::Z);
        let (gpu, index) = upload_normal_map(&image);
        let got = read_texture(ctx, &gpu.textures[index], 1, 0).expect("read back");
        // Level 1 is 8 x 8; its edge texels read clamped neighbours, so
        // the interior 6 x 6 is the checker's.
        let interior: Vec<&[u8]> = (got.bytes.chunks_exact(4).enumerate())
            .filter(|(i, _)| (1..7).contains(&(i % 8)) && (1..7).contains(&(i / 8)))
            .map(|(_, p)| p)
            .collect();
        let a = interior[0][3];
        assert!(interior.iter().all(|p| p[3] == a), "uniform interior");
        let sigma2 = normal_variance_decode(a as f32 / 255.0);
        // The encoding's step at this value: sigma^2 of the neighbouring codes.
        let step = (normal_variance_decode((a as f32 + 1.0) / 255.0)
            - normal_variance_decode((a as f32 - 1.0) / 255.0))
            * 0.5;
        eprintln!(
            "checker +-{degrees} deg: sigma^2 {sigma2:.5} (alpha {a}), bilinear field {expected:.5} (texels' own {texels:.5}), 8-bit step {step:.5}"
        );
        // Measured on lavapipe on 2026-12-05 (sigma^2 vs the fine grid):
        // +-5 deg 0.00055 vs 0.00044 (under one step), +-15 0.00347 vs
        // 0.00379, +-30 0.0181 vs 0.0172, +-45 0.0526 vs 0.0469: the
        // bake's Gauss rule is exact for the field's quadratic moments, not
        // for the normalisation (-8 % to +12 % on this Nyquist checker).
        // Threshold: the encoding's step or 15 %; the texels' own spread,
        // 9x, fails it by far.
        assert!(
            (sigma2 - expected).abs() <= step.max(0.15 * expected),
            "+-{degrees} deg: sigma^2 {sigma2} vs {expected} (step {step})"
        );
        assert_eq!(&got.bytes[..3], &[128, 128, 255], "mean normal +z");
    }
}

/// Per case one vec4 in (r, sigma^2, A, 0); one vec4 out
/// (toksvig_roughness(r, sigma^2), normal_variance_decode(A),
/// normal_variance_encode(sigma^2), 0).
const TOKSVIG_KERNEL: &str = r#"#import brdf
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if i >= arrayLength(&input) { return; }
    let c = input[i];
    output[i] = vec4f(toksvig_roughness(c.x, c.y), normal_variance_decode(c.z), normal_variance_encode(c.y), 0.0);
}
"#;

#[test]
fn toksvig_wgsl_matches_the_cpu_twin() {
    let mut rng = Pcg32::new(4);
    let mut cases: Vec<[f32; 4]> = vec![
        [0.0, 0.0, 0.0, 0.0],
        [0.1, 0.0, 1.0, 0.0],
        [1.0, 10.0, 0.5, 0.0],
        [0.3, 1e-5, 1.0 / 255.0, 0.0],
    ];
    for _ in 0..1020 {
        let v = rng.next_f32().powi(3) * 4.0;
        cases.push([rng.next_f32(), v, rng.next_f32(), 0.0]);
    }
    let out = run_compute(
        TOKSVIG_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&cases),
        (cases.len() * 16) as u64,
        [cases.len().div_ceil(64) as u32, 1, 1],
    )
    .expect("kernel");
    let got: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut worst_r, mut worst_decode, mut worst_encode) = (0.0f32, 0.0f32, 0.0f32);
    for (c, g) in cases.iter().zip(got) {
        worst_r = worst_r.max((toksvig_roughness(c[0], c[1]) - g[0]).abs());
        let d = normal_variance_decode(c[2]);
        worst_decode = worst_decode.max((d - g[1]).abs() / d.max(1.0));
        worst_encode = worst_encode.max((normal_variance_encode(c[1]) - g[2]).abs());
    }
    eprintln!(
        "toksvig_roughness {worst_r:e}, normal_variance_decode (relative) {worst_decode:e}, encode {worst_encode:e}"
    );
    // Measured on lavapipe on 2026-12-05: identical (0); 1e-5 allows other
    // drivers' sqrt and division and is far below an 8-bit G-buffer step (4e-3).
    assert!(worst_r < 1e-5 && worst_decode < 1e-5 && worst_encode < 1e-5);
    // The properties the method rests on.
    assert_eq!(toksvig_roughness(0.3, 0.0), 0.3_f32.powi(4).sqrt().sqrt());
    assert_eq!(normal_variance_encode(0.0), 0.0);
    assert_eq!(normal_variance_decode(0.0), 0.0);
    assert_eq!(toksvig_roughness(0.5, 100.0), 1.0);
    for a in 1..255 {
        let a = a as f32 / 255.0;
        assert!((normal_variance_encode(normal_variance_decode(a)) - a).abs() < 1e-5);
    }
    // Why the bake is in float: the length of an 8-bit normal is not 1.
    // Over random unit normals, the worst |1 - |n|| and the roughness a
    // mirror would get from reading it as Toksvig's |n|.
    let mut worst_len = 0.0f32;
    for _ in 0..10000 {
        let (u, v) = (rng.next_f32(), rng.next_f32());
        let (cos, phi) = (u, v * std::f32::consts::TAU);
        let sin = (1.0 - cos * cos).sqrt();
        let q = encode(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos), 0);
        let n = Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) / 255.0 * 2.0 - 1.0;
        worst_len = worst_len.max((1.0 - n.length()).abs());
    }
    eprintln!(
        "8-bit normals: |1 - |n|| up to {worst_len:.4}: a mirror would read roughness {:.2}",
        toksvig_roughness(0.0, worst_len / (1.0 - worst_len))
    );
}

/// A 20 x 20 m glTF plane at y = 0 (double-sided, +Y up), smooth metal
/// (roughness `roughness`), with a 64 x 64 normal map of white-noise bumps
/// (Gaussian slopes, 0.15 per axis: 8.5 degrees) repeated 64 times across:
/// texels of 5 mm. `mipmaps` false: the sampler's min filter is LINEAR, so
/// only level 0 is read (the supersampled reference). Written with its PNG
/// to a temporary directory.
fn bumpy_plane(roughness: f32, mipmaps: bool) -> std::path::PathBuf {
    bumpy_plane_with(roughness, mipmaps, 1.0)
}

/// [`bumpy_plane`] with metalness `metallic`.
fn bumpy_plane_with(roughness: f32, mipmaps: bool, metallic: f32) -> std::path::PathBuf {
    let dir = common::temp_dir(&format!(
        "e3-{}-{metallic}",
        if mipmaps { "mips" } else { "level0" }
    ));
    let n = 64u32;
    let mut rng = Pcg32::new(20);
    let mut gauss = || {
        // Box-Muller.
        let (u, v) = (rng.next_f32().max(1e-7), rng.next_f32());
        (-2.0 * u.ln()).sqrt() * (std::f32::consts::TAU * v).cos()
    };
    let mut rgba = Vec::new();
    for _ in 0..n * n {
        let slope = (gauss() * 0.15, gauss() * 0.15);
        rgba.extend(encode(Vec3::new(-slope.0, -slope.1, 1.0).normalize(), 255));
    }
    image::save_buffer(dir.join("bumps.png"), &rgba, n, n, image::ColorType::Rgba8)
        .expect("write PNG");
    let min_filter = if mipmaps { 9987 } else { 9729 };
    let (l, repeat) = (10.0f32, 64.0f32);
    let mut bin: Vec<u8> = Vec::new();
    let corners = [(-l, -l), (l, -l), (l, l), (-l, l)];
    for (x, z) in corners {
        bin.extend([x, 0.0, z].iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..4 {
        bin.extend([0.0f32, 1.0, 0.0].iter().flat_map(|c| c.to_le_bytes()));
    }
    for (x, z) in corners {
        let uv = [(x / l * 0.5 + 0.5) * repeat, (z / l * 0.5 + 0.5) * repeat];
        bin.extend(uv.iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.extend([0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3,"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.9,0.9,0.9,1],"metallicFactor":{metallic},"roughnessFactor":{roughness}}},"normalTexture":{{"index":0}},"doubleSided":true}}],
"textures":[{{"source":0,"sampler":0}}],"samplers":[{{"magFilter":9729,"minFilter":{min_filter},"wrapS":10497,"wrapT":10497}}],
"images":[{{"uri":"bumps.png"}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},{{"buffer":0,"byteOffset":96,"byteLength":32}},{{"buffer":0,"byteOffset":128,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-{l},0,-{l}],"max":[{l},0,{l}]}},
{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},{{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}},
{{"bufferView":3,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        bin.len(),
        common::base64(&bin)
    );
    let path = dir.join("bumpy_plane.gltf");
    std::fs::write(&path, json).expect("write glTF");
    path
}

/// Rec. 709 luminance of each pixel of the raw `lighting` view.
fn luminance(r: &mut himal::Renderer, camera: &Camera, s: &FrameSettings) -> Vec<f32> {
    common::render_rgba(r, camera, s)
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect()
}

/// `k` x `k` box mean of a `w`-wide image.
fn box_down(img: &[f32], w: usize, k: usize) -> Vec<f32> {
    let h = img.len() / w;
    let mut out = Vec::with_capacity(img.len() / (k * k));
    for y in 0..h / k {
        for x in 0..w / k {
            let mut sum = 0.0;
            for dy in 0..k {
                for dx in 0..k {
                    sum += img[(y * k + dy) * w + x * k + dx];
                }
            }
            out.push(sum / (k * k) as f32);
        }
    }
    out
}

/// Mean |a - b| over the mean of `b` (relative mean absolute error).
fn relative_error(a: &[f32], b: &[f32]) -> f32 {
    let diff: f32 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
    diff / b.iter().sum::<f32>()
}

/// A camera `height` m above the plane, pitched `pitch` degrees down along
/// -Z with a 30 degree field of view; the sun along the mirror direction of
/// its central ray.
fn camera_and_sun(scene: &mut Scene, height: f32, pitch: f32) -> Camera {
    let (s, c) = pitch.to_radians().sin_cos();
    let forward = Vec3::new(0.0, -s, -c);
    scene.sun.light = Some(SunLight {
        to_light: Vec3::new(0.0, s, -c),
        illuminance_klux: Vec3::splat(50.0),
    });
    Camera {
        position: Vec3::new(0.0, height, 0.0),
        forward,
        up: Vec3::Y,
        fov_y_deg: 30.0,
        near: 0.05,
        orthographic: None,
    }
}

fn settings(scene: &Scene, (w, h): (u32, u32), specular_aa: bool) -> FrameSettings {
    let mut s = common::raw_settings(scene, (w, h), "lighting");
    s.aa = himal::passes::aa::AaMode::None;
    s.shadow_resolution = 0;
    s.ao.mode = himal::passes::ao::AoMode::Off;
    s.specular_aa = specular_aa;
    s
}

#[test]
fn toksvig_brings_a_minified_bumpy_mirror_closer_to_its_supersampled_self() {
    let (w, h) = (80u32, 60u32);
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    // 1 m up, 25 degrees down: the map minifies ~3 mips at the centre and
    // ~6 at the top row (5 mm texels, 8.7 mrad pixels at 80 x 60).
    let view = |mipmaps| {
        let mut scene = Scene::from_gltf(&bumpy_plane(0.1, mipmaps)).expect("plane");
        let camera = camera_and_sun(&mut scene, 1.0, 25.0);
        let r = common::renderer(&scene);
        (scene, camera, r)
    };
    // Reference: level 0 only (the unfiltered bumps), 16 x 16 samples per pixel.
    let (scene0, camera, mut r0) = view(false);
    let k = 16;
    let reference = box_down(
        &luminance(&mut r0, &camera, &settings(&scene0, (w * k, h * k), false)),
        (w * k) as usize,
        k as usize,
    );
    drop(r0);
    let (scene, camera, mut r) = view(true);
    // The brief's reference: mipmapped, 4 x 4, Toksvig off.
    let k4 = 4;
    let mip_reference = box_down(
        &luminance(&mut r, &camera, &settings(&scene, (w * k4, h * k4), false)),
        (w * k4) as usize,
        k4 as usize,
    );
    let off = luminance(&mut r, &camera, &settings(&scene, (w, h), false));
    let on = luminance(&mut r, &camera, &settings(&scene, (w, h), true));
    let (e_off, e_on) = (
        relative_error(&off, &reference),
        relative_error(&on, &reference),
    );
    let (m_off, m_on) = (
        relative_error(&off, &mip_reference),
        relative_error(&on, &mip_reference),
    );
    eprintln!(
        "mean luminance: reference (level 0, 16x16) {:.2}, mipmapped 4x4 reference (off) {:.2}, off {:.2}, on {:.2}",
        mean(&reference),
        mean(&mip_reference),
        mean(&off),
        mean(&on),
    );
    eprintln!(
        "relative mean abs error vs level-0 reference: off {e_off:.3}, on {e_on:.3} (ratio {:.2}); vs mipmapped 4x4: off {m_off:.3}, on {m_on:.3}",
        e_off / e_on
    );
    // The same over 4 x 4 pixel blocks: where the light lands, without the
    // reference's remaining glint noise.
    let blocks = |v: &[f32]| box_down(v, w as usize, 4);
    let (b_off, b_on) = (
        relative_error(&blocks(&off), &blocks(&reference)),
        relative_error(&blocks(&on), &blocks(&reference)),
    );
    eprintln!(
        "over 4x4 blocks: off {b_off:.3}, on {b_on:.3} (ratio {:.2})",
        b_off / b_on
    );
    if let Some(dir) = std::env::var_os("HIMAL_E3_DUMP") {
        let dir = std::path::PathBuf::from(dir);
        let images = [
            ("reference", &reference),
            ("mip_reference", &mip_reference),
            ("off", &off),
            ("on", &on),
        ];
        for (name, img) in images {
            let px: Vec<u8> = img
                .iter()
                .map(|l| ((l / 100.0 / (1.0 + l / 100.0)).powf(1.0 / 2.2) * 255.0) as u8)
                .collect();
            image::save_buffer(
                dir.join(format!("{name}.png")),
                &px,
                w,
                h,
                image::ColorType::L8,
            )
            .expect("dump");
        }
        for y in (0..h as usize).step_by(6) {
            let row =
                |v: &[f32]| v[y * w as usize..(y + 1) * w as usize].iter().sum::<f32>() / w as f32;
            eprintln!(
                "row {y}: reference {:.1} mip reference {:.1} off {:.1} on {:.1}",
                row(&reference),
                row(&mip_reference),
                row(&off),
                row(&on)
            );
        }
    }
    // Measured on lavapipe on 2026-12-05: per pixel off 1.763, on 0.572
    // (ratio 3.08); over 4x4 blocks off 1.689, on 0.311 (5.43); before
    // level 1 took the bilinear field's variance, on 0.650 and 0.482.
    // Against the brief's mipmapped 4x4 reference, off 1.329, on 1.051: its mips smooth
    // the bumps it should average (E3.md). Thresholds: on at most half of
    // off's error per pixel, 40 % over blocks.
    assert!(e_on < e_off * 0.5, "on {e_on} vs off {e_off}");
    assert!(b_on < b_off * 0.4, "blocks: on {b_on} vs off {b_off}");

    // Temporal: the camera creeps forward 5 mm (one texel) a frame; the mean
    // per-pixel change between consecutive frames over the mean luminance.
    let flicker = |specular_aa: bool, r: &mut himal::Renderer| {
        let frames: Vec<Vec<f32>> = (0..8)
            .map(|i| {
                let mut c = camera.clone();
                c.position.z -= 0.005 * i as f32;
                luminance(r, &c, &settings(&scene, (w, h), specular_aa))
            })
            .collect();
        let change: f32 = (frames.windows(2))
            .map(|f| relative_error(&f[1], &f[0]))
            .sum::<f32>();
        change / (frames.len() - 1) as f32
    };
    let (t_off, t_on) = (flicker(false, &mut r), flicker(true, &mut r));
    eprintln!(
        "frame-to-frame change (5 mm steps): off {t_off:.3}, on {t_on:.3} (ratio {:.1})",
        t_off / t_on
    );
    // Measured on lavapipe on 2026-12-05: off 0.206, on 0.027 (ratio 7.7;
    // 0.019 with the texels' larger variance, which blurred more); threshold:
    // a quarter.
    assert!(t_on < t_off * 0.25, "temporal: on {t_on} vs off {t_off}");

    // Close up (15 cm, 60 degrees down: 1.5 mm pixels over 5 mm texels):
    // mip 0 only, which carries no variance: on = off.
    let mut scene = scene;
    let camera = camera_and_sun(&mut scene, 0.15, 60.0);
    let off = luminance(&mut r, &camera, &settings(&scene, (w, h), false));
    let on = luminance(&mut r, &camera, &settings(&scene, (w, h), true));
    let close = relative_error(&on, &off);
    eprintln!(
        "close-up (mip 0): mean luminance off {:.3}, on {:.3}, relative difference {close:.5}",
        mean(&off),
        mean(&on)
    );
    // Measured on lavapipe on 2026-12-05: identical (0: level 0's alpha is
    // 0 and trilinear filtering stays on it); threshold 1e-3 for drivers
    // that blend in level 1 at a slightly different LOD.
    assert!(close < 1e-3, "close-up on vs off: {close}");
}

#[test]
fn toksvig_keeps_the_mean_brightness_of_a_highlight_in_view() {
    // The bumpy mirror of the test above seen with a 90 degree field of
    // view, so the image holds the whole highlight (half-vectors up to
    // ~25 degrees from the normal against the bumps' 8.5 degree slopes):
    // the mean then measures the reflected energy, not the lobe's shape.
    let (w, h) = (80u32, 60u32);
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let view = |mipmaps| {
        let mut scene = Scene::from_gltf(&bumpy_plane(0.1, mipmaps)).expect("plane");
        let mut camera = camera_and_sun(&mut scene, 1.0, 25.0);
        camera.fov_y_deg = 90.0;
        let r = common::renderer(&scene);
        (scene, camera, r)
    };
    let (scene0, camera, mut r0) = view(false);
    let k = 16;
    let reference = mean(&luminance(
        &mut r0,
        &camera,
        &settings(&scene0, (w * k, h * k), false),
    ));
    drop(r0);
    let (scene, camera, mut r) = view(true);
    let off = mean(&luminance(
        &mut r,
        &camera,
        &settings(&scene, (w, h), false),
    ));
    let on = mean(&luminance(&mut r, &camera, &settings(&scene, (w, h), true)));
    let (d_off, d_on) = (off / reference - 1.0, on / reference - 1.0);
    eprintln!(
        "90 deg view, mean luminance: reference (level 0, 16x16) {reference:.2}, off {off:.2} ({:+.1} %), on {on:.2} ({:+.1} %)",
        d_off * 100.0,
        d_on * 100.0
    );
    // Measured on lavapipe on 2026-12-05: reference 19.81, off 16.92
    // (-14.6 %), on 19.26 (-2.8 %). With level 1 taking the texels'
    // variance rather than the bilinear field's (9/4 of it for these
    // white-noise bumps), on was 18.32 (-7.5 %; E3.md). Threshold: the
    // issue's 5 %.
    assert!(d_on.abs() < 0.05, "on {on} vs reference {reference}");
}

/// The bake's cost at load: a 2048 x 2048 image (DamagedHelmet's normal
/// map size) uploaded as a normal texture (E3 chain) and as a metal-rough
/// texture (plain box chain), interleaved, best of three, GPU work waited
/// for. Printed for E3.md; asserted only to finish.
#[test]
fn the_bake_costs_little_at_load() {
    let n = 2048u32;
    let mut rng = Pcg32::new(2048);
    let rgba8: Vec<u8> = (0..n * n * 4)
        .map(|_| (rng.next_u32() & 255) as u8)
        .collect();
    let image = ImageData {
        name: "2048".into(),
        width: n,
        height: n,
        rgba8,
    };
    let ctx = shared_context().expect("GPU");
    let upload = |normal: bool| {
        let t = std::time::Instant::now();
        let gpu = common::upload_one_image_material(&image, |m, t| {
            if normal {
                m.normal_texture = Some(t);
            } else {
                m.metallic_roughness_texture = Some(t);
            }
        });
        ctx.device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("poll");
        let ms = t.elapsed().as_secs_f64() * 1e3;
        drop(gpu);
        ms
    };
    upload(true);
    upload(false);
    let (mut baked, mut plain) = (f64::MAX, f64::MAX);
    for _ in 0..3 {
        baked = baked.min(upload(true));
        plain = plain.min(upload(false));
    }
    eprintln!(
        "upload of a 2048^2 image with its mips: normal (E3 bake) {baked:.1} ms, plain {plain:.1} ms (+{:.1} ms)",
        baked - plain
    );
    assert!(baked.is_finite() && plain.is_finite());
}

#[test]
fn only_images_used_just_as_normal_maps_are_baked() {
    let at = |texture| {
        Some(TextureRef {
            texture,
            tex_coord: 0,
            transform: None,
        })
    };
    // Image 0: normal here, occlusion there; 1: normal only; 2: normal and
    // clearcoat normal (both normal slots).
    let pbr = PbrSet {
        materials: vec![
            PbrMaterial {
                normal_texture: at(0),
                ..Default::default()
            },
            PbrMaterial {
                occlusion_texture: at(0),
                normal_texture: at(1),
                ..Default::default()
            },
            PbrMaterial {
                normal_texture: at(2),
                clearcoat_normal_texture: at(2),
                ..Default::default()
            },
        ],
        textures: (0..3)
            .map(|image| TextureSlot {
                image,
                sampler: SamplerDesc::default(),
            })
            .collect(),
        images: ["shared", "normal", "coat"]
            .map(|name| ImageData {
                name: name.into(),
                width: 4,
                height: 4,
                rgba8: [128u8, 128, 255, 200].repeat(16),
            })
            .to_vec(),
        mesh_material: Vec::new(),
    };
    let (baked, shared) = pbr.normal_variance_images();
    assert_eq!(baked, vec![false, true, true]);
    assert_eq!(shared, vec!["shared".to_string()]);
    // On the GPU: the shared image keeps its alpha (another slot's data),
    // the baked ones start from zero variance.
    let ctx = shared_context().expect("GPU");
    let gpu = MaterialTextures::upload(ctx, &pbr).expect("upload");
    let alpha0 = |material: usize| {
        let t = &gpu.textures[gpu.materials[material].slots[2].0];
        read_texture(ctx, t, 0, 0).expect("read back").bytes[3]
    };
    assert_eq!((alpha0(0), alpha0(1), alpha0(2)), (200, 0, 0));
}

#[test]
fn a_normal_map_shared_with_another_slot_is_named_at_load() {
    let dir = common::temp_dir("e3-shared");
    image::save_buffer(
        dir.join("n.png"),
        &[128u8, 128, 255, 255].repeat(4),
        2,
        2,
        image::ColorType::Rgba8,
    )
    .expect("write PNG");
    let mut bin: Vec<u8> = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..3 {
        bin.extend([0.0f32, 0.0, 1.0].iter().flat_map(|c| c.to_le_bytes()));
    }
    for uv in [[0.0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
        bin.extend(uv.iter().flat_map(|c| c.to_le_bytes()));
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"material":0}}]}}],
"materials":[{{"normalTexture":{{"index":0}},"occlusionTexture":{{"index":0}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":"n.png","name":"bumps"}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},{{"buffer":0,"byteOffset":72,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#,
        bin.len(),
        common::base64(&bin)
    );
    let path = dir.join("shared.gltf");
    std::fs::write(&path, json).expect("write glTF");
    let asset = himal::scene::gltf::load(&path).expect("load");
    let named: Vec<&String> = (asset.warnings.iter())
        .filter(|w| w.contains("normal texture and by another slot"))
        .collect();
    assert_eq!(named.len(), 1, "{:?}", asset.warnings);
    assert!(named[0].contains("bumps"), "{}", named[0]);
}

/// Settings of a wet frame (`gbuffer.wet`, amount 1) of debug view `view`.
fn wet_settings(scene: &Scene, size: (u32, u32), specular_aa: bool, view: &str) -> FrameSettings {
    let mut s = settings(scene, size, specular_aa);
    s.view = view.parse().expect("view");
    s.wetness = 1.0;
    s
}

#[test]
fn the_wet_pass_matches_its_cpu_twin() {
    use himal::passes::wet::reference::{GBufferCpu, wet_texel};
    // The bumpy plane, minified: the G-buffer's normals vary from pixel to
    // pixel. The dry raw views are the twin's input; the wet ones the GPU's.
    let (w, h) = (80u32, 60u32);
    // Half metal: the film darkens the dielectric part of the albedo.
    let mut scene = Scene::from_gltf(&bumpy_plane_with(0.5, true, 0.5)).expect("plane");
    let camera = camera_and_sun(&mut scene, 0.3, 40.0);
    let mut r = common::renderer(&scene);
    let view = |r: &mut himal::Renderer, name: &str, wet: bool, specular_aa: bool| {
        let mut s = wet_settings(&scene, (w, h), specular_aa, name);
        if !wet {
            s.wetness = 0.0;
        }
        common::render_rgba(r, &camera, &s)
    };
    let v4 = |p: &[f32; 4]| glam::Vec4::from_array(*p);
    let albedo = view(&mut r, "albedo", false, true);
    let normal = view(&mut r, "normal", false, true);
    let gloss = view(&mut r, "glossiness", false, true);
    let metal = view(&mut r, "metallic", false, true);
    let depth = view(&mut r, "depth", false, true);
    let g = GBufferCpu {
        width: w as usize,
        height: h as usize,
        albedo: albedo.iter().map(v4).collect(),
        normal: normal.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
        material: (gloss.iter().zip(&metal))
            .map(|(g, m)| glam::Vec4::new(g[0], 0.5, m[0], 0.0))
            .collect(),
        geometry: depth.iter().map(|d| d[0] > 0.0).collect(),
    };
    for specular_aa in [false, true] {
        let wet_albedo = view(&mut r, "albedo", true, specular_aa);
        let wet_gloss = view(&mut r, "glossiness", true, specular_aa);
        let (mut worst_albedo, mut worst_gloss, mut wet) = (0.0f32, 0.0f32, 0);
        for y in 0..h as usize {
            for x in 0..w as usize {
                let i = y * w as usize + x;
                let (a, m) = wet_texel(&g, x, y, 1.0, specular_aa);
                worst_albedo = worst_albedo.max((a.x - wet_albedo[i][0]).abs());
                worst_gloss = worst_gloss.max((m.x - wet_gloss[i][0]).abs());
                wet += usize::from(m.x > g.material[i].x + 0.1);
            }
        }
        eprintln!(
            "wet pass vs twin (E3 filter {specular_aa}): albedo {worst_albedo:.4}, glossiness {worst_gloss:.4}; {wet} of {} px made glossier",
            w * h
        );
        // Measured on lavapipe on 2026-12-05: see the eprintln. Thresholds:
        // the albedo's sRGB 8-bit step near its 0.9 x 0.6 (1/255 / 0.95 /
        // 2.4 ~ 0.004 linear per step, two steps) and one 8-bit step of
        // glossiness plus the G-buffer normal's 10-bit quantisation in the
        // filter's variance.
        assert!(worst_albedo < 0.008, "albedo {worst_albedo}");
        assert!(worst_gloss < 2.5 / 255.0, "glossiness {worst_gloss}");
        assert!(wet > (w * h / 2) as usize, "the plane is wet");
    }
}

#[test]
fn the_screen_space_filter_keeps_a_wet_bumpy_plane_from_shimmering() {
    // A rough (0.5) bumpy plane made wet (film roughness 0.08) in the
    // G-buffer: its texture-space variance (E3 part 1) widened the old
    // roughness, so only the screen-space filter widens the new one. Seen
    // from 0.3 m, 40 degrees down, where a pixel is about a texel (5 mm):
    // neighbouring pixels' normals differ as the bumps do. (From 1 m the
    // mips have averaged the bumps below a pixel; the filter then sees
    // little: shimmer 0.216 -> 0.207, E3.md.)
    let (w, h) = (80u32, 60u32);
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    let lum = |img: Vec<[f32; 4]>| -> Vec<f32> {
        img.iter()
            .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
            .collect()
    };
    let view = |mipmaps| {
        let mut scene = Scene::from_gltf(&bumpy_plane(0.5, mipmaps)).expect("plane");
        let camera = camera_and_sun(&mut scene, 0.3, 40.0);
        let r = common::renderer(&scene);
        (scene, camera, r)
    };
    let (scene0, camera, mut r0) = view(false);
    let k = 16;
    let reference = box_down(
        &lum(common::render_rgba(
            &mut r0,
            &camera,
            &wet_settings(&scene0, (w * k, h * k), false, "lighting"),
        )),
        (w * k) as usize,
        k as usize,
    );
    drop(r0);
    let (scene, camera, mut r) = view(true);
    let frame = |r: &mut himal::Renderer, c: &Camera, filter: bool| {
        lum(common::render_rgba(
            r,
            c,
            &wet_settings(&scene, (w, h), filter, "lighting"),
        ))
    };
    let (off, on) = (frame(&mut r, &camera, false), frame(&mut r, &camera, true));
    let (e_off, e_on) = (
        relative_error(&off, &reference),
        relative_error(&on, &reference),
    );
    let flicker = |filter: bool, r: &mut himal::Renderer| {
        let frames: Vec<Vec<f32>> = (0..8)
            .map(|i| {
                let mut c = camera.clone();
                c.position.z -= 0.005 * i as f32;
                frame(r, &c, filter)
            })
            .collect();
        frames
            .windows(2)
            .map(|f| relative_error(&f[1], &f[0]))
            .sum::<f32>()
            / 7.0
    };
    let (t_off, t_on) = (flicker(false, &mut r), flicker(true, &mut r));
    eprintln!(
        "wet bumpy plane: mean luminance reference {:.2}, filter off {:.2}, on {:.2}; error vs reference off {e_off:.3}, on {e_on:.3}; frame-to-frame change off {t_off:.3}, on {t_on:.3}",
        mean(&reference),
        mean(&off),
        mean(&on)
    );
    // Measured on lavapipe on 2026-12-05: mean luminance reference 102.68,
    // off 165.42, on 102.07; error off 1.978, on 0.949; frame-to-frame
    // change off 1.673, on 0.798. Thresholds: shimmer and error at most
    // 0.6 of off's, the mean within the issue's 5 %.
    assert!(t_on < 0.6 * t_off, "shimmer: on {t_on} vs off {t_off}");
    assert!(e_on < 0.6 * e_off, "error: on {e_on} vs off {e_off}");
    let brightness = mean(&on) / mean(&reference) - 1.0;
    assert!(
        brightness.abs() < 0.05,
        "mean: on {} vs {}",
        mean(&on),
        mean(&reference)
    );
}
