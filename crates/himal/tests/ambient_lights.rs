//! Ryse's ambient lights (`[[ambient_light]]`): the WGSL multiplier against
//! its CPU twin (`passes/lighting/reference.rs` `ambient_light_scale`), and
//! a rendered floor (`scenes/ambient_light_room.toml`) whose ambient light
//! is scaled by the factor inside each volume, unchanged outside and
//! continuous across the fading edge. Numbers: `cargo test --release -p
//! himal --test ambient_lights -- --nocapture`; docs/ambient-lights.md.

mod common;

use common::{pixel_ray_from, render_rgba as render, renderer};
use glam::{Vec3, Vec4};
use himal::gpu::testing::run_compute_with;
use himal::passes::lighting::ambient::AmbientLightsGpu;
use himal::passes::lighting::reference::{ambient_light_scale, ambient_scale};
use himal::scene::{AmbientLightDesc, AmbientShape, Scene, SunLight};

const SIZE: (u32, u32) = (160, 120);

#[test]
fn scale_matches_the_cpu_twin() {
    // `ambient_scale` over the uploaded lights (the buffer's layout too).
    const KERNEL: &str = r#"
#import ambient_lights
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&input)) { return; }
    output[id.x] = vec4f(ambient_scale(input[id.x].xyz), 0.0);
}
"#;
    let light = |name: &str, position, shape, yaw_deg, factor, falloff| AmbientLightDesc {
        name: name.into(),
        position,
        shape,
        yaw_deg,
        factor,
        falloff,
    };
    let lights = [
        light(
            "box",
            Vec3::new(1.0, 0.5, -2.0),
            AmbientShape::Box(Vec3::new(2.0, 1.0, 0.5)),
            35.0,
            Vec3::new(0.2, 0.5, 3.0),
            0.4,
        ),
        light(
            "sphere",
            Vec3::new(-1.0, 0.0, 0.5),
            AmbientShape::Sphere(1.5),
            0.0,
            Vec3::splat(4.0),
            1.0,
        ),
        light(
            "hard",
            Vec3::new(4.0, 0.0, 0.0),
            AmbientShape::Box(Vec3::ONE),
            -60.0,
            Vec3::splat(0.5),
            0.0,
        ),
    ];
    // A spiral through and around each volume.
    let mut points: Vec<Vec4> = Vec::new();
    for l in &lights {
        for i in 0..300 {
            let a = i as f32 * 0.37;
            let r = i as f32 / 300.0 * 3.5;
            let y = (i % 7) as f32 * 0.2 - 0.6;
            points.push((l.position + Vec3::new(r * a.cos(), y, r * a.sin())).extend(0.0));
        }
    }
    let data = AmbientLightsGpu::new(&lights);
    let extra = [("ambient_lights", bytemuck::bytes_of(&data))];
    let out = run_compute_with(
        KERNEL,
        "cs_main",
        bytemuck::cast_slice(&points),
        &extra,
        (points.len() * 16) as u64,
        [(points.len() as u32).div_ceil(64), 1, 1],
    )
    .unwrap_or_else(|e| panic!("kernel: {e}"));
    let gpu: &[Vec4] = bytemuck::cast_slice(&out);
    let cpu: Vec<Vec3> = points
        .iter()
        .map(|p| ambient_scale(&lights, p.truncate()))
        .collect();
    let worst = cpu
        .iter()
        .zip(gpu)
        .map(|(c, g)| (g.truncate() - *c).abs().max_element())
        .fold(0.0f32, f32::max);
    let inside = cpu.iter().filter(|c| **c != Vec3::ONE).count();
    // One light alone is the product's single factor.
    let one = ambient_light_scale(&lights[0], lights[0].position);
    assert_eq!(one, lights[0].factor);
    eprintln!(
        "ambient light scale: max |GPU - CPU| {worst:.2e} over {} points ({inside} inside a volume)",
        cpu.len()
    );
    assert!(inside > 300, "{inside}");
    // Measured 2026-12-05 (lavapipe): 8.3e-7 (f32 rotation and smoothstep).
    assert!(worst < 1e-4, "{worst}");
}

