//! Forward passes after lighting (passes/forward): the shading twin on the
//! GPU, and whole frames of small glTF scenes written by the test:
//! emission added exactly where the G-buffer kept the surface, BLEND as
//! premultiplied "over" in back-to-front order.
//! Measured numbers: `cargo test --release -p himal --test forward -- --nocapture`.

mod common;

use std::path::PathBuf;

use glam::{Vec2, Vec3, Vec4};
use himal::gpu::testing::run_compute;
use himal::math::brdf::{Material, surface_from_material};
use himal::math::sampling::{Pcg32, uniform_sample_sphere};
use himal::math::sh::Sh9Rgb;
use himal::passes::forward::back_to_front;
use himal::passes::forward::reference::{
    ForwardLight, TransmittedLight, forward_shade_premultiplied, over, transmission_lod,
    transmitted_radiance, volume_attenuation,
};
use himal::scene::Scene;

/// Input: 9 vec4 of SH, then per case 17 vec4: albedo|glossiness,
/// reflectance|metallic|anisotropy|ao, t, b, n, v, sun direction, sun
/// illuminance, prefiltered|alpha, dfg.xy|F90|F0 green tint, emissive, two
/// local lights (direction, illuminance), fog, Preetham radiance|distance.
/// Output per case: the premultiplied fragment, then it through the fog.
const KERNEL: &str = r#"#import forward
#import fog
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    let base = 9u + i * 17u;
    if base + 16u >= arrayLength(&input) { return; }
    var sh: Sh9;
    for (var k = 0u; k < 9u; k = k + 1u) { sh.c[k] = input[k]; }
    let m = input[base];
    let p = input[base + 1u];
    var s = surface_from_material(m.xyz, m.w, p.x, p.y, p.z);
    let pa = input[base + 8u];
    let e = input[base + 10u];
    let f = input[base + 9u];
    s.f0.g *= f.w;
    let t = input[base + 2u].xyz;
    let b = input[base + 3u].xyz;
    let n = input[base + 4u].xyz;
    let v = input[base + 5u].xyz;
    // fs_blend's blend_local, lights from the input instead of the binding.
    var local = vec3f(0.0);
    for (var k = 0u; k < 2u; k++) {
        local += brdf_cos_f90(s, f.z, t, b, n, v, input[base + 11u + 2u * k].xyz) * input[base + 12u + 2u * k].xyz;
    }
    let c = forward_shade_premultiplied(s, f.z, t, b, n, v, input[base + 6u].xyz, input[base + 7u].xyz,
        sh, pa.xyz, input[base + 9u].xy, vec3f(p.w), e.xyz, local, pa.w);
    let fp = input[base + 16u];
    output[2u * i] = c;
    output[2u * i + 1u] = fog_premultiplied(c, aerial_perspective(fp.w, v, input[base + 15u], sh, fp.xyz));
}
"#;

