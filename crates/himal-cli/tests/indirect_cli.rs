//! L5 from the command line: `himal bake --probes` bakes a scene's cells
//! into the cache (resumable: a second run reads them), `render --indirect
//! on` uses them and `--view indirect` shows them; the streamed world is
//! refused with a reason (issue #19).

mod common;

const VILLAGE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../himal/tests/scenes/l5_village.toml"
);

fn himal(cache: &std::path::Path, args: &[&str]) -> (bool, String, String) {
    common::run(args, &[("HIMAL_CACHE_DIR", cache.as_os_str())])
}

#[test]
fn bake_then_render_with_probes_and_their_view() {
    let dir = common::temp_path("indirect-cli");
    let cache = dir.join("cache");
    std::fs::create_dir_all(&dir).unwrap();
    let (ok, out, err) = himal(&cache, &["bake", "--probes", "--scene", VILLAGE]);
    assert!(ok, "bake: {err}");
    assert!(out.contains("probe cells of"), "{out}");
    assert!(err.contains("baked 36 cells (0 from the cache)"), "{err}");
    let folder = std::fs::read_dir(cache.join("probes"))
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    let files = std::fs::read_dir(&folder).unwrap().count();
    assert_eq!(files, 36, "one file per mip-0 cell in {}", folder.display());
    // A second bake reads every cell back: nothing to do.
    let (ok, _, err) = himal(&cache, &["bake", "--probes", "--scene", VILLAGE]);
    assert!(ok && !err.contains("baked"), "second bake: {err}");
    // A damaged cell is baked again, the others read.
    let one = std::fs::read_dir(&folder)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::write(&one, b"not a cell").unwrap();
    let (ok, _, err) = himal(&cache, &["bake", "--probes", "--scene", VILLAGE]);
    assert!(
        ok && err.contains("baked 1 cells (35 from the cache)"),
        "{err}"
    );

    for (view, name) in [
        ("final", "on.png"),
        ("indirect", "view.png"),
        ("probe-cells", "cells.png"),
        ("clipmap", "clip.png"),
    ] {
        let out_path = dir.join(name);
        let (ok, _, err) = himal(
            &cache,
            &[
                "render",
                "--scene",
                VILLAGE,
                "--size",
                "64x36",
                "--indirect",
                "on",
                "--view",
                view,
                "--out",
                out_path.to_str().unwrap(),
            ],
        );
        assert!(ok, "render --view {view}: {err}");
        assert!(
            !err.contains("baked"),
            "render reads the baked cells: {err}"
        );
        assert!(out_path.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_indirect_view_needs_the_probes_and_the_world_is_refused() {
    let dir = common::temp_path("indirect-cli-errors");
    let cache = dir.join("cache");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let args = [
        "render", "--scene", VILLAGE, "--size", "32x18", "--view", "indirect", "--out", out,
    ];
    let r = himal(&cache, &args);
    common::assert_fails_with(&args, &r, "need --indirect on");
    let args = [
        "render",
        "--scene",
        "world",
        "--size",
        "32x18",
        "--indirect",
        "on",
        "--out",
        out,
    ];
    let r = himal(&cache, &args);
    common::assert_fails_with(&args, &r, "streamed world's probe cells are not baked yet");
    let args = [
        "render",
        "--scene",
        VILLAGE,
        "--indirect",
        "maybe",
        "--out",
        out,
    ];
    let r = himal(&cache, &args);
    common::assert_fails_with(&args, &r, "--indirect");
    let _ = std::fs::remove_dir_all(&dir);
}
