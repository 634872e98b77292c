//! Issue #16: the malformed glTF cases that panicked inside the gltf
//! crate's readers (index accessors of float, signed-byte or short type;
//! COLOR_0 as VEC2 or BYTE; TEXCOORD_0 as SHORT or UNSIGNED_INT; an image
//! with neither uri nor bufferView; a stride smaller than the element) are
//! errors naming the file, the JSON path and the rule.

mod common;

use std::path::Path;

use himal::scene::gltf::load_from_bytes;

/// A one-triangle glTF whose accessor 1 (`extra`) is bound as `role`
/// ("indices" or an attribute name) with `component` and `kind`, 16 bytes
/// per element in its own view of `stride` (0: tightly packed).
fn triangle(role: &str, component: u32, kind: &str, stride: u32, images: &str) -> String {
    let bin = vec![0u8; 36 + 48];
    let stride = if stride > 0 {
        format!(r#","byteStride":{stride}"#)
    } else {
        String::new()
    };
    let (indices, attribute) = if role == "indices" {
        (r#","indices":1"#.to_string(), String::new())
    } else {
        (String::new(), format!(r#","{role}":1"#))
    };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0{attribute}}}{indices}}}]}}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":48{stride}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[0,0,0]}},
  {{"bufferView":1,"componentType":{component},"count":3,"type":"{kind}"}}]{images}}}"#,
        bin.len(),
        common::base64(&bin)
    )
}

fn error(json: &str, case: &str) -> String {
    let path = Path::new("malformed.gltf");
    match std::panic::catch_unwind(|| load_from_bytes(path, json.as_bytes()).map(|_| ())) {
        Err(_) => panic!("{case}: the loader panicked"),
        Ok(Ok(())) => panic!("{case}: accepted"),
        Ok(Err(e)) => {
            let e = e.to_string();
            assert!(e.contains("malformed.gltf"), "{case}: names the file: {e}");
            e
        }
    }
}

const FLOAT: u32 = 5126;
const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_INT: u32 = 5125;

#[test]
fn accessor_types_a_semantic_does_not_allow_are_errors_with_the_json_path() {
    let cases = [
        (
            "indices",
            FLOAT,
            "SCALAR",
            "meshes[0].primitives[0].indices: accessor 1 is SCALAR of FLOAT",
        ),
        (
            "indices",
            BYTE,
            "SCALAR",
            "indices: accessor 1 is SCALAR of BYTE",
        ),
        (
            "indices",
            SHORT,
            "SCALAR",
            "indices: accessor 1 is SCALAR of SHORT",
        ),
        (
            "COLOR_0",
            FLOAT,
            "VEC2",
            "attributes.COLOR_0: accessor 1 is VEC2 of FLOAT",
        ),
        (
            "COLOR_0",
            BYTE,
            "VEC4",
            "attributes.COLOR_0: accessor 1 is VEC4 of BYTE",
        ),
        (
            "TEXCOORD_0",
            SHORT,
            "VEC2",
            "attributes.TEXCOORD_0: accessor 1 is VEC2 of SHORT",
        ),
        (
            "TEXCOORD_0",
            UNSIGNED_INT,
            "VEC2",
            "attributes.TEXCOORD_0: accessor 1 is VEC2 of UNSIGNED_INT",
        ),
        (
            "NORMAL",
            UNSIGNED_BYTE,
            "VEC3",
            "attributes.NORMAL: accessor 1 is VEC3 of UNSIGNED_BYTE; it must be VEC3 of FLOAT",
        ),
    ];
    for (role, component, kind, wanted) in cases {
        let case = format!("{role} {kind} {component}");
        let e = error(&triangle(role, component, kind, 0, ""), &case);
        assert!(e.contains(wanted), "{case}: {e}");
        assert!(e.contains("it must be"), "{case}: states the rule: {e}");
    }
    // An allowed one still loads: TEXCOORD_0 as VEC2 of FLOAT.
    let ok = triangle("TEXCOORD_0", FLOAT, "VEC2", 0, "");
    load_from_bytes(Path::new("ok.gltf"), ok.as_bytes())
        .expect("VEC2 of FLOAT texture coordinates");
}

#[test]
fn a_stride_below_the_element_and_an_image_without_a_source_are_errors() {
    // VEC4 of FLOAT is 16 bytes; a stride of 8 would overlap the elements.
    let e = error(&triangle("TANGENT", FLOAT, "VEC4", 8, ""), "stride");
    assert!(
        e.contains("byte stride 8") && e.contains("smaller than its 16-byte element"),
        "{e}"
    );
    let images = r#","images":[{"mimeType":"image/png"}]"#;
    let e = error(&triangle("TANGENT", FLOAT, "VEC4", 0, images), "image");
    assert!(
        e.contains("images[0] has neither a uri nor a bufferView"),
        "{e}"
    );
}

#[test]
fn a_glb_whose_header_length_disagrees_and_an_empty_sparse_accessor_are_errors() {
    // A minimal GLB of the triangle: header (magic, version 2, length), JSON chunk.
    let json = triangle("TANGENT", FLOAT, "VEC4", 0, "");
    let mut chunk = json.into_bytes();
    while !chunk.len().is_multiple_of(4) {
        chunk.push(b' ');
    }
    let glb = |declared: u32, extra: usize| {
        let mut g = b"glTF".to_vec();
        g.extend(2u32.to_le_bytes());
        g.extend(declared.to_le_bytes());
        g.extend((chunk.len() as u32).to_le_bytes());
        g.extend(b"JSON");
        g.extend(&chunk);
        g.extend(vec![0u8; extra]);
        g
    };
    let whole = 12 + 8 + chunk.len() as u32;
    let path = Path::new("malformed.glb");
    load_from_bytes(path, &glb(whole, 0)).expect("a consistent GLB loads");
    let Err(e) = load_from_bytes(path, &glb(whole, 16)) else {
        panic!("a GLB longer than its header says was accepted");
    };
    assert!(
        e.to_string().contains(&format!(
            "GLB header declares {whole} bytes, the file has {}",
            whole + 16
        )),
        "{e}"
    );
    // sparse.count must be 1..=count.
    let sparse = triangle("TANGENT", FLOAT, "VEC4", 0, "").replace(
        r#""count":3,"type":"VEC4"}"#,
        r#""count":3,"type":"VEC4","sparse":{"count":0,"indices":{"bufferView":1,"componentType":5121},"values":{"bufferView":1}}}"#,
    );
    assert!(sparse.contains("sparse"), "the test replaced the accessor");
    let e = error(&sparse, "sparse count 0");
    assert!(e.contains("accessors[1].sparse.count is 0"), "{e}");
}
