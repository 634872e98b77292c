//! glTF deformation on the GPU (the skin pass: morph targets, then
//! skinning) against its CPU twin, on generated grids: morphed, morphed
//! and skinned under a non-uniform joint scale, and skinned normals by the
//! inverse transpose.

mod common;

use glam::{Mat4, Quat, Vec3};
use himal::scene::Scene;
use himal::scene::gltf::{self, Animated, skin_vertex};

fn animated(scene: &Scene) -> Vec<&Animated> {
    common::animated(scene)
}

/// The accessors of a generated .gltf: one buffer, one view per accessor.
#[derive(Default)]
struct GltfBin {
    bytes: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl GltfBin {
    /// An accessor of `count` elements of type `ty` (component `component`)
    /// over `data`; `bounds` adds min and max (of `comps` f32 components).
    fn add(
        &mut self,
        data: &[u8],
        component: u32,
        (count, ty): (usize, &str),
        bounds: Option<(usize, &[f32])>,
    ) -> usize {
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
            data.len()
        ));
        let bounds = bounds.map_or(String::new(), |(comps, v)| {
            let (mut lo, mut hi) = (vec![f32::MAX; comps], vec![f32::MIN; comps]);
            for e in v.chunks(comps) {
                for c in 0..comps {
                    (lo[c], hi[c]) = (lo[c].min(e[c]), hi[c].max(e[c]));
                }
            }
            format!(r#","min":{lo:?},"max":{hi:?}"#)
        });
        self.accessors.push(format!(
            r#"{{"bufferView":{},"componentType":{component},"count":{count},"type":"{ty}"{bounds}}}"#,
            self.views.len() - 1
        ));
        self.accessors.len() - 1
    }

    fn floats(&mut self, v: &[f32], ty: &str, comps: usize, bounds: bool) -> usize {
        let data: Vec<u8> = v.iter().flat_map(|f| f.to_le_bytes()).collect();
        let b = bounds.then_some((comps, v));
        self.add(&data, 5126, (v.len() / comps, ty), b)
    }
}