#[test]
fn forward_shading_matches_its_cpu_twin() {
    use himal::passes::forward::reference::{fog_premultiplied, local_radiance};
    use himal::passes::lighting::reference::aerial_perspective;
    let mut rng = Pcg32::new(82);
    let sky = Sh9Rgb {
        c: std::array::from_fn(|k| {
            Vec3::new(30.0, 35.0, 45.0) * if k == 0 { 1.0 } else { 0.2 } * (1.0 + rng.next_f32())
        }),
    };
    let mut input: Vec<[f32; 4]> = sky.c.iter().map(|c| c.extend(0.0).to_array()).collect();
    let mut cases = Vec::new();
    for case in 0..256 {
        let n = uniform_sample_sphere(rng.next_vec2());
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let mut v = uniform_sample_sphere(rng.next_vec2());
        if v.dot(n) < 0.0 {
            v = -v;
        }
        let l = uniform_sample_sphere(rng.next_vec2());
        let m = Material {
            albedo: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
            glossiness: rng.next_f32(),
            reflectance: 0.04,
            metallic: rng.next_f32(),
            anisotropy: rng.next_f32(),
        };
        let ao = rng.next_f32();
        // The sun through a shadow: fs_blend scales it by the visibility.
        let sun_visibility = rng.next_f32();
        let light = ForwardLight {
            sun_direction: l,
            sun_illuminance: Vec3::new(90.0, 85.0, 80.0) * sun_visibility,
            sky_irradiance: sky,
            prefiltered: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0,
            dfg: Vec2::new(rng.next_f32(), rng.next_f32() * 0.2),
        };
        let emissive = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 5.0;
        // Alpha beyond [0, 1] checks the clamp.
        let alpha = rng.next_f32() * 1.4 - 0.2;
        // KHR_materials_specular: F90 below 1 and a coloured F0.
        let (f90, tint) = (rng.next_f32(), 0.5 + rng.next_f32());
        // Two local lights (illuminance times their shadow), some behind the surface.
        let lights: Vec<(Vec3, Vec3)> = (0..2)
            .map(|_| {
                let dir = uniform_sample_sphere(rng.next_vec2());
                let e = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 40.0;
                (dir, e)
            })
            .collect();
        // Fog: half the cases from the sky SH (Bruneton), half Preetham.
        let fog = Vec4::new(
            rng.next_f32() * 0.01,
            rng.next_f32(),
            (case % 2) as f32,
            0.0,
        );
        let preetham = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
        let dist = rng.next_f32() * 500.0;
        input.extend([
            m.albedo.extend(m.glossiness).to_array(),
            [m.reflectance, m.metallic, m.anisotropy, ao],
            t.extend(0.0).to_array(),
            b.extend(0.0).to_array(),
            n.extend(0.0).to_array(),
            v.extend(0.0).to_array(),
            l.extend(0.0).to_array(),
            light.sun_illuminance.extend(0.0).to_array(),
            light.prefiltered.extend(alpha).to_array(),
            [light.dfg.x, light.dfg.y, f90, tint],
            emissive.extend(0.0).to_array(),
        ]);
        for (dir, e) in &lights {
            input.extend([dir.extend(0.0).to_array(), e.extend(0.0).to_array()]);
        }
        input.extend([fog.to_array(), preetham.extend(dist).to_array()]);
        let mut s = surface_from_material(&m);
        s.f0.y *= tint;
        let local = local_radiance(&s, f90, t, b, n, v, &lights);
        let c = forward_shade_premultiplied(
            &s,
            f90,
            t,
            b,
            n,
            v,
            &light,
            Vec3::splat(ao),
            emissive,
            local,
            alpha,
        );
        cases.push(c);
        cases.push(fog_premultiplied(
            c,
            aerial_perspective(dist, v, fog, &sky, preetham),
        ));
    }
    let out = run_compute(
        KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        (cases.len() * 16) as u64,
        [(cases.len() as u32 / 2).div_ceil(64), 1, 1],
    )
    .unwrap_or_else(|e| panic!("forward kernel: {e}"));
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = [0.0f32; 2];
    for (k, (cpu, g)) in cases.iter().zip(gpu).enumerate() {
        let g = Vec4::from_array(*g);
        assert!(g.is_finite(), "{g}");
        let e = ((g - *cpu).abs() / cpu.abs().max(Vec4::splat(1e-2))).max_element();
        worst[k % 2] = worst[k % 2].max(e);
    }
    eprintln!(
        "forward shading GPU vs CPU: worst relative {:.2e}, through the fog {:.2e}",
        worst[0], worst[1]
    );
    // measured 1.76e-7 on lavapipe on 2026-11-22 (sun and ambient alone);
    // with shadowed sun, local lights and fog see docs/gltf.md. Threshold 1e-5.
    assert!(worst[0] < 1e-5, "worst relative difference {}", worst[0]);
    assert!(
        worst[1] < 1e-5,
        "through the fog: worst relative difference {}",
        worst[1]
    );
}

/// Per case 9 vec4: f0|f90, dfg|alpha_t|ior, t_albedo|roughness, behind|distance,
/// attenuation colour|1/distance, t, n, v, sun direction|width. Output per
/// case: transmitted radiance|lod, transmittance.
const TRANSMISSION_KERNEL: &str = r#"#import forward
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    let base = i * 9u;
    if base + 8u >= arrayLength(&input) { return; }
    let f = input[base];
    let d = input[base + 1u];
    let a = input[base + 2u];
    let behind = input[base + 3u];
    let c = input[base + 4u];
    let t = input[base + 5u].xyz;
    let n = input[base + 6u].xyz;
    let l = input[base + 8u];
    let tr = volume_attenuation(behind.w, c.w, c.xyz);
    let rad = transmitted_radiance(f.xyz, f.w, d.xy, a.xyz, tr, behind.xyz, d.z, t, cross(n, t), n,
        input[base + 7u].xyz, l.xyz, vec3f(90.0, 85.0, 80.0));
    output[2u * i] = vec4f(rad, transmission_lod(a.w, d.w, l.w));
    output[2u * i + 1u] = vec4f(tr, 0.0);
}
"#;

