//! V6 instancing: the 10,000-box scene (`tests/scenes/instancing_boxes.toml`)
//! drawn with runs of one mesh's consecutive objects merged into instanced
//! draws, and the G-buffer culled to the camera's frustum, against one draw
//! per object: far fewer draw calls in the G-buffer and every shadow pass,
//! the same image (docs/techniques/V6.md).

mod common;

use himal::Renderer;

#[test]
fn instanced_draws_cut_the_calls_and_keep_the_image() {
    let (scene, camera) = common::scene_and_camera("instancing_boxes", "over");
    assert_eq!(
        scene.objects.len(),
        10_001,
        "100 rows of 100 boxes and the ground"
    );
    let mut r = Renderer::new(common::context(), &scene).expect("renderer");
    let mut s = common::raw_settings(&scene, (96, 54), "final");
    // Off: the path before V6 (one draw per object, nothing culled in the
    // G-buffer); on: the defaults (instanced runs, frustum culling).
    let mut frame = |instancing: bool| {
        s.instancing = instancing;
        s.frustum_culling = instancing;
        let f = r.render(&camera, &s).expect("frame");
        let rgba = f.image.to_rgba_f32().expect("rgba");
        (f.gbuffer_draws, f.shadows.draws, rgba)
    };
    let (g_off, sh_off, off) = frame(false);
    let (g_on, sh_on, on) = frame(true);
    eprintln!("G-buffer draws {g_off} -> {g_on}, shadow draws {sh_off} -> {sh_on}");
    // One per object without instancing (10,001 G-buffer draws; the shadow
    // cascades cull per object).
    assert_eq!(g_off, 10_001);
    assert!(sh_off > 10_000, "{sh_off}");
    // The bar: at most 1/50 of the draws. Measured 2026-12-02 at
    // 96x54: G-buffer 10,001 -> 80 (frustum culling cuts rows into runs; 2
    // without it), shadows 14,590 -> 140 (1/112 together).
    assert!(
        (g_on + sh_on) * 50 <= g_off + sh_off,
        "{g_on} + {sh_on} draws vs {g_off} + {sh_off}"
    );
    // Same visible triangles, same depth tests: the images match (culling
    // drops only boxes outside the frustum). Measured: max difference 0
    // (byte-identical); the bound leaves room for a driver that resolves
    // exactly coplanar ties by draw order.
    let worst = on
        .iter()
        .zip(&off)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, f32::max))
        .fold(0.0, f32::max);
    let mean = on
        .iter()
        .zip(&off)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f32>() / 3.0)
        .sum::<f32>()
        / on.len() as f32;
    eprintln!("instanced vs per-object image: mean {mean:.6}, worst {worst:.6}");
    assert!(mean <= 1e-3 && worst <= 0.05, "mean {mean}, worst {worst}");
}
