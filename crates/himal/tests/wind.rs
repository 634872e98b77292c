//! V2 wind (issue #18): the GPU tree simulation (`vegetation.simulate`)
//! and the vertex stage's bend (`shaders/object_vertex.wgsl`,
//! `tree_world`) against their CPU twins (`passes/vegetation/reference.rs`),
//! on `tests/scenes/wind_trees.toml` (8 m/s wind and a passing source).
//! Measured numbers: `cargo test --release -p himal --test wind -- --nocapture`.

mod common;

use glam::{Mat4, Vec3, Vec4};
use himal::gpu::read_buffer;
use himal::gpu::testing::{run_compute_with, shared_context};
use himal::gpu_scene::{ObjectGpu, SceneGpu};
use himal::passes::vegetation::reference::{self, Pose};
use himal::passes::vegetation::{SimFrame, VegetationMotion, VegetationPass};
use himal::scene::tree::rig::BONES;

/// Frames simulated: a reset (2 s warm-up) then 2 s at 30 frames per second.
const FRAMES: usize = 61;

fn frame_time(k: usize) -> f32 {
    3.0 + k as f32 / 30.0
}

/// The scene simulated on the GPU for FRAMES frames, and the CPU twin's
/// bones and states over the same frames.
struct Run {
    scene: himal::scene::Scene,
    gpu: SceneGpu,
    /// Per slot: the CPU twin's pose now and at the previous frame, and state.
    cpu: Vec<(Pose, Pose, [Vec4; BONES])>,
}

fn run() -> Run {
    let scene = common::scene("wind_trees");
    let ctx = shared_context().expect("GPU (lavapipe in CI)");
    let gpu = SceneGpu::upload(ctx, &scene).expect("upload");
    let mut pass = VegetationPass::new(ctx, scene.wind_field()).expect("pass");
    let layout = gpu.tree_layout.clone();
    let slots = layout.slots.len();
    assert_eq!(slots, 2, "one slot per tree (trunk and leaves share it)");
    let order = himal::gpu_scene::gpu_order(&scene);
    let models: Vec<Mat4> = (layout.slots.iter())
        .map(|s| scene.objects[order[s.object as usize]].transform)
        .collect();
    let mut cpu = vec![(Pose::default(), Pose::default(), [Vec4::ZERO; BONES]); slots];
    let mut last = None;
    for k in 0..FRAMES {
        let t = frame_time(k);
        pass.plan(ctx, &gpu, t, (true, VegetationMotion::On), None);
        pass.run_now(ctx, &gpu).expect("simulate");
        let f = SimFrame::advance(last, t);
        assert_eq!(pass.frame, Some(f));
        last = Some(t);
        let wind = f.gpu(slots as u32, &scene.wind_field(), true).wind;
        for (s, slot) in layout.slots.iter().enumerate() {
            let r = slot.rig as usize * BONES;
            let rig = &layout.rigs[r..r + BONES];
            let (now, prev, state) = &mut cpu[s];
            let pose = reference::step_slot(rig, models[s], state, &f, &wind, true);
            *prev = if f.reset { pose } else { *now };
            *now = pose;
        }
    }
    Run { scene, gpu, cpu }
}

fn max_abs(a: Mat4, b: Mat4) -> f32 {
    (a.to_cols_array().iter())
        .zip(b.to_cols_array())
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max)
}

