//! The streamed world on the GPU: the pool regions that streaming fills
//! are culled on the GPU exactly as the CPU twin culls them, every live
//! slot and nothing else is listed, and a world frame draws the same bytes
//! twice.

mod common;

use std::sync::Arc;
use std::time::Duration;

use glam::Vec2;
use himal::gpu_scene::{LodView, SceneGpu};
use himal::passes::cull::{CullPass, CullView, reference};
use himal::renderer::WorldState;
use himal::scene::world::{InstanceKind, World, WorldDesc};
use himal::{FrameSettings, Renderer};

/// A world streamed 256 m around its cameras, with small pools.
fn small_world() -> Arc<World> {
    let mut desc = WorldDesc::default();
    desc.stream.radius = 256.0;
    desc.pools.tiles = 128;
    desc.pools.instances = [1024, 1024, 1024, 256, 256, 64, 1024, 4096, 256];
    Arc::new(World::new(desc))
}

#[test]
fn streamed_pool_lists_match_the_twin() {
    let ctx = common::context();
    let world = small_world();
    let scene = world.scene();
    let pool = himal::renderer::world_pools(&world);
    let gpu = SceneGpu::upload_with_pool(&ctx, &scene, &pool).expect("upload");
    let mut cull = CullPass::new(&ctx, &gpu).expect("cull pass");
    cull.supported().expect("lavapipe draws indirectly");
    let mut state = WorldState::new(world.clone(), &scene);
    let camera = world
        .cameras
        .iter()
        .find(|c| c.name == "village")
        .expect("camera");
    let eye = camera.camera.position;
    let u = state
        .streamer
        .settle(Vec2::new(eye.x, eye.z), Duration::from_secs(120));
    state
        .apply(&u, &gpu, &mut cull, None, &ctx.queue)
        .expect("apply");
    // Then fly 300 m on: sectors leave, slots move, new ones arrive.
    let on = Vec2::new(eye.x + 300.0, eye.z - 100.0);
    let u2 = state.streamer.settle(on, Duration::from_secs(120));
    assert!(!u2.evictions.is_empty() && !u2.uploads.is_empty());
    state
        .apply(&u2, &gpu, &mut cull, None, &ctx.queue)
        .expect("apply");
    let live: u32 = u2.live.iter().sum();
    assert!(live > 200, "only {live} instances resident");
    let cam = camera.camera.clone();
    let mut moved = cam.clone();
    moved.position = glam::Vec3::new(on.x, cam.position.y, on.y);
    let views = vec![
        CullView::clip(cam.view_projection(16.0 / 9.0)),
        CullView::clip(moved.view_projection(16.0 / 9.0)),
        // Everything: a view with only keep-all planes but one far away.
        CullView::clip(
            glam::camera::rh::proj::directx::orthographic(
                -3000.0, 3000.0, -3000.0, 3000.0, -5000.0, 5000.0,
            ) * glam::camera::rh::view::look_to_mat4(
                glam::Vec3::new(on.x, 4000.0, on.y),
                glam::Vec3::NEG_Y,
                glam::Vec3::Z,
            ),
        ),
    ];
    // The eye where the pools were streamed: every resident rock and fence
    // is within its class's draw distance.
    let lod = LodView {
        eye: moved.position,
        ..LodView::default()
    };
    let got = cull.read_back(&ctx, &views, lod).expect("GPU lists");
    let want = reference::cull(&cull.layout, &views, &lod);
    assert_eq!(
        got.args, want.args,
        "indirect arguments differ from the twin"
    );
    assert_eq!(
        got.instances, want.instances,
        "instance lists differ from the twin"
    );
    // The top-down view over 6 km sees every live instance: one entry each.
    let l = &cull.layout;
    let per_view = l.batches.len() * himal::passes::cull::LISTS;
    let listed: u32 = got.args[2 * per_view..3 * per_view]
        .iter()
        .map(|a| a[1])
        .sum();
    assert_eq!(
        listed, live,
        "the whole-world view lists {listed} of {live} live instances"
    );
    // And only live slots: each listed object lies inside its region's live prefix.
    for (k, r) in gpu.pool.iter().enumerate() {
        let live_k = u2.live[k];
        for list in &got.instances[2 * per_view..3 * per_view] {
            for &e in list {
                let o = e & 0x00ff_ffff;
                if (r.first_object..r.first_object + r.capacity).contains(&o) {
                    assert!(
                        o - r.first_object < live_k,
                        "{} slot {} listed past live {live_k}",
                        InstanceKind::ALL[k].name(),
                        o - r.first_object
                    );
                }
            }
        }
    }
    // Per-class distance culling: from an eye 600 m on, rocks and fences
    // beyond their draw distance leave every view; other kinds stay.
    let far_eye = moved.position + glam::Vec3::new(600.0, 0.0, 0.0);
    let far = LodView {
        eye: far_eye,
        ..LodView::default()
    };
    let all = &views[2..];
    let got_far = cull.read_back(&ctx, all, far).expect("GPU lists");
    let l = &cull.layout;
    let want_far = reference::cull(&cull.layout, all, &far);
    assert_eq!(
        got_far.instances, want_far.instances,
        "distance culling differs from the twin"
    );
    let mut dropped = 0;
    for (k, r) in gpu.pool.iter().enumerate() {
        let kind = InstanceKind::ALL[k];
        let max = kind.draw_distance();
        let within = (0..u2.live[k])
            .filter(|&s| {
                let b = &l.bounds[(r.first_object + s) as usize];
                let d = himal::scene::lod::distance_to_box(far_eye, b.center(), b.half_extent());
                max == 0.0 || d <= max
            })
            .count();
        let region = r.first_object..r.first_object + r.capacity;
        let listed = (got_far.instances.iter().flatten())
            .filter(|&&e| region.contains(&(e & 0x00ff_ffff)))
            .count();
        assert_eq!(
            listed,
            within,
            "{}: listed {listed}, within its draw distance {within}",
            kind.name()
        );
        dropped += u2.live[k] as usize - within;
    }
    assert!(
        dropped > 0,
        "no instance was beyond its class's draw distance"
    );
    eprintln!(
        "pool: {live} live instances of {}; camera keeps {}; {dropped} culled by distance from 600 m on",
        pool.iter().map(|p| p.capacity).sum::<u32>(),
        got.args[..per_view].iter().map(|a| a[1]).sum::<u32>()
    );
}

