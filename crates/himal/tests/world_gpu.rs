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

/// L2 follows the streaming: a frame drawn before the street's sectors
/// arrive renders sky-occlusion height fields of the coarse terrain alone;
/// once the sectors stream in, those height fields are rendered again
/// (nothing else changed) and hold the terrain's tiles and the pool
/// instances: every texel between the terrain and the tallest box over it,
/// the bare ground equal to the CPU height data, houses, roofs and rocks
/// standing out of it.
#[test]
fn sky_occlusion_height_fields_hold_terrain_and_instances_and_follow_streaming() {
    use himal::passes::skyocc::{RENDER_TEXELS, SkyOccPass, TEXEL_SIZE};
    let world = small_world();
    let camera = world
        .cameras
        .iter()
        .find(|c| c.name == "street")
        .expect("camera")
        .camera
        .clone();
    let mut settings = FrameSettings::new(96, 54, world.scene().sun);
    settings.sky_occlusion = true;
    let aspect = 96.0 / 54.0;
    let mut r = Renderer::with_world(common::context(), world.clone()).expect("renderer");
    // Resident far away first: nothing near the street.
    let mut away = camera.clone();
    away.position.x += 2000.0;
    r.settle_world(&away, Duration::from_secs(120))
        .expect("streaming");
    let first = r.render(&camera, &settings).expect("frame");
    let missing = r.world_stats().expect("a world").missing;
    assert!(missing > 0, "the street's sectors arrived within one frame");
    assert!(first.sky_occlusion.rendered > 0);
    r.settle_world(&camera, Duration::from_secs(120))
        .expect("streaming");
    let again = r.render(&camera, &settings).expect("frame");
    let wanted = r.sky_occlusion().wanted(&camera, aspect);
    eprintln!(
        "sky occlusion: {} sectors rendered before the street streamed in, {} again after ({} wanted)",
        first.sky_occlusion.rendered,
        again.sky_occlusion.rendered,
        wanted.len()
    );
    assert!(again.sky_occlusion.rendered > 0, "nothing rendered again");
    // Job 0 of the last frame is the nearest wanted sector (stale ones go
    // nearest first): its raw image is the one read back.
    let sector = wanted[0];
    let back = r
        .sky_occlusion()
        .read_sector(r.context(), sector)
        .expect("read back")
        .expect("resident");
    let origin = SkyOccPass::render_origin(sector);
    let terrain = r.terrain().expect("terrain");
    let cpu = terrain.cpu();
    let scene = world.scene();
    // Every instance of the sectors under the image, as world boxes.
    let extent = RENDER_TEXELS as f32 * TEXEL_SIZE;
    let mut boxes = Vec::new();
    let mut coords = Vec::new();
    // Sectors under the image and around it (instances reach over borders).
    for dz in -1..4 {
        for dx in -1..4 {
            let p = origin + Vec2::new(dx as f32, dz as f32) * (extent / 2.0);
            if let Some(c) = world.sector_at(p).filter(|c| !coords.contains(c)) {
                coords.push(c);
            }
        }
    }
    for c in &coords {
        for i in world.sector(*c).instances {
            let b = scene.meshes[i.kind as usize]
                .bounds
                .transform(&i.transform());
            boxes.push((i.kind, b));
        }
    }
    let n = RENDER_TEXELS;
    let (mut bare, mut worst_bare, mut over, mut under) = (0, 0.0f32, 0, 0);
    for t in 0..n * n {
        let xz = origin + (Vec2::new((t % n) as f32, (t / n) as f32) + 0.5) * TEXEL_SIZE;
        let ground = cpu.heights.height(xz, false);
        let pad = TEXEL_SIZE;
        let top = boxes
            .iter()
            .filter(|(_, b)| {
                xz.x >= b.min.x - pad
                    && xz.x <= b.max.x + pad
                    && xz.y >= b.min.z - pad
                    && xz.y <= b.max.z + pad
            })
            .map(|(_, b)| b.max.y)
            .fold(f32::NEG_INFINITY, f32::max);
        let raw = back.raw[t];
        // Float32 terrain heights of ~1 km: the GPU's and the twin's
        // bilinear sums differ by a few ulps (measured 6e-5 m).
        if raw > ground.max(top) + 1e-3 {
            eprintln!("over at {xz}: raw {raw}, ground {ground}, top {top}");
            over += 1;
        }
        if raw < ground - 1e-3 {
            under += 1;
        }
        if top == f32::NEG_INFINITY {
            bare += 1;
            worst_bare = worst_bare.max((raw - ground).abs());
        }
    }
    let mut standing = 0;
    for (kind, b) in &boxes {
        use himal::scene::world::InstanceKind::*;
        let c = (b.min + b.max) * 0.5;
        let local = (Vec2::new(c.x, c.z) - origin) / TEXEL_SIZE;
        let inside = local.cmpge(Vec2::ZERO).all() && local.cmplt(Vec2::splat(n as f32)).all();
        let ground = cpu.heights.height(Vec2::new(c.x, c.z), false);
        if !inside
            || !matches!(kind, Rock0 | Rock1 | Rock2 | HouseWalls | Roof)
            || b.max.y < ground + 1.0
        {
            continue;
        }
        let raw = back.raw[local.y as usize * n + local.x as usize];
        assert!(
            raw >= ground + 0.5 * (b.max.y - ground),
            "{kind:?} at {c}: height field {raw:.2} m over ground {ground:.2} m, box top {:.2} m",
            b.max.y
        );
        standing += 1;
    }
    eprintln!(
        "sector {sector}: {} instances around, {standing} standing inside checked; {bare} bare texels, worst {worst_bare:.1e} m; {over} over the boxes, {under} under the ground",
        boxes.len()
    );
    assert!(
        standing >= 3,
        "only {standing} instances in the street's sector"
    );
    assert!(bare > n * n / 4, "only {bare} bare texels");
    assert!(worst_bare < 1e-3, "bare ground differs by {worst_bare} m");
    assert_eq!((over, under), (0, 0));
}
