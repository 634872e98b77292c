//! Sun shadows against CPU ray casting: a box on a plane under three sun
//! positions, read from the cascades (`csm`) and from the static map
//! (`csm+static` with cascades ending at 12 m, so the ground reads the static map). The GPU's sun visibility is recovered per pixel from two HDR
//! renders (shadows on and off) and the CPU twin of the sun term:
//! `vis = 1 - (L_off - L_on) / sun_term`.

mod common;

use common::{lighting_params, pixel_ray, raw_settings, render_rgba, renderer, ring, scene_with};
use glam::Vec3;
use himal::math::brdf::Material;
use himal::passes::lighting::reference::shade;
use himal::passes::shadows::ShadowMode;

/// The box of `scenes/shadow_box.toml`.
const BOX: (Vec3, Vec3) = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 6.0, 1.0));

/// Does the ray from `p` toward `d` hit the box?
fn hits_box(p: Vec3, d: Vec3) -> bool {
    common::hits_box(p, d, BOX, f32::INFINITY)
}

/// The ground point (y = 0) pixel (x, y) of a `size` frame sees, with the
/// ray's direction; `None` off the plane's inner 36 m or behind the box.
fn ground_point(
    camera: &himal::scene::Camera,
    size: (u32, u32),
    x: u32,
    y: u32,
) -> Option<(Vec3, Vec3)> {
    let dir = pixel_ray(camera, size, x, y);
    let t = -camera.position.y / dir.y;
    let p = camera.position + dir * t;
    if t <= 0.0 || p.x.abs() > 18.0 || p.z.abs() > 18.0 || hits_box(camera.position, dir) {
        return None;
    }
    Some((p, dir))
}

/// The GPU's sun visibility at pixel `i` of the ground seen along `dir`,
/// from HDR frames with shadows on and off: 1 - (L_off - L_on) / sun term.
fn sun_visibility(
    on: &[[f32; 4]],
    off: &[[f32; 4]],
    i: usize,
    light: &himal::passes::lighting::reference::LightingParams,
    dir: Vec3,
) -> f32 {
    let m = Material {
        albedo: Vec3::splat(0.7),
        glossiness: 0.1,
        reflectance: 0.04,
        metallic: 0.0,
        anisotropy: 0.0,
    };
    let v = -dir;
    let sun_term = shade(&m, 1.0, Vec3::X, Vec3::NEG_Z, Vec3::Y, v, light, 1.0)
        - shade(&m, 1.0, Vec3::X, Vec3::NEG_Z, Vec3::Y, v, light, 0.0);
    let diff = (off[i][0] - on[i][0]) + (off[i][1] - on[i][1]) + (off[i][2] - on[i][2]);
    1.0 - diff / (sun_term.x + sun_term.y + sun_term.z).max(1e-6)
}