/// A grid of `nx` × `ny` vertices over x in [0, 2], y in [0, 1] (z = 0;
/// normal +z, tangent +x) with `targets` morph targets (position, normal
/// and tangent deltas), their weights animated LINEAR from 0 at t = 0 to
/// (k + 1) / targets at t = 1. `skinned`: two joints, the second at x = 1
/// with scale (1, 2, 0.5) over its bind pose (a non-uniform joint scale)
/// and turned 40° about y at t = 1; vertices past x = 0.5 blend towards it.
fn morph_grid_gltf(
    name: &str,
    (nx, ny): (usize, usize),
    targets: usize,
    skinned: bool,
) -> std::path::PathBuf {
    let mut bin = GltfBin::default();
    let grid: Vec<(f32, f32)> = (0..ny)
        .flat_map(|j| {
            (0..nx).map(move |i| (2.0 * i as f32 / (nx - 1) as f32, j as f32 / (ny - 1) as f32))
        })
        .collect();
    let each = |f: &dyn Fn(f32, f32) -> Vec<f32>| {
        grid.iter()
            .flat_map(|&(x, y)| f(x, y))
            .collect::<Vec<f32>>()
    };
    let pos = bin.floats(&each(&|x, y| vec![x, y, 0.0]), "VEC3", 3, true);
    let nrm = bin.floats(&each(&|_, _| vec![0.0, 0.0, 1.0]), "VEC3", 3, false);
    let tan = bin.floats(&each(&|_, _| vec![1.0, 0.0, 0.0, 1.0]), "VEC4", 4, false);
    let mut indices: Vec<u32> = Vec::new();
    for j in 0..ny - 1 {
        for i in 0..nx - 1 {
            let a = (j * nx + i) as u32;
            let (b, c, d) = (a + 1, a + nx as u32, a + nx as u32 + 1);
            indices.extend([a, b, c, b, d, c]);
        }
    }
    let data: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let idx = bin.add(&data, 5125, (indices.len(), "SCALAR"), None);
    let mut target_json = Vec::new();
    for k in 0..targets {
        let f = (k + 1) as f32;
        let dp = bin.floats(
            &each(&|x, y| vec![0.05 * f * y, 0.0, 0.3 * (f * x * 1.7 + y).sin()]),
            "VEC3",
            3,
            true,
        );
        let dn = bin.floats(
            &each(&|x, _| vec![0.4 * (f * x).cos(), 0.1 * k as f32, 0.0]),
            "VEC3",
            3,
            false,
        );
        let dt = bin.floats(&each(&|_, y| vec![0.0, 0.0, 0.2 * f * y]), "VEC3", 3, false);
        target_json.push(format!(
            r#"{{"POSITION":{dp},"NORMAL":{dn},"TANGENT":{dt}}}"#
        ));
    }
    let times = bin.floats(&[0.0, 1.0], "SCALAR", 1, true);
    let mut keys = vec![0.0; targets];
    keys.extend((0..targets).map(|k| (k + 1) as f32 / targets as f32));
    let weights = bin.floats(&keys, "SCALAR", 1, false);
    let mut skin_attributes = String::new();
    let (mut nodes, mut roots, mut extra) = (
        r#"{"mesh":0,"name":"grid"}"#.to_string(),
        "0".to_string(),
        String::new(),
    );
    let mut channels = vec![r#"{"sampler":0,"target":{"node":0,"path":"weights"}}"#.to_string()];
    let mut samplers = vec![format!(
        r#"{{"input":{times},"output":{weights},"interpolation":"LINEAR"}}"#
    )];
    if skinned {
        let joints: Vec<u8> = grid
            .iter()
            .flat_map(|_| [0u16, 1, 0, 0])
            .flat_map(|j| j.to_le_bytes())
            .collect();
        let joints = bin.add(&joints, 5123, (grid.len(), "VEC4"), None);
        let w = each(&|x, _| {
            let w = (x - 0.5).clamp(0.0, 1.0);
            vec![1.0 - w, w, 0.0, 0.0]
        });
        let w = bin.floats(&w, "VEC4", 4, false);
        let ibm = [
            Mat4::IDENTITY,
            Mat4::from_translation(Vec3::new(-1.0, 0.0, 0.0)),
        ];
        let ibm: Vec<f32> = ibm.iter().flat_map(|m| m.to_cols_array()).collect();
        let ibm = bin.floats(&ibm, "MAT4", 16, false);
        let (s, c) = 20f32.to_radians().sin_cos();
        let turn = bin.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, s, 0.0, c], "VEC4", 4, false);
        skin_attributes = format!(r#","JOINTS_0":{joints},"WEIGHTS_0":{w}"#);
        nodes = r#"{"mesh":0,"skin":0,"name":"grid"},{"name":"root","children":[2]},{"name":"tip","translation":[1,0,0],"scale":[1,2,0.5]}"#.to_string();
        roots = "0,1".to_string();
        extra = format!(r#","skins":[{{"joints":[1,2],"inverseBindMatrices":{ibm}}}]"#);
        channels.push(r#"{"sampler":1,"target":{"node":2,"path":"rotation"}}"#.to_string());
        samplers.push(format!(
            r#"{{"input":{times},"output":{turn},"interpolation":"LINEAR"}}"#
        ));
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{roots}]}}],"nodes":[{nodes}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":{pos},"NORMAL":{nrm},"TANGENT":{tan}{skin_attributes}}},"indices":{idx},"targets":[{}]}}],"weights":{:?}}}],
"animations":[{{"channels":[{}],"samplers":[{}]}}]{extra},
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{}],"accessors":[{}]}}"#,
        target_json.join(","),
        vec![0.0f32; targets],
        channels.join(","),
        samplers.join(","),
        bin.bytes.len(),
        common::base64(&bin.bytes),
        bin.views.join(","),
        bin.accessors.join(",")
    );
    let path = common::temp_dir(&format!("morph-grid-{name}")).join(format!("{name}.gltf"));
    std::fs::write(&path, json).expect("write the grid");
    path
}