#[test]
fn simulation_and_bend_match_the_cpu_twins() {
    let t0 = std::time::Instant::now();
    let Run { scene, gpu, cpu } = run();
    let ctx = shared_context().expect("GPU");
    let objects_bytes = read_buffer(ctx, &gpu.objects).expect("read objects");
    let objects: &[ObjectGpu] = bytemuck::cast_slice(&objects_bytes);
    let state_bytes =
        read_buffer(ctx, &gpu.tree_buffers.as_ref().expect("trees").state).expect("state");
    let state: &[[f32; 4]] = bytemuck::cast_slice(&state_bytes);
    let layout = &gpu.tree_layout;
    let (mut worst_bone, mut worst_prev, mut worst_theta, mut largest) =
        (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let mut worst_speed = 0.0f32;
    for (s, slot) in layout.slots.iter().enumerate() {
        for b in 0..BONES {
            let rec = &objects[slot.first_record as usize + b];
            let model = Mat4::from_cols_array_2d(&rec.model);
            let prev = Mat4::from_cols_array_2d(&rec.prev_model);
            worst_bone = worst_bone.max(max_abs(model, cpu[s].0.bones[b]));
            worst_prev = worst_prev.max(max_abs(prev, cpu[s].1.bones[b]));
            worst_speed = worst_speed
                .max((rec.params[1] - cpu[s].0.speed[b]).abs())
                .max((rec.params[2] - cpu[s].1.speed[b]).abs());
            let g = Vec4::from_array(state[s * BONES + b]);
            worst_theta = worst_theta.max((g - cpu[s].2[b]).abs().max_element());
            largest = largest.max(cpu[s].2[b].truncate().truncate().length());
        }
    }
    println!(
        "simulation, {} trees x {BONES} bones, {FRAMES} frames (120 + 2 per frame steps): \
         max |GPU - CPU| bone matrix entry {worst_bone:.2e} (previous frame {worst_prev:.2e}), \
         bend state {worst_theta:.2e}, wind speed {worst_speed:.2e} m/s; largest bend {largest:.3} rad",
        layout.slots.len()
    );
    // The wind really bends the trees (8 m/s plus the source).
    assert!(largest > 0.02, "{largest}");
    // Measured on lavapipe: bone entries 4.8e-7 (now and before), state
    // 4.5e-8, wind speed 0 (the GPU's sin/cos/sqrt in the last bits over
    // 180 steps).
    assert!(
        worst_bone < 1e-4 && worst_prev < 1e-4,
        "{worst_bone} {worst_prev}"
    );
    assert!(worst_theta < 1e-4, "{worst_theta}");
    assert!(worst_speed < 1e-3, "{worst_speed}");

    // The bend: every 7th vertex of both trees' meshes (all LODs and the
    // impostor grid) through object_world on the GPU and `deform` on the CPU.
    let order = himal::gpu_scene::gpu_order(&scene);
    let mut input: Vec<[f32; 4]> = Vec::new();
    let mut expect: Vec<(Vec3, Vec3, Vec3)> = Vec::new();
    for (gi, &si) in order.iter().enumerate() {
        let o = &objects[gi];
        if o.params[1] >= 0.0 {
            continue;
        }
        let first = (-o.params[1]).round() as usize - 1;
        let s = layout
            .slots
            .iter()
            .position(|sl| sl.first_record as usize == first)
            .expect("slot");
        let mesh = &scene.meshes[scene.objects[si].mesh];
        let model = Mat4::from_cols_array_2d(&o.model);
        let inv_h = objects[first].params[0];
        for v in mesh.vertices.iter().step_by(7) {
            let p = Vec3::from(v.position);
            input.push([p.x, p.y, p.z, f32::from_bits(gi as u32)]);
            input.push([
                v.uv1[0],
                v.uv1[1],
                frame_time(FRAMES - 1),
                frame_time(FRAMES - 2),
            ]);
            let imp = v.uv1[0] < 0.0;
            let (t, tp) = (frame_time(FRAMES - 1), frame_time(FRAMES - 2));
            let now = reference::deform(model, &cpu[s].0, inv_h, p, v.uv1, t, imp);
            let prev = reference::deform(model, &cpu[s].1, inv_h, p, v.uv1, tp, imp);
            expect.push((now, prev, model.transform_point3(p)));
        }
    }
    let n = expect.len();
    let out = run_compute_with(
        KERNEL,
        "cs_main",
        bytemuck::cast_slice(&input),
        &[("objects", objects_bytes.as_slice())],
        (n * 32) as u64,
        [(n as u32).div_ceil(64), 1, 1],
    )
    .expect("bend kernel");
    let gpu_out: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut worst, mut worst_p, mut moved, mut most) = (0.0f32, 0.0f32, 0, 0.0f32);
    for (i, (now, prev, rest)) in expect.iter().enumerate() {
        let g = Vec3::from_slice(&gpu_out[2 * i][..3]);
        let gp = Vec3::from_slice(&gpu_out[2 * i + 1][..3]);
        worst = worst.max(g.distance(*now));
        worst_p = worst_p.max(gp.distance(*prev));
        let d = now.distance(*rest);
        most = most.max(d);
        if d > 0.01 {
            moved += 1;
        }
    }
    println!(
        "bend, {n} vertices: max |GPU - CPU| {worst:.2e} m (previous frame {worst_p:.2e} m); \
         {moved} moved more than 1 cm, the most {most:.2} m; {:.1} s",
        t0.elapsed().as_secs_f32()
    );
    assert!(moved > n / 4, "{moved} of {n}");
    // Measured on lavapipe: 2.9e-6 m now and before (f32 matrix products
    // of 20 m coordinates).
    assert!(worst < 1e-4 && worst_p < 1e-4, "{worst} {worst_p}");
}