#[test]
fn sun_shadow_agrees_with_ray_cast_visibility() {
    let (w, h) = (128u32, 128u32);
    let variants = [
        ("csm", ShadowMode::Csm, 400.0),
        ("static", ShadowMode::CsmStatic, 12.0),
    ];
    // The box as a scene primitive and as a glTF model (glTF objects cast
    // like any other: issue #22 found they cast nothing).
    let cube = common::cube_gltf(
        "shadow-box",
        "",
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0.7,0.7,0.7,1]}}"#,
    );
    let gltf_box = format!(
        "[[gltf]]\nfile = {:?}\ntranslation = [0.0, 3.0, 0.0]\nscale = [2.0, 6.0, 2.0]\n",
        cube.display().to_string()
    );
    let primitive_box = "[[object]]\nname = \"box\"\nprimitive = \"box\"\nmaterial = \"white\"\nsize = [2.0, 6.0, 2.0]\nposition = [0.0, 3.0, 0.0]\n";
    let sources = [("primitive", None), ("gltf", Some(gltf_box.as_str()))];
    for ((time, (variant, mode, max_distance)), (source, replace)) in ["09:00", "12:00", "16:30"]
        .into_iter()
        .flat_map(|t| variants.map(|v| (t, v)))
        .flat_map(|tv| sources.map(|s| (tv, s)))
    {
        let time_of_day = format!("time = \"{time}\"");
        let mut overrides = vec![("time = \"12:00\"", time_of_day.as_str())];
        if let Some(r) = replace {
            overrides.push((primitive_box, r));
        }
        let scene = scene_with("shadow_box", &overrides);
        let camera = scene.camera("top").expect("camera").clone();
        let mut r = renderer(&scene);
        let mut s = raw_settings(&scene, (w, h), "lighting");
        s.aerial_extinction = 0.0;
        s.shadows.mode = mode;
        s.shadows.max_distance = max_distance;
        s.shadows.static_resolution = 1024;
        let frame = r.render(&camera, &s).expect("on");
        assert_eq!(frame.shadows.static_shown, mode == ShadowMode::CsmStatic);
        let on = frame.image.to_rgba_f32().expect("f32");
        s.shadow_resolution = 0;
        let off = render_rgba(&mut r, &camera, &s);

        let light = lighting_params(&scene);
        // [cpu shadowed, cpu lit] -> (pixels, GPU agrees)
        let mut counts = [(0usize, 0usize); 2];
        for y in 0..h {
            for x in 0..w {
                // ground pixels the box does not hide, away from the plane's edge
                let Some((p, dir)) = ground_point(&camera, (w, h), x, y) else {
                    continue;
                };
                // Away from penumbrae: every point within 0.15 m agrees.
                let cpu_lit = !hits_box(p, light.sun_direction);
                let stable = ring(p, 0.15).all(|o| hits_box(o, light.sun_direction) != cpu_lit);
                if !stable {
                    continue;
                }
                let vis = sun_visibility(&on, &off, (y * w + x) as usize, &light, dir);
                let c = &mut counts[usize::from(cpu_lit)];
                c.0 += 1;
                c.1 += usize::from((vis > 0.5) == cpu_lit);
            }
        }
        let [(shadowed, shadowed_ok), (lit, lit_ok)] = counts;
        let (rs, rl) = (
            shadowed_ok as f64 / shadowed.max(1) as f64,
            lit_ok as f64 / lit.max(1) as f64,
        );
        eprintln!(
            "{time} {variant} {source}: shadowed {shadowed_ok}/{shadowed} ({:.2}%), lit {lit_ok}/{lit} ({:.2}%)",
            100.0 * rs,
            100.0 * rl
        );
        assert!(
            lit > 5000 && shadowed > 50,
            "{time}: too few pixels ({lit} lit, {shadowed} shadowed)"
        );
        // Issue #6 asks >= 97% agreement away from penumbra edges, here for the
        // shadowed and the lit pixels separately (a missing shadow cannot hide
        // in the lit majority). Measured 2026-11-22 on lavapipe: 100% / 100% at
        // all three times, cascades and static map alike.
        assert!(rs >= 0.97 && rl >= 0.97, "{time}: shadowed {rs}, lit {rl}");
    }
}