#[test]
fn transmission_matches_its_cpu_twin() {
    let mut rng = Pcg32::new(83);
    let mut input: Vec<[f32; 4]> = Vec::new();
    let mut cases = Vec::new();
    let sun = Vec3::new(90.0, 85.0, 80.0);
    let rgb = |rng: &mut Pcg32| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    for k in 0..256 {
        let n = uniform_sample_sphere(rng.next_vec2());
        let t = n.any_orthonormal_vector();
        let mut v = uniform_sample_sphere(rng.next_vec2());
        if v.dot(n) < 0.0 {
            v = -v;
        }
        // Half the suns behind the surface (the lobe), half in front (none).
        let mut l = uniform_sample_sphere(rng.next_vec2());
        if (l.dot(n) < 0.0) != (k % 2 == 0) {
            l = -l;
        }
        let (f0, f90) = (rgb(&mut rng) * 0.1, rng.next_f32());
        let dfg = Vec2::new(rng.next_f32(), rng.next_f32() * 0.2);
        let (roughness, ior) = (rng.next_f32(), 1.0 + rng.next_f32());
        let alpha_t =
            himal::passes::forward::reference::transmission_roughness(roughness * roughness, ior);
        let t_albedo = rgb(&mut rng);
        let behind = rgb(&mut rng) * 30.0;
        let distance = rng.next_f32() * 2.0;
        // Every fourth case without absorption (1/distance 0).
        let inv = if k % 4 == 0 {
            0.0
        } else {
            0.2 + rng.next_f32() * 3.0
        };
        let colour = rgb(&mut rng);
        let width = 64.0 + (rng.next_f32() * 2000.0).floor();
        input.extend([
            f0.extend(f90).to_array(),
            [dfg.x, dfg.y, alpha_t, ior],
            t_albedo.extend(roughness).to_array(),
            behind.extend(distance).to_array(),
            colour.extend(inv).to_array(),
            t.extend(0.0).to_array(),
            n.extend(0.0).to_array(),
            v.extend(0.0).to_array(),
            l.extend(width).to_array(),
        ]);
        let light = TransmittedLight {
            behind,
            transmittance: volume_attenuation(distance, inv, colour),
        };
        let rad = transmitted_radiance(
            f0,
            f90,
            dfg,
            t_albedo,
            &light,
            alpha_t,
            (t, n.cross(t), n),
            v,
            l,
            sun,
        );
        cases.push((
            rad.extend(transmission_lod(roughness, ior, width)),
            light.transmittance,
        ));
    }
    let out = run_compute(
        TRANSMISSION_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        (cases.len() * 32) as u64,
        [(cases.len() as u32).div_ceil(64), 1, 1],
    )
    .unwrap_or_else(|e| panic!("transmission kernel: {e}"));
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = 0.0f32;
    for (k, (rad, tr)) in cases.iter().enumerate() {
        let (g_rad, g_tr) = (
            Vec4::from_array(gpu[2 * k]),
            Vec4::from_array(gpu[2 * k + 1]),
        );
        assert!(
            g_rad.is_finite() && g_tr.is_finite(),
            "case {k}: {g_rad} {g_tr}"
        );
        let e = ((g_rad - *rad).abs() / rad.abs().max(Vec4::splat(1e-2))).max_element();
        let e_tr = ((g_tr.truncate() - *tr).abs() / tr.abs().max(Vec3::splat(1e-3))).max_element();
        worst = worst.max(e).max(e_tr);
    }
    eprintln!("transmission GPU vs CPU: worst relative {worst:.2e}");
    // measured 1.20e-5 on lavapipe on 2026-12-04 (the sun lobe is a
    // near-delta at small alpha); threshold 1e-4.
    assert!(worst < 1e-4, "worst relative difference {worst}");
}

#[test]
fn blend_draws_sort_far_to_near() {
    let centres = [
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(0.0, 0.0, -5.0),
        Vec3::new(3.0, 0.0, 0.0),
    ];
    assert_eq!(back_to_front(&centres, Vec3::ZERO), vec![1, 2, 0]);
    assert_eq!(
        back_to_front(&centres, Vec3::new(0.0, 0.0, -6.0)),
        vec![2, 0, 1]
    );
}