/// `scene` uploaded, its objects updated to `t` (previous frame `t_prev`)
/// and the `skin` pass run: the deformed vertices and the previous
/// positions (after the header) read back.
fn gpu_deform(
    ctx: &himal::gpu::GpuContext,
    gpu: &himal::gpu_scene::SceneGpu,
    (t, t_prev): (f32, f32),
) -> (Vec<himal::scene::Vertex>, Vec<[f32; 4]>) {
    gpu.update_objects(&ctx.queue, t, t_prev);
    let pass = himal::passes::skin::SkinPass::new(ctx).expect("pass");
    let mut graph = himal::graph::FrameGraph::new();
    pass.add(&mut graph, gpu);
    let mut pool = himal::graph::TexturePool::new();
    let commands = graph
        .compile()
        .expect("compile")
        .execute(&ctx.device, &mut pool, None)
        .expect("execute");
    ctx.queue.submit([commands]);
    let skins = gpu.skins.as_ref().expect("deformed meshes");
    let bytes = himal::gpu::read_buffer(ctx, &skins.skinned).expect("read back");
    let got = bytemuck::cast_slice(&bytes).to_vec();
    let bytes = himal::gpu::read_buffer(ctx, &gpu.deform).expect("read back");
    let prev: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    (got, prev[1..].to_vec())
}

/// Largest |difference| of positions, normals and tangents (xyz) between
/// `got` and `want`.
fn max_errors(
    got: &[himal::scene::Vertex],
    want: &[([f32; 3], [f32; 3], [f32; 4])],
) -> (f32, f32, f32) {
    let v3 = |v: &[f32]| Vec3::from_slice(&v[..3]);
    let (mut dp, mut dn, mut dt) = (0.0f32, 0.0f32, 0.0f32);
    assert_eq!(got.len(), want.len());
    for (g, (p, n, t)) in got.iter().zip(want) {
        dp = dp.max((v3(&g.position) - v3(p)).abs().max_element());
        dn = dn.max((v3(&g.normal) - v3(n)).abs().max_element());
        dt = dt.max((v3(&g.tangent) - v3(t)).abs().max_element());
        assert_eq!(g.tangent[3], t[3], "handedness kept");
    }
    (dp, dn, dt)
}

/// The GPU morph (`skin.wgsl`) against its CPU twin (`reference::deform`)
/// and against the CPU morph drawn before it (`MorphTargets::apply`), on
/// SimpleMorph and on a 10,000-vertex grid with 4 targets (position,
/// normal and tangent deltas); the previous positions likewise. Measured
/// on lavapipe: SimpleMorph max error 0 / 0 / 0 (position, normal,
/// tangent); grid 0 / 1.2e-7 / 1.8e-7 against the twin, 0 / 1.2e-7 /
/// 3.6e-7 against `apply`; previous positions 0. Threshold 1e-5 (positions
/// within 2.5 units, unit vectors): ~30 × the largest, a few f32 ulps of
/// the sums in another order.
/// Also prints the CPU cost per frame of the CPU morph it replaces (the
/// shape and the previous shape, each morphed and uploaded) against
/// `update_objects` now (weights only); the pass's GPU time is in `himal
/// bench --play` (docs/gltf.md).
#[test]
fn morphing_on_the_gpu_matches_its_cpu_twin() {
    let ctx = common::context();
    let cases = [
        (
            "SimpleMorph",
            common::gltf_sample("SimpleMorph"),
            (1.5, 1.4),
        ),
        (
            "grid",
            morph_grid_gltf("grid", (100, 100), 4, false),
            (0.6, 0.55),
        ),
    ];
    for (name, path, (t, t_prev)) in cases {
        let scene = Scene::from_gltf(&path).unwrap();
        let gpu = himal::gpu_scene::SceneGpu::upload(&ctx, &scene).expect("upload");
        let (got, prev) = gpu_deform(&ctx, &gpu, (t, t_prev));
        let object = (scene.objects.iter())
            .find(|o| o.motion.is_some())
            .expect("animated");
        let a = object.motion.as_ref().unwrap().animated.as_ref().unwrap();
        let drawn = &scene.meshes[object.mesh].vertices;
        let want = himal::passes::skin::reference::deform(a, drawn, t);
        let (dp, dn, dt) = max_errors(&got, &want);
        let mut cpu = drawn.clone();
        let morph = a.morph.as_ref().expect("morphed");
        morph.apply(&mut cpu, &a.weights_at(t));
        let cpu: Vec<_> = cpu
            .iter()
            .map(|v| (v.position, v.normal, v.tangent))
            .collect();
        let (cp, cn, ct) = max_errors(&got, &cpu);
        let want_prev = himal::passes::skin::reference::deform(a, drawn, t_prev);
        let dprev = (prev.iter().zip(&want_prev))
            .map(|(g, w)| {
                (Vec3::from_slice(&g[..3]) - Vec3::from(w.0))
                    .abs()
                    .max_element()
            })
            .fold(0.0f32, f32::max);
        eprintln!(
            "{name} ({} vertices): GPU vs twin {dp:e} / {dn:e} / {dt:e}; vs MorphTargets::apply {cp:e} / {cn:e} / {ct:e}; previous {dprev:e}",
            drawn.len()
        );
        for e in [dp, dn, dt, cp, cn, ct, dprev] {
            assert!(e < 1e-5, "{name}: {dp} {dn} {dt} {cp} {cn} {ct} {dprev}");
        }
        let moved = (got.iter().zip(drawn))
            .filter(|(g, r)| (Vec3::from(g.position) - Vec3::from(r.position)).length() > 1e-3)
            .count();
        assert!(moved > 0, "{name}: {moved} vertices moved");
        if name != "grid" {
            continue;
        }
        // Cost per frame (printed, not asserted), 20 frames 1/30 s apart.
        let frames: Vec<f32> = (0..20).map(|i| 0.1 + i as f32 / 30.0).collect();
        let start = std::time::Instant::now();
        for &t in &frames {
            // The CPU path this replaces (gpu_scene/morph.rs before):
            // morph and upload the shape, then the previous positions.
            let mut v = drawn.clone();
            morph.apply(&mut v, &a.weights_at(t));
            ctx.queue
                .write_buffer(&gpu.vertices, 0, bytemuck::cast_slice(&v));
            let mut p = drawn.clone();
            morph.apply(&mut p, &a.weights_at(t - 1.0 / 30.0));
            let p: Vec<[f32; 4]> = p
                .iter()
                .map(|v| [v.position[0], v.position[1], v.position[2], 1.0])
                .collect();
            ctx.queue
                .write_buffer(&gpu.deform, 16, bytemuck::cast_slice(&p));
        }
        let before = start.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
        let start = std::time::Instant::now();
        for &t in &frames {
            gpu.update_objects(&ctx.queue, t, t - 1.0 / 30.0);
        }
        let after = start.elapsed().as_secs_f64() * 1e3 / frames.len() as f64;
        eprintln!(
            "10,000 vertices x 4 targets, CPU ms per frame: CPU morph + upload {before:.3}, update_objects {after:.4}"
        );
    }
}

