//! S3 local-light shadows: a box on a plane under a point light and a spot
//! light; each light's channel of the shadow mask against CPU ray casting
//! toward the light, and the channels chosen (G for the first, B for the
//! second as their ranges overlap); the lights' shading against the CPU
//! twin in `passes/lighting/reference.rs`.

mod common;

use common::{
    parse_scene, pixel_ray, raw_settings, render_rgba, renderer, ring, scene_and_camera,
    scene_text_with,
};
use glam::Vec3;

/// Does the segment from `p` to `to` cross the box of `scenes/shadow_local.toml`?
fn hits_box(p: Vec3, to: Vec3) -> bool {
    let box_ = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
    common::hits_box(p, to - p, box_, 1.0)
}

#[test]
fn local_light_shadows_agree_with_ray_casting() {
    let (scene, camera) = scene_and_camera("shadow_local", "top");
    let mut r = renderer(&scene);
    let size = 128;
    let mut s = raw_settings(&scene, (size, size), "shadow-mask");
    s.shadows.atlas_resolution = 4096;
    let frame = r.render(&camera, &s).expect("frame");
    // The camera is inside both ranges: importance 1, the largest tiles.
    assert_eq!(frame.shadows.atlas_tiles, 7, "6 faces + 1 spot");
    let mask = frame.image.to_rgba_f32().expect("f32");
    for (light, channel) in [(&scene.lights[0], 1usize), (&scene.lights[1], 2usize)] {
        let cone = light.outer_deg.to_radians().cos();
        let (mut counts, mut total) = ([(0usize, 0usize); 2], 0);
        for y in 0..size {
            for x in 0..size {
                let d = pixel_ray(&camera, (size, size), x, y);
                let p = camera.position + d * (-camera.position.y / d.y);
                if hits_box(camera.position, p) || p.distance(light.position) > light.range * 0.9 {
                    continue;
                }
                // Inside the spot's cone only (outside it is unlit anyway).
                let dir = (p - light.position).normalize();
                if channel == 2 && dir.dot(light.direction) < cone + 0.05 {
                    continue;
                }
                let lit = !hits_box(p, light.position);
                let stable = ring(p, 0.12).all(|o| hits_box(o, light.position) != lit);
                if !stable {
                    continue;
                }
                total += 1;
                let c = &mut counts[usize::from(lit)];
                c.0 += 1;
                c.1 += usize::from((mask[(y * size + x) as usize][channel] > 0.5) == lit);
            }
        }
        let [(sh, sh_ok), (li, li_ok)] = counts;
        let (rs, rl) = (
            sh_ok as f64 / sh.max(1) as f64,
            li_ok as f64 / li.max(1) as f64,
        );
        eprintln!(
            "{}: shadowed {sh_ok}/{sh} ({:.2}%), lit {li_ok}/{li} ({:.2}%), of {total}",
            light.name,
            100.0 * rs,
            100.0 * rl
        );
        assert!(sh > 100 && li > 1000, "{}: too few pixels", light.name);
        // Measured 2026-11-22 on lavapipe: 100% / 100% for the lamp (cube
        // faces) and the spot; threshold 97% each.
        assert!(
            rs >= 0.97 && rl >= 0.97,
            "{}: shadowed {rs}, lit {rl}",
            light.name
        );
    }
}

/// The same scene at night without its `[[light]]` tables.
fn without_lights(text: &str) -> String {
    let start = text.find("[[light]]").expect("lights");
    let end = text.find("[[camera]]").expect("camera");
    format!("{}{}", &text[..start], &text[end..])
}