/// A .gltf with quads (2 x 2 m, facing +Z) at `quads` = (x, z) offsets,
/// each with its own material JSON; written to a temporary file.
fn quads_gltf(name: &str, quads: &[((f32, f32), String)]) -> PathBuf {
    let mut bin: Vec<u8> = Vec::new();
    for p in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    for _ in 0..4 {
        bin.extend([0.0f32, 0.0, 1.0].iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let b64 = common::base64(&bin);
    let nodes: Vec<String> = quads
        .iter()
        .enumerate()
        .map(|(i, ((x, z), _))| format!(r#"{{"mesh":{i},"translation":[{x},0,{z}]}}"#))
        .collect();
    let meshes: Vec<String> = (0..quads.len())
        .map(|i| format!(r#"{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"material":{i}}}]}}"#))
        .collect();
    let materials: Vec<&str> = quads.iter().map(|(_, m)| m.as_str()).collect();
    let scene_nodes: Vec<String> = (0..quads.len()).map(|i| i.to_string()).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"materials":[{}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},{{"buffer":0,"byteOffset":96,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        scene_nodes.join(","),
        nodes.join(","),
        meshes.join(","),
        materials.join(","),
        bin.len()
    );
    let path =
        std::env::temp_dir().join(format!("himal-forward-{}-{name}.gltf", std::process::id()));
    std::fs::write(&path, json).expect("write temporary glTF");
    path
}

const SIZE: u32 = 64;

/// Raw views (`lighting` = linear HDR after the forward passes, `depth`)
/// of the scene in `path`, seen by the camera framing `frame` (so scenes
/// that differ only in materials share one camera).
fn render(path: &std::path::Path, camera: &himal::scene::Camera) -> (Vec<Vec3>, Vec<f32>) {
    let scene = Scene::from_gltf(path).unwrap_or_else(|e| panic!("{e}"));
    let [hdr, depth]: [Vec<[f32; 4]>; 2] =
        common::raw_views(&scene, camera, SIZE, &["lighting", "depth"])
            .try_into()
            .expect("two views");
    let hdr = hdr.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect();
    let depth = depth.iter().map(|p| p[0]).collect();
    (hdr, depth)
}

fn material(alpha_mode: &str, rgba: [f32; 4], emissive: [f32; 3]) -> String {
    format!(
        r#"{{"pbrMetallicRoughness":{{"baseColorFactor":{rgba:?},"metallicFactor":0,"roughnessFactor":1}},"emissiveFactor":{emissive:?},"alphaMode":"{alpha_mode}"}}"#
    )
}

#[test]
fn emission_is_added_exactly_where_the_surface_is() {
    let e = [4.0f32, 2.0, 1.0];
    let lit = quads_gltf(
        "emit",
        &[((0.0, 0.0), material("OPAQUE", [0.0, 0.0, 0.0, 1.0], e))],
    );
    let dark = quads_gltf(
        "dark",
        &[(
            (0.0, 0.0),
            material("OPAQUE", [0.0, 0.0, 0.0, 1.0], [0.0; 3]),
        )],
    );
    let scene = Scene::from_gltf(&lit).expect("scene");
    let camera = scene.camera("default").expect("camera").clone();
    let (with, depth) = render(&lit, &camera);
    let (without, _) = render(&dark, &camera);
    let (mut covered, mut missing, mut worst) = (0, 0, 0.0f32);
    for ((a, b), d) in with.iter().zip(&without).zip(&depth) {
        let diff = *a - *b;
        if *d > 0.0 {
            covered += 1;
            let err = ((diff - Vec3::from(e)).abs() / Vec3::from(e)).max_element();
            if err > 0.05 {
                missing += 1;
            }
            worst = worst.max(err);
        } else {
            assert!(
                diff.abs().max_element() < 1e-3,
                "emission off the surface: {diff}"
            );
        }
    }
    eprintln!(
        "emissive: {covered} surface pixels, {missing} without it, worst relative {worst:.2e}"
    );
    assert!(covered > (SIZE * SIZE / 4) as usize, "{covered} pixels");
    // measured 0 pixels missing (depth Equal with @invariant positions),
    // worst 9.46e-4 (fp16 HDR) on 2026-11-22; thresholds 0 and 0.01.
    assert_eq!(missing, 0);
    assert!(worst < 0.01, "{worst}");
    let _ = std::fs::remove_file(lit);
    let _ = std::fs::remove_file(dark);
}

#[test]
fn blend_is_premultiplied_over_in_back_to_front_order() {
    let a = 0.6f32;
    let red = material("BLEND", [1.0, 0.05, 0.05, a], [0.0; 3]);
    let blue = material("BLEND", [0.05, 0.05, 1.0, a], [0.0; 3]);
    let clear = |rgb: [f32; 3]| material("BLEND", [rgb[0], rgb[1], rgb[2], 0.0], [0.0; 3]);
    // Near red quad at z = 1 on the left, far blue one at z = 0 on the right.
    let layout = |near: String, far: String| [((-0.5, 1.0), near), ((0.5, 0.0), far)];
    let both = quads_gltf("both", &layout(red.clone(), blue.clone()));
    let near = quads_gltf("near", &layout(red.clone(), clear([0.05, 0.05, 1.0])));
    let far = quads_gltf("far", &layout(clear([1.0, 0.05, 0.05]), blue.clone()));
    let none = quads_gltf("none", &layout(clear([1.0; 3]), clear([1.0; 3])));
    let scene = Scene::from_gltf(&both).expect("scene");
    let camera = scene.camera("default").expect("camera").clone();
    let (ab, _) = render(&both, &camera);
    let (n, _) = render(&near, &camera);
    let (f, _) = render(&far, &camera);
    let (bg, _) = render(&none, &camera);
    let (mut overlap, mut err_sum, mut swapped_sum) = (0usize, 0.0f32, 0.0f32);
    for i in 0..ab.len() {
        let (dn, df) = (n[i] - bg[i], f[i] - bg[i]);
        if dn.abs().max_element() < 1e-2 || df.abs().max_element() < 1e-2 {
            continue;
        }
        overlap += 1;
        // near over (far over background), with src = N - (1 - a) B.
        let src_near = (n[i] - bg[i] * (1.0 - a)).extend(a);
        let src_far = (f[i] - bg[i] * (1.0 - a)).extend(a);
        let expected = over(src_near, over(src_far, bg[i].extend(1.0))).truncate();
        let swapped = over(src_far, over(src_near, bg[i].extend(1.0))).truncate();
        let scale = expected.max_element().max(1e-3);
        err_sum += (ab[i] - expected).abs().max_element() / scale;
        swapped_sum += (ab[i] - swapped).abs().max_element() / scale;
    }
    let (err, swapped) = (err_sum / overlap as f32, swapped_sum / overlap as f32);
    eprintln!(
        "blend: {overlap} overlap pixels, mean relative error {err:.2e}, against the swapped order {swapped:.3}"
    );
    assert!(overlap > 50, "{overlap} overlapping pixels");
    // measured 3.60e-4 (fp16 HDR, 375 pixels) vs 0.605 for the wrong order on 2026-11-22;
    // thresholds 0.005 and 0.05.
    assert!(err < 0.005, "{err}");
    assert!(swapped > 0.05, "{swapped}: order does not matter?");
    for p in [both, near, far, none] {
        let _ = std::fs::remove_file(p);
    }
}

/// Input per case, 12 vec4: sheen colour|sheen roughness, clearcoat|coat
/// roughness|sheen albedo|ao, n, n_c, v, sun direction, sun, sheen env|coat
/// dfg.x, coat env|coat dfg.y, base F0 delta|F90 delta, base env|base
/// roughness, base dfg. Output: one vec4 per case.
const LAYERS_KERNEL: &str = r#"#import layers
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    let base = i * 12u;
    if base + 11u >= arrayLength(&input) { return; }
    let a = input[base];
    let b = input[base + 1u];
    let d = input[base + 9u];
    let e = input[base + 10u];
    let m = Layers(a.xyz, a.w, b.x, b.y, d.xyz, d.w, e.w);
    var light: LayerLight;
    light.sun_direction = input[base + 5u].xyz;
    light.sun = input[base + 6u].xyz;
    light.sheen_env = input[base + 7u].xyz;
    light.coat_env = input[base + 8u].xyz;
    light.coat_dfg = vec2f(input[base + 7u].w, input[base + 8u].w);
    light.sheen_albedo = b.z;
    light.ao = b.w;
    light.base_env = e.xyz;
    light.base_dfg = input[base + 11u].xy;
    output[i] = layers_shade(m, input[base + 2u].xyz, input[base + 3u].xyz, input[base + 4u].xyz, light);
}
"#;

#[test]
fn clearcoat_and_sheen_match_their_cpu_twin() {
    use himal::passes::forward::reference::{LayerLight, Layers, layers_shade};
    let mut rng = Pcg32::new(7);
    let mut input: Vec<[f32; 4]> = Vec::new();
    let mut cases = Vec::new();
    for k in 0..512 {
        let n = uniform_sample_sphere(rng.next_vec2());
        // The coat normal near the base's (a coat normal map tilts it).
        let n_c = (n + 0.3 * uniform_sample_sphere(rng.next_vec2())).normalize();
        let mut v = uniform_sample_sphere(rng.next_vec2());
        if v.dot(n) < 0.0 {
            v = -v;
        }
        let l = uniform_sample_sphere(rng.next_vec2());
        // A quarter of the cases without a sheen, a quarter without a coat,
        // half with KHR_materials_specular's correction of the base.
        let specular = k % 2 == 0;
        let m = Layers {
            sheen_color: if k % 4 == 0 {
                Vec3::ZERO
            } else {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
            },
            sheen_roughness: rng.next_f32(),
            clearcoat: if k % 4 == 1 { 0.0 } else { rng.next_f32() },
            clearcoat_roughness: rng.next_f32(),
            base_f0_delta: if specular {
                Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 0.1 - 0.04
            } else {
                Vec3::ZERO
            },
            base_f90_delta: if specular { -rng.next_f32() } else { 0.0 },
            base_roughness: rng.next_f32(),
        };
        let light = LayerLight {
            sun_direction: l,
            sun: Vec3::new(90.0, 85.0, 80.0) * rng.next_f32(),
            sheen_env: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0,
            coat_env: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0,
            coat_dfg: Vec2::new(rng.next_f32(), rng.next_f32() * 0.2),
            sheen_albedo: rng.next_f32() * 0.5,
            base_env: Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0,
            base_dfg: Vec2::new(rng.next_f32(), rng.next_f32() * 0.2),
            ao: rng.next_f32(),
        };
        input.extend([
            m.sheen_color.extend(m.sheen_roughness).to_array(),
            [
                m.clearcoat,
                m.clearcoat_roughness,
                light.sheen_albedo,
                light.ao,
            ],
            n.extend(0.0).to_array(),
            n_c.extend(0.0).to_array(),
            v.extend(0.0).to_array(),
            l.extend(0.0).to_array(),
            light.sun.extend(0.0).to_array(),
            light.sheen_env.extend(light.coat_dfg.x).to_array(),
            light.coat_env.extend(light.coat_dfg.y).to_array(),
            m.base_f0_delta.extend(m.base_f90_delta).to_array(),
            light.base_env.extend(m.base_roughness).to_array(),
            [light.base_dfg.x, light.base_dfg.y, 0.0, 0.0],
        ]);
        cases.push(layers_shade(&m, n, n_c, v, &light));
    }
    let out = run_compute(
        LAYERS_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        (cases.len() * 16) as u64,
        [(cases.len() as u32).div_ceil(64), 1, 1],
    )
    .unwrap_or_else(|e| panic!("layers kernel: {e}"));
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = 0.0f32;
    for (cpu, g) in cases.iter().zip(gpu) {
        let g = Vec4::from_array(*g);
        assert!(g.is_finite(), "{g}");
        assert!((0.0..=1.0).contains(&g.w), "base weight {g}");
        let e = ((g - *cpu).abs() / cpu.abs().max(Vec4::splat(1e-2))).max_element();
        worst = worst.max(e);
    }
    eprintln!("layers GPU vs CPU: worst relative {worst:.2e}");
    assert!(worst < 1e-4, "worst relative difference {worst}");
}

/// The sheen albedo table: within [0, 1] (the lobe reflects at most what
/// arrives), converged (96² cells against 384²), and the GPU lookup in
/// `layers.wgsl` reads the same bilinear values as the CPU twin.
#[test]
fn sheen_albedo_table_is_converged_and_energy_bounded() {
    use himal::passes::forward::reference::{SHEEN_TABLE_SIZE, sheen_albedo, sheen_albedo_table};
    let table = sheen_albedo_table();
    assert_eq!(table.len(), SHEEN_TABLE_SIZE * SHEEN_TABLE_SIZE);
    assert!(table.iter().all(|e| (0.0..=1.0).contains(e)));
    // Away from grazing the lobe itself conserves energy (measured
    // 2026-12-03: at most 0.672); the table clamps the grazing views.
    let mut most = 0.0f32;
    for j in 0..=10 {
        for i in 1..=10 {
            most = most.max(sheen_albedo(i as f32 / 10.0, j as f32 / 10.0, 96));
        }
    }
    eprintln!("largest E for n.v >= 0.1: {most:.3}");
    assert!(most <= 1.0, "{most}");
    let mut worst = 0.0f32;
    for &(n_o_v, r) in &[
        (1.0, 1.0),
        (0.5, 0.5),
        (0.1, 0.3),
        (0.9, 0.07),
        (0.02, 1.0),
        (0.3, 0.15),
    ] {
        let (coarse, fine) = (sheen_albedo(n_o_v, r, 96), sheen_albedo(n_o_v, r, 384));
        worst = worst.max((coarse - fine).abs());
        eprintln!("E({n_o_v}, {r}) = {fine:.4} (96 cells: {coarse:.4})");
    }
    assert!(
        worst < 2e-3,
        "96 cells off the 384-cell integral by {worst}"
    );
}

/// `unlit_radiance` (shaders/forward.wgsl) against its CPU twin. Input: 9
/// vec4 of SH, then per case base colour, sun direction, sun illuminance.
const UNLIT_KERNEL: &str = r#"#import forward
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    let base = 9u + i * 3u;
    if base + 2u >= arrayLength(&input) { return; }
    var sh: Sh9;
    for (var k = 0u; k < 9u; k = k + 1u) { sh.c[k] = input[k]; }
    output[i] = vec4f(unlit_radiance(input[base].xyz, input[base + 1u].xyz, input[base + 2u].xyz, sh), 0.0);
}
"#;

#[test]
fn unlit_radiance_matches_its_cpu_twin() {
    use himal::passes::forward::reference::unlit_radiance;
    let mut rng = Pcg32::new(31);
    let sky = Sh9Rgb {
        c: std::array::from_fn(|k| {
            Vec3::new(30.0, 35.0, 45.0) * if k == 0 { 1.0 } else { 0.2 } * (1.0 + rng.next_f32())
        }),
    };
    let mut input: Vec<[f32; 4]> = sky.c.iter().map(|c| c.extend(0.0).to_array()).collect();
    let mut cases = Vec::new();
    for _ in 0..128 {
        let base = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        let light = ForwardLight {
            sun_direction: uniform_sample_sphere(rng.next_vec2()),
            sun_illuminance: Vec3::new(90.0, 85.0, 80.0) * rng.next_f32(),
            sky_irradiance: sky,
            prefiltered: Vec3::ZERO,
            dfg: Vec2::ZERO,
        };
        input.extend([
            base.extend(0.0).to_array(),
            light.sun_direction.extend(0.0).to_array(),
            light.sun_illuminance.extend(0.0).to_array(),
        ]);
        cases.push(unlit_radiance(base, &light));
    }
    let out = run_compute(
        UNLIT_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        (cases.len() * 16) as u64,
        [(cases.len() as u32).div_ceil(64), 1, 1],
    )
    .unwrap_or_else(|e| panic!("unlit kernel: {e}"));
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let mut worst = 0.0f32;
    for (cpu, g) in cases.iter().zip(gpu) {
        let g = Vec3::from_slice(&g[..3]);
        worst = worst.max(((g - *cpu).abs() / cpu.abs().max(Vec3::splat(1e-2))).max_element());
    }
    eprintln!("unlit GPU vs CPU: worst relative {worst:.2e}");
    assert!(worst < 1e-5, "worst relative difference {worst}");
}

/// The flat opaque box over `scenes/blend_shadow.toml`'s card.
const BLOCKER: (Vec3, Vec3) = (Vec3::new(-1.0, 3.75, -1.0), Vec3::new(1.0, 4.25, 1.0));
/// Height of the card's top face and the card's half size (m).
const CARD_TOP: f32 = 2.05;
const CARD_HALF: f32 = 6.0;

/// `blend_shadow.toml` with its card: a 12 x 0.1 x 12 m box of an opaque-
/// coverage (alpha 1) BLEND material, so `forward.blend` alone shades it.
fn blend_shadow_scene(overrides: &[(&str, &str)]) -> Scene {
    let card = common::cube_gltf(
        "blend-card",
        r#""scale":[12,0.1,12]"#,
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1.0],"metallicFactor":0,"roughnessFactor":1},"alphaMode":"BLEND"}"#,
    );
    let file = format!("file = {:?}", card.display().to_string());
    let mut all = vec![("file = \"CARD\"", file.as_str())];
    all.extend_from_slice(overrides);
    common::scene_with("blend_shadow", &all)
}

/// The card's pixels by what the ray from their point toward the light
/// (`toward(p)`: unit direction and distance) says, [shadowed by the box,
/// lit] -> (pixels, where the GPU agrees), and the mean L_on / L_off of
/// each class. GPU: shadowed when the luminance ratio of the frames with
/// shadows on and off is below the midpoint of 1 and the darkest card
/// pixel's. Pixels within 0.15 m of the shadow's edge, near the card's
/// rim or behind the box are left out.
fn blend_card_counts(
    on: &[[f32; 4]],
    off: &[[f32; 4]],
    camera: &himal::scene::Camera,
    (w, h): (u32, u32),
    toward: impl Fn(Vec3) -> (Vec3, f32),
) -> ([(usize, usize); 2], [f32; 2]) {
    let lit = |p: Vec3| {
        let (d, t) = toward(p);
        !common::hits_box(p, d, BLOCKER, t)
    };
    let mut pixels = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let dir = common::pixel_ray(camera, (w, h), x, y);
            let t = (CARD_TOP - camera.position.y) / dir.y;
            let p = camera.position + dir * t;
            if p.x.abs() > CARD_HALF - 0.3 || p.z.abs() > CARD_HALF - 0.3 {
                continue;
            }
            if common::hits_box(camera.position, dir, BLOCKER, t) {
                continue;
            }
            let cpu = lit(p);
            if !common::ring(p, 0.15).all(|o| lit(o) == cpu) {
                continue;
            }
            let i = (y * w + x) as usize;
            let ratio =
                (on[i][0] + on[i][1] + on[i][2]) / (off[i][0] + off[i][1] + off[i][2]).max(1e-6);
            pixels.push((cpu, ratio));
        }
    }
    let darkest = pixels.iter().map(|p| p.1).fold(1.0f32, f32::min);
    let threshold = 0.5 * (1.0 + darkest);
    let mut counts = [(0usize, 0usize); 2];
    let mut sums = [0.0f32; 2];
    for (cpu, ratio) in pixels {
        let class = usize::from(cpu);
        counts[class].0 += 1;
        counts[class].1 += usize::from((ratio > threshold) == cpu);
        sums[class] += ratio;
    }
    let means = [0, 1].map(|k| sums[k] / counts[k].0.max(1) as f32);
    (counts, means)
}