/// R3: the close-up of `scenes/r3_closeup.toml` with the default cascades
/// (camera near to 400 m, lambda 0.85) and with the camera's cinematic
/// shadows (1 to 12 m, logarithmic). Per ground pixel: the shadow texel's
/// world size over the pixel's footprint (below 1: the map out-resolves the
/// screen), and the sun visibility against a hard ray cast.
#[test]
fn r3_cinematic_shadows_out_resolve_the_screen_in_a_close_up() {
    let scene = common::scene("r3_closeup");
    let (w, h) = (160u32, 90u32);
    let light = lighting_params(&scene);
    let mut results = Vec::new();
    for name in ["closeup_default", "closeup"] {
        let camera = scene.camera(name).expect("camera").clone();
        let mut r = renderer(&scene);
        let mut s = raw_settings(&scene, (w, h), "lighting");
        s.aerial_extinction = 0.0;
        s.shadows.cinematic = scene.cinematic_shadows_for(name);
        let frame = r.render(&camera, &s).expect("on");
        let (fits, splits) = (frame.shadows.fits.clone(), frame.shadows.splits);
        let on = frame.image.to_rgba_f32().expect("f32");
        s.shadow_resolution = 0;
        let off = render_rgba(&mut r, &camera, &s);
        let pixel_angle = 2.0 * (camera.fov_y_deg.to_radians() * 0.5).tan() / h as f32;
        let (mut ratios, mut error, mut penumbra, mut n) = (Vec::new(), 0.0f32, 0, 0);
        for y in 0..h {
            for x in 0..w {
                let Some((p, dir)) = ground_point(&camera, (w, h), x, y) else {
                    continue;
                };
                // The mask picks the cascade by distance along the view axis.
                let axis = (p - camera.position).dot(camera.forward.normalize());
                let Some(k) = splits.iter().position(|&d| axis <= d) else {
                    continue;
                };
                let dist = p.distance(camera.position);
                ratios.push(fits[k].texel_world / (dist * pixel_angle));
                let vis = sun_visibility(&on, &off, (y * w + x) as usize, &light, dir);
                let cpu = if hits_box(p, light.sun_direction) {
                    0.0
                } else {
                    1.0
                };
                error += (vis.clamp(0.0, 1.0) - cpu).abs();
                penumbra += usize::from(vis > 0.1 && vis < 0.9);
                n += 1;
            }
        }
        ratios.sort_by(f32::total_cmp);
        let q = |f: f32| ratios[((ratios.len() - 1) as f32 * f) as usize];
        let mean_error = error / n.max(1) as f32;
        // The fits depend on the aspect, not the size: at 1920x1080 the
        // footprint is 90/1080 of this one.
        let hd = 1080.0 / h as f32;
        eprintln!(
            "R3 {name}: splits {splits:?}; texel/pixel median {:.3}, p90 {:.3}, max {:.3} \
             (at 1080p: {:.2}, {:.2}, {:.2}); visibility error {mean_error:.4} over {n} px, \
             {penumbra} penumbra px",
            q(0.5),
            q(0.9),
            q(1.0),
            q(0.5) * hd,
            q(0.9) * hd,
            q(1.0) * hd
        );
        assert!(n > 5000, "{name}: {n} ground pixels");
        results.push((q(0.5), q(0.9), mean_error, penumbra));
    }
    let (default, cinematic) = (results[0], results[1]);
    // Measured 2026-12-06 (lavapipe, 160x90, 2048 cascades): texel/pixel
    // median 0.370 -> 0.111, p90 0.555 -> 0.138 (at 1080p 4.44 -> 1.33);
    // visibility error 0.0030 -> 0.0012; penumbra pixels 103 -> 43.
    assert!(cinematic.0 < 1.0 && cinematic.1 < 1.0, "{cinematic:?}");
    assert!(cinematic.0 < 0.5 * default.0, "{default:?} {cinematic:?}");
    assert!(cinematic.2 < default.2, "{default:?} {cinematic:?}");
}

/// A 6 x 6 m double-sided card in the XZ plane (uv = ((x + 3) / 6, (z + 3)
/// / 6)) whose base colour texture is 4 x 4 texels of alpha `alphas` (row
/// major, NEAREST), material `alpha` (e.g. `"alphaMode":"MASK"`).
fn card_gltf(name: &str, alpha: &str, alphas: [u8; 16]) -> std::path::PathBuf {
    let rgba: Vec<u8> = alphas.iter().flat_map(|&a| [200, 200, 200, a]).collect();
    let image = image::RgbaImage::from_raw(4, 4, rgba).expect("4 x 4");
    let mut png = std::io::Cursor::new(Vec::new());
    image
        .write_to(&mut png, image::ImageFormat::Png)
        .expect("encode PNG");
    let png = common::base64(&png.into_inner());
    let corners = [(-3.0f32, -3.0f32), (3.0, -3.0), (3.0, 3.0), (-3.0, 3.0)];
    let mut bin: Vec<u8> = Vec::new();
    for (x, z) in corners {
        bin.extend([x, 0.0, z].iter().flat_map(|c| c.to_le_bytes()));
    }
    for (x, z) in corners {
        bin.extend(
            [(x + 3.0) / 6.0, (z + 3.0) / 6.0]
                .iter()
                .flat_map(|c| c.to_le_bytes()),
        );
    }
    bin.extend([0u16, 2, 1, 0, 3, 2].iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":2,"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}},"metallicFactor":0}},"doubleSided":true,{alpha}}}],
