//! E4 particles (`passes/particles/`): the simulation against its CPU twin,
//! determinism, the capacity under a burst, the scene file's checks.

mod common;

use himal::gpu::testing::shared_context;
use himal::passes::particles::reference::simulate;
use himal::passes::particles::{ParticleGpu, ParticlesPass, births};

/// Clocks of a short run: a reset (pre-warm), frames at 30 Hz, a frame
/// without time passing, a longer step.
const CLOCKS: [f32; 6] = [
    2.0,
    2.0 + 1.0 / 30.0,
    2.0 + 2.0 / 30.0,
    2.0 + 2.0 / 30.0,
    2.2,
    2.25,
];

/// The pass after a run, the particle buffer and the counters of each frame.
type Run = (ParticlesPass, Vec<Vec<ParticleGpu>>, Vec<Vec<[u32; 2]>>);

fn run(clocks: &[f32]) -> Run {
    let ctx = shared_context().expect("GPU");
    let scene = common::scene("particles_smoke");
    let mut pass = ParticlesPass::new(ctx, &scene).expect("pass");
    let (mut states, mut counters) = (Vec::new(), Vec::new());
    for &t in clocks {
        pass.run_simulation(ctx, t).expect("simulate");
        states.push(pass.read_particles(ctx).expect("read"));
        counters.push(pass.read_counters(ctx).expect("counters"));
    }
    (pass, states, counters)
}

/// Runs `scene` over [`CLOCKS`] on the GPU and on the CPU twin; returns
/// the largest difference of position, age or velocity, the pass and the
/// twin's final particles. Counters and alive flags must agree exactly.
fn against_twin(scene: &himal::scene::Scene) -> (f32, ParticlesPass, Vec<ParticleGpu>) {
    let ctx = shared_context().expect("GPU");
    let mut pass = ParticlesPass::new(ctx, scene).expect("pass");
    let mut cpu = vec![ParticleGpu::default(); pass.sim.slots() as usize];
    let mut worst = 0.0f32;
    for &t in &CLOCKS {
        let frame = pass.run_simulation(ctx, t).expect("simulate");
        let twin_counts = simulate(&mut cpu, &frame);
        let gpu = pass.read_particles(ctx).expect("read");
        let gpu_counts = pass.read_counters(ctx).expect("counters");
        // Alive flags and counts exactly: births are integer arithmetic,
        // deaths compare ages that agree to ~1e-6 s, far from a boundary.
        assert_eq!(gpu_counts, twin_counts, "counters at t = {t}");
        for (i, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            assert_eq!(
                g.vel_alive[3], c.vel_alive[3],
                "alive flag of slot {i} at t = {t}"
            );
            let d = (0..4)
                .map(|k| {
                    (g.pos_age[k] - c.pos_age[k])
                        .abs()
                        .max((g.vel_alive[k] - c.vel_alive[k]).abs())
                })
                .fold(0.0, f32::max);
            worst = worst.max(d);
        }
    }
    (worst, pass, cpu)
}

#[test]
fn simulation_matches_cpu_twin() {
    let (worst, ..) = against_twin(&common::scene("particles_smoke"));
    println!("largest |GPU - CPU| over positions, ages, velocities: {worst:.2e}");
    // Measured 0 on lavapipe (the same f32 operations in the same order,
    // over 121 pre-warm steps); a driver that contracts to FMA may differ
    // by rounding: 1e-4 m is far below a particle's size.
    assert!(worst < 1e-4, "GPU and CPU differ by {worst}");
}

#[test]
fn two_runs_give_the_same_bytes() {
    let (_, a, ca) = run(&CLOCKS);
    let (_, b, cb) = run(&CLOCKS);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            bytemuck::cast_slice::<_, u8>(x) == bytemuck::cast_slice::<_, u8>(y),
            "frame {k} differs between runs"
        );
    }
    assert_eq!(ca, cb);
}

