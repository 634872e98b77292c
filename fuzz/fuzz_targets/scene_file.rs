//! Fuzz target for scene files: the input, as UTF-8 text, is built as a
//! scene (`Scene::from_toml_str`) under a 256 MiB memory budget, its
//! relative paths resolving in a folder that does not exist. Every outcome
//! must be `Ok` or a `SceneError` naming the file; a panic, hang or abort
//! is a bug. Bytes that are not UTF-8 are the reader's to refuse
//! (`Scene::load`), not the parser's.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let budget = himal::budget::MemoryBudget { bytes: 256 << 20 };
    let dir = Path::new("/nonexistent-himal-fuzz");
    if let Err(e) = himal::scene::Scene::from_toml_str_within(text, "input.toml", dir, budget) {
        assert!(e.to_string().contains("input.toml"), "error without the file: {e}");
    }
});