/// A raw `lighting` frame lit by the sky alone (the sun's illuminance
/// zero: every pixel is ambient diffuse + specular), ambient lights on/off.
fn frame(scene: &Scene, on: bool) -> Vec<[f32; 4]> {
    let camera = scene.camera("top").expect("camera").clone();
    let mut s = common::raw_settings(scene, SIZE, "lighting");
    let sky = himal::passes::sky::SkyLight::of_sun(&scene.sun);
    s.sun.light = Some(SunLight {
        to_light: sky.sun_direction,
        illuminance_klux: Vec3::ZERO,
    });
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.ambient_lights = on;
    let mut r = renderer(scene);
    render(&mut r, &camera, &s)
}

#[test]
fn rendered_ambient_is_scaled_inside_and_unchanged_outside() {
    let scene = common::scene("ambient_light_room");
    assert_eq!(scene.ambient_lights.len(), 2);
    let camera = scene.camera("top").expect("camera").clone();
    let on = frame(&scene, true);
    let off = frame(&scene, false);
    let (mut worst, mut inside, mut outside, mut worst_outside) = (0.0f32, 0, 0, 0.0f32);
    let mut ratios = vec![Vec3::ONE; (SIZE.0 * SIZE.1) as usize];
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let (o, d) = pixel_ray_from(&camera, SIZE, x, y);
            let p = o + d * (-o.y / d.y);
            let i = (y * SIZE.0 + x) as usize;
            let a = Vec3::from_slice(&on[i][..3]);
            let b = Vec3::from_slice(&off[i][..3]).max(Vec3::splat(1e-6));
            let ratio = a / b;
            ratios[i] = ratio;
            let twin = ambient_scale(&scene.ambient_lights, p);
            worst = worst.max(((ratio - twin) / twin).abs().max_element());
            if twin == Vec3::ONE {
                outside += 1;
                worst_outside = worst_outside.max((ratio - Vec3::ONE).abs().max_element());
            } else if (twin - scene.ambient_lights[0].factor).abs().max_element() < 1e-6 {
                inside += 1;
            }
        }
    }
    // Continuity: the largest step between neighbouring pixels, relative to
    // the largest |factor - 1| (a hard edge would step by the whole of it).
    let mut step = 0.0f32;
    for y in 0..SIZE.1 as usize {
        for x in 1..SIZE.0 as usize {
            let w = SIZE.0 as usize;
            step = step.max(
                (ratios[y * w + x] - ratios[y * w + x - 1])
                    .abs()
                    .max_element(),
            );
        }
    }
    // The same field with hard edges (falloff 0) steps by the whole factor.
    let hard: Vec<AmbientLightDesc> = (scene.ambient_lights.iter())
        .map(|l| AmbientLightDesc {
            falloff: 0.0,
            ..l.clone()
        })
        .collect();
    let mut hard_step = 0.0f32;
    for y in 0..SIZE.1 {
        for x in 1..SIZE.0 {
            let at = |x| {
                let (o, d) = pixel_ray_from(&camera, SIZE, x, y);
                ambient_scale(&hard, o + d * (-o.y / d.y))
            };
            hard_step = hard_step.max((at(x) - at(x - 1)).abs().max_element());
        }
    }
    eprintln!(
        "ambient lights: max relative |GPU ratio - twin| {worst:.2e}; {inside} px at the interior's full factor, {outside} px outside (max |ratio - 1| {worst_outside:.2e}); largest neighbour step {step:.3} (hard edges: {hard_step:.3})"
    );
    assert!(
        inside > 500 && outside > 2000,
        "{inside} inside, {outside} outside"
    );
    // Measured 2026-12-05 (lavapipe, 160x120): relative 9.3e-4 (two
    // Rgba16Float frames, 4.9e-4 each); outside exactly 1; largest
    // neighbour step 0.274 against 1.750 with hard edges (0.16 of it).
    assert!(worst < 3e-3, "{worst}");
    assert!(worst_outside < 1e-3, "{worst_outside}");
    assert!(step < 0.25 * hard_step, "{step} vs {hard_step}");
}

