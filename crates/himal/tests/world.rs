//! The open world (`scene::world`): per-sector generation is deterministic
//! and independent, the world has its features, and streaming along the
//! flight path keeps the pools flat and the camera's surroundings resident.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec2;
use himal::scene::world::{
    InstanceKind, SECTOR_SIZE, SectorCoord, TILE_RES, World, WorldDesc, stream::Streamer,
};

fn world_with(radius: f32, tiles: u32) -> Arc<World> {
    let mut desc = WorldDesc::default();
    desc.stream.radius = radius;
    desc.pools.tiles = tiles;
    Arc::new(World::new(desc))
}

#[test]
fn sectors_are_deterministic_independent_and_seamless() {
    let w = World::new(WorldDesc::default());
    let a = SectorCoord { x: 80, z: 80 };
    let b = SectorCoord { x: 81, z: 80 };
    let c = SectorCoord { x: 80, z: 81 };
    let t0 = Instant::now();
    let first = w.sector(a);
    let gen_s = t0.elapsed().as_secs_f64();
    let _ = w.sector(b);
    assert_eq!(first, w.sector(a), "a sector differs when generated again");
    // A second world from the same description: nothing depends on history.
    let other = World::new(WorldDesc::default());
    assert_eq!(first, other.sector(a));
    let (right, below) = (w.sector(b), w.sector(c));
    for k in 0..TILE_RES {
        let edge = first.heights[k * TILE_RES + TILE_RES - 1];
        assert_eq!(
            edge.to_bits(),
            right.heights[k * TILE_RES].to_bits(),
            "east seam row {k}"
        );
        let edge = first.heights[(TILE_RES - 1) * TILE_RES + k];
        assert_eq!(
            edge.to_bits(),
            below.heights[k].to_bits(),
            "south seam column {k}"
        );
    }
    eprintln!(
        "sector {:?}: {} instances, heights [{:.1}, {:.1}] m, generated in {:.1} ms",
        a,
        first.instances.len(),
        first.min_height,
        first.max_height,
        gen_s * 1e3
    );
}

#[test]
fn the_world_has_mountains_river_villages_forests_and_rocks() {
    let w = World::new(WorldDesc::default());
    let t = &w.terrain;
    let villages = t.villages().count();
    assert!(villages >= 20, "{villages} villages");
    // The village nearest the middle: its sectors hold houses, roofs, fields and fences.
    let v = t
        .villages()
        .min_by(|a, b| a.center.length().total_cmp(&b.center.length()))
        .copied()
        .expect("a village");
    let mut counts = [0usize; InstanceKind::ALL.len()];
    let mut max_height = f32::MIN;
    let c = w.sector_at(v.center).expect("village inside the world");
    for dz in -3i32..=3 {
        for dx in -3i32..=3 {
            let s = SectorCoord {
                x: (c.x as i32 + dx) as u16,
                z: (c.z as i32 + dz) as u16,
            };
            for i in w.sector(s).instances {
                counts[i.kind as usize] += 1;
                // Village buildings stand on the levelled ground.
                if i.kind == InstanceKind::HouseWalls {
                    assert!((i.position.y - v.height).abs() < 1e-3);
                }
            }
        }
    }
    // Over a line of sectors across the world: forests, rocks and snow-capped peaks.
    for x in (0..160).step_by(4) {
        for z in [40u16, 80, 120] {
            let s = w.sector(SectorCoord { x, z });
            max_height = max_height.max(s.max_height);
            for i in s.instances {
                counts[i.kind as usize] += 1;
            }
        }
    }
    eprintln!(
        "villages {villages}; instances by kind {:?}; highest sampled ground {max_height:.0} m",
        InstanceKind::ALL
            .iter()
            .map(|k| (k.name(), counts[*k as usize]))
            .collect::<Vec<_>>()
    );
    for k in InstanceKind::ALL {
        assert!(
            counts[k as usize] > 0,
            "no {} in the sampled sectors",
            k.name()
        );
    }
    assert!(
        max_height > w.desc.shape.snow_line,
        "no ground above the snow line"
    );
    // The river: its bed lies below the water all the way across the world.
    for i in 0..100 {
        let z = -5000.0 + i as f32 * 100.0;
        let x = t.river_x(z);
        assert!(t.height(x, z) < t.river_level(z), "dry river at z {z}");
    }
}

#[test]
fn cameras_and_the_flight_path_cover_the_world() {
    let w = World::new(WorldDesc::default());
    let names: Vec<&str> = w.cameras.iter().map(|c| c.name.as_str()).collect();
    for n in ["air", "river", "village", "peak", "grazing", "top"] {
        assert!(names.contains(&n), "camera {n} missing: {names:?}");
    }
    for c in &w.cameras {
        let p = c.camera.position;
        let ground = w.terrain.height(p.x, p.z);
        assert!(
            p.y > ground,
            "camera {} below ground ({} < {ground})",
            c.name,
            p.y
        );
    }
    let path = &w.paths[0];
    assert_eq!(path.name, "across");
    assert!(path.length() >= 8000.0, "flight only {} m", path.length());
    // Above the ground all along (sampled every 10 m).
    let mut s = 0.0;
    while s < path.length() {
        let p = path.position(s);
        assert!(
            p.y > w.terrain.height(p.x, p.z) + 20.0,
            "path at {s} m is {p}"
        );
        s += 10.0;
    }
}

