//! E1 pipeline cache on the adapter present (lavapipe in CI): after a
//! pre-warm, a 16-frame sequence in a fresh process-like context compiles
//! nothing; a corrupted or incompatible cache file is detected, ignored
//! (with a warning) and rebuilt. Each test uses its own temporary directory.

use std::path::Path;

mod common;

use himal::gpu::GpuContext;
use himal::gpu::cache::{LoadStatus, cache_file};
use himal::scene::Scene;
use himal::{FrameSettings, Renderer};

/// A new context (as a new process would have) with the cache in `dir` opened.
fn context(dir: &Path) -> (GpuContext, LoadStatus) {
    let ctx = common::context();
    let status = ctx.open_pipeline_cache(dir);
    (ctx, status)
}

/// The lit sphere of `scenes/lit_sphere.toml`, coarsely tessellated.
fn scene() -> Scene {
    common::scene_with("lit_sphere", &[("segments = 128", "segments = 16")])
}

#[test]
fn after_prewarm_a_16_frame_sequence_compiles_nothing() {
    let dir = common::temp_dir("cache-prewarm");
    let scene = scene();
    let (ctx, status) = context(&dir);
    assert!(matches!(status, LoadStatus::Missing(_)), "{status:?}");
    let mut warm = Renderer::new(ctx, &scene).expect("renderer");
    warm.prewarm().expect("prewarm");
    let prewarm = warm.context().pipelines.stats();
    let written = warm.context().save_pipeline_cache().expect("save");
    assert!(written.is_some_and(|p| p.exists()), "cache file written");
    eprintln!("prewarm: {prewarm}");

    let (ctx, status) = context(&dir);
    let LoadStatus::Loaded { keys, .. } = status else {
        panic!("cache not loaded: {status:?}");
    };
    // Measured 77 permutations: the passes' fixed pipelines (environment
    // filtering included), 16 lighting and 4 tone-map permutations, 8 Kawase
    // offsets, the debug and AO views x 2 formats, the scene's G-buffer ones.
    assert_eq!(
        keys as u64, prewarm.compiles,
        "index holds every pre-warmed key"
    );
    let mut r = Renderer::new(ctx, &scene).expect("renderer");
    let start = r.context().pipelines.stats();
    let camera = scene.camera("front").expect("camera").clone();
    let mut settings = FrameSettings::new(48, 32, scene.sun.clone());
    settings.white_point = Some(4.0);
    for i in 0..16 {
        let mut cam = camera.clone();
        cam.position += cam.forward * (0.05 * i as f32);
        // Bloom off for the second half: another tone-map permutation
        // mid-sequence; fog and shadows off for 4 frames: lighting permutations.
        settings.bloom.enabled = i < 8;
        settings.aerial_extinction = if (4..8).contains(&i) { 0.0 } else { 2e-4 };
        settings.shadow_resolution = if (10..14).contains(&i) { 0 } else { 512 };
        r.render(&cam, &settings).expect("frame");
    }
    let total = r.context().pipelines.stats();
    let sequence = total.since(&start);
    eprintln!("start-up: {start}; 16 frames: {sequence}");
    assert_eq!(
        total.compiles, 0,
        "pipelines compiled after pre-warm: {total}"
    );
    assert!(total.disk_hits > 0, "nothing came from disk: {total}");
    // Permutations first used mid-sequence (tone map with bloom off, Kawase
    // offsets, lighting without fog or shadows) come from disk, not from the
    // compiler: measured 9 disk hits.
    assert_eq!(sequence.compiles, 0, "compiled mid-sequence: {sequence}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn corrupted_or_foreign_cache_is_ignored_and_rebuilt() {
    let dir = common::temp_dir("cache-corrupt");
    let scene = scene();
    let (ctx, _) = context(&dir);
    let path = cache_file(&dir, &ctx.adapter.get_info());
    let first = Renderer::new(ctx, &scene).expect("renderer");
    let compiled = first.context().pipelines.stats().compiles;
    first.context().save_pipeline_cache().expect("save");
    let good = std::fs::read(&path).expect("cache file");

    // Damage: one flipped bit in the middle (checksum), an old format
    // version, a truncated file, another adapter's identity.
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    let mut old = good.clone();
    old[8] = old[8].wrapping_add(1);
    let truncated = good[..good.len() / 3].to_vec();
    let mut foreign = good.clone();
    let at = foreign
        .windows(4)
        .position(|w| w == b"|wgp")
        .expect("identity in header");
    foreign[at - 1] ^= 0x01; // last byte of the driver info, checksum refreshed below
    let n = foreign.len() - 8;
    let sum = himal::gpu::cache::fnv1a(&foreign[..n]);
    foreign[n..].copy_from_slice(&sum.to_le_bytes());
    for (what, bytes, reason) in [
        ("flipped bit", &flipped, "checksum"),
        ("old version", &old, "version"),
        ("truncated", &truncated, ""),
        ("other adapter", &foreign, "another adapter"),
    ] {
        std::fs::write(&path, bytes).expect("write damaged file");
        let (ctx, status) = context(&dir);
        let LoadStatus::Rejected { reason: got, .. } = &status else {
            panic!("{what}: damaged file accepted: {status:?}");
        };
        eprintln!("{what}: rejected: {got}");
        assert!(got.contains(reason), "{what}: reason \"{got}\"");
        if what == "flipped bit" {
            // Ignored: everything compiles again, and the save rebuilds the file.
            let r = Renderer::new(ctx, &scene).expect("renderer despite a bad cache");
            let stats = r.context().pipelines.stats();
            assert_eq!((stats.disk_hits, stats.compiles), (0, compiled), "{stats}");
            r.context().save_pipeline_cache().expect("rebuild");
            let (ctx, status) = context(&dir);
            assert!(
                matches!(status, LoadStatus::Loaded { .. }),
                "rebuilt: {status:?}"
            );
            let r = Renderer::new(ctx, &scene).expect("renderer");
            let stats = r.context().pipelines.stats();
            assert_eq!((stats.compiles, stats.disk_hits), (0, compiled), "{stats}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn prewarm_covers_the_material_types_of_the_scene() {
    // E1's material-type axis: a scene with vegetation pre-warms the
    // vegetation G-buffer permutation, one without does not.
    let grass = common::scene("grass_patch");
    let count = |scene: &Scene| {
        let mut r = common::renderer(scene);
        r.prewarm().expect("prewarm");
        r.context().pipelines.len()
    };
    let (plain, with_grass) = (count(&scene()), count(&grass));
    // Measured 2026-11-22: 77 and 78 (+ gbuffer.vegetation).
    eprintln!("pre-warmed pipelines: {plain} without vegetation, {with_grass} with");
    assert_eq!(with_grass, plain + 1);
}
