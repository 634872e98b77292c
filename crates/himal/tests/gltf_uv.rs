//! glTF UV sets (issue #22): a texture slot reads the vertex UV slot
//! holding the set its `texCoord` names, on MultiUVTest (docs/gltf.md
//! "UV sets"). Moved from gltf_render.rs.

mod common;

use himal::scene::Scene;

/// MultiUVTest: the emissive texture reads TEXCOORD_1 (the base colour
/// TEXCOORD_0). The emitted light alone (HDR frame minus the frame with
/// emission off) is checked per pixel against a CPU ray cast of the cube
/// from the file's own accessors: uv1 interpolated at the hit, the emissive
/// image decoded and sampled there. Reading TEXCOORD_0 instead (as before)
/// matches the other hypothesis.
#[test]
fn the_second_uv_set_maps_the_emissive_texture() {
    emission_follows_uv_set(&common::gltf_sample("MultiUVTest"), "TEXCOORD_1");
}

/// The same cube with the emissive's set renamed TEXCOORD_2 and TEXCOORD_0
/// also given as TEXCOORD_1: a material reading sets 0 and 2 carries both
/// in the vertex's two slots (PbrMaterial::uv_sets). Before, set 2 was
/// drawn with TEXCOORD_0 and warned about.
#[test]
fn a_third_uv_set_maps_the_emissive_texture() {
    let from = common::gltf_sample("MultiUVTest");
    let dir = std::env::temp_dir().join(format!("himal-uv2-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    for f in ["MultiUVTest.bin", "uv0.png", "uv1.png"] {
        std::fs::copy(from.with_file_name(f), dir.join(f)).expect("copy");
    }
    let json = std::fs::read_to_string(&from).expect("gltf");
    let renamed = json
        .replace(
            "\"TEXCOORD_1\" : 5",
            "\"TEXCOORD_2\" : 5, \"TEXCOORD_1\" : 4",
        )
        .replace("\"texCoord\" : 1", "\"texCoord\" : 2");
    assert!(renamed.contains("TEXCOORD_2") && renamed.contains("\"texCoord\" : 2"));
    let path = dir.join("MultiUVTest.gltf");
    std::fs::write(&path, renamed).expect("write");
    let loaded = himal::scene::gltf::load(&path).expect("loads");
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(loaded.pbr.materials[0].uv_sets(), [0, 2]);
    emission_follows_uv_set(&path, "TEXCOORD_2");

    // A third set (occlusion through TEXCOORD_1 beside 0 and 2) is drawn
    // with the first slot's and named in one warning.
    let three = std::fs::read_to_string(&path).expect("gltf").replace(
        "\"emissiveTexture\"",
        "\"occlusionTexture\" : { \"index\" : 0, \"texCoord\" : 1 }, \"emissiveTexture\"",
    );
    std::fs::write(&path, three).expect("write");
    let loaded = himal::scene::gltf::load(&path).expect("loads");
    let m = &loaded.pbr.materials[0];
    assert_eq!((m.uv_sets(), m.uv_sets_past_slots()), ([0, 1], vec![2]));
    assert!(
        loaded
            .warnings
            .iter()
            .any(|w| w.contains("Material (TEXCOORD_2)")),
        "{:?}",
        loaded.warnings
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The emission of the cube at `path` per pixel against the emissive image
/// looked up at UV set `set`, and not at TEXCOORD_0.
fn emission_follows_uv_set(path: &std::path::Path, set: &str) {
    let path = path.to_path_buf();
    let mut scene = Scene::from_gltf(&path).expect("model");
    let size = 160u32;
    let camera = himal::scene::gltf::orbit_camera(&scene.bounds, 35.0, 20.0, None, 40.0);
    let hdr = |scene: &Scene| common::raw_views(scene, &camera, size, &["lighting"]).remove(0);
    let lit = hdr(&scene);
    for m in &mut scene.pbr.materials {
        m.emissive = glam::Vec3::ZERO;
    }
    let dark = hdr(&scene);

    let file = common::GltfFile::open(&path);
    let prim = &file.json["meshes"][0]["primitives"][0];
    let acc = |k: &str| prim["attributes"][k].as_u64().unwrap() as usize;
    let indices = prim["indices"].as_u64().unwrap() as usize;
    let tri: Vec<usize> = (0..file.count(indices))
        .map(|i| file.element(indices, i, 1)[0] as usize)
        .collect();
    let p = |i: usize| file.vec3(acc("POSITION"), i);
    let uv = |set: &str, i: usize| glam::Vec2::from_slice(&file.element(acc(set), i, 2));
    let emissive = image::open(path.with_file_name("uv1.png"))
        .expect("uv1.png")
        .to_rgb32f();
    let srgb = |c: f32| {
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    // Bilinear, repeat (the file's default sampler), linear light.
    let sample = |uv: glam::Vec2| {
        let (w, h) = emissive.dimensions();
        let x = uv.x.rem_euclid(1.0) * w as f32 - 0.5;
        let y = uv.y.rem_euclid(1.0) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |dx: f32, dy: f32| {
            let tx = ((x0 + dx) as i64).rem_euclid(w as i64) as u32;
            let ty = ((y0 + dy) as i64).rem_euclid(h as i64) as u32;
            glam::Vec3::from(emissive.get_pixel(tx, ty).0.map(srgb))
        };
        let top = texel(0.0, 0.0).lerp(texel(1.0, 0.0), fx);
        let bottom = texel(0.0, 1.0).lerp(texel(1.0, 1.0), fx);
        top.lerp(bottom, fy)
    };
    let (mut err1, mut err0, mut n) = (0.0f32, 0.0f32, 0u32);
    for y in 0..size {
        for x in 0..size {
            let (o, d) = common::pixel_ray_from(&camera, (size, size), x, y);
            let Some((t, k, b)) = tri
                .chunks_exact(3)
                .enumerate()
                .filter_map(|(k, c)| {
                    common::ray_triangle(o, d, [p(c[0]), p(c[1]), p(c[2])]).map(|(t, b)| (t, k, b))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
            else {
                continue;
            };
            // Skip pixels near a face edge (mip blur across the seam).
            if b.min_element() < 0.04 || t <= 0.0 {
                continue;
            }
            let c = &tri[3 * k..3 * k + 3];
            let at = |set: &str| uv(set, c[0]) * b.x + uv(set, c[1]) * b.y + uv(set, c[2]) * b.z;
            let i = (y * size + x) as usize;
            let measured =
                glam::Vec3::from_slice(&lit[i][..3]) - glam::Vec3::from_slice(&dark[i][..3]);
            err1 += (measured - sample(at(set))).abs().element_sum() / 3.0;
            err0 += (measured - sample(at("TEXCOORD_0"))).abs().element_sum() / 3.0;
            n += 1;
        }
    }
    let (err1, err0) = (err1 / n as f32, err0 / n as f32);
    eprintln!(
        "{n} cube pixels: mean |emission - {set} lookup| {err1}, |emission - uv0 lookup| {err0}"
    );
    assert!(n > 3000, "the cube covers {n} pixels");
    assert!(err1 < 0.05, "emission against the {set} lookup: {err1}");
    assert!(err0 > 4.0 * err1, "uv0 {err0} vs uv1 {err1}");
}