#[test]
fn bad_ambient_lights_name_the_file_and_the_problem() {
    let bad = |table: &str, expect: &str| {
        let text = format!("[[ambient_light]]\nposition = [0.0, 0.0, 0.0]\n{table}\n");
        let e = Scene::from_toml_str(&text, "room.toml", &common::scenes_dir())
            .err()
            .unwrap_or_else(|| panic!("{table}: accepted"))
            .to_string();
        assert!(
            e.contains("room.toml") && e.contains(expect),
            "{table}: {e}"
        );
    };
    bad("factor = 0.5", "size (box half-extents) or radius");
    bad(
        "factor = 0.5\nsize = [1.0, 1.0, 1.0]\nradius = 1.0",
        "not both",
    );
    bad("factor = -1.0\nradius = 1.0", "factor");
    bad("factor = [1.0, 20.0, 1.0]\nradius = 1.0", "factor");
    bad("factor = 0.5\nradius = 1.0\nfalloff = 1.5", "falloff");
    bad("factor = 0.5\nsize = [1.0, 0.0, 1.0]", "size");
    bad("factor = 0.5\nradius = 1.0\nshape = 2", "unknown field");
    // More than the buffer holds is an error, not a silent drop.
    let table = "[[ambient_light]]\nposition = [0.0, 0.0, 0.0]\nradius = 1.0\nfactor = 0.5\n";
    let text = table.repeat(himal::scene::MAX_AMBIENT_LIGHTS + 1);
    let Err(e) = Scene::from_toml_str(&text, "many.toml", &common::scenes_dir()) else {
        panic!("65 lights accepted");
    };
    let e = e.to_string();
    assert!(e.contains("many.toml") && e.contains("at most 64"), "{e}");
    let ok = table.repeat(himal::scene::MAX_AMBIENT_LIGHTS);
    let scene = Scene::from_toml_str(&ok, "ok.toml", &common::scenes_dir()).expect("64 lights");
    assert_eq!(scene.ambient_lights.len(), 64);
}

/// Forward passes agree: a half-transparent BLEND glTF cube inside the
/// interior volume is scaled like the opaque floor behind it, so its pixels
/// show the factor too (before the forward passes applied the lights, the
/// cube's own ambient stayed unscaled).
#[test]
fn blended_surfaces_are_scaled_like_opaque_ones() {
    let material =
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.9,0.6,0.3,0.5]},"alphaMode":"BLEND"}"#;
    let cube = common::cube_gltf("ambient_blend", r#""scale":[0.6,0.6,0.6]"#, material);
    let gltf = format!(
        "[[gltf]]\nfile = \"{}\"\ntranslation = [-1.0, 0.3, 0.0]\n",
        cube.display()
    );
    let plain = common::scene("ambient_light_room");
    let text = common::scene_text("ambient_light_room") + &gltf;
    let scene = common::parse_scene(&text, "ambient_light_room.toml + cube");
    let without = frame(&plain, false);
    let off = frame(&scene, false);
    let on = frame(&scene, true);
    let factor = scene.ambient_lights[0].factor;
    let (mut n, mut worst) = (0, 0.0f32);
    for i in 0..on.len() {
        let b = Vec3::from_slice(&off[i][..3]);
        if (b - Vec3::from_slice(&without[i][..3])).abs().max_element() < 0.02 * b.max_element() {
            continue; // not the cube
        }
        n += 1;
        let ratio = Vec3::from_slice(&on[i][..3]) / b.max(Vec3::splat(1e-6));
        worst = worst.max(((ratio - factor) / factor).abs().max_element());
    }
    eprintln!("blended cube: {n} px, max relative |on/off - factor| {worst:.2e}");
    assert!(n > 60, "{n} cube pixels");
    // Measured 2026-12-05 (lavapipe, 160x120): 99 px, 1.1e-3 (Rgba16Float);
    // with the blend pass's `ambient_scale` taken out: 1.01.
    assert!(worst < 3e-3, "{worst}");
}
