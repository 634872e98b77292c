//! glTF import: counts against the Khronos sample files, tangents, bad input.

mod common;

use glam::Vec3;
use himal::scene::gltf::{self, AlphaMode};

/// (model, file, meshes, primitives, materials, textures, images, objects),
/// counted from the JSON independently of the loader (materials: the
/// file's, plus glTF's default one where a primitive names none).
type Counts = (
    &'static str,
    &'static str,
    usize,
    usize,
    usize,
    usize,
    usize,
    usize,
);

const MODELS: [Counts; 9] = [
    (
        "AlphaBlendModeTest",
        "AlphaBlendModeTest.gltf",
        9,
        9,
        6,
        4,
        4,
        9,
    ),
    (
        "AnisotropyRotationTest",
        "AnisotropyRotationTest.gltf",
        6,
        6,
        6,
        7,
        6,
        11,
    ),
    (
        "AnisotropyStrengthTest",
        "AnisotropyStrengthTest.gltf",
        50,
        50,
        50,
        1,
        1,
        50,
    ),
    ("DamagedHelmet", "DamagedHelmet.gltf", 1, 1, 1, 5, 5, 1),
    (
        "MetalRoughSpheresNoTextures",
        "MetalRoughSpheresNoTextures.gltf",
        102,
        123,
        99,
        0,
        0,
        123,
    ),
    (
        "NormalTangentMirrorTest",
        "NormalTangentMirrorTest.gltf",
        1,
        1,
        1,
        3,
        3,
        1,
    ),
    (
        "NormalTangentTest",
        "NormalTangentTest.gltf",
        1,
        1,
        1,
        3,
        3,
        1,
    ),
    (
        "OrientationTest",
        "OrientationTest.gltf",
        13,
        13,
        7,
        0,
        0,
        13,
    ),
    (
        "TextureSettingsTest",
        "TextureSettingsTest.gltf",
        10,
        10,
        10,
        9,
        3,
        10,
    ),
];

#[test]
fn every_sample_model_loads_with_the_files_counts() {
    for (model, file, meshes, prims, mats, tex, imgs, objects) in MODELS {
        let a =
            gltf::load(&common::gltf_asset(model, file)).unwrap_or_else(|e| panic!("{model}: {e}"));
        let got = (
            a.gltf_meshes,
            a.gltf_primitives,
            a.pbr.materials.len(),
            a.pbr.textures.len(),
            a.pbr.images.len(),
            a.objects.len(),
        );
        assert_eq!(got, (meshes, prims, mats, tex, imgs, objects), "{model}");
        assert_eq!(a.meshes.len(), prims, "{model}: one mesh per primitive");
        assert_eq!(a.pbr.mesh_material.len(), prims, "{model}");
        // No sample model has KHR_lights_punctual or cameras.
        assert_eq!((a.lights.len(), a.cameras.len()), (0, 0), "{model}");
        for m in &a.meshes {
            assert!(
                m.indices.iter().all(|&i| (i as usize) < m.vertices.len()),
                "{model} {}",
                m.name
            );
            for v in &m.vertices {
                let t = Vec3::from_slice(&v.tangent[..3]);
                assert!(
                    t.is_finite() && v.tangent[3].abs() == 1.0,
                    "{model} {}: tangent {:?}",
                    m.name,
                    v.tangent
                );
            }
        }
        assert!(
            !a.bounds.is_empty() && a.bounds.min.is_finite() && a.bounds.max.is_finite(),
            "{model}"
        );
    }
}