#[test]
fn burst_respects_capacity_and_counts() {
    let (pass, states, counters) = run(&CLOCKS);
    let emitters = &pass.sim.emitters;
    let burst = emitters
        .iter()
        .position(|e| e.name == "burst")
        .expect("burst");
    let e = &emitters[burst];
    // 2000/s over 1.5 s wants 3000 alive: the ring holds 128.
    assert!(e.rate * e.lifetime > 10.0 * e.capacity as f32);
    let mut last = None::<f64>;
    for (k, (&t, c)) in CLOCKS.iter().zip(&counters).enumerate() {
        let (alive, born) = (c[burst][0], c[burst][1]);
        assert!(alive <= e.capacity, "frame {k}: {alive} alive > capacity");
        // Births per frame: the clock's births, at most a ring's worth per
        // step (the first frame's pre-warm steps are checked by the twin test).
        if let Some(l) = last {
            assert_eq!(born, births(e, l, t as f64).spawn[1], "frame {k}: births");
        }
        // The alive counter is the number of live slots in the buffer.
        let first = (0..burst).map(|i| emitters[i].capacity).sum::<u32>() as usize;
        let slots = &states[k][first..first + e.capacity as usize];
        let live = slots.iter().filter(|p| p.vel_alive[3] > 0.5).count() as u32;
        assert_eq!(alive, live, "frame {k}: counter vs buffer");
        last = Some(t as f64);
    }
    // The smoke's ring is larger than its rate x lifetime: all alive, no loss.
    let smoke = emitters
        .iter()
        .position(|e| e.name == "smoke")
        .expect("smoke");
    let want = (emitters[smoke].rate * emitters[smoke].lifetime).round() as u32;
    let got = counters[0][smoke][0];
    assert!(got.abs_diff(want) <= 1, "smoke alive {got}, want {want}");
}

#[test]
fn emitters_draw_far_to_near() {
    let ctx = shared_context().expect("GPU");
    let scene = common::scene("particles_smoke");
    let mut pass = ParticlesPass::new(ctx, &scene).expect("pass");
    // Smoke (slots 0..256) at 9.0 m from this eye, the burst (256..384) at 10.9 m.
    pass.sort(glam::Vec3::new(0.0, 4.0, 9.0));
    assert_eq!(pass.draw_order(), &[256..384, 0..256]);
    // From the other side the smoke is farther.
    pass.sort(glam::Vec3::new(4.0, 0.5, -6.0));
    assert_eq!(pass.draw_order(), &[0..256, 256..384]);
}

#[test]
fn scene_file_checks_emitters() {
    let base = common::scene_text("particles_smoke");
    let bad = [
        (
            "capacity = 128",
            "capacity = 100000",
            "capacity = 100000 is out of range",
        ),
        ("rate = 2000.0", "rate = -1.0", "rate = -1 is out of range"),
        (
            "lifetime = 1.5",
            "lifetime = 0.0",
            "lifetime = 0 is out of range",
        ),
        ("size = [0.1, 0.05]", "size = [0.1]", "2 numbers"),
        (
            "color_end = [0.3, 0.1, 0.05, 0.0]",
            "color_end = [0.3, 0.1, 0.05, 2.0]",
            "alpha in [0, 1]",
        ),
        ("name = \"burst\"", "name = \"smoke\"", "defined twice"),
        ("wind = 0.1", "wind = nan", "wind = NaN is out of range"),
    ];
    for (from, to, want) in bad {
        let text = base.replacen(from, to, 1);
        assert_ne!(text, base, "{from} not in the scene");
        let e = himal::scene::Scene::from_toml_str(
            &text,
            "particles_smoke.toml",
            &common::scenes_dir(),
        )
        .err()
        .unwrap_or_else(|| panic!("{to} accepted"))
        .to_string();
        assert!(
            e.contains("particles_smoke.toml") && e.contains(want),
            "{to}: {e}"
        );
    }
}

const GATHER_KERNEL: &str = r#"
#import shadow

@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<f32>;
@group(0) @binding(2) var map: texture_depth_2d_array;
@group(0) @binding(3) var cmp: sampler_comparison;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= arrayLength(&input)) {
        return;
    }
    output[i] = shadow_gather_4x4(map, cmp, 0, input[i].xy, input[i].z);
}
"#;