/// glTF 2.0: morph, then skin. A 12 × 4 grid with 4 targets, skinned by two
/// joints, the second non-uniformly scaled and turning: the GPU (`skin`)
/// against its CPU twin (`reference::deform`) at 0.7 s (previous frame
/// 0.6 s), the morph visibly changing the pose, every sampled time inside
/// the swept bounds, and the frame against the twin's pose drawn static.
/// Measured on lavapipe: max error 2.4e-7 / 6.0e-8 / 1.8e-7 (position,
/// normal, tangent), previous 1.2e-7 (threshold 1e-5, as above); the morph
/// moves the pose by up to 0.537; frame (normals, 96 px) mean difference
/// 0.0000 against the twin, 0.0488 against t = 0 (thresholds as for the
/// fox).
#[test]
fn morph_then_skin_on_the_gpu_matches_its_cpu_twin() {
    let path = morph_grid_gltf("skinned", (12, 4), 4, true);
    let asset = gltf::load(&path).unwrap();
    assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    let scene = Scene::from_gltf(&path).unwrap();
    let a = animated(&scene)[0].clone();
    let (skin, bind) = a.skin.clone().expect("skinned");
    assert!(a.morph.is_some(), "the skinned mesh keeps its targets");
    let o = scene.objects.iter().find(|o| o.motion.is_some()).unwrap();
    let drawn = scene.meshes[o.mesh].vertices.clone();
    let ctx = common::context();
    let gpu = himal::gpu_scene::SceneGpu::upload(&ctx, &scene).expect("upload");
    let (t, t_prev) = (0.7, 0.6);
    let (got, prev) = gpu_deform(&ctx, &gpu, (t, t_prev));
    let want = himal::passes::skin::reference::deform(&a, &drawn, t);
    let (dp, dn, dt) = max_errors(&got, &want);
    let want_prev = himal::passes::skin::reference::deform(&a, &drawn, t_prev);
    let dprev = (prev.iter().zip(&want_prev))
        .map(|(g, w)| {
            (Vec3::from_slice(&g[..3]) - Vec3::from(w.0))
                .abs()
                .max_element()
        })
        .fold(0.0f32, f32::max);
    // Skinned without the morph: the targets move the pose.
    let unmorphed = himal::passes::skin::reference::skin(&bind, &a.joints_at(t));
    let morph_moves = (want.iter().zip(&unmorphed))
        .map(|(w, u)| (Vec3::from(w.0) - Vec3::from(u.0)).length())
        .fold(0.0f32, f32::max);
    eprintln!(
        "morph + skin: GPU vs twin {dp:e} / {dn:e} / {dt:e}, previous {dprev:e}; the morph moves the pose by up to {morph_moves:.3} (skin {skin})"
    );
    for e in [dp, dn, dt, dprev] {
        assert!(e < 1e-5, "{dp} {dn} {dt} {dprev}");
    }
    assert!(morph_moves > 0.1, "{morph_moves}");
    for t in [0.0, 0.25, 0.5, 0.7, 1.0] {
        let b = scene.objects[0].swept_bounds(&scene.meshes[o.mesh].bounds);
        for (p, _, _) in himal::passes::skin::reference::deform(&a, &drawn, t) {
            assert!(
                b.contains_point(Vec3::from(p), 1e-4),
                "t = {t}: {p:?} outside {b:?}"
            );
        }
    }
    let mut posed = scene.clone();
    let po = posed
        .objects
        .iter_mut()
        .find(|o| o.motion.is_some())
        .unwrap();
    for (v, (p, n, tg)) in posed.meshes[po.mesh].vertices.iter_mut().zip(&want) {
        (v.position, v.normal, v.tangent) = (*p, *n, *tg);
    }
    po.motion = None;
    let camera = gltf::orbit_camera(&scene.bounds, 20.0, 20.0, None, 40.0);
    let (same, moved) = common::frame_against(&scene, &posed, &camera, t);
    eprintln!("mean difference: CPU twin {same:.4}, t = 0 {moved:.4}");
    assert!(same < 1e-3, "GPU pose vs CPU twin: {same}");
    assert!(moved > 5e-3, "the pose changed the image: {moved}");
}