#[test]
fn materials_map_metal_rough_alpha_and_anisotropy() {
    let a = gltf::load(&common::gltf_asset(
        "AlphaBlendModeTest",
        "AlphaBlendModeTest.gltf",
    ))
    .unwrap();
    let modes: Vec<AlphaMode> = a.pbr.materials.iter().map(|m| m.alpha_mode).collect();
    assert!(modes.contains(&AlphaMode::Blend) && modes.contains(&AlphaMode::Opaque));
    // The file's cut-offs: default 0.5 plus explicit 0.25 and 0.75.
    for cutoff in [0.25, 0.5, 0.75] {
        assert!(
            modes.contains(&AlphaMode::Mask(cutoff)),
            "{modes:?} lacks cut-off {cutoff}"
        );
    }
    let s = gltf::load(&common::gltf_asset(
        "AnisotropyStrengthTest",
        "AnisotropyStrengthTest.gltf",
    ))
    .unwrap();
    let strengths: Vec<f32> = s
        .pbr
        .materials
        .iter()
        .map(|m| m.anisotropy_strength)
        .collect();
    assert!(
        strengths.contains(&0.0) && strengths.contains(&1.0),
        "{strengths:?}"
    );
    let r = gltf::load(&common::gltf_asset(
        "AnisotropyRotationTest",
        "AnisotropyRotationTest.gltf",
    ))
    .unwrap();
    let rot: Vec<f32> = r
        .pbr
        .materials
        .iter()
        .map(|m| m.anisotropy_rotation)
        .collect();
    assert!(
        rot.iter()
            .any(|x| (x - std::f32::consts::FRAC_PI_6).abs() < 1e-6),
        "{rot:?}"
    );
    assert!(
        r.pbr
            .materials
            .iter()
            .filter(|m| m.anisotropy_texture.is_some())
            .count()
            >= 2
    );
    // Roughness 0.1 -> glossiness 0.9 (the inverse of M1's 1 - glossiness).
    assert!((r.pbr.materials[0].glossiness() - 0.9).abs() < 1e-6);
    let h = gltf::load(&common::gltf_asset("DamagedHelmet", "DamagedHelmet.gltf")).unwrap();
    let m = &h.pbr.materials[0];
    assert_eq!(m.texture_count(), 5);
    assert!(m.emissive.max_element() > 0.0);
    assert_eq!(m.vertex_surface()[1], gltf::GLTF_DIELECTRIC_F0);
}

#[test]
fn anisotropy_mapping_matches_the_extension_ratio() {
    assert_eq!(gltf::anisotropy_from_khr(0.0, 0.3), 0.0);
    for (s, alpha) in [(0.5f32, 0.01f32), (0.3, 0.2), (1.0, 0.5)] {
        let a = gltf::anisotropy_from_khr(s, alpha);
        let khr_ratio = (alpha + (1.0 - alpha) * s * s) / alpha;
        let himal_ratio = 1.0 / (1.0 - 0.9 * a);
        // Exact unless clamped at anisotropy 1 (ratio 10).
        assert!(
            (himal_ratio - khr_ratio.min(10.0)).abs() < 1e-3 * khr_ratio,
            "{s} {alpha}: {himal_ratio} vs {khr_ratio}"
        );
    }
}

/// MikkTSpace on the mirror test's geometry reproduces the tangents its
/// exporter supplied (same algorithm), including the mirrored half's sign.
#[test]
fn generated_tangents_match_the_supplied_ones() {
    let path = common::gltf_asset("NormalTangentMirrorTest", "NormalTangentMirrorTest.gltf");
    let text = std::fs::read_to_string(&path).unwrap();
    // The same file with TANGENT removed from the attributes.
    let stripped = text.replace("\"TANGENT\"", "\"_TANGENT\"");
    assert_ne!(stripped, text, "the file names TANGENT");
    let supplied = gltf::load(&path).unwrap();
    let generated = gltf::load_from_bytes(&path, stripped.as_bytes()).unwrap();
    let (s, g) = (&supplied.meshes[0], &generated.meshes[0]);
    assert!(
        s.vertices.iter().any(|v| v.tangent[3] < 0.0),
        "mirrored UVs have w = -1"
    );
    // Compare per position + normal + uv (welding may reorder).
    let key = |v: &himal::scene::Vertex| format!("{:?}{:?}{:?}", v.position, v.normal, v.uv);
    let map: std::collections::HashMap<String, [f32; 4]> =
        s.vertices.iter().map(|v| (key(v), v.tangent)).collect();
    let (mut agree, mut total) = (0, 0);
    for v in &g.vertices {
        if let Some(t) = map.get(&key(v)) {
            total += 1;
            let dot = Vec3::from_slice(&t[..3])
                .normalize()
                .dot(Vec3::from_slice(&v.tangent[..3]).normalize());
            if dot > 0.9 && t[3] == v.tangent[3] {
                agree += 1;
            }
        }
    }
    let share = agree as f32 / total.max(1) as f32;
    eprintln!("tangents agreeing: {agree} of {total}");
    // measured 2770 of 2770 (1.0) on 2026-11-22; threshold 0.95
    assert!(
        total > 100 && share > 0.95,
        "{agree} of {total} tangents agree"
    );
}