#[test]
fn gather_filter_matches_cpu_twin() {
    use himal::passes::shadows::reference::DepthMap;
    const N: u32 = 16;
    // Depths on a 1/16 grid, queries halfway between: no comparison ties.
    let mut rng = common::Lcg(11);
    let stored: Vec<u16> = (0..N * N)
        .map(|_| ((rng.next() * 16.0).floor() / 16.0 * 65535.0).round() as u16)
        .collect();
    let depth: Vec<f32> = stored.iter().map(|&s| s as f32 / 65535.0).collect();
    let queries: Vec<[f32; 4]> = (0..512)
        .map(|_| {
            [
                rng.next(),
                rng.next(),
                ((rng.next() * 16.0).floor() + 0.5) / 16.0,
                0.0,
            ]
        })
        .collect();
    let bytes = common::run_depth_map_kernel(
        GATHER_KERNEL,
        &stored,
        N,
        &queries,
        4 * queries.len() as u64,
    );
    let gpu: &[f32] = bytemuck::cast_slice(&bytes);
    let map = DepthMap {
        width: N,
        height: N,
        depth: &depth,
    };
    let (mut worst, mut partial) = (0.0f32, 0);
    for (q, g) in queries.iter().zip(gpu) {
        let c = map.gather_4x4(glam::Vec2::new(q[0], q[1]), q[2]);
        worst = worst.max((c - g).abs());
        partial += usize::from(c > 0.0 && c < 1.0);
    }
    println!("4x4 gather: largest |GPU - CPU| {worst:.2e}, {partial} of 512 partly lit");
    // Measured 1.2e-7 on lavapipe: the same f32 weights over exact 0/1
    // comparisons (gathers do not filter), summed in another order.
    assert!(worst < 1e-5, "gather filter differs by {worst}");
    assert!(partial > 100, "too few penumbra queries: {partial}");
}

fn settings(scene: &himal::scene::Scene) -> himal::FrameSettings {
    common::particle_settings(scene)
}