const KERNEL: &str = r#"
#import object_vertex
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@group(0) @binding(2) var<storage, read> objects: array<Object>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (2u * id.x + 1u >= arrayLength(&input)) { return; }
    let a = input[2u * id.x];
    let b = input[2u * id.x + 1u];
    let o = objects[bitcast<u32>(a.w)];
    if (b.x < 0.0) {
        output[2u * id.x] = impostor_world(o, a.xyz, false, b.z);
        output[2u * id.x + 1u] = impostor_world(o, a.xyz, true, b.w);
    } else {
        output[2u * id.x] = object_world(o, false, a.xyz, vec2f(0.0), b.xy, true, b.z);
        output[2u * id.x + 1u] = object_world(o, true, a.xyz, vec2f(0.0), b.xy, true, b.w);
    }
}
"#;

/// The grass ripple: 40 frames at 30 per second of the step on the GPU and
/// its CPU twin, the camera walking 3 m (the window scrolls by 12 cells),
/// then the bend the grass vertex stage reads at points over the window.
#[test]
fn ripple_matches_the_cpu_twin() {
    use himal::passes::vegetation::ripple::{RIPPLE_CELL, RippleCpu};
    let scene = common::scene("wind_grass");
    let ctx = shared_context().expect("GPU (lavapipe in CI)");
    let gpu = SceneGpu::upload(ctx, &scene).expect("upload");
    let mut pass = VegetationPass::new(ctx, scene.wind_field()).expect("pass");
    let mut cpu = RippleCpu::new(gpu.ripple_n);
    for k in 0..40 {
        let t = 1.0 + k as f32 / 30.0;
        let camera = Vec3::new(0.075 * k as f32, 1.7, 0.0);
        pass.plan_ripple(ctx, &gpu, t, camera, true);
        pass.run_ripple_now(ctx, &gpu).expect("ripple");
        let (h, step) = pass.ripple.expect("planned");
        cpu.step(h, &step);
    }
    let bytes = read_buffer(ctx, &gpu.ripple).expect("read ripple");
    let cells: &[[f32; 4]] = bytemuck::cast_slice(&bytes[32..]);
    let (mut worst, mut deepest) = (0.0f32, 0.0f32);
    for (g, c) in cells.iter().zip(&cpu.cells) {
        worst = worst.max((g[0] - c[0]).abs()).max((g[1] - c[1]).abs());
        assert_eq!((g[2], g[3]), (c[2], c[3]), "cell tags");
        deepest = deepest.min(c[0]);
    }
    // The bend at points across the window, GPU (the draws' function) and CPU.
    let h = cpu.header;
    let lo = Vec3::new(h.window[0] as f32, 0.0, h.window[1] as f32) * RIPPLE_CELL;
    let extent = h.window[3] as f32 * RIPPLE_CELL;
    let mut points = Vec::new();
    for j in 0..64 {
        for i in 0..64 {
            let p = glam::Vec2::new(lo.x, lo.z)
                + glam::Vec2::new(i as f32 + 0.37, j as f32 + 0.61) * (extent / 64.0);
            points.push([p.x, p.y, 0.0, 0.0]);
        }
    }
    let out = run_compute_with(
        RIPPLE_KERNEL,
        "cs_main",
        bytemuck::cast_slice(&points),
        &[("ripple", bytes.as_slice())],
        (points.len() * 16) as u64,
        [(points.len() as u32).div_ceil(64), 1, 1],
    )
    .expect("bend kernel");
    let bends: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut worst_bend, mut largest) = (0.0f32, 0.0f32);
    for (p, g) in points.iter().zip(bends) {
        let c = cpu.bend(glam::Vec2::new(p[0], p[1]));
        worst_bend = worst_bend.max((glam::Vec2::new(g[0], g[1]) - c).length());
        largest = largest.max(c.length());
    }
    println!(
        "ripple, {n} x {n} cells, 40 frames: max |GPU - CPU| height/velocity {worst:.2e}, \
         deepest {deepest:.3} m; bend at {} points: max |GPU - CPU| {worst_bend:.2e} m, largest {largest:.3} m",
        points.len(),
        n = gpu.ripple_n
    );
    // The source presses the grass and bends it.
    assert!(deepest < -0.05 && largest > 0.05, "{deepest} {largest}");
    // Measured on lavapipe: 0 (height, velocity) and 0 m (bend).
    assert!(worst < 1e-4 && worst_bend < 1e-4, "{worst} {worst_bend}");
}