#[test]
fn a_world_frame_is_the_same_twice_and_draws_the_village() {
    let world = small_world();
    let camera = world
        .cameras
        .iter()
        .find(|c| c.name == "village")
        .expect("camera")
        .camera
        .clone();
    let settings = FrameSettings::new(160, 90, world.scene().sun);
    let render = || {
        let mut r = Renderer::with_world(common::context(), world.clone()).expect("renderer");
        let stats = r
            .settle_world(&camera, Duration::from_secs(120))
            .expect("streaming")
            .expect("a world");
        assert_eq!(stats.missing, 0);
        r.render(&camera, &settings).expect("frame")
    };
    let (a, b) = (render(), render());
    assert_eq!(
        a.image.bytes, b.image.bytes,
        "a world frame differs between runs"
    );
    assert_eq!(a.culling, himal::Culling::Gpu);
    // The village's houses fill part of the frame: pixels differ from the sky's.
    let px = |i: usize| &a.image.bytes[4 * i..4 * i + 3];
    let n = (settings.width * settings.height) as usize;
    let sky = px(0).to_vec();
    let differ = (0..n).filter(|&i| px(i) != sky.as_slice()).count();
    eprintln!("{differ} of {n} pixels differ from the top-left pixel");
    assert!(
        differ > n / 20,
        "the frame is nearly empty ({differ} pixels)"
    );
}
