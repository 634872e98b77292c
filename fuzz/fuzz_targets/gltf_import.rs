//! Fuzz target for the glTF import path: the input is fed to
//! `himal::scene::gltf::load_from_bytes` as a .glb and as a .gltf (the
//! loader tells them apart by the GLB magic; the names only affect
//! messages and where relative URIs resolve: a folder that does not exist,
//! so external buffers and images fail to read). Every outcome must be
//! `Ok` or a `SceneError` naming the file; a panic, hang or abort is a bug.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for name in ["/nonexistent-himal-fuzz/input.glb", "/nonexistent-himal-fuzz/input.gltf"] {
        let path = Path::new(name);
        if let Err(e) = himal::scene::gltf::load_from_bytes(path, data) {
            assert!(e.to_string().contains("input.gl"), "error without the file: {e}");
        }
    }
});
