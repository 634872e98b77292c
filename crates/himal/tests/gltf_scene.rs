//! Scene files that place glTF models (`[[gltf]]`, scene/gltf/placement.rs).

mod common;

use std::path::Path;

use glam::{Quat, Vec3};
use himal::scene::Scene;

const ASSETS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/assets");

fn scene(text: &str) -> Result<Scene, String> {
    Scene::from_toml_str(text, "placed.toml", Path::new(ASSETS)).map_err(|e| e.to_string())
}

const TWO_MODELS: &str = r#"
[[material]]
name = "stone"
albedo = [0.5, 0.5, 0.5]

[[object]]
name = "plinth"
primitive = "box"
material = "stone"
size = [2, 1, 2]

[[gltf]]
file = "gltf/DamagedHelmet/glTF/DamagedHelmet.gltf"
name = "helmet"
translation = [10, 2, -3]
rotation = 90
scale = 2

[[gltf]]
file = "gltf/TextureSettingsTest/glTF/TextureSettingsTest.gltf"
rotation = [0, 0, 0, 1]
"#;

#[test]
fn gltf_entries_are_placed_and_renumbered() {
    let s = scene(TWO_MODELS).unwrap_or_else(|e| panic!("{e}"));
    // 1 plinth + 1 helmet node + 10 TextureSettingsTest nodes (counts of gltf_load.rs).
    assert_eq!(s.objects.len(), 12);
    let helmet = s
        .objects
        .iter()
        .find(|o| o.name.starts_with("helmet/"))
        .expect("helmet object");
    let alone = himal::scene::gltf::load(
        &Path::new(ASSETS).join("gltf/DamagedHelmet/glTF/DamagedHelmet.gltf"),
    )
    .expect("helmet");
    let expected = glam::Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_rotation_y(90f32.to_radians()),
        Vec3::new(10.0, 2.0, -3.0),
    ) * alone.objects[0].transform;
    assert!(
        helmet.transform.abs_diff_eq(expected, 1e-5),
        "{:?}",
        helmet.transform
    );
    assert!(s.objects.iter().any(|o| o.name.starts_with("gltf1/")));
    // Materials 0 (helmet) + 10; textures 5 + 9; images 5 + 3.
    assert_eq!(
        (
            s.pbr.materials.len(),
            s.pbr.textures.len(),
            s.pbr.images.len()
        ),
        (11, 14, 8)
    );
    // Every textured mesh exists, every material's textures and images resolve,
    // and the second model's textures point at its own images.
    for (mesh, mat) in &s.pbr.mesh_material {
        assert!(*mesh < s.meshes.len() && *mat < s.pbr.materials.len());
    }
    assert_eq!(
        s.pbr.material_of(s.objects[0].mesh),
        None,
        "plinth untextured"
    );
    let second: Vec<_> = s.pbr.materials[1..]
        .iter()
        .filter_map(|m| m.base_color_texture)
        .collect();
    assert!(!second.is_empty());
    for t in second {
        assert!(t.texture >= 5, "texture {} not shifted", t.texture);
        assert!(s.pbr.textures[t.texture].image >= 5);
    }
    assert!(s.bounds.contains_point(Vec3::new(10.0, 2.0, -3.0), 0.0));
}

#[test]
fn bad_gltf_entries_name_the_line_and_the_problem() {
    let cases = [
        (
            "[[gltf]]\nfile = \"gltf/missing.gltf\"\n",
            "placed.toml:2:",
            "missing.gltf",
        ),
        (
            "[[gltf]]\nfile = \"gltf/DamagedHelmet/glTF/DamagedHelmet.gltf\"\nrotation = [0, 0, 0, 0]\n",
            "placed.toml:3:",
            "non-zero quaternion",
        ),
        (
            "[[gltf]]\nfile = \"gltf/DamagedHelmet/glTF/DamagedHelmet.gltf\"\nscale = -1\n",
            "placed.toml:3:",
            "must lie in [0.0001, 10000]",
        ),
        (
            "[[gltf]]\nfile = \"gltf/DamagedHelmet/glTF/DamagedHelmet.gltf\"\nspin = 3\n",
            "placed.toml:3:",
            "spin",
        ),
        (
            "[[gltf]]\nfile = \"builtin:Nope.glb\"\n",
            "placed.toml:2:",
            "built in: DamagedHelmet.glb",
        ),
        // A file that exists but is not glTF: the loader's message comes through.
        (
            "[[gltf]]\nfile = \"README.md\"\n",
            "placed.toml:2:",
            "not valid glTF",
        ),
    ];
    for (text, place, problem) in cases {
        let e = scene(text)
            .err()
            .unwrap_or_else(|| panic!("accepted:\n{text}"));
        assert!(
            e.contains(place) && e.contains(problem),
            "{e}\n(wanted {place} and {problem})"
        );
    }
}