#[test]
fn full_pools_keep_the_nearest_sectors() {
    // 40 tiles for a disc of ~150 sectors.
    let w = world_with(400.0, 40);
    let mut s = Streamer::new(w.clone());
    let eye = Vec2::new(100.0, -300.0);
    let u = s.settle(eye, Duration::from_secs(60));
    assert_eq!(u.stats.tiles_used, 40);
    assert!(u.stats.over_capacity > 100, "{:?}", u.stats);
    let (wanted, _) = s.wanted(eye);
    let nearest: std::collections::BTreeSet<SectorCoord> = wanted.iter().map(|w| w.1).collect();
    let resident: std::collections::BTreeSet<SectorCoord> = s.resident().keys().copied().collect();
    assert_eq!(nearest, resident);
    // Moving on: the pool stays full, the farthest go first.
    let eye2 = eye + Vec2::new(0.0, -3.0 * SECTOR_SIZE);
    let u2 = s.settle(eye2, Duration::from_secs(60));
    assert_eq!(u2.stats.tiles_used, 40);
    assert!(!u2.evictions.is_empty());
    let far = u2
        .evictions
        .iter()
        .map(|e| w.sector_distance(e.coord, eye2))
        .fold(f32::MAX, f32::min);
    let kept = s
        .resident()
        .keys()
        .map(|&c| w.sector_distance(c, eye2))
        .fold(0.0, f32::max);
    assert!(
        far >= kept,
        "evicted a sector at {far} m, kept one at {kept} m"
    );
}

#[test]
fn settling_is_the_same_on_every_run() {
    let w = world_with(300.0, 128);
    let eye = Vec2::new(-700.0, 1200.0);
    let layout = |s: &Streamer| {
        let mut v: Vec<(SectorCoord, u32, Vec<Vec<u32>>)> = s
            .resident()
            .iter()
            .map(|(c, r)| (*c, r.tile, r.slots.clone()))
            .collect();
        v.sort_by_key(|e| e.0);
        v
    };
    let mut a = Streamer::new(w.clone());
    a.settle(eye, Duration::from_secs(60));
    let mut b = Streamer::new(w.clone());
    b.settle(eye, Duration::from_secs(60));
    assert!(!layout(&a).is_empty());
    assert_eq!(layout(&a), layout(&b));
}

/// A listener's record of the resident set (the L5/L2/S2 hook).
#[derive(Default)]
struct Mirror {
    resident: std::collections::BTreeSet<SectorCoord>,
    loads: usize,
}

struct Listener(Arc<std::sync::Mutex<Mirror>>);

impl himal::scene::world::stream::SectorListener for Listener {
    fn loaded(&mut self, sector: &Arc<himal::scene::world::SectorData>) {
        let mut m = self.0.lock().unwrap();
        assert!(
            m.resident.insert(sector.coord),
            "{:?} loaded twice",
            sector.coord
        );
        m.loads += 1;
    }
    fn evicted(&mut self, sector: SectorCoord) {
        let mut m = self.0.lock().unwrap();
        assert!(
            m.resident.remove(&sector),
            "{sector:?} evicted, never loaded"
        );
    }
}

/// Sector listeners follow the streaming: one added late is first told of
/// what is resident, and after every update both mirror the resident set.
#[test]
fn sector_listeners_mirror_the_resident_set() {
    let w = world_with(300.0, 128);
    let mut s = Streamer::new(w.clone());
    let early = Arc::new(std::sync::Mutex::new(Mirror::default()));
    s.add_listener(Box::new(Listener(early.clone())));
    let path = &w.paths[0];
    let eye = |t: f32| {
        let p = path.camera_at(t, 60.0).position;
        Vec2::new(p.x, p.z)
    };
    s.settle(eye(0.0), Duration::from_secs(60));
    let late = Arc::new(std::sync::Mutex::new(Mirror::default()));
    s.add_listener(Box::new(Listener(late.clone())));
    let resident = |s: &Streamer| -> std::collections::BTreeSet<SectorCoord> {
        s.resident().keys().copied().collect()
    };
    assert_eq!(late.lock().unwrap().resident, resident(&s));
    // 40 frames at 20 m each: sectors come and go.
    for i in 1..=40 {
        s.update(eye(i as f32 / 3.0));
        std::thread::sleep(Duration::from_millis(5));
        for m in [&early, &late] {
            assert_eq!(m.lock().unwrap().resident, resident(&s), "frame {i}");
        }
    }
    let loads = early.lock().unwrap().loads;
    assert!(
        loads > resident(&s).len(),
        "no sector came or went ({loads} loads)"
    );
}
