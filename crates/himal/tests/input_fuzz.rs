//! Deterministic mutations of scene files and environment maps fed to
//! their loaders: every result is `Ok` or an error naming the input;
//! nothing panics. The stable, bounded twins of the `cargo fuzz` targets
//! `fuzz/fuzz_targets/scene_file.rs` and `environment_map.rs`
//! (docs/reliability.md).

mod common;

use std::path::Path;

use himal::budget::MemoryBudget;
use himal::math::sampling::Pcg32;
use himal::scene::{EnvironmentDesc, EnvironmentFormat, EnvironmentImage, Scene};

/// A small budget keeps mutated sizes (segments, resolutions) cheap.
const BUDGET: MemoryBudget = MemoryBudget { bytes: 64 << 20 };

/// Builds `text` as `input.toml`; panics on a panic or an error that does
/// not name it. Returns whether it loaded.
fn scene(text: &str, dir: &Path, case: &str) -> bool {
    let r = std::panic::catch_unwind(|| {
        Scene::from_toml_str_within(text, "input.toml", dir, BUDGET).map(|_| ())
    });
    match r {
        Err(_) => panic!("{case}: the scene builder panicked"),
        Ok(Ok(())) => true,
        Ok(Err(e)) => {
            let m = e.to_string();
            assert!(
                m.contains("input.toml"),
                "{case}: error without the file: {m}"
            );
            false
        }
    }
}

fn environment(bytes: &[u8], format: EnvironmentFormat, case: &str) -> bool {
    let name = match format {
        EnvironmentFormat::Hdr => "input.hdr",
        EnvironmentFormat::Exr => "input.exr",
    };
    let desc = EnvironmentDesc::new(name);
    let r =
        std::panic::catch_unwind(|| EnvironmentImage::from_bytes(&desc, bytes, format).map(|_| ()));
    match r {
        Err(_) => panic!("{case}: the environment loader panicked"),
        Ok(Ok(())) => true,
        Ok(Err(e)) => {
            let m = e.to_string();
            assert!(m.contains(name), "{case}: error without the file: {m}");
            false
        }
    }
}

#[test]
fn mutated_scene_files_are_errors_or_scenes() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = root.join("tests/scenes");
    let mut rng = Pcg32::new(0x16);
    let (mut ok, mut errors) = (0, 0);
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/scenes")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "test scenes: {files:?}");
    let extremes = [
        "0",
        "-1",
        "nan",
        "inf",
        "-inf",
        "1e30",
        "4097",
        "4294967296",
        "1e-30",
        "99999",
    ];
    for file in &files {
        let text = std::fs::read_to_string(file).expect("scene");
        let label = file
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let mut tally = |loaded: bool| if loaded { ok += 1 } else { errors += 1 };
        tally(scene(&text, &dir, &format!("{label} as is")));
        // Numbers replaced by extreme values.
        let runs = common::number_runs(&text);
        for k in 0..24 {
            let (s, e) = runs[rng.next_u32() as usize % runs.len()];
            let v = extremes[k % extremes.len()];
            let t = format!("{}{v}{}", &text[..s], &text[e..]);
            tally(scene(&t, &dir, &format!("{label}: number at {s} = {v}")));
        }
        // Lines deleted and duplicated.
        let lines: Vec<&str> = text.lines().collect();
        for k in 0..8 {
            let i = rng.next_u32() as usize % lines.len();
            let mut l = lines.clone();
            if k % 2 == 0 {
                l.remove(i);
            } else {
                l.insert(i, lines[i]);
            }
            tally(scene(
                &l.join("\n"),
                &dir,
                &format!("{label}: line {i} edited"),
            ));
        }
        // Truncations and single-character flips (ASCII, so the text stays UTF-8).
        for k in 0..8 {
            let cut = text.len() * k / 8;
            let cut = (0..=cut)
                .rev()
                .find(|&c| text.is_char_boundary(c))
                .unwrap_or(0);
            tally(scene(&text[..cut], &dir, &format!("{label}: cut at {cut}")));
            let mut b = text.clone().into_bytes();
            let i = rng.next_u32() as usize % b.len();
            if b[i].is_ascii() {
                b[i] = b"[]{}=\",.#x0\n"[rng.next_u32() as usize % 12];
            }
            if let Ok(t) = String::from_utf8(b) {
                tally(scene(&t, &dir, &format!("{label}: byte {i} flipped")));
            }
        }
    }
    eprintln!("scene mutations: {ok} loaded, {errors} errors");
    // Both outcomes occur, or the mutations test nothing.
    assert!(ok > 20 && errors > 200, "loaded {ok}, errors {errors}");
}

/// A valid 8x4 Radiance file (flat RGBE) with a gradient.
fn hdr_bytes() -> Vec<u8> {
    let mut b = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n".to_vec();
    for i in 0..32u8 {
        b.extend([100 + i, 90 + i, 80 + i, 129]);
    }
    b
}

/// A valid 8x4 float EXR written by the exr crate.
fn exr_bytes() -> Vec<u8> {
    use exr::prelude::*;
    let img = Image::from_channels(
        (8, 4),
        SpecificChannels::rgb(|p: Vec2<usize>| (p.x() as f32 * 0.1, p.y() as f32 * 0.2, 0.5)),
    );
    let mut out = std::io::Cursor::new(Vec::new());
    img.write().to_buffered(&mut out).expect("exr");
    out.into_inner()
}

#[test]
fn mutated_environment_maps_are_errors_or_images() {
    let mut rng = Pcg32::new(0xe1);
    let (mut ok, mut errors) = (0, 0);
    for (format, bytes) in [
        (EnvironmentFormat::Hdr, hdr_bytes()),
        (EnvironmentFormat::Exr, exr_bytes()),
    ] {
        let mut tally = |loaded: bool| if loaded { ok += 1 } else { errors += 1 };
        assert!(
            environment(&bytes, format, "as is"),
            "{format:?} as is must load"
        );
        for k in 0..64 {
            let len = bytes.len() * k / 64;
            tally(environment(
                &bytes[..len],
                format,
                &format!("{format:?} cut at {len}"),
            ));
        }
        for k in 0..200 {
            let mut b = bytes.clone();
            for _ in 0..1 + k % 4 {
                let i = rng.next_u32() as usize % b.len();
                b[i] ^= (rng.next_u32() % 255 + 1) as u8;
            }
            tally(environment(&b, format, &format!("{format:?} flip {k}")));
        }
        // Header integers (sizes, windows, offsets) set to extremes.
        for k in 0..64 {
            let mut b = bytes.clone();
            let i = rng.next_u32() as usize % b.len().saturating_sub(4);
            let v: u32 = [0, 1, 0x7fff_ffff, 0xffff_ffff, 40_000, 0x8000_0000][k % 6];
            b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            tally(environment(
                &b,
                format,
                &format!("{format:?} u32 at {i} = {v}"),
            ));
        }
    }
    eprintln!("environment mutations: {ok} loaded, {errors} errors");
    assert!(ok > 10 && errors > 200, "loaded {ok}, errors {errors}");
}
