//! Deterministic mutations of a sample glTF (the JSON with its .bin) and of
//! a .glb built from it, fed through the loader: every result is `Ok` or an
//! error naming the file; nothing panics. The stable, bounded twin of the
//! `cargo fuzz` target `fuzz/fuzz_targets/gltf_import.rs` (docs/gltf.md).

mod common;

use std::path::{Path, PathBuf};

use himal::math::sampling::Pcg32;
use himal::scene::gltf::load_from_bytes;

fn orientation_test() -> PathBuf {
    common::gltf_sample("OrientationTest")
}

/// Loads `bytes` as `name`; panics (with the case) on a panic or an error
/// that does not name the file.
fn check(path: &Path, bytes: &[u8], case: &str) -> bool {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("?")
        .to_string();
    let result = std::panic::catch_unwind(|| load_from_bytes(path, bytes).map(|_| ()));
    match result {
        Err(_) => panic!("{case}: the loader panicked"),
        Ok(Ok(())) => true,
        Ok(Err(e)) => {
            let msg = e.to_string();
            assert!(
                msg.contains(&name),
                "{case}: error does not name {name}: {msg}"
            );
            false
        }
    }
}

#[test]
fn mutated_inputs_are_errors_or_models_never_panics() {
    let path = orientation_test();
    let json = std::fs::read_to_string(&path).expect("OrientationTest.gltf");
    let bin =
        std::fs::read(path.with_file_name("OrientationTest.bin")).expect("OrientationTest.bin");
    // The same document with its buffer in a BIN chunk.
    let glb_json = json.replace(", \n            \"uri\" : \"OrientationTest.bin\"", "");
    assert_ne!(glb_json, json, "the buffer URI was not found");
    let glb_bytes = common::glb(&glb_json, &bin);
    let glb_path = path.with_file_name("mutated.glb");
    assert!(check(&path, json.as_bytes(), "json as is"));
    assert!(check(&glb_path, &glb_bytes, "glb as is"));

    let mut rng = Pcg32::new(0x8f);
    let (mut ok, mut errors) = (0, 0);
    let mut tally = |loaded: bool| if loaded { ok += 1 } else { errors += 1 };
    // 1. Truncations of the .glb at 120 lengths (header, JSON, BIN chunk).
    for k in 0..120 {
        let len = glb_bytes.len() * k / 120;
        tally(check(
            &glb_path,
            &glb_bytes[..len],
            &format!("glb truncated to {len}"),
        ));
    }
    // 2. Byte flips in the .glb: one to four bytes XORed with random values.
    for k in 0..150 {
        let mut b = glb_bytes.clone();
        for _ in 0..1 + k % 4 {
            let i = rng.next_u32() as usize % b.len();
            b[i] ^= (rng.next_u32() % 255 + 1) as u8;
        }
        tally(check(&glb_path, &b, &format!("glb flip {k}")));
    }
    // 3. Numbers of the JSON replaced by extreme values (valid JSON, bad
    //    counts, offsets, indices, transforms), with the real .bin beside it.
    let digits = common::number_runs(&json);
    let extremes = [
        "0",
        "4294967295",
        "1e30",
        "99999999999",
        "3",
        "65535",
        "0.0001",
    ];
    for k in 0..150 {
        let (start, end) = digits[rng.next_u32() as usize % digits.len()];
        let mutated = format!(
            "{}{}{}",
            &json[..start],
            extremes[k % extremes.len()],
            &json[end..]
        );
        tally(check(
            &path,
            mutated.as_bytes(),
            &format!(
                "json number {start}..{end} = {}",
                extremes[k % extremes.len()]
            ),
        ));
    }
    // 4. JSON truncations and deleted characters.
    for k in 0..60 {
        let cut = json.len() * k / 60;
        tally(check(
            &path,
            &json.as_bytes()[..cut],
            &format!("json truncated to {cut}"),
        ));
        let i = rng.next_u32() as usize % json.len();
        let mut b = json.as_bytes().to_vec();
        b.remove(i);
        tally(check(&path, &b, &format!("json without byte {i}")));
    }
    eprintln!("mutations: {ok} loaded, {errors} named errors, no panic");
    // The case the random mutations first found: the gltf crate's own
    // validation indexed a POSITION accessor past the end and panicked.
    let bad = json.replacen("\"POSITION\" : 19", "\"POSITION\" : 65535", 1);
    assert_ne!(bad, json);
    let e = load_from_bytes(&path, bad.as_bytes())
        .err()
        .map(|e| e.to_string());
    assert!(
        e.as_deref()
            .is_some_and(|e| e.contains("OrientationTest.gltf")
                && e.contains("POSITION accessor 65535 does not exist")),
        "{e:?}"
    );
    // measured 162 loaded, 378 named errors on 2026-11-22. Mostly errors,
    // but some mutations (e.g. a changed translation) still load.
    assert!(errors > 300 && ok > 0, "{ok} loaded, {errors} errors");
}