const RIPPLE_KERNEL: &str = r#"
#import ripple
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@group(0) @binding(2) var<storage, read> ripple: Ripple;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&input)) { return; }
    output[id.x] = vec4f(ripple_bend(input[id.x].xy), 0.0, 0.0);
}
"#;

/// V5 leaf flutter: the G-buffer's noise against its CPU twin over cards
/// and times.
#[test]
fn leaf_flutter_matches_the_cpu_twin() {
    let mut input = Vec::new();
    for k in 0..4096u32 {
        let uv = glam::Vec2::new((k % 64) as f32 * 0.173 + 3.0, (k / 64) as f32 / 64.0);
        input.push([
            uv.x,
            uv.y,
            0.37 * (k % 13) as f32 + 100.0 * (k % 2) as f32,
            0.0,
        ]);
    }
    let out = run_compute_with(
        r#"
#import scene
@group(0) @binding(0) var<storage, read> input: array<vec4f>;
@group(0) @binding(1) var<storage, read_write> output: array<vec4f>;
@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x >= arrayLength(&input)) { return; }
    output[id.x] = vec4f(leaf_flutter(input[id.x].xy, input[id.x].z), 0.0, 0.0);
}
"#,
        "cs_main",
        bytemuck::cast_slice(&input),
        &[],
        (input.len() * 16) as u64,
        [(input.len() as u32).div_ceil(64), 1, 1],
    )
    .expect("flutter kernel");
    let gpu: &[[f32; 4]] = bytemuck::cast_slice(&out);
    let (mut worst, mut spread) = (0.0f32, 0.0f32);
    for (i, g) in input.iter().zip(gpu) {
        let c = reference::leaf_flutter(glam::Vec2::new(i[0], i[1]), i[2]);
        worst = worst.max((glam::Vec2::new(g[0], g[1]) - c).abs().max_element());
        spread = spread.max(c.abs().max_element());
    }
    println!(
        "leaf flutter, {} samples: max |GPU - CPU| {worst:.2e}; largest {spread:.2}",
        input.len()
    );
    assert!(spread > 0.5, "{spread}");
    // Measured on lavapipe: 0 (the same f32 operations).
    assert!(worst < 1e-5, "{worst}");
}
