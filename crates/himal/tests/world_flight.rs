//! Streaming along the world's flight path in real time (its own test
//! binary, so no other test takes the cores the workers need).

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec2;
use himal::scene::world::stream::{StreamUpdate, Streamer};
use himal::scene::world::{InstanceKind, World, WorldDesc};

fn world_with(radius: f32, tiles: u32) -> Arc<World> {
    let mut desc = WorldDesc::default();
    desc.stream.radius = radius;
    desc.pools.tiles = tiles;
    Arc::new(World::new(desc))
}

/// Streaming along the flight: nothing grows, every sector near the
/// camera is resident on every frame, the caller's thread never waits.
#[test]
fn flight_streaming_keeps_pools_flat_and_the_surroundings_resident() {
    // Radius 384 m, detail needed within 256 m: 128 m of prefetch.
    let (radius, inner) = (384.0, 256.0);
    let w = world_with(radius, 256);
    let path = w.paths[0].clone();
    let mut s = Streamer::new(w.clone());
    let start = path.position(0.0);
    let settled = s.settle(Vec2::new(start.x, start.z), Duration::from_secs(120));
    assert_eq!(settled.stats.missing, 0, "{:?}", settled.stats);
    // 8 m per frame, frames paced at 16 ms (a 500 m/s flight at 60 Hz).
    let (step, frame) = (8.0, Duration::from_millis(16));
    let frames = (8000.0 / step) as usize;
    let (mut lo, mut hi) = (u32::MAX, 0u32);
    let (mut uploaded, mut bytes, mut worst_update) = (0u64, 0u64, 0.0f64);
    let mut updates = Vec::with_capacity(frames);
    for f in 0..frames {
        let t0 = Instant::now();
        let p = path.position(f as f32 * step);
        let eye = Vec2::new(p.x, p.z);
        let u = s.update(eye);
        updates.push(u.stats.cpu_s);
        worst_update = worst_update.max(u.stats.cpu_s);
        uploaded += u.stats.uploaded as u64;
        bytes += u.stats.upload_bytes;
        // Every sector within the inner radius is resident this frame.
        for (d, c) in s.wanted(eye).0 {
            if d <= inner {
                assert!(
                    s.resident().contains_key(&c),
                    "frame {f}: sector {c:?} at {d:.0} m not resident ({:?})",
                    u.stats
                );
            }
        }
        assert!(u.stats.tiles_used <= u.stats.tiles_total);
        if f % 100 == 0 {
            check_instance_slots(&s, &u);
        }
        let per_worker = himal::scene::world::stream::MAX_IN_FLIGHT_PER_WORKER;
        assert!(u.stats.in_flight as usize <= per_worker * himal::scene::world::worker_count(0));
        // Warm-up: until the resident ring behind the camera (the unload
        // margin, 128 m) has formed.
        if f >= 64 {
            lo = lo.min(u.stats.tiles_used);
            hi = hi.max(u.stats.tiles_used);
        }
        if let Some(rest) = frame.checked_sub(t0.elapsed()) {
            std::thread::sleep(rest);
        }
    }
    updates.sort_by(f64::total_cmp);
    let median = updates[updates.len() / 2];
    eprintln!(
        "flight {frames} frames x {step} m: tiles in use [{lo}, {hi}] of 256, {uploaded} sectors \
         uploaded ({:.1} MB), Streamer::update median {:.3} ms, worst {:.3} ms",
        bytes as f64 / 1e6,
        median * 1e3,
        worst_update * 1e3
    );
    // The wanted disc keeps its area along the path (it stays 600 m inside
    // the edges): resident tiles flat within 10 %.
    assert!(hi as f32 <= 1.1 * lo as f32, "pool use [{lo}, {hi}]");
    // Measured median 0.044 ms on 2 cores (2026-12-02), the worst frame a
    // few ms only when the tests beside it take the core: the caller's
    // thread does bookkeeping only. 0.5 ms would be a thirtieth of a frame.
    assert!(median < 0.0005, "Streamer::update median {median} s");
}

/// Every resident instance sits at the slot its sector records, the slot
/// names it back, and the regions are packed (live = resident instances).
fn check_instance_slots(s: &Streamer, u: &StreamUpdate) {
    let mut live = [0u32; InstanceKind::ALL.len()];
    for r in s.resident().values() {
        for (k, slots) in r.slots.iter().enumerate() {
            live[k] += slots.len() as u32;
            for (i, &slot) in slots.iter().enumerate() {
                let want = &r.data.instances[r.by_kind[k][i] as usize];
                assert_eq!(s.instance(InstanceKind::ALL[k], slot), Some(want));
            }
        }
    }
    assert_eq!(live.to_vec(), u.live, "regions not packed");
}

/// Trees resident along the flight with the default radius (1 km) and
/// pools: the forests of issue #18 item 6 (at least 50,000 trees in the
/// world at once), every wanted sector placed (no pool over capacity).
#[test]
fn the_default_pools_hold_the_forests_along_the_flight() {
    let w = Arc::new(World::new(WorldDesc::default()));
    let path = w.paths[0].clone();
    let mut s = Streamer::new(w.clone());
    let (larch, rose) = (
        InstanceKind::Larch as usize,
        InstanceKind::Rosewood as usize,
    );
    let cap = |k: usize| w.desc.pools.instances[k];
    let (mut most, mut least, mut peak) = (0u32, u32::MAX, [0u32; 2]);
    let t0 = Instant::now();
    for k in 0..=8 {
        let p = path.position(k as f32 * 1000.0);
        let u = s.settle(Vec2::new(p.x, p.z), Duration::from_secs(300));
        assert_eq!(
            (u.stats.missing, u.stats.over_capacity),
            (0, 0),
            "{:?}",
            u.stats
        );
        let (l, r) = (u.live[larch], u.live[rose]);
        let mut ys: Vec<f32> = (s.resident().values())
            .flat_map(|r| r.data.instances.iter())
            .filter(|i| i.kind.species().is_some())
            .map(|i| i.position.y)
            .collect();
        ys.sort_by(f32::total_cmp);
        let q = |f: f32| {
            ys.get((f * ys.len() as f32) as usize)
                .copied()
                .unwrap_or(0.0)
        };
        eprintln!(
            "        tree heights {:.0} / {:.0} / {:.0} / {:.0} / {:.0} m (0, 25, 50, 75, 99 %)",
            q(0.0),
            q(0.25),
            q(0.5),
            q(0.75),
            q(0.99)
        );
        eprintln!(
            "{:>5.0} m: {l} larches, {r} rosewoods resident",
            k as f32 * 1000.0
        );
        peak = [peak[0].max(l), peak[1].max(r)];
        if l + r > most {
            most = l + r;
        }
        least = least.min(l + r);
    }
    eprintln!(
        "trees resident along the flight: {least}..{most}; peaks {} of {} larch and {} of {} rosewood slots ({:.1} s)",
        peak[0],
        cap(larch),
        peak[1],
        cap(rose),
        t0.elapsed().as_secs_f64()
    );
    assert!(most >= 50_000, "at most {most} trees resident");
    // Headroom: a denser stretch than the flight's still fits.
    assert!(peak[0] < cap(larch) && peak[1] < cap(rose));
}
