//! S3 atlas allocator properties over random light sets (CPU): tiles never
//! overlap and stay inside the atlas, more important lights never get
//! smaller tiles, and tiles stay put while lights move a little.

mod common;

use common::Lcg;
use glam::Vec3;
use himal::passes::shadows::atlas::{AtlasAllocator, AtlasRequest, AtlasTile, importance};

fn random_requests(rng: &mut Lcg, n: usize) -> Vec<AtlasRequest> {
    (0..n)
        .map(|i| AtlasRequest {
            light: i as u32,
            faces: if rng.next() < 0.6 { 6 } else { 1 },
            importance: rng.next().powi(2),
        })
        .collect()
}

fn check_layout(a: &AtlasAllocator, tiles: &[AtlasTile]) {
    for (i, t) in tiles.iter().enumerate() {
        assert!(
            t.x + t.size <= a.size && t.y + t.size <= a.size,
            "{t:?} outside"
        );
        assert!(t.size.is_power_of_two() && t.size >= a.min_tile && t.size <= a.max_tile);
        for o in &tiles[i + 1..] {
            assert!(!t.overlaps(o), "{t:?} overlaps {o:?}");
        }
    }
}

#[test]
fn tiles_never_overlap_and_follow_importance() {
    let mut rng = Lcg(3);
    let (mut dropped, mut shrunk) = (0, 0);
    for case in 0..300 {
        // Fresh allocator: no hysteresis, so the order is strict.
        // 512² of 32² units: 256 faces at most, so the larger sets crowd it.
        let mut a = AtlasAllocator::new(512, 32, 256);
        let n = 1 + (rng.next() * 60.0) as usize;
        let req = random_requests(&mut rng, n);
        let tiles = a.allocate(&req);
        check_layout(&a, &tiles);
        let size_of = |l: u32| tiles.iter().find(|t| t.light == l).map(|t| t.size);
        for r in &req {
            let faces = tiles.iter().filter(|t| t.light == r.light).count();
            assert!(
                faces == 0 || faces == r.faces as usize,
                "case {case}: light {} has {faces} faces",
                r.light
            );
            for o in &req {
                if r.importance > o.importance {
                    match (size_of(r.light), size_of(o.light)) {
                        (Some(a), Some(b)) => {
                            assert!(a >= b, "case {case}: {r:?} ({a}) < {o:?} ({b})")
                        }
                        // Only the least important lose their shadows.
                        (None, Some(_)) => panic!("case {case}: {r:?} dropped before {o:?}"),
                        _ => {}
                    }
                }
            }
            dropped += usize::from(faces == 0);
        }
        // Crowded: every tile at the minimum although some light wanted more.
        shrunk += usize::from(
            tiles.iter().all(|t| t.size == a.min_tile) && req.iter().any(|r| r.importance > 0.5),
        );
    }
    // The random sets must reach the crowded cases too (measured 2026-11-22:
    // 10 lights without a tile, 13 cases all at the minimum tile).
    eprintln!("300 cases: {dropped} lights without a tile, {shrunk} cases at the minimum tile");
    assert!(dropped > 0 && shrunk > 0);
}

#[test]
fn tiles_stay_put_while_lights_move() {
    let mut rng = Lcg(11);
    // Lights whose importance sits exactly on a tile-size boundary
    // (max_tile · range / distance = a power of two): the worst case.
    let lights: Vec<(Vec3, f32, u32)> = (0..12)
        .map(|i| {
            let range = 6.0 + rng.next() * 10.0;
            let d = range * 2f32.powi(1 + i % 4);
            let a = rng.next() * std::f32::consts::TAU;
            let p = Vec3::new(a.cos() * d, 2.0, a.sin() * d);
            (p, range, if rng.next() < 0.6 { 6 } else { 1 })
        })
        .collect();
    let mut a = AtlasAllocator::new(4096, 64, 1024);
    let camera = Vec3::new(0.0, 2.0, 0.0);
    let (mut prev, mut changed) = (Vec::new(), 0);
    let frames = 200;
    for f in 0..frames {
        // Lights sway by up to 1.5 m (lanterns in the wind, a carried torch).
        let req: Vec<AtlasRequest> = lights
            .iter()
            .enumerate()
            .map(|(i, (p, r, faces))| {
                let sway = p.normalize() * (f as f32 * 0.3 + i as f32).sin() * 1.5;
                AtlasRequest {
                    light: i as u32,
                    faces: *faces,
                    importance: importance(*p + sway, *r, camera),
                }
            })
            .collect();
        let mut tiles = a.allocate(&req);
        check_layout(&a, &tiles);
        tiles.sort_by_key(|t| (t.light, t.face));
        changed += usize::from(f > 0 && tiles != prev);
        prev = tiles;
    }
    eprintln!("{frames} frames: layout changed in {changed}");
    // Measured 2026-11-22: changed in 2 of 200 frames; without the
    // hysteresis band (wish within [-0.25, +1.25) of last frame's level) 129.
    // Threshold 5.
    assert!(
        changed <= 5,
        "layout changed in {changed} of {frames} frames"
    );
}
