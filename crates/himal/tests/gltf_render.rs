//! glTF sample models rendered at 256x256 against goldens reviewed by eye
//! next to the Khronos screenshots (docs/gltf.md). Set
//! `HIMAL_UPDATE_GOLDENS=1` to rewrite them after a deliberate change.

mod common;

use std::path::{Path, PathBuf};

use himal::FrameSettings;
use himal::scene::Scene;

const MODELS: [&str; 9] = [
    "AlphaBlendModeTest",
    "AnisotropyRotationTest",
    "AnisotropyStrengthTest",
    "DamagedHelmet",
    "MetalRoughSpheresNoTextures",
    "NormalTangentMirrorTest",
    "NormalTangentTest",
    "OrientationTest",
    "TextureSettingsTest",
];

fn golden_path(model: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/goldens/gltf"))
        .join(format!("{model}.png"))
}

/// RGB of the final frame, 8-bit sRGB as written to PNG.
fn render(model: &str) -> (u32, u32, Vec<u8>) {
    let scene = Scene::from_gltf(&common::gltf_sample(model)).expect("model");
    let camera = scene.camera("default").expect("auto-framed camera").clone();
    let settings = FrameSettings::new(256, 256, scene.sun.clone());
    let mut r = common::renderer(&scene);
    let frame = r.render(&camera, &settings).expect("frame").image;
    let rgba = frame.to_rgba_f32().expect("rgba");
    let rgb = rgba
        .iter()
        .flat_map(|p| [p[0], p[1], p[2]])
        .map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    (frame.width, frame.height, rgb)
}

/// Root-mean-square difference in 8-bit steps over all channels.
fn rmse(a: &[u8], b: &[u8]) -> f64 {
    let sum: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).powi(2))
        .sum();
    (sum / a.len() as f64).sqrt()
}