#[test]
fn optional_missing_gltf_is_skipped() {
    let s = scene("[[gltf]]\nfile = \"gltf/missing.gltf\"\noptional = true\n")
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(s.objects.is_empty() && s.pbr.materials.is_empty());
}

#[test]
fn rest_on_puts_the_model_on_its_support() {
    let text = r#"
[[material]]
name = "stone"
albedo = [0.5, 0.5, 0.5]

[[object]]
name = "plinth"
primitive = "box"
material = "stone"
size = [2, 1, 2]
position = [0, 3, 0]

[[gltf]]
file = "gltf/DamagedHelmet/glTF/DamagedHelmet.gltf"
translation = [0, 0.25, 0]
scale = 0.5
rest_on = "plinth"
"#;
    let s = scene(text).unwrap_or_else(|e| panic!("{e}"));
    let bottom = s.objects[1..]
        .iter()
        .map(|o| s.meshes[o.mesh].bounds.transform(&o.transform).min.y)
        .fold(f32::INFINITY, f32::min);
    // plinth top 3.5, plus translation.y 0.25
    assert!((bottom - 3.75).abs() < 1e-4, "bottom {bottom}");
    let e = scene(&text.replace("rest_on = \"plinth\"", "rest_on = \"nothing\""))
        .err()
        .unwrap_or_default();
    assert!(
        e.contains("placed.toml:17:") && e.contains("\"nothing\""),
        "{e}"
    );
}

/// The helmet lay in ../shared: a user's clone rendered an empty plinth.
/// It is built in now, and the demo names no file outside the library.
#[test]
fn the_demo_world_shows_the_helmet() {
    let text = include_str!("../../../scenes/demo.toml");
    for line in text.lines().filter(|l| l.trim_start().starts_with("file")) {
        assert!(line.contains("\"builtin:"), "the demo reads a file: {line}");
    }
    let s = Scene::demo().unwrap_or_else(|e| panic!("{e}"));
    let helmet: Vec<_> = s
        .objects
        .iter()
        .filter(|o| o.name.starts_with("helmet/"))
        .collect();
    let plinth = s
        .objects
        .iter()
        .find(|o| o.name == "helmet_plinth")
        .expect("plinth");
    let top = s.meshes[plinth.mesh]
        .bounds
        .transform(&plinth.transform)
        .max
        .y;
    let b = s.meshes[helmet[0].mesh]
        .bounds
        .transform(&helmet[0].transform);
    eprintln!("helmet bounds {b:?}, plinth top {top}");
    assert_eq!(helmet.len(), 1);
    assert!((b.min.y - top).abs() < 1e-3, "{} vs {top}", b.min.y);
    let camera = s.camera("helmet").expect("helmet camera");
    let to_helmet = (b.center() - camera.position).normalize();
    assert!(to_helmet.dot(camera.forward) > 0.99);
}

/// A node that mirrors its mesh (negative determinant) turns the mesh's
/// triangles clockwise: the mirrored cube must look like the plain one
/// (same geometry), not show its inside through back-face culling, and a
/// double-sided mirrored cube must not be lit with flipped normals.
/// Before the fix: the depth differed by up to 0.14 (its far faces drawn)
/// and the lighting by 24 (of ~26).
#[test]
fn mirrored_nodes_keep_their_front_faces_and_normals() {
    let views = |node: &str, double_sided: bool| {
        let material = format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[0.8,0.8,0.8,1],"metallicFactor":0,"roughnessFactor":0.6}},"doubleSided":{double_sided}}}"#
        );
        let name = format!("mirror-{}-{double_sided}", node.len());
        let path = common::cube_gltf(&name, node, &material);
        let scene = Scene::from_gltf(&path).unwrap_or_else(|e| panic!("{e}"));
        let camera = scene.camera("default").expect("camera").clone();
        common::raw_views(&scene, &camera, 64, &["lighting", "depth", "normal"])
    };
    for double_sided in [false, true] {
        let plain = views(r#""scale":[1,1,1]"#, double_sided);
        for mirror in [
            r#""scale":[-1,1,1]"#,
            r#""scale":[1,1,-1],"rotation":[0,1,0,0]"#,
        ] {
            let mirrored = views(mirror, double_sided);
            let covered = plain[1].iter().filter(|p| p[0] > 0.0).count();
            // Largest per-channel difference, relative to `scale(a)`.
            let worst = |k: usize, scale: fn(f32) -> f32| {
                (plain[k].iter().zip(&mirrored[k]))
                    .flat_map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs() / scale(a[c])))
                    .fold(0.0, f32::max)
            };
            let lighting = worst(0, |a| a.abs().max(1e-3));
            let (depth, normal) = (worst(1, |_| 1.0), worst(2, |_| 1.0));
            eprintln!(
                "{mirror} double-sided {double_sided}: {covered} cube pixels, max relative lighting {lighting:.2e}, depth {depth:.2e}, normal {normal:.2e}"
            );
            assert!(covered > 500, "the cube covers {covered} pixels");
            // Same triangles in another order: measured 3e-8.
            assert!(depth < 1e-4, "{mirror}: depth differs by {depth}");
            // The G-buffer's quantised tangent frame errs mirrored too:
            // normals measured 0.012 apart, lighting 0.8 % (a flipped normal
            // is 2 apart and turns a lit face dark).
            assert!(normal < 0.03, "{mirror}: normals differ by {normal}");
            assert!(lighting < 0.03, "{mirror}: lighting differs by {lighting}");
        }
    }
}

