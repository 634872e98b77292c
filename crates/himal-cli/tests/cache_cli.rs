//! `himal prewarm`, `himal bake` and the post options from the command
//! line (E1, L1, H2, H3).

mod common;

/// `himal` with the pipeline cache off unless `--cache` names one.
fn himal(args: &[&str]) -> (bool, String, String) {
    common::run(args, &[("HIMAL_CACHE_DIR", "off".as_ref())])
}

#[test]
fn render_after_prewarm_compiles_nothing() {
    let dir = common::temp_path("cli-prewarm");
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_string_lossy().to_string();
    let (ok, out, err) = himal(&["prewarm", "--cache", &d]);
    assert!(ok, "{err}");
    assert!(out.contains("compiles"), "{out}");
    let png = dir.join("f.png").to_string_lossy().to_string();
    let (ok, out, err) = himal(&[
        "render", "--cache", &d, "--size", "32x18", "--view", "bloom", "--out", &png,
    ]);
    assert!(ok, "{err}");
    assert!(
        out.contains(" 0 compiles"),
        "render after prewarm compiled: {out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_post_options_are_rejected() {
    for (args, needle) in [
        (
            &["render", "--exposure", "bright", "--size", "8x8"][..],
            "--exposure bright",
        ),
        (
            &["render", "--bloom", "maybe", "--size", "8x8"][..],
            "--bloom maybe",
        ),
        (
            &["render", "--bloom-passes", "99", "--size", "8x8"][..],
            "--bloom-passes 99",
        ),
        (
            &["render", "--white-point", "-1", "--size", "8x8"][..],
            "--white-point -1",
        ),
        (
            &["render", "--specular-aa", "maybe", "--size", "8x8"][..],
            "--specular-aa maybe",
        ),
        (
            &["render", "--visibility-remap", "maybe", "--size", "8x8"][..],
            "--visibility-remap maybe",
        ),
        (
            &["render", "--cinematic-shadows", "maybe", "--size", "8x8"][..],
            "--cinematic-shadows maybe",
        ),
        (
            &["render", "--ao-large-scale", "maybe", "--size", "8x8"][..],
            "--ao-large-scale maybe",
        ),
        (&["prewarm", "--cache", "off"][..], "cache directory"),
        (&["bake", "--cache", "off"][..], "cache directory"),
        (
            &["bake", "--tables", "nope", "--cache", "/nonexistent"][..],
            "--tables nope",
        ),
        (
            &["render", "--sky-tables", "huge", "--size", "8x8"][..],
            "--sky-tables huge",
        ),
    ] {
        common::assert_fails_with(args, &himal(args), needle);
    }
}

#[test]
fn bake_writes_the_sky_tables_once() {
    let dir = common::temp_path("cli-bake");
    let _ = std::fs::remove_dir_all(&dir);
    let d = dir.to_string_lossy().to_string();
    let (ok, out, err) = himal(&["bake", "--cache", &d]);
    assert!(ok, "{err}");
    assert!(
        out.contains("default sky tables (scattering 256x64x16)"),
        "{out}"
    );
    let files: Vec<_> = std::fs::read_dir(&dir)
        .expect("cache dir")
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".himal-sky"))
        .collect();
    assert_eq!(files.len(), 1, "one table file");
    let (ok, out, err) = himal(&["bake", "--cache", &d]);
    assert!(ok, "{err}");
    assert!(out.contains("already baked"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The cache files of `dir` (pipeline cache and sky tables), by name.
fn cache_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .expect("cache dir")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x != "png"))
        .collect();
    v.sort();
    v
}

/// Issue #16: four runs sharing one empty cache directory all succeed and
/// leave valid files; then each way of damaging both files (a flipped
/// byte, half a file, zeros, trailing bytes, 0xFF = NaN texels, another
/// format version) is a warning naming the file and a rebuild, and the run
/// after it loads the rebuilt files without a warning.
#[test]
fn concurrent_runs_and_damaged_caches() {
    let dir = common::temp_path("cli-cache-race");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let d = dir.to_string_lossy().to_string();
    let render = |out: &str| -> Vec<String> {
        ["render", "--size", "16x16", "--cache", &d, "--out", out]
            .iter()
            .map(|s| s.to_string())
            .collect()
    };
    let children: Vec<_> = (0..4)
        .map(|i| {
            let out = dir
                .join(format!("race{i}.png"))
                .to_string_lossy()
                .to_string();
            std::process::Command::new(env!("CARGO_BIN_EXE_himal"))
                .args(render(&out))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("spawn")
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().expect("wait");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let files = cache_files(&dir);
    let names: Vec<String> = files
        .iter()
        .map(|f| {
            f.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        })
        .collect();
    assert!(
        names.iter().all(|n| !n.contains(".tmp")),
        "temporary files left: {names:?}"
    );
    assert!(
        names.iter().any(|n| n.ends_with(".himal-sky")) && files.len() == 2,
        "expected the pipeline cache and the sky tables: {names:?}"
    );
    let out = dir.join("after.png").to_string_lossy().to_string();
    let args = render(&out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let (ok, _, err) = himal(&args);
    assert!(
        ok && !err.contains("WARN"),
        "the raced files are not valid:\n{err}"
    );
    type Damage = fn(&mut Vec<u8>);
    let damages: [(&str, Damage); 6] = [
        ("flipped", |b| {
            let i = b.len() * 2 / 3;
            b[i] ^= 0x5a;
        }),
        ("half", |b| b.truncate(b.len() / 2)),
        ("zeroed", |b| b.iter_mut().for_each(|x| *x = 0)),
        ("extended", |b| b.extend_from_slice(b"trailing")),
        ("nan", |b| {
            let n = b.len();
            b[64.min(n)..].iter_mut().for_each(|x| *x = 0xff)
        }),
        ("version", |b| b[8] = b[8].wrapping_add(7)),
    ];
    for (what, damage) in damages {
        for f in &files {
            let mut bytes = std::fs::read(f).expect("read cache");
            damage(&mut bytes);
            std::fs::write(f, bytes).expect("damage");
        }
        let (ok, _, err) = himal(&args);
        assert!(ok, "{what}: {err}");
        for f in &files {
            let name = f.file_name().unwrap_or_default().to_string_lossy();
            assert!(
                err.contains(name.as_ref()),
                "{what}: no warning names {name}:\n{err}"
            );
        }
        let (ok, _, err) = himal(&args);
        assert!(ok && !err.contains("WARN"), "{what}: not rebuilt:\n{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