"textures":[{{"source":0,"sampler":0}}],"samplers":[{{"magFilter":9728,"minFilter":9728,"wrapS":33071,"wrapT":33071}}],
"images":[{{"uri":"data:image/png;base64,{png}"}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":32}},{{"buffer":0,"byteOffset":80,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-3,0,-3],"max":[3,0,3]}},
{{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"}},{{"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
        bin.len(),
        common::base64(&bin)
    );
    let path = std::env::temp_dir().join(format!("himal-{}-{name}.gltf", std::process::id()));
    std::fs::write(&path, json).expect("write temporary glTF");
    path
}

/// Issue #22: a glTF card with alpha MASK (and BLEND, cast as a mask at 0.5)
/// casts its holes into the sun's cascades. CPU twin: the ray from each
/// ground point toward the sun meets the card's plane at (u, v); its texel's
/// alpha through `AlphaMode::cuts` says lit or shadowed. With
/// `ShadowSettings::alpha_test` off (the cards cast as opaque quads, as
/// before) the ground under the holes is shadowed: the check can fail.
#[test]
fn alpha_tested_gltf_cards_cast_their_holes() {
    use himal::scene::gltf::AlphaMode;
    let (w, h) = (120u32, 120u32);
    // A checker: (i + j) even opaque, odd a hole.
    let checker = |opaque: u8, hole: u8| {
        std::array::from_fn::<u8, 16, _>(|k| {
            if (k % 4 + k / 4) % 2 == 0 {
                opaque
            } else {
                hole
            }
        })
    };
    let variants = [
        (
            "mask",
            r#""alphaMode":"MASK","alphaCutoff":0.5"#,
            AlphaMode::Mask(0.5),
            checker(255, 0),
            true,
        ),
        (
            "blend",
            r#""alphaMode":"BLEND""#,
            AlphaMode::Blend,
            checker(204, 77),
            true,
        ),
        (
            "mask, alpha test off",
            r#""alphaMode":"MASK","alphaCutoff":0.5"#,
            AlphaMode::Mask(0.5),
            checker(255, 0),
            false,
        ),
    ];
    for (name, alpha_json, mode, alphas, alpha_test) in variants {
        let card = card_gltf(&format!("card-{}", name.len()), alpha_json, alphas);
        let file = format!("file = {:?}", card.display().to_string());
        let scene = scene_with("shadow_card", &[("file = \"CARD\"", file.as_str())]);
        let camera = scene.camera("top").expect("camera").clone();
        let mut r = renderer(&scene);
        let mut s = raw_settings(&scene, (w, h), "lighting");
        s.aerial_extinction = 0.0;
        s.shadows.alpha_test = alpha_test;
        let on = render_rgba(&mut r, &camera, &s);
        s.shadow_resolution = 0;
        let off = render_rgba(&mut r, &camera, &s);
        let light = lighting_params(&scene);
        let sun = light.sun_direction;
        // The card's texel the sun ray from ground point p crosses, if any.
        let texel = |p: Vec3, d: Vec3| {
            let q = p + d * ((2.0 - p.y) / d.y);
            let (u, v) = ((q.x + 3.0) / 6.0, (q.z + 3.0) / 6.0);
            ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v))
                .then(|| (u * 4.0) as usize + 4 * (v * 4.0) as usize)
        };
        // CPU twin: (lit, under the card).
        let cpu = |p: Vec3| match texel(p, sun) {
            Some(t) => (mode.cuts(alphas[t] as f32 / 255.0, true), true),
            None => (true, false),
        };
        let counts = card_counts(&camera, (w, h), &cpu, |i, dir| {
            sun_visibility(&on, &off, i, &light, dir) > 0.5
        });
        check_card_counts(name, counts, alpha_test);
    }
}

/// The texel of `card_gltf`'s card (2 m up) that the ray from ground point
/// `p` along `d` crosses, if any.
fn card_texel(p: Vec3, d: Vec3) -> Option<usize> {
    let q = p + d * ((2.0 - p.y) / d.y);
    let (u, v) = ((q.x + 3.0) / 6.0, (q.z + 3.0) / 6.0);
    ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v) && d.y > 0.0)
        .then(|| (u * 4.0) as usize + 4 * (v * 4.0) as usize)
}