/// Skinned normals by the inverse transpose (through the cofactor matrix,
/// `gltf::normal_matrix`): under a non-uniform joint scale (1, 3, 0.5),
/// turned and moved, a surface's skinned normal stays perpendicular to its
/// skinned tangent directions (to 1e-6), and equals glam's M⁻ᵀ n; M n
/// (drawn before) leaves the surface (|n' · e2'| printed, > 0.1). A mirrored
/// joint (scale −1 in x) gives M⁻ᵀ n too.
#[test]
fn skinned_normals_use_the_inverse_transpose() {
    let (e1, e2) = (Vec3::X, Vec3::new(0.0, 1.0, 1.0).normalize());
    let n = e1.cross(e2).normalize();
    let v = gltf::SkinVertex {
        position: [0.0; 4],
        normal: [n.x, n.y, n.z, 0.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        weights: [1.0, 0.0, 0.0, 0.0],
        joints: [0; 4],
    };
    for scale in [Vec3::new(1.0, 3.0, 0.5), Vec3::new(-1.0, 3.0, 0.5)] {
        let m = Mat4::from_scale_rotation_translation(
            scale,
            Quat::from_rotation_z(0.3),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let (_, skinned, _) = skin_vertex(&v, &[m]);
        let skinned = Vec3::from(skinned);
        let (f1, f2) = (
            m.transform_vector3(e1).normalize(),
            m.transform_vector3(e2).normalize(),
        );
        let inverse_transpose = (glam::Mat3::from_mat4(m).inverse().transpose() * n).normalize();
        let by_m = m.transform_vector3(n).normalize();
        eprintln!(
            "scale {scale}: n'.e1' {:.1e}, n'.e2' {:.1e}, |n' - M^-T n| {:.1e}; by M: n.e2' {:.3}",
            skinned.dot(f1),
            skinned.dot(f2),
            (skinned - inverse_transpose).length(),
            by_m.dot(f2)
        );
        assert!(skinned.dot(f1).abs() < 1e-6 && skinned.dot(f2).abs() < 1e-6);
        assert!((skinned - inverse_transpose).length() < 1e-6);
        assert!(by_m.dot(f2).abs() > 0.1, "the case tells M from M^-T");
    }
}