#[test]
fn sample_models_match_their_goldens() {
    let update = std::env::var_os("HIMAL_UPDATE_GOLDENS").is_some();
    let mut report = Vec::new();
    for model in MODELS {
        let (w, h, rgb) = render(model);
        let path = golden_path(model);
        if update {
            image::RgbImage::from_raw(w, h, rgb.clone())
                .expect("size")
                .save(&path)
                .expect("write golden");
        }
        let golden = image::open(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
            .into_rgb8();
        assert_eq!(golden.dimensions(), (w, h), "{model}");
        let e = rmse(&rgb, golden.as_raw());
        report.push(format!("{model} {e:.3}"));
        // measured 0.000 for every model (same machine, lavapipe) on 2026-11-22;
        // threshold 2.0 steps RMSE leaves room for other drivers' rounding,
        // while a lost texture, a wrong colour space or flipped normals moves
        // these images by 10+ steps (measured: sRGB as linear on the helmet: see docs/gltf.md).
        assert!(e < 2.0, "{model}: RMSE {e:.3} against {}", path.display());
    }
    eprintln!("gltf goldens RMSE: {}", report.join(", "));
}

/// A2: under temporal anti-aliasing textured materials sample with mip bias
/// -0.5, so the albedo the G-buffer stores keeps more texture detail.
#[test]
fn temporal_aa_biases_texture_mips() {
    let scene = Scene::from_gltf(&common::gltf_sample("DamagedHelmet")).expect("model");
    let camera = scene.camera("default").expect("camera").clone();
    let mut r = common::renderer(&scene);
    let mut detail = |aa| {
        let mut s = FrameSettings::new(128, 128, scene.sun.clone());
        s.view = "albedo".parse().expect("view");
        s.raw = true;
        s.aa = aa;
        let img = r.render(&camera, &s).expect("frame").image;
        let px = img.to_rgba_f32().expect("rgba");
        let w = img.width as usize;
        // Mean absolute horizontal difference of green: texture detail.
        let sum: f32 = px
            .chunks(w)
            .flat_map(|row| row.windows(2).map(|p| (p[1][1] - p[0][1]).abs()))
            .sum();
        sum / px.len() as f32
    };
    let plain = detail(himal::passes::aa::AaMode::None);
    let biased = detail(himal::passes::aa::AaMode::Tfq);
    eprintln!("albedo detail: mip bias 0 {plain:.5}, -0.5 {biased:.5}");
    // Measured 2026-11-22: 0.01671 without, 0.01754 with the bias (+5.0%);
    // without the permutation the two are equal.
    assert!(biased > plain * 1.03, "{biased} vs {plain}");
}

/// Orthographic cameras rendered as 40° perspective ones. The Cameras
/// sample's second camera is orthographic (ymag 1, zfar 100) at (0.5, 0.5, 3)
/// looking at a unit square tilted 45° about X: in parallel projection the
/// square covers exactly 1 m by cos 45° m, 128 x 90.5 px of a 256 px image
/// 2 m tall, wherever it lies in depth (AO under orthographic cameras:
/// tests/ao.rs::orthographic_hbao_is_close_to_ray_traced_ao).
#[test]
fn orthographic_cameras_project_in_parallel() {
    let scene = Scene::from_gltf(&common::gltf_sample("Cameras")).expect("model");
    let ortho = scene
        .cameras
        .iter()
        .find(|c| c.camera.orthographic.is_some())
        .expect("an orthographic camera");
    let o = ortho.camera.orthographic.unwrap();
    assert_eq!((o.half_height, o.far), (1.0, 100.0));
    let mut r = common::renderer(&scene);
    let mut settings = FrameSettings::new(256, 256, scene.sun.clone());
    settings.view = "albedo".parse().expect("view");
    let albedo = r.render(&ortho.camera, &settings).expect("frame").image;
    let px = albedo.to_rgba_f32().expect("rgba");
    // The square's albedo is the default material's white; the sky is black.
    let on = |x: u32, y: u32| px[(y * 256 + x) as usize][0] > 0.5;
    let (mut x0, mut x1, mut y0, mut y1) = (u32::MAX, 0, u32::MAX, 0);
    for y in 0..256 {
        for x in 0..256 {
            if on(x, y) {
                (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
            }
        }
    }
    let (w, h) = (x1 + 1 - x0, y1 + 1 - y0);
    eprintln!("orthographic square: {w} x {h} px at ({x0}, {y0})");
    // Parallel projection: top and bottom edges equally wide (a perspective
    // camera shows the tilted square as a trapezoid), 128 x 90.5 px.
    let row = |y: u32| (0..256).filter(|&x| on(x, y)).count() as i32;
    assert!(
        (row(y0 + 2) - row(y1 - 2)).abs() <= 1,
        "{} vs {}",
        row(y0 + 2),
        row(y1 - 2)
    );
    assert!(
        (w as i32 - 128).abs() <= 1 && (h as i32 - 90).abs() <= 1,
        "{w} x {h}"
    );
    assert!(
        (x0 as i32 - 64).abs() <= 1,
        "centred under the camera: x0 {x0}"
    );
}

/// KHR_texture_transform was ignored: TextureTransformTest's top row showed
/// its yellow "not supported" image three times. With the offsets applied
/// the three quads show the green U, blue V and cyan UV checks (the
/// README's "correct" look); albedo seen straight on.
#[test]
fn texture_transforms_show_the_samples_checks() {
    let px = straight_on("TextureTransformTest", 256, "albedo");
    // The top row's quads (measured on the render: x 38..93, 100..155,
    // 162..217; y 67..122), 6 px inside their edges.
    let quads = [(44, 87), (106, 149), (168, 211)];
    let expected = ["green U", "blue V", "cyan UV"];
    for (k, (x0, x1)) in quads.into_iter().enumerate() {
        let (mut yellow, mut hit, mut n) = (0, 0, 0);
        for y in 73..116u32 {
            for x in x0..x1 {
                let [r, g, b, _] = px[(y * 256 + x) as usize];
                n += 1;
                if r > 0.3 && g > 0.3 && b < 0.1 {
                    yellow += 1;
                }
                let is = match k {
                    0 => g > 0.2 && r < 0.05 && b < 0.05,
                    1 => b > 0.3 && r < 0.05 && g < 0.05,
                    _ => g > 0.2 && b > 0.2 && r < 0.05,
                };
                hit += is as u32;
            }
        }
        eprintln!("quad {k}: {hit}/{n} {}, {yellow} yellow", expected[k]);
        // Measured 2026-12-03: 0 yellow, 77-81 % the check's colour (the
        // rest its white mark); before, the yellow not-supported image.
        assert_eq!(yellow, 0, "quad {k}: the not-supported image shows");
        assert!(hit * 2 > n, "quad {k}: {hit}/{n} pixels {}", expected[k]);
    }
}

/// Renders `model` straight on (orbit 0, 0) at `size`² with `view`.
fn straight_on(model: &str, size: u32, view: &str) -> Vec<[f32; 4]> {
    let scene = Scene::from_gltf(&common::gltf_sample(model)).expect("model");
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let mut settings = FrameSettings::new(size, size, scene.sun.clone());
    settings.view = view.parse().expect("view");
    let mut r = common::renderer(&scene);
    let img = r.render(&camera, &settings).expect("frame").image;
    img.to_rgba_f32().expect("rgba")
}

/// VertexColorTest: COLOR_0 multiplies the base colour, so the top
/// ("test") row of checks looks like the bottom ("sample pass") row; an
/// engine ignoring vertex colours shows X marks in the top row's other
/// channels. Mean albedo of each top quad against the quad below it (the
/// checks sit a pixel or two apart between rows: means, not pixels).
#[test]
fn vertex_colours_make_the_test_row_match_the_sample_row() {
    let px = straight_on("VertexColorTest", 384, "albedo");
    // Quads measured on the render: x 101..155, 165..219, 234..288; the top
    // row at y 126..179, the bottom row 101 px lower.
    let mean = |x0: u32, x1: u32, y0: u32| {
        let mut m = [0.0f32; 3];
        for y in y0..y0 + 45 {
            for x in x0..x1 {
                let p = px[(y * 384 + x) as usize];
                (0..3).for_each(|c| m[c] += p[c]);
            }
        }
        m.map(|v| v / (45 * (x1 - x0)) as f32)
    };
    for (k, (x0, x1)) in [(105, 151), (169, 215), (238, 284)].into_iter().enumerate() {
        let (test, sample) = (mean(x0, x1, 130), mean(x0, x1, 231));
        eprintln!("check {k}: test row {test:?}, sample row {sample:?}");
        // The other two channels carry the X marks when COLOR_0 is ignored.
        for c in (0..3).filter(|&c| c != k) {
            // Measured 2026-12-03: differences below 0.01.
            assert!(
                (test[c] - sample[c]).abs() < 0.03,
                "check {k} channel {c}: {} vs {}",
                test[c],
                sample[c]
            );
        }
        assert!(
            test[k] > 2.0 * test[(k + 1) % 3],
            "check {k} is its colour: {test:?}"
        );
    }
}

/// EmissiveStrengthTest: each cube doubles the one before's emissive
/// strength (1x .. 16x). The emitted light alone, the HDR frame minus the
/// same frame with emission off, must step by 2 from cube to cube.
#[test]
fn emissive_strength_doubles_from_cube_to_cube() {
    let mut scene = Scene::from_gltf(&common::gltf_sample("EmissiveStrengthTest")).expect("model");
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let hdr = |scene: &Scene| common::raw_views(scene, &camera, 256, &["lighting"]).remove(0);
    let lit = hdr(&scene);
    for m in &mut scene.pbr.materials {
        m.emissive = glam::Vec3::ZERO;
    }
    let dark = hdr(&scene);
    // Cube face centres measured on the render (faces 12-14 px wide).
    let e: Vec<f32> = [60u32, 94, 130, 164, 199]
        .iter()
        .map(|&x| {
            let i = (116 * 256 + x) as usize;
            let l = |p: [f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            l(lit[i]) - l(dark[i])
        })
        .collect();
    eprintln!("emitted luminance per cube: {e:?}");
    for w in e.windows(2) {
        let ratio = w[1] / w[0];
        // Measured 2026-12-03: 2.00 each (fp16 HDR); without the extension
        // every ratio is 1.
        assert!((1.9..=2.1).contains(&ratio), "ratio {ratio} in {e:?}");
    }
}

/// The G-buffer and forward passes made a bind group per material every
/// frame; `MaterialGroups` makes them once per uploaded scene: a second
/// frame gets the same groups, a new upload (another `SceneGpu::id`) new
/// ones.
#[test]
fn material_bind_groups_are_made_once_per_scene() {
    let scene = Scene::from_gltf(std::path::Path::new("builtin:DamagedHelmet.glb")).unwrap();
    let ctx = common::context();
    let program =
        himal::gpu::pipeline::Program::new(&ctx, "passes/gbuffer/textured.wgsl").expect("program");
    let groups = himal::gpu_scene::textures::MaterialGroups::default();
    let first = himal::gpu_scene::SceneGpu::upload(&ctx, &scene).expect("upload");
    let m = first.materials.as_ref().expect("materials");
    let a = groups.get(first.id, m, &program, &ctx.device).unwrap();
    let b = groups.get(first.id, m, &program, &ctx.device).unwrap();
    assert!(std::sync::Arc::ptr_eq(&a, &b) && groups.builds() == 1);
    assert_eq!(a.len(), m.materials.len());
    let second = himal::gpu_scene::SceneGpu::upload(&ctx, &scene).expect("upload");
    assert_ne!(first.id, second.id);
    let c = groups.get(
        second.id,
        second.materials.as_ref().unwrap(),
        &program,
        &ctx.device,
    );
    assert!(!std::sync::Arc::ptr_eq(&a, &c.unwrap()) && groups.builds() == 2);
}

/// `scene` with only the object of glTF node `node`, moved to the
/// origin, seen by `camera`: linear HDR (`lighting`) and the G-buffer's
/// world normal per pixel, `None` off the object.
fn alone(
    scene: &Scene,
    node: &str,
    camera: &himal::scene::Camera,
    size: u32,
) -> Vec<Option<(glam::Vec3, glam::Vec3)>> {
    let mut one = scene.clone();
    one.objects.retain(|o| o.name == node);
    assert_eq!(one.objects.len(), 1, "one object named {node}");
    let t = one.objects[0].transform;
    one.objects[0].transform = glam::Mat4::from_translation(-t.w_axis.truncate()) * t;
    let views = common::raw_views(&one, camera, size, &["lighting", "depth", "normal"]);
    let [hdr, depth, normal]: [Vec<[f32; 4]>; 3] = views.try_into().expect("three views");
    let v3 = |p: &[f32; 4]| glam::Vec3::new(p[0], p[1], p[2]);
    (hdr.iter().zip(&depth).zip(&normal))
        .map(|((p, d), n)| (d[0] > 0.0).then(|| (v3(p), v3(n))))
        .collect()
}

/// ClearCoatTest's reading rule: the "Coated" column shows the highlights
/// of both outer columns ("Base layer" and "Coating only", a black
/// dielectric with the coat's roughness). Each sample is rendered alone at
/// the origin with one camera, so pixels correspond, and the coated dome
/// must be base (1 − F) + coating only, F = 0.04 + 0.96 (1 − n·v)⁵ with the
/// G-buffer's normal. With the extension ignored the coated dome equals
/// the base one and misses the coating. Rows: simple, and rough stripes
/// (coat roughness texture); the normal-map rows' coat normal is not the
/// G-buffer's, and the partial row's coating-only emulation is alpha
/// blended, so pixels do not correspond there.
#[test]
fn clearcoat_combines_the_base_and_the_coating() {
    let scene = Scene::from_gltf(&common::gltf_sample("ClearCoatTest")).expect("model");
    let size = 96;
    let dome = himal::scene::Aabb::new(glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0));
    let camera = himal::scene::gltf::orbit_camera(&dome, 0.0, 0.0, None, 40.0);
    for row in ["", "R2_"] {
        let name = |s: &str| format!("{row}{s}");
        let base = alone(&scene, &name("BaseLayerSample"), &camera, size);
        let coated = alone(&scene, &name("ClearCoatSample"), &camera, size);
        let coating = alone(&scene, &name("CoatOnlySample"), &camera, size);
        let (mut layered, mut ignored, mut coat, mut n) = (0.0f32, 0.0f32, 0.0f32, 0);
        for (i, ((b, c), o)) in base.iter().zip(&coated).zip(&coating).enumerate() {
            let (Some((b, _)), Some((c, normal)), Some((o, _))) = (b, c, o) else {
                continue;
            };
            let (x, y) = (i as u32 % size, i as u32 / size);
            let (_, d) = common::pixel_ray_from(&camera, (size, size), x, y);
            let n_o_v = normal.normalize().dot(-d).clamp(0.0, 1.0);
            let f = 0.04 + 0.96 * (1.0 - n_o_v).powi(5);
            let expected = *b * (1.0 - f) + *o;
            // Within 5 % (the sun's highlight on a roughness-0.03 coat is a
            // few pixels of large radiance: counted, not averaged).
            let close =
                |x: glam::Vec3| (x - expected).abs().element_sum() <= 0.05 * expected.element_sum();
            layered += close(*c) as u32 as f32;
            ignored += close(*b) as u32 as f32;
            coat += o.element_sum() / b.element_sum();
            n += 1;
        }
        let (layered, ignored, coat) = (layered / n as f32, ignored / n as f32, coat / n as f32);
        eprintln!(
            "{}: {n} px, within 5 % of base (1 - F) + coating: {:.1} % (the base alone: {:.1} %; coating / base {coat:.3})",
            name("ClearCoatSample"),
            100.0 * layered,
            100.0 * ignored
        );
        assert!(n > 1500, "{row}: the dome covers {n} pixels");
        // Measured 2026-12-03: 99.9 % and 100.0 % (the base alone 28.4 % and
        // 10.5 %, what ignoring the extension gave).
        assert!(layered > 0.98, "{row}: {layered}");
        assert!(ignored < 0.4, "{row}: {ignored}");
    }
}

/// SheenChair: the Mango Velvet fabric's sheen (colour 1, 0.33, 0.1,
/// roughness 0.8) brightens the fabric; the wood, metal and label (no
/// sheen) are untouched.
#[test]
fn sheen_brightens_the_fabric_and_nothing_else() {
    let mut scene = Scene::from_gltf(&common::gltf_sample("SheenChair")).expect("model");
    let size = 128;
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 35.0, 20.0, None, 40.0);
    let views = |scene: &Scene| common::raw_views(scene, &camera, size, &["lighting", "depth"]);
    let with = views(&scene);
    for m in &mut scene.pbr.materials {
        m.sheen_color = glam::Vec3::ZERO;
    }
    let without = views(&scene);
    // Where the fabric can show: its depth drawn alone.
    let mut fabric = scene.clone();
    fabric
        .objects
        .retain(|o| o.name.ends_with("SheenChair_fabric"));
    assert_eq!(fabric.objects.len(), 1);
    let fabric = views(&fabric);
    let l = |p: [f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let (mut changed, mut added, mut base, mut elsewhere) = (0, 0.0f32, 0.0f32, 0);
    for i in 0..(size * size) as usize {
        let d = l(with[0][i]) - l(without[0][i]);
        if d.abs() < 1e-4 {
            continue;
        }
        changed += 1;
        elsewhere += (fabric[1][i][0] <= 0.0) as u32;
        added += d;
        base += l(without[0][i]);
    }
    eprintln!(
        "{changed} px changed ({elsewhere} off the fabric), luminance +{:.1} % there",
        100.0 * added / base
    );
    assert_eq!(elsewhere, 0, "pixels off the fabric changed");
    assert!(changed > 1500, "the sheen changed {changed} pixels");
    // Measured 2026-12-03: +21.2 % over 2,472 pixels, none off the fabric.
    assert!(added > 0.1 * base, "sheen added {added} to {base}");
}

/// UnlitTest: "the visible surface of these two objects should appear as a
/// uniform color, so much so that the 3D effect is intentionally lost".
/// Each object's HDR pixels (drawn alone) are one colour, the base colour
/// factor's: channel ratios as the factor's. Lit (the flag cleared), the
/// same objects shade with their faces.
#[test]
fn unlit_objects_are_one_uniform_colour() {
    let scene =
        Scene::from_gltf(&common::gltf_sample("UnlitTest")).expect("loads (required extension)");
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 35.0, 20.0, None, 40.0);
    let spread = |scene: &Scene, node: &str| {
        let px: Vec<glam::Vec3> = alone(scene, node, &camera, 96)
            .into_iter()
            .flatten()
            .map(|(c, _)| c)
            .collect();
        let mean = px.iter().copied().sum::<glam::Vec3>() / px.len() as f32;
        let worst = (px.iter()).map(|c| ((*c - mean).abs() / mean.max_element()).max_element());
        (mean, worst.fold(0.0f32, f32::max), px.len())
    };
    for (node, factor) in [
        ("Orange Object", [1.0, 0.2176376, 0.0]),
        ("Blue Object", [0.0, 0.2176376, 1.0]),
    ] {
        let (mean, worst, n) = spread(&scene, node);
        let ratio = mean / mean.max_element();
        eprintln!("{node}: {n} px, mean {mean}, ratios {ratio}, worst deviation {worst:.2e}");
        assert!(n > 500, "{node}: {n} pixels");
        // Measured 2026-12-03: 0 (every covered pixel the same fp16 value).
        assert!(worst < 0.01, "{node}: worst deviation {worst}");
        assert!(
            (ratio - glam::Vec3::from(factor)).abs().max_element() < 1e-3,
            "{node}: {ratio}"
        );
        let mut lit = scene.clone();
        for m in &mut lit.pbr.materials {
            m.unlit = false;
        }
        let (_, lit_worst, _) = spread(&lit, node);
        assert!(lit_worst > 0.1, "{node} lit: {lit_worst}");
    }
}

/// Per sphere of SpecularTest, linear HDR: per-channel medians of its
/// centre (n·v > 0.8), its rim (n·v < 0.4) and all of it (medians: the
/// sun's highlight on roughness 0 is a few pixels of huge radiance, which
/// land on pixel centres differently from sphere to sphere), and the mean
/// of all of it. Its pixels: each pixel's ray cast at the sphere (centre
/// and radius from the scene), kept where the G-buffer normal agrees.
#[derive(Clone, Copy, Debug, Default)]
struct SphereStats {
    centre: glam::Vec3,
    rim: glam::Vec3,
    median: glam::Vec3,
    mean: glam::Vec3,
}

fn median3(px: &mut [glam::Vec3]) -> glam::Vec3 {
    let mut m = [0.0f32; 3];
    for (c, m) in m.iter_mut().enumerate() {
        px.sort_by(|a, b| a[c].total_cmp(&b[c]));
        *m = px[px.len() / 2][c];
    }
    glam::Vec3::from(m)
}

/// SpecularTest's reading rules (its README): row 1's leftmost sphere
/// (specularFactor 0) is perfectly black; row 2 (specularTexture) matches
/// row 1 and is not purple (the texture's RGB must not be read); the
/// colour rows change F0 only, so the yellow spheres' centres lose their
/// blue while their rims stay as white as the white row's; colour factors
/// above 1 make row 7's last sphere a mirror (F0 clamped to 1).
#[test]
fn specular_factor_and_colour_follow_the_sample_rows() {
    use glam::Vec3;
    let scene = Scene::from_gltf(&common::gltf_sample("SpecularTest")).expect("model");
    let size = 448;
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    // Without aerial perspective, whose in-scattering would light even a
    // black sphere.
    let views = |scene: &Scene| {
        let mut r = common::renderer(scene);
        ["lighting", "normal"].map(|view| {
            let mut s = common::raw_settings(scene, (size, size), view);
            s.aa = himal::passes::aa::AaMode::None;
            s.aerial_extinction = 0.0;
            common::render_rgba(&mut r, &camera, &s)
        })
    };
    let frame = views(&scene);
    // The colour rows against themselves with the colour factor 1: each
    // sphere sees the same sky (which varies from row to row).
    let mut uncoloured = scene.clone();
    for m in &mut uncoloured.pbr.materials {
        m.specular_color = Vec3::ONE;
    }
    let uncoloured = views(&uncoloured);
    let object = |name: &str| {
        let o = (scene.objects.iter().find(|o| o.name == name))
            .unwrap_or_else(|| panic!("node {name}"));
        scene.meshes[o.mesh].bounds.transform(&o.transform)
    };
    // Row 1's spheres give the columns' x and the radius; the texture
    // rows are one mesh of five spheres at those columns.
    let columns: Vec<(f32, f32)> = (1..=5)
        .map(|k| {
            let b = object(&format!("1.{k}_specularFactor"));
            (b.center().x, 0.5 * b.extent().x)
        })
        .collect();
    let radius = columns[0].1;
    let row = |name: &str| -> Vec<Vec3> {
        if let Some(k) = name.find('#') {
            (1..=5)
                .map(|i| object(&format!("{}{i}{}", &name[..k], &name[k + 1..])).center())
                .collect()
        } else {
            let b = object(name);
            let (lo, hi) = (b.min.x, b.max.x);
            assert!(
                (lo - (columns[0].0 - radius)).abs() < 1e-3
                    && (hi - (columns[4].0 + radius)).abs() < 1e-3,
                "{name} spans the five columns: {lo}..{hi}"
            );
            columns
                .iter()
                .map(|&(x, _)| Vec3::new(x, b.center().y, b.center().z))
                .collect()
        }
    };
    let means = |[hdr, normal]: &[Vec<[f32; 4]>; 2], centres: &[Vec3]| -> Vec<SphereStats> {
        let mut regions = vec![[Vec::new(), Vec::new(), Vec::new()]; centres.len()];
        for y in 0..size {
            for x in 0..size {
                let (o, d) = common::pixel_ray_from(&camera, (size, size), x, y);
                for (k, c) in centres.iter().enumerate() {
                    // Ray-sphere: the nearer root of |o + t d - c| = radius.
                    let oc = o - *c;
                    let b = oc.dot(d);
                    let disc = b * b - (oc.length_squared() - radius * radius);
                    if disc <= 0.0 {
                        continue;
                    }
                    let p = o + d * (-b - disc.sqrt());
                    // The tessellated sphere's silhouette lies inside the
                    // analytic one: pixels there show what is behind.
                    let i = (y * size + x) as usize;
                    let n = Vec3::new(normal[i][0], normal[i][1], normal[i][2]);
                    if n.dot((p - *c) / radius) < 0.9 {
                        continue;
                    }
                    let n_o_v = n.normalize().dot(-d);
                    let px = Vec3::new(hdr[i][0], hdr[i][1], hdr[i][2]);
                    regions[k][0].push(px);
                    if n_o_v > 0.8 {
                        regions[k][1].push(px);
                    } else if n_o_v < 0.4 {
                        regions[k][2].push(px);
                    }
                }
            }
        }
        (regions.iter_mut())
            .map(|[all, centre, rim]| {
                let counts = (all.len(), centre.len(), rim.len());
                assert!(
                    counts.0 > 400 && counts.1 > 100 && counts.2 > 40,
                    "sphere coverage {counts:?}"
                );
                SphereStats {
                    mean: all.iter().sum::<Vec3>() / all.len() as f32,
                    median: median3(all),
                    centre: median3(centre),
                    rim: median3(rim),
                }
            })
            .collect()
    };
    let lum = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let factor = means(&frame, &row("1.#_specularFactor"));
    let texture = means(&frame, &row("2_specularTexture"));
    let white = means(&frame, &row("3.#_whiteColorFactor"));
    let white_texture = means(&frame, &row("4_whiteColorTexture"));
    let yellow = means(&frame, &row("5.#_yellowColorFactor"));
    let yellow_texture = means(&frame, &row("6_yellowColorTexture"));
    let hdr_row = means(&frame, &row("7.#_HDR_colorFactor"));
    let report = |name: &str, row: &[SphereStats]| {
        let l: Vec<String> = row
            .iter()
            .map(|m| format!("{:.4}", lum(m.median)))
            .collect();
        eprintln!("{name}: median luminance {}", l.join(" "));
    };
    for (name, r) in [
        ("row 1 specularFactor", &factor),
        ("row 2 specularTexture", &texture),
        ("row 3 white factor", &white),
        ("row 4 white texture", &white_texture),
        ("row 5 yellow factor", &yellow),
        ("row 6 yellow texture", &yellow_texture),
        ("row 7 HDR factor", &hdr_row),
    ] {
        report(name, r);
    }
    let bright = lum(factor[4].mean);
    // specularFactor 0: F0 = F90 = 0 on a black base, nothing reflects.
    // The deferred pass's F90 = 1 lobe less forward.layers' delta leaves
    // what their normals differ by (the G-buffer's packed frame against the
    // vertex normal), at the rim where Schlick's (1 - n.v)^5 is steep:
    // measured 2026-12-04 2.6e-3 of sphere 1.5 (ignoring the extension
    // leaves the sphere as bright as sphere 1.5).
    let black = lum(factor[0].mean).abs();
    eprintln!(
        "sphere 1.1: {:.2e} of sphere 1.5's {bright:.3}",
        black / bright
    );
    assert!(black < 5e-3 * bright, "sphere 1.1 is not black: {black}");
    for k in 1..5 {
        assert!(
            lum(factor[k].median) > 1.2 * lum(factor[k - 1].median),
            "row 1 rises at {k}"
        );
    }
    // Texture rows against factor rows: the texel steps (8-bit) and sphere
    // UVs make a few per cent (measured 2026-12-04: within 5 %).
    let same = |a: &[SphereStats], b: &[SphereStats], what: &str| {
        for k in 0..5 {
            let (x, y) = (a[k].median, b[k].median);
            let worst = (x - y).abs().max_element();
            assert!(
                worst <= 0.08 * x.max_element().max(y.max_element()) + 1e-3 * bright,
                "{what} sphere {}: {x} vs {y}",
                k + 1
            );
        }
    };
    same(&factor, &texture, "row 2 against row 1");
    same(&white, &white_texture, "row 4 against row 3");
    same(&yellow, &yellow_texture, "row 6 against row 5");
    // Yellow against the same sphere uncoloured: the centre's F0 loses its
    // blue (F0 (0.04, 0.04, 0)), the rim's F90 stays white.
    let uncoloured_yellow = means(&uncoloured, &row("5.#_yellowColorFactor"));
    let (y5, w5) = (yellow[4], uncoloured_yellow[4]);
    let centre_blue = y5.centre.z / w5.centre.z;
    let rim_blue = y5.rim.z / w5.rim.z;
    let red = y5.centre.x / w5.centre.x;
    eprintln!(
        "sphere 5.5 / uncoloured: centre blue {centre_blue:.3}, rim blue {rim_blue:.3}, centre red {red:.3}"
    );
    // Measured 2026-12-04: centre blue 0.000, rim blue ~0.7 (Schlick at
    // n.v 0..0.4 keeps F0's share), centre red 1.02 (the G-buffer's grey
    // F0 is 10/255, the layers' F0 0.04).
    assert!(
        centre_blue < 0.05,
        "yellow centres keep blue: {centre_blue}"
    );
    assert!(rim_blue > 0.5, "yellow rims lose white: {rim_blue}");
    assert!((red - 1.0).abs() < 0.05, "yellow centres' red: {red}");
    // Colour 0 keeps F90: sphere 3.1's rim nearly as bright as uncoloured,
    // its centre dark.
    let uncoloured_white = means(&uncoloured, &row("3.#_whiteColorFactor"));
    let (centre, rim) = (
        lum(white[0].centre) / lum(uncoloured_white[0].centre),
        lum(white[0].rim) / lum(uncoloured_white[0].rim),
    );
    eprintln!("sphere 3.1 / uncoloured: centre {centre:.3}, rim {rim:.3}");
    assert!(centre < 0.05 && rim > 0.5, "sphere 3.1: {centre} {rim}");
    // Colour 25: F0 = min(0.04 x 25, 1) = 1, a mirror: its centre reflects
    // about 1 / 0.04 = 25 times what it does uncoloured.
    let uncoloured_hdr = means(&uncoloured, &row("7.#_HDR_colorFactor"));
    let mirror = lum(hdr_row[4].centre) / lum(uncoloured_hdr[4].centre);
    eprintln!("sphere 7.5 / uncoloured, centre: {mirror:.1}");
    assert!(mirror > 15.0, "sphere 7.5 is no mirror: {mirror}");
    // Not purple: row 2's colour is row 1's. The rows see a slightly
    // different sky (measured 2026-12-04: chroma within 0.053); the purple
    // RGB would put F0's green near 0.
    let chroma = |c: Vec3| c / c.max_element().max(1e-9);
    for k in 1..5 {
        let d = (chroma(texture[k].median) - chroma(factor[k].median))
            .abs()
            .max_element();
        eprintln!("row 2 sphere {}: chroma off row 1's by {d:.3}", k + 1);
        assert!(d < 0.15, "row 2 sphere {} tinted: {d}", k + 1);
    }
}

/// Pearson correlation of `a` and `b`.
fn correlation(a: &[f32], b: &[f32]) -> f32 {
    let n = a.len() as f32;
    let (ma, mb) = (a.iter().sum::<f32>() / n, b.iter().sum::<f32>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt().max(1e-12)
}

/// TransmissionTest: the transmissive spheres show the checkered backdrop
/// behind them. Straight on, each sphere's inner disc (0.8 of its radius)
/// is compared pixel by pixel with the backdrop rendered alone: the smooth
/// thin-walled sphere samples the scene straight behind, so its luminance
/// follows the checks; with transmission off it does not; the rough
/// sphere's blurred sample follows them less. A KHR_materials_volume on
/// the smooth sphere (thickness its diameter, attenuation colour
/// (1, 0.25, 0.25) at that distance) turns its transmitted light red and
/// refracts (moves) the checks, and its depth is written.
#[test]
fn transmission_shows_what_is_behind() {
    use glam::Vec3;
    let scene = Scene::from_gltf(&common::gltf_sample("TransmissionTest")).expect("model");
    let size = 384;
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let render = |scene: &Scene, view: &str| {
        let mut r = common::renderer(scene);
        let mut s = common::raw_settings(scene, (size, size), view);
        s.aa = himal::passes::aa::AaMode::None;
        s.aerial_extinction = 0.0;
        common::render_rgba(&mut r, &camera, &s)
    };
    let sphere = |name: &str| {
        let o = (scene.objects.iter().find(|o| o.name == name))
            .unwrap_or_else(|| panic!("node {name}"));
        let b = scene.meshes[o.mesh].bounds.transform(&o.transform);
        (b.center(), 0.5 * b.extent().x)
    };
    let disc = |name: &str| -> Vec<usize> {
        let (c, radius) = sphere(name);
        let r = 0.8 * radius;
        let mut px = Vec::new();
        for y in 0..size {
            for x in 0..size {
                let (o, d) = common::pixel_ray_from(&camera, (size, size), x, y);
                let oc = o - c;
                let b = oc.dot(d);
                if b * b - (oc.length_squared() - r * r) > 0.0 {
                    px.push((y * size + x) as usize);
                }
            }
        }
        assert!(px.len() > 200, "{name}: {} pixels", px.len());
        px
    };
    let lum = |img: &[[f32; 4]], px: &[usize]| -> Vec<f32> {
        (px.iter())
            .map(|&i| 0.2126 * img[i][0] + 0.7152 * img[i][1] + 0.0722 * img[i][2])
            .collect()
    };
    let mut backdrop = scene.clone();
    backdrop.objects.retain(|o| o.name == "Cloth Backdrop 01");
    let behind = render(&backdrop, "lighting");
    let frame = render(&scene, "lighting");
    let mut opaque = scene.clone();
    for m in &mut opaque.pbr.materials {
        m.transmission = 0.0;
    }
    let opaque = render(&opaque, "lighting");
    let (smooth, rough) = (disc("YellowTrans"), disc("YellowTransRough"));
    let corr = |img: &[[f32; 4]], px: &[usize]| correlation(&lum(img, px), &lum(&behind, px));
    let (c_smooth, c_opaque, c_rough) = (
        corr(&frame, &smooth),
        corr(&opaque, &smooth),
        corr(&frame, &rough),
    );
    eprintln!(
        "backdrop correlation: smooth {c_smooth:.3}, transmission off {c_opaque:.3}, rough {c_rough:.3}"
    );
    // measured smooth 0.995, off 0.027, rough 0.386 on lavapipe on 2026-12-04.
    assert!(
        c_smooth > 0.9,
        "the smooth sphere shows the checks: {c_smooth}"
    );
    assert!(c_opaque.abs() < 0.5, "opaque, it does not: {c_opaque}");
    assert!(
        c_rough < c_smooth - 0.05,
        "the rough one blurs them: {c_rough}"
    );

    // KHR_materials_volume on the smooth sphere.
    let (_, radius) = sphere("YellowTrans");
    let mut volume = scene.clone();
    let mat = (volume
        .pbr
        .materials
        .iter_mut()
        .find(|m| m.name == "YellowTrans"))
    .expect("material");
    mat.thickness = 2.0 * radius;
    mat.attenuation_distance = 2.0 * radius;
    mat.attenuation_color = Vec3::new(1.0, 0.25, 0.25);
    let thick = render(&volume, "lighting");
    let mean = |img: &[[f32; 4]]| {
        (smooth.iter())
            .map(|&i| Vec3::new(img[i][0], img[i][1], img[i][2]))
            .sum::<Vec3>()
            / smooth.len() as f32
    };
    let (thin_rgb, thick_rgb) = (mean(&frame), mean(&thick));
    let c_thick = corr(&thick, &smooth);
    eprintln!(
        "volume: mean g/r thin {:.3}, thick {:.3}; backdrop correlation {c_thick:.3}",
        thin_rgb.y / thin_rgb.x,
        thick_rgb.y / thick_rgb.x
    );
    // measured g/r thin 1.103, thick 0.352; correlation 0.365 (2026-12-04).
    assert!(
        thick_rgb.y / thick_rgb.x < 0.7 * thin_rgb.y / thin_rgb.x,
        "absorption reddens: {thin_rgb} -> {thick_rgb}"
    );
    assert!(
        c_thick < c_smooth - 0.05,
        "refraction moves the checks: {c_thick}"
    );
    let depth = render(&scene, "depth");
    let covered = smooth.iter().filter(|&&i| depth[i][0] > 0.0).count();
    let behind_depth = render(&backdrop, "depth");
    let nearer = (smooth.iter())
        .filter(|&&i| depth[i][0] > behind_depth[i][0])
        .count();
    assert!(
        covered == smooth.len() && nearer == smooth.len(),
        "the sphere's depth is written: {nearer} of {} nearer than the backdrop",
        smooth.len()
    );
}