fn luminance(p: &[f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// Must-show (issue #21): a white diffuse particle and a white diffuse
/// surface of the world side by side under sun, sky and a point light.
#[test]
fn a_white_particle_is_lit_like_a_white_wall() {
    let (scene, camera) = common::scene_and_camera("particles_consistency", "front");
    let mut r = common::renderer(&scene);
    let (w, h) = (160usize, 120usize);
    let mut s = common::raw_settings(&scene, (w as u32, h as u32), "lighting");
    s.ao.mode = himal::passes::ao::AoMode::Off;
    s.time_s = 1.0;
    let sun = |r: &himal::Renderer| r.sky_light().map(|l| (l.sun_direction, l.sun_illuminance));
    let on = common::render_rgba(&mut r, &camera, &s);
    let (dir, e_sun) = sun(&r).expect("sun");
    assert!(dir.z > 0.1, "the sun must light the +z faces: {dir}");
    let mut off_s = s.clone();
    off_s.particles = false;
    let off = common::render_rgba(&mut r, &camera, &off_s);
    // The particle's centre: the mean of the pixels it changed.
    let changed: Vec<(usize, usize)> = (0..w * h)
        .filter(|&i| (luminance(&on[i]) - luminance(&off[i])).abs() > 1e-3)
        .map(|i| (i % w, i / w))
        .collect();
    assert!(
        changed.len() > 20,
        "particle covers {} pixels",
        changed.len()
    );
    let n = changed.len() as f32;
    let cx = (changed.iter().map(|p| p.0 as f32).sum::<f32>() / n).round() as usize;
    let cy = (changed.iter().map(|p| p.1 as f32).sum::<f32>() / n).round() as usize;
    // The wall point mirrored about x = 0 (the camera sits on that plane).
    let (mx, my) = (w - 1 - cx, cy);
    let mean = |img: &[[f32; 4]], x: usize, y: usize| {
        let mut sum = 0.0;
        for dy in 0..2 {
            for dx in 0..2 {
                sum += luminance(&img[(y + dy - 1) * w + x + dx - 1]);
            }
        }
        sum / 4.0
    };
    let wall = mean(&on, mx, my);
    let rel = |particle: f32| (particle - wall).abs() / wall;
    let particle = mean(&on, cx, cy);
    let mut probe_s = s.clone();
    probe_s.particles_probe_ambient = true;
    let probe = mean(&common::render_rgba(&mut r, &camera, &probe_s), cx, cy);
    println!(
        "sun {dir} {e_sun}: wall ({mx}, {my}) luminance {wall:.4}; particle ({cx}, {cy}) {particle:.4} \
         ({:.2} %), with the probe's lowest mip as ambient {probe:.4} ({:.2} %)",
        100.0 * rel(particle),
        100.0 * rel(probe)
    );
    // The issue's bar: at most 5 % apart (measured 2.6 %: the particle gets
    // the wall's sun, lamp and sky terms; what is left is the wall's rough
    // specular). Ryse's probe-mip ambient lacks the SH's ground bounce of
    // the sun here: measured 11.9 % darker, so it is not the default.
    assert!(
        rel(particle) <= 0.05,
        "particle {particle} vs wall {wall}: {:.1} %",
        100.0 * rel(particle)
    );
    assert!(probe < particle, "the probe ambient was not used");
}

/// Must-show (issue #21): per-vertex lighting (the quad's centre and
/// corners, interpolated) and lighting once per particle, each against the
/// per-pixel reference of the same particles: the image difference (FLIP
/// mean over the particles' pixels, and the raw HDR's relative
/// difference) and the cost of the lighting paths, frames interleaved; by
/// day (sun, a distant lamp) and by night with the lamp inside the plume
/// (its light varies across a quad). `HIMAL_PARTICLE_FRAMES` sets the
/// timed frames per path (default 4).
#[test]
fn per_vertex_and_per_particle_light_against_per_pixel() {
    let night = [
        ("time = \"15:00\"", "time = \"23:30\""),
        ("position = [1.5, 2.5, 1.0]", "position = [0.6, 4.5, 0.8]"),
    ];
    let vertex = |_: &mut himal::FrameSettings| {};
    let centre = |s: &mut himal::FrameSettings| s.particles_light_corners = false;
    let per_pixel = |s: &mut himal::FrameSettings| s.particles_per_pixel = true;
    // [day, night] x [per vertex, per particle]: (FLIP, HDR apart).
    let mut flips = Vec::new();
    for (label, overrides) in [("day", &[][..]), ("night, lamp in the plume", &night[..])] {
        let scene = common::scene_with("particles_smoke", overrides);
        let camera = scene.camera("side").expect("camera").clone();
        let mut row = Vec::new();
        let paths: [(&str, &SetPath); 2] = [("per vertex", &vertex), ("per particle", &centre)];
        for (path, base) in paths {
            let label = format!("{label}, {path}");
            let (flip, rel, covered) = compare_paths(&scene, &camera, &label, base, &per_pixel);
            assert!(covered > 200, "{label}: particles cover {covered} pixels");
            row.push((flip, rel));
        }
        flips.push(row);
    }
    // By day the sun is the same over a quad (and the canopy shades whole
    // quads): measured FLIP 0.0018 per vertex, 0.0000 per particle. At
    // night the lamp's 1/d^2 inside the plume varies across a quad, Ryse's
    // "lights with harsh fall off": measured FLIP 0.056 per vertex (HDR
    // 5.8 % apart), 0.070 per particle (9.6 %) (160 x 120, lavapipe).
    assert!(flips[0][0].0 < 0.01, "day: FLIP {}", flips[0][0].0);
    assert!(
        flips[0][1].0 < 0.01,
        "day, per particle: FLIP {}",
        flips[0][1].0
    );
    assert!(
        flips[1][0].1 > 0.01,
        "night: the two paths drew the same image"
    );
    assert!(flips[1][0].0 < 0.08, "night: FLIP {}", flips[1][0].0);
    // The corners follow the falloff the centre alone cannot.
    assert!(
        flips[1][0].0 < flips[1][1].0 && flips[1][0].1 < flips[1][1].1,
        "night: per vertex {:?} not closer than per particle {:?}",
        flips[1][0],
        flips[1][1]
    );
}

/// Must-show (issue #21): particle shadows from the static map (4 x 4
/// gather once per particle, Ryse) against the world's per-pixel cascaded
/// lookup (S1 Poisson filter at every pixel): image difference and cost,
/// frames interleaved, `--shadows csm+static` by day (the burst under the
/// canopy in its shadow, the plume in the sun). `HIMAL_PARTICLE_FRAMES`.
#[test]
fn static_map_shadows_against_cascaded_per_pixel() {
    let (scene, camera) = common::scene_and_camera("particles_shadow", "side");
    let cascaded = |s: &mut himal::FrameSettings| s.particles_cascaded_shadows = true;
    let (flip, rel, covered) = compare_paths(
        &scene,
        &camera,
        "static map vs cascaded",
        &|_| {},
        &cascaded,
    );
    assert!(covered > 200, "particles cover {covered} pixels");
    // Measured FLIP 0.0239, HDR 1.9 % apart per vertex (0.0138, 1.2 % lit
    // once per particle; 160 x 120, lavapipe; 33 of 121 particles in the
    // slab's shadow): the static map's coarser texels and the filters move
    // the shadow edge; the quads' corners reach past their discs into it.
    assert!(flip < 0.05 && rel < 0.05, "FLIP {flip}, HDR {rel}");
    assert!(rel > 1e-3, "the two shadows drew the same image");
}

/// Sets a lighting path on a frame's settings.
type SetPath = dyn Fn(&mut himal::FrameSettings);

/// (FLIP mean over the particles' pixels, mean relative HDR difference
/// there, pixels covered) of the path `base` sets (from the default:
/// per-vertex light, static map) against the reference `reference` sets.
fn compare_paths(
    scene: &himal::scene::Scene,
    camera: &himal::scene::Camera,
    label: &str,
    base: &SetPath,
    reference: &SetPath,
) -> (f32, f32, usize) {
    let mut r = common::renderer(scene);
    let (w, h) = (160usize, 120usize);
    let mut s = settings(scene);
    base(&mut s);
    s.shadows.mode = himal::passes::shadows::ShadowMode::CsmStatic;
    // Each frame exposed for itself: no adaptation drifting between the paths.
    s.adaptation.enabled = false;
    let frames: usize = std::env::var("HIMAL_PARTICLE_FRAMES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4);
    let rgb = |i: &[[f32; 4]]| i.iter().map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>();
    // Raw HDR of both paths and without particles (no exposure involved).
    let mut raw = common::raw_settings(scene, (w as u32, h as u32), "lighting");
    base(&mut raw);
    raw.time_s = s.time_s;
    raw.shadows.mode = s.shadows.mode;
    // Settle the static map (time-sliced) before anything is compared.
    for _ in 0..4 {
        r.render(camera, &s).expect("frame");
    }
    let vertex_raw = common::render_rgba(&mut r, camera, &raw);
    let light = r.particles().read_light(r.context()).expect("light");
    let alive = r
        .particles()
        .read_particles(r.context())
        .expect("particles");
    let vis: Vec<f32> = (light.iter().zip(&alive))
        .filter(|(_, p)| p.vel_alive[3] > 0.5)
        .map(|(l, _)| l[0].d[3])
        .collect();
    println!(
        "{label}: {} particles, {} in the sun's shadow, {} partly (static map shown: {})",
        vis.len(),
        vis.iter().filter(|&&v| v < 0.01).count(),
        vis.iter().filter(|&&v| (0.01..0.99).contains(&v)).count(),
        r.render(camera, &s).expect("frame").shadows.static_shown
    );
    reference(&mut raw);
    let pixel_raw = common::render_rgba(&mut r, camera, &raw);
    raw.particles = false;
    let off_raw = common::render_rgba(&mut r, camera, &raw);
    let (mut vertex_ms, mut pixel_ms) = (Vec::new(), Vec::new());
    let (mut vertex, mut pixel) = (Vec::new(), Vec::new());
    // The same clock every frame: the particles do not move between paths.
    for k in 0..2 * frames {
        let per_pixel = k % 2 == 1;
        let mut sk = s.clone();
        if per_pixel {
            reference(&mut sk);
        }
        let f = r.render(camera, &sk).expect("frame");
        let ms: f64 = f
            .timings
            .iter()
            .filter(|t| t.id == "particles.light" || t.id == "forward.particles")
            .map(|t| t.gpu_ms)
            .sum();
        let img = f.image.to_rgba_f32().expect("rgba");
        if per_pixel {
            pixel_ms.push(ms);
            pixel = img;
        } else {
            vertex_ms.push(ms);
            vertex = img;
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (tv, tp) = (median(&mut vertex_ms), median(&mut pixel_ms));
    let flip = himal_reference::flip::flip_map(
        &rgb(&pixel),
        &rgb(&vertex),
        w,
        h,
        himal_reference::flip::DEFAULT_PIXELS_PER_DEGREE,
    )
    .expect("FLIP");
    let lum = |p: &[f32; 4]| luminance(p);
    let covered: Vec<usize> = (0..w * h)
        .filter(|&i| {
            (lum(&pixel_raw[i]) - lum(&off_raw[i])).abs() > 1e-3 * lum(&off_raw[i]).max(1e-3)
        })
        .collect();
    let n = covered.len().max(1) as f64;
    let flip_covered = (covered.iter().map(|&i| flip[i] as f64).sum::<f64>() / n) as f32;
    let rel = (covered
        .iter()
        .map(|&i| {
            ((lum(&vertex_raw[i]) - lum(&pixel_raw[i])).abs() / lum(&pixel_raw[i]).max(1e-6)) as f64
        })
        .sum::<f64>()
        / n) as f32;
    println!(
        "{label}: against the reference over {} particle pixels: FLIP mean {flip_covered:.4}, \
         HDR luminance {:.2} % apart; lighting cost {tv:.3} ms (particles.light + forward.particles) \
         vs {tp:.3} ms (reference forward.particles), ratio {:.2}, {frames} frames each, interleaved",
        covered.len(),
        100.0 * rel,
        tp / tv.max(1e-9)
    );
    (flip_covered, rel, covered.len())
}

/// Trail energy of particles under temporal AA `aa`: mean |luma(aa) −
/// luma(none)| of the last frame over the pixels the puffs covered in the
/// previous 8 frames but not now (covered: the none render with particles
/// differs from the one without), minus the same mean over pixels no puff
/// touched (the AA's own difference). Returns (energy, trail pixels).
fn particle_trail(aa: himal::passes::aa::AaMode, reactive: bool) -> (f32, usize) {
    use himal::passes::aa::AaMode;
    let (scene, camera) = common::scene_and_camera("particles_trail", "main");
    let mut r = common::renderer(&scene);
    let n = 128;
    let frames = 16usize;
    let mut s = himal::FrameSettings::new(n, n, scene.sun.clone());
    s.shadow_resolution = 0;
    s.aerial_extinction = 0.0;
    s.bloom.enabled = false;
    s.adaptation.enabled = false;
    s.particles_reactive = reactive;
    let luma = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    // 0.1 s a frame: a puff moves 0.3 m (about 6 px).
    let mut run = |aa: AaMode, particles: bool| {
        let mut sk = s.clone();
        sk.aa = aa;
        sk.particles = particles;
        r.reset_history();
        (0..=frames)
            .map(|i| {
                sk.time_s = 2.0 + i as f32 * 0.1;
                let f = r.render(&camera, &sk).expect("frame");
                let px = f.image.to_rgba_f32().expect("rgba");
                px.iter().map(luma).collect::<Vec<f32>>()
            })
            .collect::<Vec<_>>()
    };
    let off = run(AaMode::None, false).pop().expect("frame");
    let none = run(AaMode::None, true);
    let with_aa = run(aa, true);
    let covered = |f: usize, k: usize| (none[f][k] - off[k]).abs() > 0.02;
    let (mut sum, mut count, mut base, mut nb) = (0.0, 0, 0.0, 0);
    for k in 0..off.len() {
        let d = (with_aa[frames][k] - none[frames][k]).abs();
        if (frames - 8..frames).any(|f| covered(f, k)) && !covered(frames, k) {
            sum += d;
            count += 1;
        } else if !(0..=frames).any(|f| covered(f, k)) {
            base += d;
            nb += 1;
        }
    }
    let energy = sum / count.max(1) as f32 - base / nb.max(1) as f32;
    (energy.max(0.0), count)
}

/// Must-show (issue #21): no trails behind moving smoke under TAA / HRAA.
#[test]
fn moving_particles_leave_no_trail_under_temporal_aa() {
    use himal::passes::aa::AaMode;
    let mut res = Vec::new();
    for aa in [AaMode::Taa, AaMode::Hraa] {
        for reactive in [false, true] {
            let (e, n) = particle_trail(aa, reactive);
            println!("{aa:?}, reactive {reactive}: trail energy {e:.4} over {n} trail pixels");
            res.push((e, n));
        }
    }
    assert!(
        res.iter().all(|r| r.1 > 50),
        "trail mask too small: {res:?}"
    );
    // Measured (128 x 128, 16 frames, lavapipe): TAA 0.0156 without the
    // reactive mask, 0.0000 with; HRAA 0.0243 without, 0.0036 with (the
    // ball of aa_frame's ghosting test leaves 0.016). Bars: at most a
    // third of the trail without, TAA below 0.003, HRAA below 0.008.
    assert!(
        res[1].0 <= res[0].0 / 3.0 && res[1].0 < 0.003,
        "TAA: {res:?}"
    );
    assert!(
        res[3].0 <= res[2].0 / 3.0 && res[3].0 < 0.008,
        "HRAA: {res:?}"
    );
}

/// `particles.sort`: inside each emitter the live particles draw far to
/// near along the view direction, then the dead; the permutation equals
/// the CPU twin's. Off, ring order.
#[test]
fn particles_drift_downwind_on_gpu_and_twin() {
    let scene = common::scene("particles_wind");
    // `speed = 3, direction = 90`: toward -z.
    let wind = scene.wind;
    assert!(
        (wind - glam::Vec3::new(0.0, 0.0, -3.0)).length() < 1e-6,
        "{wind}"
    );
    // The same wind as a vector.
    let as_vector = common::scene_with(
        "particles_wind",
        &[(
            "speed = 3.0\ndirection = 90.0",
            "velocity = [0.0, 0.0, -3.0]",
        )],
    );
    assert_eq!(as_vector.wind, glam::Vec3::new(0.0, 0.0, -3.0));
    let (worst, pass, cpu) = against_twin(&scene);
    println!("wind: largest |GPU - CPU| {worst:.2e}");
    // Measured 0 on lavapipe, as in the smoke scene (bar: see there).
    assert!(worst < 1e-4, "GPU and CPU differ by {worst}");
    // Downwind on the twin (the GPU equals it): every live particle's
    // offset from the emitter is along the wind, as far as
    // x(t) = w (t - (1 - e^(-kt)) / k) for a particle born at rest (plus
    // the spread's 0.05 m/s times its age).
    let e = &pass.sim.emitters[0];
    let k = e.wind;
    let (mut live, mut worst_rel) = (0, 0.0f32);
    for p in cpu.iter().filter(|p| p.vel_alive[3] > 0.5) {
        let age = p.pos_age[3];
        let offset = glam::Vec3::from_slice(&p.pos_age[..3]) - e.position;
        let want = wind * (age - (1.0 - (-k * age).exp()) / k);
        let slack = e.spread * age * 3f32.sqrt();
        let cross = (offset - offset.project_onto(wind)).length();
        assert!(
            cross <= slack + 1e-4,
            "age {age}: {cross} m across the wind"
        );
        if age > 1.0 {
            worst_rel = worst_rel.max((offset - want).length() / want.length());
            // Semi-implicit Euler at 30 Hz runs ahead of the exact curve
            // (v follows w a step early), the spread adds up to `slack`:
            // together 5.5 % at most, measured.
            assert!(
                (offset - want).length() <= slack + 0.05 * want.length(),
                "age {age}: offset {offset}, want {want}"
            );
        }
        live += 1;
    }
    println!("{live} live particles downwind; largest |x - x(t)| / |x(t)| past 1 s {worst_rel:.3}");
    assert!(live > 50, "{live} live");
}

#[test]
fn scene_file_checks_wind() {
    let base = common::scene_text("particles_wind");
    let from = "speed = 3.0\ndirection = 90.0";
    let bad = [
        ("speed = -1.0", "wind speed = -1 is out of range"),
        (
            "speed = 3.0\ndirection = nan",
            "wind direction = NaN is out of range",
        ),
        (
            "speed = 3.0\nvelocity = [1.0, 0.0, 0.0]",
            "give speed (with direction) or velocity, not both",
        ),
        (
            "velocity = [1.0, 0.0, 0.0]\ndirection = 10.0",
            "wind direction goes with speed",
        ),
        (
            "velocity = [1.0, 0.0, 1000.0]",
            "each axis in [-100, 100] m/s",
        ),
        (
            "direction = 10.0",
            "speed (m/s, with direction in degrees) or velocity",
        ),
        ("gust = 2.0", "unknown field `gust`"),
    ];
    for (to, want) in bad {
        let text = base.replacen(from, to, 1);
        assert_ne!(text, base, "{from} not in the scene");
        let e =
            himal::scene::Scene::from_toml_str(&text, "particles_wind.toml", &common::scenes_dir())
                .err()
                .unwrap_or_else(|| panic!("{to} accepted"))
                .to_string();
        assert!(
            e.contains("particles_wind.toml") && e.contains(want),
            "{to}: {e}"
        );
    }
    // No table: the default breeze.
    let calm = base.replacen("[wind]\n", "", 1).replacen(from, "", 1);
    let s = common::parse_scene(&calm, "particles_wind.toml");
    assert_eq!(s.wind, himal::scene::DEFAULT_WIND);
}

#[test]
fn emitters_ride_moving_objects() {
    use glam::Vec3;
    use himal::passes::particles::Simulation;
    let scene = common::scene("particles_follow");
    let cart = scene.objects.iter().position(|o| o.name == "cart");
    let e = &scene.emitters[0];
    // 0.1 m above the box's top (0.4 m above its centre), 0.6 m behind.
    let local = Vec3::new(0.0, 0.5, -0.6);
    let follow = e.follow.expect("the emitter rides the cart");
    assert_eq!(Some(follow.object), cart);
    assert!((follow.local - local).length() < 1e-6, "{}", follow.local);
    // At time 0 the cart is at (3, 0.4, 0), unturned.
    assert!((e.position - Vec3::new(3.0, 0.9, -0.6)).length() < 1e-6);
    let cart = &scene.objects[follow.object];
    let (worst, _, cpu) = against_twin(&scene);
    println!("riding: largest |GPU - CPU| {worst:.2e}");
    // Measured 0 on lavapipe, as in the smoke scene (bar: see there).
    assert!(worst < 1e-4, "GPU and CPU differ by {worst}");
    // Each particle keeps its birth velocity (no gravity, no wind
    // response): it was born at x - v age, which must be where the
    // emitter rode at t - age, from Object::transform_at.
    let t = *CLOCKS.last().expect("clocks") as f64;
    let (mut worst_birth, mut live) = (0.0f32, 0);
    let mut births: Vec<Vec3> = Vec::new();
    for p in cpu.iter().filter(|p| p.vel_alive[3] > 0.5) {
        let age = p.pos_age[3];
        let x = Vec3::from_slice(&p.pos_age[..3]);
        let v = Vec3::from_slice(&p.vel_alive[..3]);
        let born = x - v * age;
        let want = (cart.transform_at((t - age as f64) as f32)).transform_point3(local);
        worst_birth = worst_birth.max((born - want).length());
        births.push(born);
        live += 1;
    }
    let reach = births
        .iter()
        .flat_map(|a| births.iter().map(move |b| a.distance(*b)))
        .fold(0.0f32, f32::max);
    println!(
        "{live} live; birth points {worst_birth:.2e} m from the ridden path at most, spread over {reach:.2} m"
    );
    // The birth lies on the chord between the step's ends; the longest
    // step here (0.133 s, 0.42 m of arc) measured 7.5e-3 m off the circle
    // (its sagitta, r (1 - cos(theta / 2)) = 7.3e-3 m).
    assert!(worst_birth < 0.01, "births {worst_birth} m off the path");
    // One second of a 3.1 m/s path: the births spread along it (a fixed
    // emitter would put them all in one point).
    assert!(reach > 2.5, "births span {reach} m");
    assert_eq!(live, 30, "30/s for 1 s");
    // The frame's GPU path: the renderer's first frame pre-warms at its
    // clock; the twin of the same plan gives the same particles.
    let mut r = common::renderer(&scene);
    let camera = scene.camera("top").expect("camera").clone();
    let mut s = settings(&scene);
    s.time_s = t as f32;
    common::render_rgba(&mut r, &camera, &s);
    let gpu = r
        .particles()
        .read_particles(r.context())
        .expect("particles");
    let mut sim = Simulation::new(&scene.emitters, scene.wind, &scene.objects);
    let mut twin = vec![ParticleGpu::default(); gpu.len()];
    simulate(&mut twin, &sim.advance(t));
    let d = gpu
        .iter()
        .zip(&twin)
        .flat_map(|(g, c)| (0..4).map(move |k| (g.pos_age[k] - c.pos_age[k]).abs()))
        .fold(0.0f32, f32::max);
    println!("frame: largest |GPU - twin| position/age {d:.2e}");
    assert!(d < 1e-4, "frame's particles differ from the twin by {d}");
}