/// `extensionsRequired`: an extension himal implements loads (issue #22:
/// the gltf crate's own list refused `KHR_materials_anisotropy`); one it
/// does not is an error naming the file and the extension.
#[test]
fn required_extensions_load_when_implemented_and_are_named_when_not() {
    let with = |name: &str, extensions: &str| {
        let path = common::cube_gltf(name, "", r#"{"pbrMetallicRoughness":{}}"#);
        let json = std::fs::read_to_string(&path).expect("read");
        let json = json.replacen(
            '{',
            &format!(r#"{{"extensionsUsed":{extensions},"extensionsRequired":{extensions},"#),
            1,
        );
        std::fs::write(&path, json).expect("write");
        (
            path.clone(),
            Scene::from_gltf(&path).map_err(|e| e.to_string()),
        )
    };
    for ours in [
        r#"["KHR_materials_anisotropy"]"#,
        r#"["KHR_lights_punctual","KHR_materials_emissive_strength"]"#,
    ] {
        let (path, loaded) = with("required-ours", ours);
        let scene = loaded.unwrap_or_else(|e| panic!("{}: {ours}: {e}", path.display()));
        assert_eq!(scene.objects.len(), 1);
    }
    let (path, loaded) = with("required-draco", r#"["KHR_draco_mesh_compression"]"#);
    let e = loaded.expect_err("an unimplemented required extension");
    eprintln!("{e}");
    let file = path.file_name().and_then(|f| f.to_str()).expect("name");
    assert!(
        e.contains(file) && e.contains("KHR_draco_mesh_compression"),
        "{e}"
    );
}

/// `KHR_lights_punctual` directional lights were dropped: a model lit by
/// one rendered under the default afternoon sun. The first directional
/// light now stands in for the sun: the sky light the renderer lights with
/// points towards it and carries its illuminance (lux to klux).
#[test]
fn a_directional_light_becomes_the_sun() {
    let q = Quat::from_rotation_y(0.7) * Quat::from_rotation_x(-1.1);
    let shines = q * Vec3::NEG_Z;
    let node = format!(
        r#""children":[1]}},{{"rotation":[{},{},{},{}],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}"#,
        q.x, q.y, q.z, q.w
    );
    let path = common::cube_gltf("directional", &node, r#"{"pbrMetallicRoughness":{}}"#);
    let json = std::fs::read_to_string(&path).expect("read");
    let json = json.replacen(
        '{',
        r#"{"extensionsUsed":["KHR_lights_punctual"],"extensions":{"KHR_lights_punctual":{"lights":[{"type":"directional","color":[1.0,0.5,0.25],"intensity":4000.0,"name":"key"}]}},"#,
        1,
    );
    std::fs::write(&path, json).expect("write");
    let scene = Scene::from_gltf(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let sun = scene.sun.light.expect("the directional light is the sun");
    assert!(
        sun.to_light.abs_diff_eq(-shines, 1e-5),
        "{:?} vs {:?}",
        sun.to_light,
        -shines
    );
    assert!(
        sun.illuminance_klux
            .abs_diff_eq(Vec3::new(4.0, 2.0, 1.0), 1e-5)
    );
    // The renderer lights with it (and draws the sky for that direction).
    let mut r = common::renderer(&scene);
    let camera = scene.camera("default").expect("camera").clone();
    let settings = himal::FrameSettings::new(32, 32, scene.sun.clone());
    r.render(&camera, &settings).expect("frame");
    let light = r.sky_light().expect("sky light after a frame");
    assert!(light.sun_direction.abs_diff_eq(sun.to_light, 1e-5));
    assert_eq!(light.sun_illuminance, sun.illuminance_klux);
    assert!(light.sky.sun_direction().abs_diff_eq(sun.to_light, 1e-5));
}

/// `--gltf builtin:DamagedHelmet.glb` (README) opens the built-in model.
#[test]
fn built_in_models_open_by_name() {
    let s = Scene::from_gltf(Path::new("builtin:DamagedHelmet.glb")).expect("built in");
    assert_eq!((s.objects.len(), s.pbr.images.len()), (1, 5));
    let e = Scene::from_gltf(Path::new("builtin:Nope.glb"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("builtin:Nope.glb") && e.contains("DamagedHelmet.glb"),
        "{e}"
    );
}

/// `--orbit YAW,PITCH[,DISTANCE]`: the camera sits on the orbit sphere at
/// those angles, looks at the bounds' centre, and by default frames the
/// bounding sphere (distance sin(fov/2) = 1.1 r); the front framing camera
/// is the orbit at yaw 0, pitch atan(1/4).
#[test]
fn orbit_cameras_sit_where_their_angles_say() {
    use himal::scene::Aabb;
    use himal::scene::gltf::{framing_camera, orbit_camera};
    let bounds = Aabb {
        min: Vec3::new(-1.0, 0.0, -2.0),
        max: Vec3::new(3.0, 2.0, 0.0),
    };
    let (centre, r) = (bounds.center(), bounds.extent().length() * 0.5);
    let side = orbit_camera(&bounds, 90.0, 0.0, Some(10.0), 30.0);
    assert!(
        side.position.abs_diff_eq(centre + Vec3::X * 10.0, 1e-4),
        "{}",
        side.position
    );
    assert!(side.forward.abs_diff_eq(Vec3::NEG_X, 1e-5));
    let above = orbit_camera(&bounds, -30.0, 45.0, None, 40.0);
    let to = above.position - centre;
    assert!((to.length() * 20f32.to_radians().sin() - 1.1 * r).abs() < 1e-3);
    assert!((to.y / to.length() - 45f32.to_radians().sin()).abs() < 1e-5);
    assert!(to.x < 0.0 && to.z > 0.0, "yaw -30: front-left, {to}");
    let front = framing_camera(&bounds, 40.0);
    let dir = (front.position - centre).normalize();
    assert!(
        dir.abs_diff_eq(Vec3::new(0.0, 0.25, 1.0).normalize(), 1e-5),
        "{dir}"
    );
}

/// EXT_mesh_gpu_instancing was ignored: SimpleInstancing showed one cube
/// instead of 125. Each instance is now an object of the one mesh with the
/// instance's T * R * S (read independently here from the file's
/// accessors), and the renderer draws them instanced.
#[test]
fn gpu_instancing_nodes_draw_every_instance_instanced() {
    let path = common::gltf_sample("SimpleInstancing");
    let scene = Scene::from_gltf(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.objects.len(), 125);
    assert!(scene.objects.iter().all(|o| o.mesh == 0));
    // The accessors, read by hand: TRANSLATION 3, ROTATION 4, SCALE 5.
    let file = common::GltfFile::open(&path);
    let floats = |accessor: usize, i: usize, n: usize| file.element(accessor, i, n);
    for i in [0, 62, 124] {
        let (t, r, s) = (floats(3, i, 3), floats(4, i, 4), floats(5, i, 3));
        let expected = glam::Mat4::from_scale_rotation_translation(
            Vec3::from_slice(&s),
            Quat::from_slice(&r).normalize(),
            Vec3::from_slice(&t),
        );
        let o = &scene.objects[i];
        assert!(
            o.transform.abs_diff_eq(expected, 1e-5),
            "instance {i}: {:?} vs {expected:?}",
            o.transform
        );
    }
    let mut r = common::renderer(&scene);
    let camera = scene.camera("default").expect("camera").clone();
    let settings = himal::FrameSettings::new(64, 64, scene.sun.clone());
    let frame = r.render(&camera, &settings).expect("frame");
    // One mesh, 125 objects: instanced into a handful of draws (125 before,
    // one per textured object; measured 1), the same image as one draw per object.
    eprintln!("SimpleInstancing: {} G-buffer draws", frame.gbuffer_draws);
    assert!(
        frame.gbuffer_draws <= 4,
        "{} G-buffer draws",
        frame.gbuffer_draws
    );
    let mut each = settings.clone();
    each.instancing = false;
    let mut r2 = common::renderer(&scene);
    let one_by_one = r2.render(&camera, &each).expect("frame");
    assert_eq!(one_by_one.gbuffer_draws, 125);
    assert!(
        frame.image.bytes == one_by_one.image.bytes,
        "instanced and per-object images differ"
    );
}