/// Issue #22: the same MASK card under a point light casts its holes into
/// the local lights' atlas (the shadow mask's G channel) as the ray toward
/// the light through the card's texel says; with the alpha test off the
/// holes are shadowed.
#[test]
fn alpha_tested_gltf_cards_cast_their_holes_under_local_lights() {
    use himal::scene::gltf::AlphaMode;
    let (w, h) = (120u32, 120u32);
    let alphas =
        std::array::from_fn::<u8, 16, _>(|k| if (k % 4 + k / 4) % 2 == 0 { 255 } else { 0 });
    let card = card_gltf(
        "card-lamp",
        r#""alphaMode":"MASK","alphaCutoff":0.5"#,
        alphas,
    );
    let file = format!("file = {:?}", card.display().to_string());
    let lamp = "[[light]]\nname = \"lamp\"\nkind = \"point\"\nposition = [4.0, 7.0, 2.0]\nintensity = 500.0\nrange = 25.0\n\n[[camera]]";
    let overrides = [("file = \"CARD\"", file.as_str()), ("[[camera]]", lamp)];
    let scene = scene_with("shadow_card", &overrides);
    let camera = scene.camera("top").expect("camera").clone();
    let light = scene.lights[0].position;
    let cpu = |p: Vec3| match card_texel(p, (light - p).normalize()) {
        Some(t) => (
            AlphaMode::Mask(0.5).cuts(alphas[t] as f32 / 255.0, true),
            true,
        ),
        None => (true, false),
    };
    for alpha_test in [true, false] {
        let mut r = renderer(&scene);
        let mut s = raw_settings(&scene, (w, h), "shadow-mask");
        s.shadows.atlas_resolution = 4096;
        s.shadows.alpha_test = alpha_test;
        let mask = render_rgba(&mut r, &camera, &s);
        let counts = card_counts(&camera, (w, h), &cpu, |i, _| mask[i][1] > 0.5);
        check_card_counts(
            &format!("lamp, alpha test {alpha_test}"),
            counts,
            alpha_test,
        );
    }
}

/// The card tests' ground pixels, by what the CPU twin `cpu` (lit, under
/// the card) says: [shadowed, lit through a hole, lit beside the card] ->
/// (pixels, where `gpu_lit(pixel, ray)` agrees). Pixels off the plane's
/// inner 36 m, seeing the card (0.1 m margin), or within 0.15 m of a hole's
/// edge are left out.
fn card_counts(
    camera: &himal::scene::Camera,
    (w, h): (u32, u32),
    cpu: &dyn Fn(Vec3) -> (bool, bool),
    gpu_lit: impl Fn(usize, Vec3) -> bool,
) -> [(usize, usize); 3] {
    let mut counts = [(0usize, 0usize); 3];
    for y in 0..h {
        for x in 0..w {
            let dir = pixel_ray(camera, (w, h), x, y);
            let p = camera.position + dir * (-camera.position.y / dir.y);
            let seen = camera.position + dir * ((2.0 - camera.position.y) / dir.y);
            if p.x.abs() > 18.0 || p.z.abs() > 18.0 || (seen.x.abs() < 3.1 && seen.z.abs() < 3.1) {
                continue;
            }
            let (lit, under) = cpu(p);
            if !ring(p, 0.15).all(|o| cpu(o).0 == lit) {
                continue;
            }
            let class = match (lit, under) {
                (false, _) => 0,
                (true, true) => 1,
                (true, false) => 2,
            };
            counts[class].0 += 1;
            counts[class].1 += usize::from(gpu_lit((y * w + x) as usize, dir) == lit);
        }
    }
    counts
}

/// The card tests' verdict: (pixels, agreeing with the ray cast) for the
/// card's shadow, its holes and beside it.
fn check_card_counts(name: &str, counts: [(usize, usize); 3], alpha_test: bool) {
    let rate = |(n, ok): (usize, usize)| ok as f64 / n.max(1) as f64;
    let [shadowed, holes, beside] = counts.map(rate);
    eprintln!(
        "{name}: shadowed {:?} {:.1}%, holes {:?} {:.1}%, beside {:?} {:.1}%",
        counts[0],
        100.0 * shadowed,
        counts[1],
        100.0 * holes,
        counts[2],
        100.0 * beside
    );
    assert!(
        counts[0].0 > 200 && counts[1].0 > 200,
        "{name}: too few pixels {counts:?}"
    );
    if alpha_test {
        // Measured 2026-12-06 on lavapipe: see docs/gltf.md "Alpha in shadows".
        assert!(
            shadowed >= 0.97 && holes >= 0.97 && beside >= 0.97,
            "{name}: {counts:?}"
        );
    } else {
        // The opaque card shadows its holes too.
        assert!(
            holes < 0.1,
            "{name}: holes lit without the alpha test: {counts:?}"
        );
    }
}
