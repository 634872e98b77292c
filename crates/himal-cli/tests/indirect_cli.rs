//! L5 from the command line: `himal bake --probes` bakes a scene's cells
//! into the cache (resumable: a second run reads them), `render --indirect
//! on` uses them and `--view indirect` shows them; in a streamed world
//! `bake --probes --radius` bakes blocks around its cameras and `render
//! --indirect on` bakes what its camera still needs, the same bytes twice.

mod common;

const VILLAGE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../himal/tests/scenes/l5_village.toml"
);

/// A 1 km streamed world (16 x 16 sectors, 4 x 4 bake blocks).
const WORLD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../himal/tests/scenes/world_heightmap.toml"
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
fn the_indirect_view_needs_the_probes_and_bad_switches_are_refused() {
    let dir = common::temp_path("indirect-cli-errors");
    let cache = dir.join("cache");
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let args = [
        "render", "--scene", VILLAGE, "--size", "32x18", "--view", "indirect", "--out", out,
    ];
    let r = himal(&cache, &args);
    common::assert_fails_with(&args, &r, "need --indirect on");
    let args = ["bake", "--probes", "--scene", WORLD, "--radius", "-5"];
    let r = himal(&cache, &args);
    common::assert_fails_with(&args, &r, "--radius -5");
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

#[test]
fn a_streamed_world_bakes_blocks_around_its_cameras_and_renders_with_them() {
    let dir = common::temp_path("indirect-cli-world");
    let cache = dir.join("cache");
    std::fs::create_dir_all(&dir).unwrap();
    let (ok, out, err) = himal(
        &cache,
        &["bake", "--probes", "--scene", WORLD, "--radius", "0"],
    );
    assert!(ok, "bake: {err}");
    assert!(out.contains("world probe cells baked"), "{out}");
    let (ok, out2, err) = himal(
        &cache,
        &["bake", "--probes", "--scene", WORLD, "--radius", "0"],
    );
    assert!(
        ok && out2.contains(" 0 world probe cells baked"),
        "{out2} {err}"
    );
    let mut frames = Vec::new();
    for name in ["a.png", "b.png"] {
        let path = dir.join(name);
        let (ok, _, err) = himal(
            &cache,
            &[
                "render",
                "--scene",
                WORLD,
                "--size",
                "48x27",
                "--indirect",
                "on",
                "--out",
                path.to_str().unwrap(),
            ],
        );
        assert!(ok, "render: {err}");
        frames.push(std::fs::read(&path).unwrap());
    }
    assert_eq!(frames[0], frames[1], "same command, same bytes");
    let _ = std::fs::remove_dir_all(&dir);
}