fn load_err(name: &str, bytes: &[u8]) -> String {
    let dir = std::env::temp_dir().join(format!("himal-gltf-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    let e = gltf::load(&path).expect_err(name).to_string();
    assert!(e.contains(name), "message does not name the file: {e}");
    e
}

#[test]
fn bad_input_is_an_error_naming_file_and_problem() {
    let orig = std::fs::read_to_string(common::gltf_asset(
        "OrientationTest",
        "OrientationTest.gltf",
    ))
    .unwrap();
    let bin = std::fs::read(common::gltf_asset("OrientationTest", "OrientationTest.bin")).unwrap();
    // Invalid JSON.
    let e = load_err("broken.gltf", &orig.as_bytes()[..orig.len() / 2]);
    assert!(e.contains("not valid glTF"), "{e}");
    // Missing .bin (the URI resolves beside the temporary file).
    let e = load_err("nobin.gltf", orig.as_bytes());
    assert!(e.contains("OrientationTest.bin"), "{e}");
    // A GLB: the same JSON with the BIN chunk; then truncated.
    let glb = common::glb(
        &orig.replace("\"uri\" : \"OrientationTest.bin\"", "\"name\" : \"bin\""),
        &bin,
    );
    let dir = std::env::temp_dir().join(format!("himal-gltf-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("ok.glb"), &glb).unwrap();
    let ok = gltf::load(&dir.join("ok.glb")).expect("well-formed GLB");
    assert_eq!(ok.objects.len(), 13);
    let e = load_err("truncated.glb", &glb[..glb.len() - 100]);
    assert!(e.contains("not valid glTF") || e.contains("bytes"), "{e}");
    // A short BIN chunk: the declared buffer length does not fit.
    let e = load_err(
        "short.glb",
        &common::glb(
            &orig.replace("\"uri\" : \"OrientationTest.bin\"", "\"name\" : \"bin\""),
            &bin[..bin.len() / 2],
        ),
    );
    assert!(e.contains("bytes"), "{e}");
    // A point primitive is left out and named, the rest of the file loads.
    let points = orig.replacen("\"material\"", "\"mode\" : 0, \"material\"", 1);
    std::fs::write(dir.join("OrientationTest.bin"), &bin).unwrap();
    std::fs::write(dir.join("points.gltf"), &points).unwrap();
    let a = gltf::load(&dir.join("points.gltf")).expect("points do not reject the file");
    assert_eq!((a.meshes.len(), a.objects.len()), (12, 12));
    assert!(
        a.warnings.len() == 1 && a.warnings[0].contains("(Points)"),
        "{:?}",
        a.warnings
    );
    // Non-finite transforms: 1e39 overflows f32 to infinity (JSON has no NaN).
    let nan = orig.replacen(
        "\"translation\" : [",
        "\"translation\" : [1e39, 0, 0], \"extras\" : [",
        1,
    );
    std::fs::write(dir.join("nan.gltf"), &nan).unwrap();
    let e = gltf::load(&dir.join("nan.gltf")).unwrap_err().to_string();
    assert!(e.contains("nan.gltf") && e.contains("non-finite"), "{e}");
    // Out-of-range accessor: the first accessor claims 100x its count.
    let text = orig.replacen("\"count\" : ", "\"count\" : 100", 1);
    std::fs::write(dir.join("range.gltf"), &text).unwrap();
    let e = gltf::load(&dir.join("range.gltf")).unwrap_err().to_string();
    assert!(e.contains("range.gltf") && e.contains("runs past"), "{e}");
}

/// Points and lines anywhere in a file rejected the whole file, and strips
/// and fans were refused. MeshPrimitiveModes holds one primitive of each
/// of the seven modes over the same hexagon: the three triangle modes load
/// as lists covering the hexagon with one winding, the four others are
/// named in one warning.
#[test]
fn triangle_strips_and_fans_load_and_points_and_lines_are_named() {
    let a = gltf::load(&common::gltf_sample("MeshPrimitiveModes")).expect("loads");
    assert_eq!((a.gltf_meshes, a.gltf_primitives), (7, 7));
    let names: Vec<&str> = a.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "mesh with TRIANGLES.0",
            "mesh with GL_TRIANGLE_STRIP.0",
            "mesh with GL_TRIANGLE_FAN.0"
        ]
    );
    assert_eq!(a.objects.len(), 3, "one node per drawn primitive");
    assert_eq!(a.pbr.mesh_material.len(), 3);
    let warning = a.warnings.join("\n");
    for mode in [
        "POINTS.0 (Points)",
        "LINES.0 (Lines)",
        "LINE_LOOP.0 (LineLoop)",
    ] {
        assert!(warning.contains(mode), "{mode} not named in: {warning}");
    }
    assert!(warning.contains("4 point or line"), "{warning}");
    // Signed area (z of the summed cross products) per mesh: the strip (4
    // triangles, vertex 0 unused) and the fan (6) cover the same hexagon as
    // the list (6), each triangle wound the same way.
    let hexagon = |m: &himal::scene::Mesh| {
        let p = |i: u32| Vec3::from(m.vertices[i as usize].position);
        let z: Vec<f32> = (m.indices.chunks(3))
            .map(|t| 0.5 * (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).z)
            .collect();
        (z.len(), z.iter().sum::<f32>(), z.iter().all(|&z| z > 0.0))
    };
    let list = hexagon(&a.meshes[0]);
    assert_eq!((list.0, list.2), (6, true), "{list:?}");
    for (m, triangles) in [(&a.meshes[1], 4), (&a.meshes[2], 6)] {
        let (n, area, same_winding) = hexagon(m);
        assert_eq!(n, triangles, "{}", m.name);
        assert!(
            same_winding,
            "{}: a triangle is wound the other way",
            m.name
        );
        assert!(
            (area - list.1).abs() < 1e-4,
            "{}: area {area} vs {}",
            m.name,
            list.1
        );
    }
}

/// Morph targets were ignored: SimpleMorph drew its base shape. The mesh's
/// default weights (0.5, 0.5) now morph the positions: P0 + 0.5 dP0 +
/// 0.5 dP1, read here from the file's accessors by hand. (SimpleMorph's
/// clip animates the weights, so its drawn mesh starts at the clip's first
/// key; the rest pose, `--animation none`, is the defaults' shape.)
#[test]
fn morph_targets_apply_the_default_weights() {
    let path = common::gltf_sample("SimpleMorph");
    let a = gltf::load(&path).expect("loads");
    let file = common::GltfFile::open(&path);
    let vec3 = |accessor: usize, i: usize| file.vec3(accessor, i);
    let morph = (a.objects[0].motion.as_ref())
        .and_then(|m| m.animated.as_ref()?.morph.clone())
        .expect("animated weights keep the targets");
    assert_eq!(morph.defaults, [0.5, 0.5]);
    let mut m = a.meshes[0].clone();
    morph.apply(&mut m.vertices, &morph.defaults);
    let n = file.count(1);
    assert_eq!(m.vertices.len(), n);
    let mut moved = 0;
    for (i, v) in m.vertices.iter().enumerate() {
        let expected = vec3(1, i) + 0.5 * vec3(2, i) + 0.5 * vec3(3, i);
        assert!(
            Vec3::from(v.position).abs_diff_eq(expected, 1e-6),
            "vertex {i}"
        );
        moved += (expected != vec3(1, i)) as usize;
    }
    assert!(moved > 0, "the targets move some vertices");
}

/// Skins and animations are applied (tests/gltf_animation.rs), so the
/// skinned and animated samples load without a warning (they once named
/// them as not shown).
#[test]
fn skins_and_animations_load_without_warnings() {
    for model in [
        "Fox",
        "CesiumMan",
        "RiggedSimple",
        "SimpleSkin",
        "AnimatedCube",
    ] {
        let a = gltf::load(&common::gltf_sample(model)).expect("loads");
        assert!(a.warnings.is_empty(), "{model}: {:?}", a.warnings);
        assert!(
            a.objects.iter().any(|o| o.motion.is_some()),
            "{model} moves"
        );
    }
}

/// KHR_materials_variants: SheenChair's seat is "Mango Velvet" by default
/// (its primitive's material) and "Peacock Velvet" when asked for; an
/// unknown variant is an error listing the file's.
#[test]
fn material_variants_pick_the_mapped_materials() {
    use himal::budget::MemoryBudget;
    let path = common::gltf_sample("SheenChair");
    let material_of_seat = |variant: Option<&str>| {
        let a = gltf::load_with(&path, MemoryBudget::default(), variant).expect("loads");
        assert_eq!(a.variants, ["Mango Velvet", "Peacock Velvet"]);
        let m = a.pbr.material_of(0).expect("seat material");
        a.pbr.materials[m].name.clone()
    };
    assert_eq!(material_of_seat(None), "fabric Mystere Mango Velvet");
    assert_eq!(
        material_of_seat(Some("Mango Velvet")),
        "fabric Mystere Mango Velvet"
    );
    assert_eq!(
        material_of_seat(Some("Peacock Velvet")),
        "fabric Mystere Peacock Velvet"
    );
    let e = gltf::load_with(&path, MemoryBudget::default(), Some("Tartan"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("Tartan") && e.contains("Mango Velvet, Peacock Velvet"),
        "{e}"
    );
}

/// KHR_mesh_quantization: integer positions (SHORT), normals (normalized
/// BYTE) and UVs (normalized UNSIGNED_SHORT), dequantized by the node's
/// scale, load as the floats they stand for; without the extension named
/// the same accessors are an error naming the rule.
#[test]
fn quantized_attributes_load_as_floats() {
    let mut bin: Vec<u8> = Vec::new();
    let corners: [[i16; 3]; 4] = [[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]];
    for c in corners {
        // Vertex attributes stay 4-byte aligned: 6 bytes + 2 of padding.
        bin.extend(c.iter().flat_map(|v| v.to_le_bytes()));
        bin.extend([0, 0]);
    }
    for _ in 0..4 {
        bin.extend([0u8, 0, 127, 0]);
    }
    for uv in [[0u16, 0], [65535, 0], [65535, 65535], [0, 65535]] {
        bin.extend(uv.iter().flat_map(|v| v.to_le_bytes()));
    }
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|v| v.to_le_bytes()));
    let json = |used: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},{used}"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0,"scale":[0.5,0.5,0.5]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":32,"byteStride":8}},{{"buffer":0,"byteOffset":32,"byteLength":16,"byteStride":4}},
{{"buffer":0,"byteOffset":48,"byteLength":16,"byteStride":4}},{{"buffer":0,"byteOffset":64,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5122,"count":4,"type":"VEC3","min":[0,0,0],"max":[2,2,0]}},
{{"bufferView":1,"componentType":5120,"normalized":true,"count":4,"type":"VEC3"}},
{{"bufferView":2,"componentType":5123,"normalized":true,"count":4,"type":"VEC2"}},
{{"bufferView":3,"componentType":5123,"count":6,"type":"SCALAR"}}]}}"#,
            bin.len(),
            common::base64(&bin)
        )
    };
    let dir = std::env::temp_dir().join(format!("himal-quantized-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("quad.gltf");
    let used = r#""extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],"#;
    std::fs::write(&path, json(used)).expect("write");
    let a = gltf::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let m = &a.meshes[0];
    for (v, c) in m.vertices.iter().zip(corners) {
        assert_eq!(v.position, c.map(f32::from));
        assert_eq!(v.normal, [0.0, 0.0, 1.0]);
    }
    assert_eq!(m.vertices[2].uv, [1.0, 1.0]);
    // The node's scale dequantizes: the quad spans 0..1 in the world.
    assert!(
        a.bounds.max.abs_diff_eq(Vec3::new(1.0, 1.0, 0.0), 1e-6),
        "{:?}",
        a.bounds
    );
    std::fs::write(&path, json("")).expect("write");
    let e = gltf::load(&path).unwrap_err().to_string();
    assert!(e.contains("POSITION") && e.contains("VEC3 of FLOAT"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// KHR_materials_clearcoat and KHR_materials_sheen are read with their
/// factors and textures (ClearCoatTest, SheenChair), and MultiUVTest's
/// emissive slot keeps TEXCOORD_1; none of the three is warned about.
#[test]
fn clearcoat_sheen_and_second_uv_sets_load() {
    let a = gltf::load(&common::gltf_sample("ClearCoatTest")).expect("loads");
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let m = |name: &str| {
        (a.pbr.materials.iter().find(|m| m.name == name))
            .unwrap_or_else(|| panic!("material {name}"))
    };
    let simple = m("Simple_Coated");
    assert_eq!((simple.clearcoat, simple.clearcoat_roughness), (1.0, 0.03));
    assert!(simple.layered() && !m("Simple_Base").layered());
    assert!(m("Partial_Coated").clearcoat_texture.is_some());
    assert!(
        m("RoughVariations_Coated")
            .clearcoat_roughness_texture
            .is_some()
    );
    let coat_normal = m("CoatNorm_Coated");
    assert!(coat_normal.clearcoat_normal_texture.is_some() && coat_normal.normal_texture.is_none());
    assert_eq!(coat_normal.clearcoat_normal_scale, 1.0);

    let a = gltf::load(&common::gltf_sample("SheenChair")).expect("loads");
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let mango = (a.pbr.materials.iter())
        .find(|m| m.name == "fabric Mystere Mango Velvet")
        .expect("mango");
    assert_eq!(mango.sheen_color, Vec3::new(1.0, 0.329, 0.1));
    assert_eq!(mango.sheen_roughness, 0.8);

    let a = gltf::load(&common::gltf_sample("MultiUVTest")).expect("loads");
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let m = &a.pbr.materials[0];
    assert_eq!(m.emissive_texture.map(|t| t.tex_coord), Some(1));
    assert_eq!(m.base_color_texture.map(|t| t.tex_coord), Some(0));
    // The vertices carry both sets: TEXCOORD_1 spans [0, 0.25].
    let uv1_max = (a.meshes.iter().flat_map(|m| &m.vertices))
        .map(|v| v.uv1[0].max(v.uv1[1]))
        .fold(0.0f32, f32::max);
    assert!((uv1_max - 0.25).abs() < 1e-6, "{uv1_max}");
}

/// KHR_materials_ior: the dielectric F0 ((n − 1)/(n + 1))² is himal's
/// reflectance (1/9 at ior 2; 0.04 at the default 1.5); an ior below 1 is
/// an error naming the material.
#[test]
fn ior_sets_the_dielectric_reflectance() {
    let material = r#"{"name":"glass","pbrMetallicRoughness":{"metallicFactor":0},"extensions":{"KHR_materials_ior":{"ior":2.0}}}"#;
    let path = common::cube_gltf("ior2", "", material);
    let a = gltf::load(&path).expect("loads");
    let r = a.meshes[0].vertices[0].surface[1];
    assert!((r - 1.0 / 9.0).abs() < 1e-6, "{r}");
    let default = common::cube_gltf("ior_default", "", r#"{"pbrMetallicRoughness":{}}"#);
    let a = gltf::load(&default).expect("loads");
    assert_eq!(a.meshes[0].vertices[0].surface[1], gltf::GLTF_DIELECTRIC_F0);
    let bad = common::cube_gltf(
        "ior_low",
        "",
        r#"{"name":"odd","extensions":{"KHR_materials_ior":{"ior":0.5}}}"#,
    );
    let e = gltf::load(&bad).expect_err("ior 0.5").to_string();
    assert!(e.contains("odd") && e.contains("ior 0.5"), "{e}");
}

/// KHR_materials_specular (SpecularTest): factors and textures are read,
/// the colour factor unbounded above (row 7 reaches 25); materials whose
/// dielectric Fresnel the G-buffer cannot hold are layered, the default
/// (factor 1, colour 1) is not; a colour that is not three numbers is an
/// error naming the material.
#[test]
fn specular_factors_and_textures_load() {
    let a = gltf::load(&common::gltf_sample("SpecularTest")).expect("loads");
    assert!(a.warnings.is_empty(), "{:?}", a.warnings);
    let m = |name: &str| {
        (a.pbr.materials.iter().find(|m| m.name == name))
            .unwrap_or_else(|| panic!("material {name}"))
    };
    assert_eq!(m("M1.1_specFac").specular, 0.0);
    assert_eq!(m("M1.4_specFac").specular, 0.520996);
    assert!(m("M1.1_specFac").layered() && !m("M1.5_specFac").layered());
    assert!(!m("LabelMat").layered());
    let tex = m("M2_SpecTex");
    assert!(tex.specular_texture.is_some() && tex.specular_color_texture.is_none());
    assert_eq!(
        m("M5.4_yellowFac").specular_color,
        Vec3::new(0.520996, 0.520996, 0.0)
    );
    assert!(m("M6_yellowTex").specular_color_texture.is_some());
    let hdr = m("M7.5_HDR");
    assert_eq!(hdr.specular_color, Vec3::splat(25.0));
    // F0 = min(0.04 x 25, 1) x 1, F90 = 1.
    let (f0, f90) = hdr.dielectric_fresnel(1.0, Vec3::ONE);
    assert!(f0.abs_diff_eq(Vec3::ONE, 1e-6) && f90 == 1.0, "{f0} {f90}");
    let (f0, f90) = m("M1.1_specFac").dielectric_fresnel(1.0, Vec3::ONE);
    assert_eq!((f0, f90), (Vec3::ZERO, 0.0));
    // A fully metallic surface has no dielectric to correct.
    let metal = r#"{"pbrMetallicRoughness":{"metallicFactor":1},"extensions":{"KHR_materials_specular":{"specularFactor":0.2}}}"#;
    let a = gltf::load(&common::cube_gltf("specular_metal", "", metal)).expect("loads");
    assert!(!a.pbr.materials[0].layered());
    let bad = common::cube_gltf(
        "specular_bad",
        "",
        r#"{"name":"odd","extensions":{"KHR_materials_specular":{"specularColorFactor":[1,1]}}}"#,
    );
    let e = gltf::load(&bad).expect_err("two numbers").to_string();
    assert!(
        e.contains("odd") && e.contains("specularColorFactor"),
        "{e}"
    );
}

/// KHR_materials_transmission (TransmissionTest) and _volume: factors and
/// textures are read; transmissive materials leave the G-buffer's layered
/// path; a volume's thickness, attenuation distance (absent: infinite)
/// and colour are read, and a negative thickness or a zero distance is an
/// error naming the material.
#[test]
fn transmission_and_volume_load() {
    let a = gltf::load(&common::gltf_sample("TransmissionTest")).expect("loads");
    let m = |name: &str| {
        (a.pbr.materials.iter().find(|m| m.name == name))
            .unwrap_or_else(|| panic!("material {name}"))
    };
    let yellow = m("YellowTrans");
    assert_eq!(yellow.transmission, 1.0);
    assert!(yellow.transmits() && yellow.transmission_texture.is_none());
    assert!(m("RedTransTexture").transmission_texture.is_some());
    assert!(!m("Cloth Backdrop").transmits() && !m("LabelMaterial").transmits());
    assert_eq!(yellow.thickness, 0.0);
    assert!(yellow.attenuation_distance.is_infinite());
    assert!(
        !(a.warnings.iter()).any(|w| w.contains("KHR_materials_transmission")),
        "{:?}",
        a.warnings
    );
    let glass = r#"{"name":"glass","extensions":{"KHR_materials_transmission":{"transmissionFactor":0.75},"KHR_materials_volume":{"thicknessFactor":0.5,"attenuationDistance":2,"attenuationColor":[0.9,0.5,0.25]}}}"#;
    let a = gltf::load(&common::cube_gltf("volume", "", glass)).expect("loads");
    let g = &a.pbr.materials[0];
    assert_eq!(
        (g.transmission, g.thickness, g.attenuation_distance),
        (0.75, 0.5, 2.0)
    );
    assert_eq!(g.attenuation_color, Vec3::new(0.9, 0.5, 0.25));
    assert!(g.transmits() && !g.layered());
    for (bad, key) in [
        (r#""thicknessFactor":-1"#, "thicknessFactor"),
        (r#""attenuationDistance":0"#, "attenuationDistance"),
    ] {
        let json = format!(r#"{{"name":"odd","extensions":{{"KHR_materials_volume":{{{bad}}}}}}}"#);
        let e = gltf::load(&common::cube_gltf("volume_bad", "", &json))
            .expect_err(bad)
            .to_string();
        assert!(e.contains("odd") && e.contains(key), "{e}");
    }
}

/// A node's own `weights` replace its mesh's defaults (glTF 2.0 3.7.2.2):
/// one triangle with one target (vertex 2 moves up by 1), mesh weights [0],
/// drawn by a node with weights [1] and by one without. Before, both drew
/// the mesh's weights and the first was named in a warning.
#[test]
fn a_nodes_own_morph_weights_replace_the_meshs() {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let delta: [f32; 9] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let bin: Vec<u8> = positions
        .iter()
        .chain(&delta)
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0,"weights":[1.0],"name":"own"}},{{"mesh":0,"translation":[2,0,0],"name":"plain"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"targets":[{{"POSITION":1}}]}}],"weights":[0.0]}}],
"buffers":[{{"byteLength":72,"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,1,0]}}]}}"#,
        common::base64(&bin)
    );
    let path = common::temp_dir("node-weights").join("weights.gltf");
    std::fs::write(&path, json).unwrap();
    let a = gltf::load(&path).expect("loads");
    assert!(
        !a.warnings.iter().any(|w| w.contains("weights")),
        "{:?}",
        a.warnings
    );
    let top = |name: &str| {
        let o = a.objects.iter().find(|o| o.name == name).expect("object");
        a.meshes[o.mesh].vertices[2].position[1]
    };
    assert_eq!((top("own"), top("plain")), (2.0, 1.0));
}

/// An instanced node's own `weights` (EXT_mesh_gpu_instancing) morph its
/// instances: the triangle above drawn twice by a node with weights [1]
/// and once by a node without. Before, the instanced node drew the mesh's
/// weights (0) and was named in a warning.
#[test]
fn an_instanced_nodes_own_morph_weights_morph_its_instances() {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let delta: [f32; 9] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let offsets: [f32; 6] = [0.0, 0.0, 0.0, 0.0, 0.0, 3.0];
    let bin: Vec<u8> = (positions.iter().chain(&delta).chain(&offsets))
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],"extensionsUsed":["EXT_mesh_gpu_instancing"],
"nodes":[{{"mesh":0,"weights":[1.0],"name":"own","extensions":{{"EXT_mesh_gpu_instancing":{{"attributes":{{"TRANSLATION":2}}}}}}}},{{"mesh":0,"translation":[2,0,0],"name":"plain"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"targets":[{{"POSITION":1}}]}}],"weights":[0.0]}}],
"buffers":[{{"byteLength":96,"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},{{"buffer":0,"byteOffset":72,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,1,0]}},
{{"bufferView":2,"componentType":5126,"count":2,"type":"VEC3"}}]}}"#,
        common::base64(&bin)
    );
    let path = common::temp_dir("instanced-weights").join("weights.gltf");
    std::fs::write(&path, json).unwrap();
    let a = gltf::load(&path).expect("loads");
    assert!(
        !a.warnings.iter().any(|w| w.contains("weights")),
        "{:?}",
        a.warnings
    );
    let tops: Vec<(String, usize, f32)> = (a.objects.iter())
        .map(|o| {
            (
                o.name.clone(),
                o.mesh,
                a.meshes[o.mesh].vertices[2].position[1],
            )
        })
        .collect();
    let own: Vec<_> = tops.iter().filter(|t| t.0.starts_with("own#")).collect();
    assert_eq!(own.len(), 2, "{tops:?}");
    assert!(own.iter().all(|t| t.2 == 2.0), "{tops:?}");
    // One copy at the node's weights, shared by its instances.
    assert_eq!(own[0].1, own[1].1, "{tops:?}");
    let plain = tops.iter().find(|t| t.0 == "plain").expect("plain");
    assert_eq!(plain.2, 1.0, "{tops:?}");
}
