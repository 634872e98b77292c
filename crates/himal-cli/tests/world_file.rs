//! `himal render --scene FILE` where the file has a `[world]` table: the
//! streamed world built from it renders (terrain passes in the graph, the
//! file's camera first), and bad values fail before the GPU starts,
//! naming the file, line, column and key.

mod common;

use std::path::PathBuf;

fn himal(args: &[&str]) -> (bool, String, String) {
    // Tests never touch the user's pipeline cache.
    let cache = common::temp_path("world-cli-cache");
    common::run(args, &[("HIMAL_CACHE_DIR", cache.as_os_str())])
}

/// The 1 km height-map world of the library's tests.
fn heightmap_scene() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../himal/tests/scenes/world_heightmap.toml")
        .to_string_lossy()
        .into()
}

#[test]
fn a_bad_world_file_names_file_line_and_key() {
    let dir = common::temp_path("world-cli-bad");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("bad_world.toml");
    std::fs::write(&path, "[world]\nsectors = 16\n\n[world.pools]\ntiles = 0\n").expect("write");
    let p = path.to_string_lossy().to_string();
    let args = ["render", "--scene", &p, "--size", "8x8"];
    common::assert_fails_with(
        &args,
        &himal(&args),
        "bad_world.toml:5:9: world.pools.tiles = 0 is out of range [1, 2048]",
    );
}

#[test]
fn the_file_cameras_join_the_world_cameras() {
    let s = heightmap_scene();
    let args = [
        "render", "--scene", &s, "--camera", "nowhere", "--size", "8x8",
    ];
    common::assert_fails_with(&args, &himal(&args), "known: overview, air, river");
}

#[test]
fn a_world_file_renders_as_a_streamed_world() {
    let s = heightmap_scene();
    let (ok, graph, err) = himal(&["render", "--scene", &s, "--graph", "--size", "64x36"]);
    assert!(ok, "{err}");
    assert!(
        graph.contains(" terrain ") && graph.contains("terrain.shadow0"),
        "no terrain passes in:\n{graph}"
    );
    let dir = common::temp_path("world-cli-png");
    let out = dir.join("w.png").to_string_lossy().to_string();
    let (ok, _, err) = himal(&["render", "--scene", &s, "--size", "64x36", "--out", &out]);
    assert!(ok, "{err}");
    let img = image::open(&out).expect("a PNG").to_rgb8();
    assert_eq!(img.dimensions(), (64, 36));
    // The file's camera looks down on the peak: ground and snow, not one colour.
    let first = img.get_pixel(0, 0);
    assert!(img.pixels().any(|p| p != first), "a uniform image");
}