#[test]
fn local_lighting_matches_the_cpu_twin() {
    use himal::math::brdf::Material;
    use himal::passes::lighting::reference::shade_local;
    let night = scene_text_with("shadow_local", &[("time = \"12:00\"", "time = \"00:30\"")]);
    let lit = parse_scene(&night, "shadow_local.toml");
    let dark = parse_scene(&without_lights(&night), "dark.toml");
    let camera = lit.camera("top").expect("camera").clone();
    let size = 96;
    let mut s = raw_settings(&lit, (size, size), "lighting");
    s.aerial_extinction = 0.0;
    // Unshadowed on both sides: the difference is the lights' term alone.
    s.shadow_resolution = 0;
    let on = render_rgba(&mut renderer(&lit), &camera, &s);
    let off = render_rgba(&mut renderer(&dark), &camera, &s);
    let m = Material {
        albedo: glam::Vec3::splat(0.7),
        glossiness: 0.5,
        reflectance: 0.04,
        metallic: 0.0,
        anisotropy: 0.0,
    };
    let (mut sum, mut worst, mut n) = (0.0f64, 0.0f32, 0);
    for y in 0..size {
        for x in 0..size {
            let d = pixel_ray(&camera, (size, size), x, y);
            let p = camera.position + d * (-camera.position.y / d.y);
            if hits_box(camera.position, p) {
                continue;
            }
            let cpu: Vec3 = lit
                .lights
                .iter()
                .map(|l| shade_local(&m, Vec3::X, Vec3::NEG_Z, Vec3::Y, -d, p, l))
                .sum();
            let i = (y * size + x) as usize;
            let gpu = Vec3::new(
                on[i][0] - off[i][0],
                on[i][1] - off[i][1],
                on[i][2] - off[i][2],
            );
            if cpu.element_sum() < 1e-3 {
                continue;
            }
            let e = (gpu - cpu).abs().element_sum() / cpu.element_sum();
            sum += e as f64;
            worst = worst.max(e);
            n += 1;
        }
    }
    let mean = sum / n.max(1) as f64;
    eprintln!(
        "local lights, GPU vs CPU twin over {n} ground pixels: mean relative error {mean:.5}, worst {worst:.5}"
    );
    assert!(n > 3000, "too few lit pixels ({n})");
    // Measured 2026-11-22 on lavapipe: mean 0.00096, worst 0.0022 (Rgba16Float
    // HDR rounding); thresholds 0.005 / 0.02.
    assert!(mean < 0.005 && worst < 0.02, "mean {mean}, worst {worst}");
}

/// #23: a shadowed light with no caster in its reach gets no atlas tiles
/// (no projector passes) and no mask channel; the mask is unchanged, since
/// its tiles would hold no depth (`ShadowSettings::skip_casterless`).
#[test]
fn lights_without_casters_get_no_projector_pass() {
    let (scene, camera) = scene_and_camera("shadow_local_casterless", "top");
    let size = 96;
    let mut s = raw_settings(&scene, (size, size), "shadow-mask");
    let mut masks = Vec::new();
    for (skip, tiles) in [(true, 6), (false, 12)] {
        s.shadows.skip_casterless = skip;
        let frame = renderer(&scene).render(&camera, &s).expect("frame");
        assert_eq!(
            frame.shadows.atlas_tiles, tiles,
            "skip {skip}: 6 faces each"
        );
        masks.push(frame.image.to_rgba_f32().expect("f32"));
    }
    let worst = (masks[0].iter().flatten())
        .zip(masks[1].iter().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    let shadowed = masks[0].iter().filter(|m| m[1] < 0.5).count();
    eprintln!(
        "mask skip vs keep: worst channel difference {worst}, lamp-shadowed pixels {shadowed}"
    );
    // The lamp's shadow is there on both sides (the box's, > 100 pixels).
    assert!(shadowed > 100, "{shadowed}");
    // Measured 2026-12-06 on lavapipe: 0 (identical); the far light only
    // changes which tiles the atlas holds.
    assert!(worst <= 1e-6, "{worst}");
}

/// #23: `shadows.mask_tiles` (a map lit or shadowed over a whole 16 x 16
/// tile costs the mask no tap) leaves the mask as it was: the sun (R) and
/// the local lights (G, B, A) on the box-and-lamps scene and the demo's
/// cameras, at 128 x 72.
#[test]
fn mask_tiles_leave_the_mask_unchanged() {
    let demo = himal::scene::Scene::demo().expect("demo");
    let local = common::scene("shadow_local");
    let mut cases = vec![(
        &local,
        local.camera("top").expect("top").clone(),
        "shadow_local top",
    )];
    for name in ["fox", "village"] {
        cases.push((&demo, demo.camera(name).expect("camera").clone(), name));
    }
    for (scene, camera, name) in cases {
        let mut masks = Vec::new();
        for tiles in [false, true] {
            let mut s = raw_settings(scene, (128, 72), "shadow-mask");
            s.shadows.mask_tiles = tiles;
            masks.push(render_rgba(&mut renderer(scene), &camera, &s));
        }
        let diffs: Vec<f32> = (masks[0].iter().flatten())
            .zip(masks[1].iter().flatten())
            .map(|(a, b)| (a - b).abs())
            .collect();
        let worst = diffs.iter().copied().fold(0.0f32, f32::max);
        let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
        let shadowed = masks[0].iter().flatten().filter(|&&v| v < 0.5).count();
        eprintln!(
            "{name}: mask tiles on vs off: worst {worst}, mean {mean}; channels < 0.5: {shadowed}"
        );
        assert!(shadowed > 50, "{name}: no shadow to compare ({shadowed})");
        // Exact by construction (a tile is lit or shadowed only if every tap
        // of every pixel agrees); measured 0 on lavapipe.
        assert!(worst <= 1e-6, "{name}: worst {worst}, mean {mean}");
    }
}
