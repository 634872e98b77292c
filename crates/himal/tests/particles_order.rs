//! E4 particles: the draw order inside each emitter (`particles.sort`)
//! against its CPU twin, on rings shorter and longer than one sort chunk,
//! and the particle buffers in the memory report.

mod common;

/// Renders `name`'s camera "side" and checks the GPU's draw order: every
/// ring a permutation, live slots far to near, the dead last, the same
/// permutation as the twin; with sorting off, ring order. Returns the
/// live particles.
fn check_draw_order(name: &str) -> usize {
    use himal::passes::particles::reference::draw_order;
    let (scene, camera) = common::scene_and_camera(name, "side");
    let mut r = common::renderer(&scene);
    let mut s = common::particle_settings(&scene);
    let f = r.render(&camera, &s).expect("frame");
    let ms: Vec<f64> = (f.timings.iter())
        .filter(|t| t.id == "particles.sort")
        .map(|t| t.gpu_ms)
        .collect();
    let ctx = r.context();
    let particles = r.particles().read_particles(ctx).expect("particles");
    let order = r.particles().read_order(ctx).expect("order");
    let records = r.particles().sim.records().to_vec();
    let twin = draw_order(&particles, &records, camera.position, camera.forward, true);
    let differ = order.iter().zip(&twin).filter(|(a, b)| a != b).count();
    let depth = |slot: u32| {
        let p = &particles[slot as usize];
        (p.vel_alive[3] > 0.5).then(|| {
            (glam::Vec3::from_slice(&p.pos_age[..3]) - camera.position).dot(camera.forward)
        })
    };
    let mut alive = 0;
    for e in &records {
        let [first, cap, ..] = e.slots;
        let ring = &order[first as usize..(first + cap) as usize];
        let mut sorted_ring = ring.to_vec();
        sorted_ring.sort();
        let expect: Vec<u32> = (first..first + cap).collect();
        assert_eq!(sorted_ring, expect, "{name}: not a permutation of the ring");
        let keys: Vec<Option<f32>> = ring.iter().map(|&s| depth(s)).collect();
        alive += keys.iter().flatten().count();
        for w in keys.windows(2) {
            match (w[0], w[1]) {
                (Some(a), Some(b)) => assert!(a >= b, "{name}: near before far: {a} then {b}"),
                (None, Some(_)) => panic!("{name}: a dead slot before a live one"),
                _ => {}
            }
        }
    }
    let caps: Vec<u32> = records.iter().map(|e| e.slots[1]).collect();
    println!(
        "{name}: rings {caps:?}, {alive} alive, {differ} of {} slots differ from the twin; \
         particles.sort {ms:?} ms (lavapipe)",
        order.len()
    );
    // Measured 0: the same f32 depths, a strict order (ties by slot).
    assert_eq!(differ, 0, "{name}: GPU order differs from the twin");
    // Off: ring order.
    s.particles_sort = false;
    common::render_rgba(&mut r, &camera, &s);
    let ring = r.particles().read_order(r.context()).expect("order");
    assert!(
        ring.iter().enumerate().all(|(i, &v)| v == i as u32),
        "{name}: sort off: ring order"
    );
    alive
}

#[test]
fn particles_draw_far_to_near_inside_each_emitter() {
    // 2 emitters, 384 slots: each ring one chunk.
    let alive = check_draw_order("particles_smoke");
    assert!(alive > 100, "{alive} alive");
}

#[test]
fn rings_longer_than_a_chunk_are_sorted_too() {
    // 5000 + 2048 + 100 slots: chunks of 1024 merged by rank.
    let alive = check_draw_order("particles_rings");
    assert!(alive > 6000, "{alive} alive");
}

#[test]
fn particle_buffers_are_listed_in_memory() {
    let scene = common::scene("particles_smoke");
    let r = common::renderer(&scene);
    let rows: Vec<(String, u64)> = (r.memory().into_iter())
        .filter(|(k, _)| k.starts_with("particles."))
        .collect();
    for (k, b) in &rows {
        println!("{k}: {b} B");
    }
    // 384 slots: state 32 B, light 5 x 32 B (centre, corners), order and sort key
    // 4 + 8 B; params: the uniform
    // (32 B, then V2's wind field: 16 B + 8 sources of 32 B), 2 emitter
    // records (112 B), 121 pre-warm steps of 2 emitters (64 B), 2 counter
    // pairs (8 B).
    let slots = 384u64;
    let want = [
        ("particles.state", slots * 32),
        ("particles.light", slots * 160),
        ("particles.order", slots * 12),
        (
            "particles.params",
            32 + (16 + 8 * 32) + 2 * 112 + 121 * 2 * 64 + 2 * 8,
        ),
        // The puff's layer, 128^2 RGBA8 and its mips.
        ("particles.sprites (1 layers)", 87_380),
    ];
    assert_eq!(rows.len(), want.len(), "{rows:?}");
    for ((k, b), (name, bytes)) in rows.iter().zip(want) {
        assert!(k.starts_with(name), "{k} is not {name}");
        assert_eq!(*b, bytes, "{k}");
    }
    // Particle slots are what the scene file's budget charges (204 B each).
    let total: u64 = rows.iter().take(3).map(|(_, b)| b).sum();
    assert_eq!(total, slots * himal::scene::SLOT_BYTES);
    // Without emitters: no particle buffer, no row.
    let plain = common::renderer(&common::scene("shadow_local"));
    let none: Vec<_> = (plain.memory().into_iter())
        .filter(|(k, _)| k.starts_with("particles."))
        .collect();
    assert!(none.is_empty(), "{none:?}");
}