/// Issue #22: a BLEND surface takes the sun's shadow (its own lookup in
/// the cascades, the shadow mask holding the ground behind it) and a local
/// light's atlas shadow: on the card, the pixels the ray toward the light
/// says the box shadows are darker with shadows on than off, the others
/// unchanged. Before, forward.blend's sun and lights were unshadowed.
#[test]
fn blend_surfaces_take_sun_and_local_light_shadows() {
    let size = (120u32, 120u32);
    let lamp_pos = Vec3::new(3.0, 6.0, 2.0);
    let lamp = "[[light]]\nname = \"lamp\"\nkind = \"point\"\nposition = [3.0, 6.0, 2.0]\nintensity = 500.0\nrange = 25.0\n\n[[camera]]";
    let cases = [
        ("sun", blend_shadow_scene(&[])),
        (
            "lamp",
            blend_shadow_scene(&[
                ("time = \"16:30\"", "time = \"23:00\""),
                ("[[camera]]", lamp),
            ]),
        ),
    ];
    for (name, scene) in cases {
        let camera = scene.camera("top").expect("camera").clone();
        let mut r = common::renderer(&scene);
        let mut s = common::raw_settings(&scene, size, "lighting");
        s.aerial_extinction = 0.0;
        s.shadows.atlas_resolution = 4096;
        let on = common::render_rgba(&mut r, &camera, &s);
        s.shadow_resolution = 0;
        let off = common::render_rgba(&mut r, &camera, &s);
        let sun = common::lighting_params(&scene).sun_direction;
        let toward = |p: Vec3| match name {
            "sun" => (sun, f32::INFINITY),
            _ => ((lamp_pos - p).normalize(), (lamp_pos - p).length()),
        };
        let (counts, means) = blend_card_counts(&on, &off, &camera, size, toward);
        let rate = |(n, ok): (usize, usize)| ok as f64 / n.max(1) as f64;
        eprintln!(
            "{name}: card shadowed {:?} {:.1}% (mean L_on/L_off {:.3}), lit {:?} {:.1}% (mean {:.3})",
            counts[0],
            100.0 * rate(counts[0]),
            means[0],
            counts[1],
            100.0 * rate(counts[1]),
            means[1]
        );
        assert!(
            counts[0].0 > 100 && counts[1].0 > 100,
            "{name}: too few pixels {counts:?}"
        );
        // Measured 2026-12-06 on lavapipe: see docs/gltf.md "Forward passes".
        assert!(
            rate(counts[0]) >= 0.97 && rate(counts[1]) >= 0.97,
            "{name}: {counts:?} {means:?}"
        );
        assert!(means[0] < 0.7, "{name}: the shadow is too faint: {means:?}");
    }
}
