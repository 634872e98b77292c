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
            "bloom passes 99",
        ),
        (
            &["render", "--white-point", "-1", "--size", "8x8"][..],
            "white point",
        ),
        (&["prewarm", "--cache", "off"][..], "cache directory"),
        (&["bake", "--cache", "off"][..], "cache directory"),
        (
            &["bake", "--tables", "nope", "--cache", "/nonexistent"][..],
            "--tables nope",
        ),
        (
            &["render", "--sky-tables", "huge", "--size", "8x8"][..],
            "sky tables huge",
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
