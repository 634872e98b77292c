//! The world's forests (issue #18 item 6, `docs/world.md` "Forests"): V1's
//! larches and rosewoods streamed into the pool, trunks opaque and leaves
//! among the vegetation batches, drawn the same on the GPU and CPU culling
//! paths, the same twice, with as many draw calls at any tree density;
//! far trees at V3's impostor levels.

mod common;

use std::sync::Arc;

use himal::scene::world::{World, WorldDesc};
use himal::{Culling, FrameSettings, Renderer};

/// A world streamed 256 m around its cameras, with small pools; trees at
/// `density` times the default (the tests use a fifth at most: lavapipe
/// takes minutes per frame of the full forest, docs/world.md "Forests").
fn world(density: f32) -> Arc<World> {
    let mut desc = WorldDesc::default();
    desc.stream.radius = 256.0;
    desc.pools.tiles = 128;
    // Trees: 68 sectors of at most 256 (4 m cells) within 256 m.
    desc.pools.instances = [1024, 1024, 1024, 256, 256, 64, 1024, 16384, 16384, 256];
    desc.rules.tree_density = density;
    Arc::new(World::new(desc))
}

const SIZE: (u32, u32) = (160, 90);
/// `--lod-threshold`'s default (the library's is LOD0 everywhere).
const LOD_PX: f32 = 4.0;

/// Albedo pixels: leaves are green (the needles' and leaves' albedos and
/// tints), bark brown; the terrain's grass is green too, so trees are
/// counted where the frame without trees differs.
fn green(p: &[f32; 4]) -> bool {
    p[1] > p[0] * 1.15 && p[1] > p[2]
}

#[test]
fn forests_draw_trunks_and_leaves_the_same_on_both_culling_paths() {
    let trees = world(0.2);
    let camera = common::world_camera(&trees, "forest");
    let mut r = common::settled_world(&trees, &camera);
    let scene = trees.scene();
    let frame = |r: &mut Renderer, culling, view: &str| {
        let mut s = common::raw_settings(&scene, SIZE, view);
        s.culling = culling;
        // The CLI's E2 default: far trees at the impostor levels.
        s.lod_threshold_px = LOD_PX;
        r.reset_history();
        // Twice: the second frame has the static map the first filled.
        r.render(&camera, &s).expect("frame");
        r.render(&camera, &s).expect("frame")
    };
    let gpu = frame(&mut r, Culling::Gpu, "albedo");
    let cpu = frame(&mut r, Culling::Cpu, "albedo");
    assert_eq!(gpu.culling, Culling::Gpu);
    let lit_gpu = frame(&mut r, Culling::Gpu, "final");
    let lit_cpu = frame(&mut r, Culling::Cpu, "final");
    let again = frame(
        &mut common::settled_world(&trees, &camera),
        Culling::Gpu,
        "final",
    );
    assert_eq!(
        gpu.image.bytes, cpu.image.bytes,
        "the CPU path's forest albedo differs from the GPU path's"
    );
    assert_eq!(
        lit_gpu.image.bytes, lit_cpu.image.bytes,
        "the CPU path's lit forest differs from the GPU path's"
    );
    assert_eq!(
        lit_gpu.image.bytes, again.image.bytes,
        "a forest frame differs between runs"
    );
    // The same world without trees: where it differs, trees are drawn.
    let bare_world = world(0.0);
    let mut bare = common::settled_world(&bare_world, &camera);
    let bare = frame(&mut bare, Culling::Gpu, "albedo");
    let (a, b) = (
        gpu.image.to_rgba_f32().expect("rgba"),
        bare.image.to_rgba_f32().expect("rgba"),
    );
    let tree: Vec<&[f32; 4]> = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| x != y)
        .map(|p| p.0)
        .collect();
    let leaves = tree.iter().filter(|p| green(p)).count();
    let bark = tree.len() - leaves;
    let n = a.len();
    eprintln!(
        "forest camera: {} of {n} pixels are trees ({leaves} leaves, {bark} bark); G-buffer draws {} (GPU) {} (CPU), shadow draws {} {}",
        tree.len(),
        gpu.gbuffer_draws,
        cpu.gbuffer_draws,
        gpu.shadows.draws,
        cpu.shadows.draws
    );
    assert!(tree.len() > n / 20, "only {} tree pixels", tree.len());
    assert!(
        leaves > tree.len() / 2,
        "{leaves} leaf pixels of {}",
        tree.len()
    );
    assert!(bark > 0, "no bark pixel");
    // Impostors: most resident trees are far; the impostor view tints them.
    let imp = frame(&mut r, Culling::Gpu, "impostor");
    let imp = imp.image.to_rgba_f32().expect("rgba");
    let tinted = imp
        .iter()
        .filter(|p| p[0].max(p[1]).max(p[2]) - p[0].min(p[1]).min(p[2]) > 0.6)
        .count();
    let mut counted = common::raw_settings(&scene, SIZE, "final");
    counted.lod_threshold_px = LOD_PX;
    let levels = r.count_drawn(&camera, &counted).expect("counts").instances;
    eprintln!("{tinted} impostor pixels; camera's instances per level {levels:?}");
    // Measured 2026-12-07: 3,512 impostor pixels; instances per level
    // [4, 12, 649, 205, 614] (trunks and leaves): the far impostor (level
    // 4, 32 triangles) draws the farthest trees, the impostor the next.
    assert!(tinted > 1000, "{tinted} impostor pixels");
    assert!(levels[3] > 100 && levels[4] > 300, "{levels:?}");
}

/// V6 for trees: the G-buffer and shadow draw calls of the GPU path do not
/// depend on how many trees stand (one multi-draw per list).
#[test]
fn vegetation_draw_calls_do_not_depend_on_the_tree_count() {
    let mut counts = Vec::new();
    for density in [0.2, 0.05] {
        let w = world(density);
        let camera = common::world_camera(&w, "forest");
        let mut r = common::settled_world(&w, &camera);
        let mut s = FrameSettings::new(SIZE.0, SIZE.1, w.scene().sun);
        s.lod_threshold_px = LOD_PX;
        let f = r.render(&camera, &s).expect("frame");
        let live = r.world_stats().expect("a world").instances;
        eprintln!(
            "tree density {density}: {live} instances resident, G-buffer draws {}, shadow draws {}",
            f.gbuffer_draws, f.shadows.draws
        );
        counts.push((live, f.gbuffer_draws, f.shadows.draws));
    }
    assert!(counts[0].0 > counts[1].0 + 500, "{counts:?}");
    assert_eq!(
        (counts[0].1, counts[0].2),
        (counts[1].1, counts[1].2),
        "draw calls changed with the tree count: {counts:?}"
    );
}
