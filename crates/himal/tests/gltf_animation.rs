//! glTF animation and skinning on the CPU: keyframes sampled as the file
//! says, joints and weights applied, clips chosen by name. The expected
//! values are computed here from the files' accessors, read by hand
//! (`common::GltfFile`), not by the loader.

mod common;

use glam::{Mat4, Quat, Vec3};
use himal::scene::Scene;
use himal::scene::gltf::{self, Animated, skin_vertex};

fn animated(scene: &Scene) -> Vec<&Animated> {
    common::animated(scene)
}

/// AnimatedCube: one LINEAR rotation channel on its node. At each key time
/// the object's rotation is the key's quaternion; between keys, their slerp.
#[test]
fn animated_cube_turns_through_its_rotation_keys() {
    let path = common::gltf_sample("AnimatedCube");
    let scene = Scene::from_gltf(&path).unwrap_or_else(|e| panic!("{e}"));
    let file = common::GltfFile::open(&path);
    let o = &scene.objects[0];
    assert!(o.motion.is_some(), "the animated node moves");
    assert_eq!(scene.animations(), ["animation_AnimatedCube"]);
    let key = |k: usize| {
        let t = file.element(0, k, 1)[0];
        (t, Quat::from_slice(&file.element(1, k, 4)).normalize())
    };
    let rotation_at = |t: f32| {
        let (_, r, _) = o.transform_at(t).to_scale_rotation_translation();
        r
    };
    let same = |a: Quat, b: Quat| a.dot(b).abs() > 1.0 - 1e-5;
    for k in 0..file.count(0) {
        let (t, r) = key(k);
        // The last key is the loop's end: it wraps to the first.
        let t = if k + 1 == file.count(0) { t - 1e-4 } else { t };
        assert!(
            same(rotation_at(t), r),
            "key {k} at {t} s: {:?} vs {r:?}",
            rotation_at(t)
        );
    }
    let ((t0, r0), (t1, r1)) = (key(0), key(1));
    let mid = rotation_at(0.25 * t0 + 0.75 * t1);
    assert!(same(mid, r0.slerp(r1, 0.75)), "between keys: slerp");
    // Bounds cover the turn: the rotating cube's box is at least its rest box.
    let rest = scene.meshes[o.mesh].bounds.transform(&o.transform_at(0.0));
    assert!(scene.bounds.contains(&rest, 1e-4));
}

/// SimpleSkin: two joints (nodes 1 and 2), node 2 rotated by a LINEAR
/// channel. Each vertex is Σ w_i (W_joint_i · IBM_i) p, with W from the
/// nodes' rest transforms and the key rotation, computed here by hand.
#[test]
fn simple_skin_bends_its_vertices_by_joint_weights() {
    let path = common::gltf_sample("SimpleSkin");
    let asset = gltf::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(asset.warnings.is_empty(), "{:?}", asset.warnings);
    let file = common::GltfFile::open(&path);
    let scene = Scene::from_gltf(&path).unwrap();
    let a = animated(&scene);
    assert_eq!(a.len(), 1);
    let a = a[0];
    assert!(a.skin.is_some());
    // Key 3 is the strongest bend (|z| largest).
    let (times, rotations) = (5, 6);
    let k = (0..file.count(times))
        .max_by(|&i, &j| {
            let z = |k: usize| file.element(rotations, k, 4)[2].abs();
            z(i).total_cmp(&z(j))
        })
        .unwrap();
    let t = file.element(times, k, 1)[0];
    let r = Quat::from_slice(&file.element(rotations, k, 4)).normalize();
    assert!(r.to_axis_angle().1 > 0.5, "a real bend");
    let w1 = Mat4::IDENTITY;
    let w2 = Mat4::from_translation(Vec3::Y) * Mat4::from_quat(r);
    let ibm = |i: usize| Mat4::from_cols_slice(&file.element(4, i, 16));
    let skin = [w1 * ibm(0), w2 * ibm(1)];
    let joints = a.joints_at(t);
    let vertices = &a.skin.as_ref().unwrap().1;
    let mut moved = 0;
    for i in 0..file.count(1) {
        let p = file.vec3(1, i);
        let (j, w) = (file.element(2, i, 4), file.element(3, i, 4));
        let m: Mat4 = (0..4).fold(Mat4::ZERO, |m, c| m + skin[j[c] as usize] * w[c]);
        let expected = m.transform_point3(p);
        let got = Vec3::from(skin_vertex(&vertices[i], &joints).0);
        assert!(
            got.abs_diff_eq(expected, 1e-5),
            "vertex {i}: {got} vs {expected}"
        );
        moved += usize::from((expected - p).length() > 0.1);
    }
    assert!(moved >= 4, "the upper vertices bend ({moved} moved)");
}

/// The Fox: one skinned mesh on 24 joints, three clips. Walk moves its
/// legs (vertices differ between two times) inside the swept bounds; a clip
/// the file lacks is an error naming the ones it has.
#[test]
fn the_fox_walks_inside_its_swept_bounds() {
    let path = common::gltf_sample("Fox");
    let mut scene = Scene::from_gltf(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.animations(), ["Survey", "Walk", "Run"]);
    scene.set_animation(Some("Walk")).unwrap();
    let err = scene.set_animation(Some("Swim")).unwrap_err().to_string();
    assert!(
        err.contains("Fox.gltf") && err.contains("Survey, Walk, Run"),
        "{err}"
    );
    let a = animated(&scene)[0].clone();
    let (skin, vertices) = a.skin.clone().unwrap();
    assert_eq!(a.rig.skins[skin].joints.len(), 24);
    assert_eq!(a.rig.clips[a.clip.unwrap()].name, "Walk");
    let pose = |t: f32| -> Vec<Vec3> {
        let joints = a.joints_at(t);
        vertices
            .iter()
            .map(|v| Vec3::from(skin_vertex(v, &joints).0))
            .collect()
    };
    let (p0, p1) = (pose(0.0), pose(0.35));
    let mut largest = 0.0f32;
    for t in [0.0, 0.2, 0.35, 0.5, 0.7] {
        for p in pose(t) {
            assert!(
                a.swept.contains_point(p, 1e-3),
                "t {t}: {p} outside {:?}",
                a.swept
            );
        }
    }
    for (a, b) in p0.iter().zip(&p1) {
        largest = largest.max((*a - *b).length());
    }
    // The fox is ~150 units long; a stride moves a paw by far more than 1.
    assert!(largest > 5.0, "the legs move: {largest}");
    // Rest pose (no clip): the bind pose, where J_i · p = p for rigid vertices.
    scene.set_animation(None).unwrap();
    assert!(animated(&scene)[0].clip.is_none());
}

/// A weight above zero on a joint the skin does not have is an error
/// naming the file, not a read past the joint buffer.
#[test]
fn a_joint_outside_the_skin_is_an_error() {
    let src = common::gltf_sample("SimpleSkin");
    let dir = common::temp_dir("gltf_bad_joint");
    for f in std::fs::read_dir(src.parent().unwrap()).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, dir.join(f.file_name().unwrap())).unwrap();
    }
    let text = std::fs::read_to_string(&src).unwrap();
    // The skin keeps one joint of two: vertices weighted to joint 1 name a missing one.
    let text = text.replace(
        "\"inverseBindMatrices\" : 4,\n    \"joints\" : [ 1, 2 ]",
        "\"joints\" : [ 1 ]",
    );
    assert!(text.contains("\"joints\" : [ 1 ]"));
    let path = dir.join("SimpleSkin.gltf");
    std::fs::write(&path, text).unwrap();
    let err = gltf::load(&path).unwrap_err().to_string();
    assert!(
        err.contains("SimpleSkin.gltf") && err.contains("joint"),
        "{err}"
    );
}

/// `skin` on the GPU against its CPU twin: the Fox's 1,728 vertices
/// walking at 0.4 s. Measured on lavapipe: max error 7.6e-6 units in
/// position (the fox is ~150 long), 1.2e-7 in normals and tangents; bounds
/// 1e-3 / 1e-4 / 1e-4.
#[test]
fn skinning_on_the_gpu_matches_its_cpu_twin() {
    let mut scene = Scene::from_gltf(&common::gltf_sample("Fox")).unwrap();
    scene.set_animation(Some("Walk")).unwrap();
    let ctx = common::context();
    let gpu = himal::gpu_scene::SceneGpu::upload(&ctx, &scene).expect("upload");
    let skins = gpu.skins.as_ref().expect("the fox is skinned");
    assert_eq!(skins.vertex_count, 1728);
    let (t, t_prev) = (0.4, 0.35);
    gpu.update_objects(&ctx.queue, t, t_prev);
    let pass = himal::passes::skin::SkinPass::new(&ctx).expect("pass");
    let mut graph = himal::graph::FrameGraph::new();
    pass.add(&mut graph, &gpu);
    let mut pool = himal::graph::TexturePool::new();
    let commands = graph
        .compile()
        .expect("compile")
        .execute(&ctx.device, &mut pool, None)
        .expect("execute");
    ctx.queue.submit([commands]);
    let bytes = himal::gpu::read_buffer(&ctx, &skins.skinned).expect("read back");
    let got: &[himal::scene::Vertex] = bytemuck::cast_slice(&bytes);
    let sources = &animated(&scene)[0].skin.as_ref().unwrap().1;
    let want = himal::passes::skin::reference::skin(sources, &skins.joint_matrices(t));
    let (mut dp, mut dn, mut dt) = (0.0f32, 0.0f32, 0.0f32);
    let v3 = |v: &[f32]| Vec3::from_slice(&v[..3]);
    for (g, (p, n, t)) in got.iter().zip(&want) {
        dp = dp.max((v3(&g.position) - v3(p)).abs().max_element());
        dn = dn.max((v3(&g.normal) - v3(n)).abs().max_element());
        dt = dt.max((v3(&g.tangent) - v3(t)).abs().max_element());
        assert_eq!(g.tangent[3], t[3], "handedness kept");
        assert!(
            v3(&g.normal).dot(v3(&g.tangent)).abs() < 1e-4,
            "t orthogonal to n"
        );
    }
    eprintln!("max error: position {dp:e}, normal {dn:e}, tangent {dt:e}");
    assert!(
        dp < 1e-3 && dn < 1e-4 && dt < 1e-4,
        "position {dp}, normal {dn}, tangent {dt}"
    );
    // The previous frame's pose (motion vectors): header, then each
    // vertex under the joints at t_prev.
    let bytes = himal::gpu::read_buffer(&ctx, &gpu.deform).expect("read back");
    let prev: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    assert_eq!(prev[0][0].to_bits(), skins.first_vertex);
    assert_eq!(prev[0][1].to_bits(), 1728);
    let want =
        himal::passes::skin::reference::prev_positions(sources, &skins.joint_matrices(t_prev));
    let dprev = (prev[1..].iter().zip(&want))
        .map(|(g, w)| (v3(g) - Vec3::from(*w)).abs().max_element())
        .fold(0.0f32, f32::max);
    eprintln!("previous pose: max position error {dprev:e}");
    // As the current pose's position: f32 blends of the same matrices.
    assert!(dprev < 1e-3, "previous position {dprev}");
    // Not the rest pose: the walk moved the vertices the upload drew.
    let rest = &scene.meshes[scene.objects[0].mesh].vertices;
    let moved = (got.iter().zip(rest))
        .filter(|(g, r)| (Vec3::from(g.position) - Vec3::from(r.position)).length() > 1.0)
        .count();
    assert!(moved > 100, "{moved} vertices moved");
}

/// End to end: the frame at t draws the GPU-skinned pose. The same fox
/// made static with the CPU twin's pose at t renders the same normals
/// image; t = 0 differs. Measured on lavapipe, 96 px: mean |difference|
/// 0.0000 (identical) against the CPU pose, 0.0280 against t = 0.
#[test]
fn the_frame_draws_the_pose_at_its_time() {
    let mut scene = Scene::from_gltf(&common::gltf_sample("Fox")).unwrap();
    scene.set_animation(Some("Walk")).unwrap();
    let camera = gltf::orbit_camera(&scene.bounds, 90.0, 10.0, None, 40.0);
    let t = 0.4;
    let mut posed = scene.clone();
    let a = animated(&scene)[0].clone();
    let joints = a.joints_at(t);
    let (o, sources) = (&mut posed.objects[0], &a.skin.as_ref().unwrap().1);
    for (v, s) in posed.meshes[o.mesh].vertices.iter_mut().zip(sources.iter()) {
        (v.position, v.normal, v.tangent) = skin_vertex(s, &joints);
    }
    o.motion = None;
    let (same, moved) = common::frame_against(&scene, &posed, &camera, t);
    eprintln!("mean difference: CPU pose {same:.4}, t = 0 {moved:.4}");
    assert!(same < 1e-3, "GPU pose vs CPU pose: {same}");
    assert!(moved > 5e-3, "the pose changed the image: {moved}");
}

/// The objects of one rig share its pose per frame: asking again at the
/// same time reuses it (the rigid path evaluated the whole rig once per
/// object before), a new time computes one new pose, and the shared pose
/// is the one `Rig::pose` gives.
#[test]
fn a_rigs_pose_is_computed_once_per_time() {
    let scene = Scene::from_gltf(&common::gltf_sample("Fox")).expect("fox");
    let fox = animated(&scene)[0];
    let rig = &fox.rig;
    let before = rig.poses_computed();
    let a = fox.joints_at(0.5);
    let b = fox.joints_at(0.5);
    assert_eq!(a, b);
    assert_eq!(
        rig.poses_computed(),
        before + 1,
        "the same time again reuses the pose"
    );
    fox.joints_at(0.6);
    assert_eq!(rig.poses_computed(), before + 2);
    let (skin, _) = fox.skin.as_ref().expect("skinned");
    assert_eq!(a, rig.joint_matrices(*skin, &rig.pose(fox.clip, 0.5)));
}

/// SimpleMorph: a LINEAR weights channel (5 keys, 2 targets) on its node.
/// At each key time the object's weights are the key's, halfway between
/// keys their mean; the morphed positions are P0 + w0 ΔP0 + w1 ΔP1 from
/// the accessors read by hand. Before issue #22's morph playback the
/// channel was only named in a warning and the weights stayed 0.5, 0.5.
#[test]
fn animated_morph_weights_follow_their_keys() {
    let path = common::gltf_sample("SimpleMorph");
    let asset = gltf::load(&path).unwrap();
    assert!(
        !asset.warnings.iter().any(|w| w.contains("morph")),
        "{:?}",
        asset.warnings
    );
    let scene = Scene::from_gltf(&path).unwrap();
    let a = animated(&scene);
    assert_eq!(a.len(), 1);
    let a = a[0];
    let morph = a.morph.as_ref().expect("the node's weights are animated");
    let file = common::GltfFile::open(&path);
    let times: Vec<f32> = (0..file.count(4))
        .map(|j| file.element(4, j, 1)[0])
        .collect();
    let keys: Vec<[f32; 2]> = (0..times.len())
        .map(|j| {
            [
                file.element(5, 2 * j, 1)[0],
                file.element(5, 2 * j + 1, 1)[0],
            ]
        })
        .collect();
    let mesh = &scene.meshes[scene.objects[0].mesh];
    let check = |t: f32, want: [f32; 2]| {
        let w = a.weights_at(t);
        assert!(
            (w[0] - want[0]).abs() < 1e-6 && (w[1] - want[1]).abs() < 1e-6,
            "t = {t}: {w:?}, want {want:?}"
        );
        let mut v = mesh.vertices.clone();
        morph.apply(&mut v, &w);
        for (i, v) in v.iter().enumerate() {
            let p = file.vec3(1, i) + want[0] * file.vec3(2, i) + want[1] * file.vec3(3, i);
            assert!(
                (Vec3::from(v.position) - p).length() < 1e-6,
                "t = {t}, vertex {i}"
            );
        }
    };
    for (j, &t) in times.iter().enumerate() {
        check(t, keys[j]);
        if let Some(&next) = times.get(j + 1) {
            let k = [
                (keys[j][0] + keys[j + 1][0]) / 2.0,
                (keys[j][1] + keys[j + 1][1]) / 2.0,
            ];
            check((t + next) / 2.0, k);
        }
    }
    // Cost of the CPU morph (printed, not asserted): 10,000 vertices with
    // positions, normals and tangents under 4 targets.
    let n = 10_000;
    let field = |k: usize| {
        (0..n)
            .map(|i| [(i * k) as f32 * 1e-4, 0.1, 0.2])
            .collect::<Vec<_>>()
    };
    let big = gltf::MorphTargets {
        defaults: vec![0.0; 4],
        positions: field(1),
        normals: Some(vec![[0.0, 1.0, 0.0]; n]),
        tangents: Some(vec![[1.0, 0.0, 0.0]; n]),
        targets: (1..5)
            .map(|k| gltf::MorphTarget {
                positions: field(k),
                normals: field(k + 1),
                tangents: field(k + 2),
            })
            .collect(),
    };
    let mut v = vec![mesh.vertices[0]; n];
    let start = std::time::Instant::now();
    for i in 0..20 {
        big.apply(&mut v, &[0.1 * i as f32, 0.2, 0.3, 0.4]);
    }
    eprintln!(
        "MorphTargets::apply, 10,000 vertices x 4 targets: {:.3} ms",
        start.elapsed().as_secs_f64() * 1e3 / 20.0
    );
    // The swept bounds hold every key's shape.
    let b = scene.objects[0].swept_bounds(&mesh.bounds);
    for k in &keys {
        for i in 0..3 {
            let p = file.vec3(1, i) + k[0] * file.vec3(2, i) + k[1] * file.vec3(3, i);
            assert!(b.contains_point(p, 1e-5), "{p} outside {b:?}");
        }
    }
}

/// End to end: the frame at t draws the morph at t's weights. SimpleMorph
/// made static with the CPU twin's shape at t renders the same normals
/// image; t = 0 differs. Measured on lavapipe, 96 px: mean |difference|
/// 0.00000 against the CPU morph, 0.01896 against t = 0.
#[test]
fn the_frame_draws_the_morph_at_its_time() {
    let scene = Scene::from_gltf(&common::gltf_sample("SimpleMorph")).unwrap();
    let camera = gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let t = 1.5;
    let mut morphed = scene.clone();
    let a = animated(&scene)[0].clone();
    let o = &mut morphed.objects[0];
    let m = a.morph.as_ref().unwrap();
    m.apply(&mut morphed.meshes[o.mesh].vertices, &a.weights_at(t));
    o.motion = None;
    let (same, moved) = common::frame_against(&scene, &morphed, &camera, t);
    eprintln!("mean difference: CPU morph {same:.5}, t = 0 {moved:.5}");
    assert!(same < 1e-3, "GPU frame vs CPU morph: {same}");
    assert!(moved > 5e-3, "the morph changed the image: {moved}");
}

/// Motion vectors of a deforming mesh against the CPU twin: frames at t0
/// then t1 (the camera still); per pixel the twin ray-casts the shape at t1
/// (`posed(t1)`, world positions of `indices`' vertices), takes the hit's
/// barycentric mix of the same vertices at t0, and projects both: motion =
/// previous − current pixel position. Returns (pixels hit, of them moving >
/// 0.5 px, median and 90th percentile |GPU − CPU| in px, share within
/// 0.05 px, the largest motion with `deform_motion` off).
fn deformation_motion(
    scene: &Scene,
    camera: &himal::scene::Camera,
    (t0, t1): (f32, f32),
    indices: &[u32],
    posed: impl Fn(f32) -> Vec<Vec3>,
) -> (usize, usize, f32, f32, f32, f32) {
    use glam::Vec2;
    let size = (128u32, 96u32);
    let frames = |deform: bool| {
        let mut r = common::renderer(scene);
        let mut s = common::raw_settings(scene, size, "motion");
        s.aa = himal::passes::aa::AaMode::None;
        s.deform_motion = deform;
        s.time_s = t0;
        common::render_rgba(&mut r, camera, &s);
        s.time_s = t1;
        common::render_rgba(&mut r, camera, &s)
    };
    let (on, off) = (frames(true), frames(false));
    let (now, before) = (posed(t1), posed(t0));
    let project = |p: Vec3| {
        let (w, h) = (size.0 as f32, size.1 as f32);
        let c = camera.view_projection(w / h) * p.extend(1.0);
        let ndc = c.truncate() / c.w;
        Vec2::new((ndc.x * 0.5 + 0.5) * w, (0.5 - ndc.y * 0.5) * h)
    };
    let (mut errors, mut moving, mut off_max) = (Vec::new(), 0usize, 0.0f32);
    for y in 0..size.1 {
        for x in 0..size.0 {
            let d = common::pixel_ray(camera, size, x, y);
            let hit = (indices.chunks_exact(3))
                .filter_map(|tri| {
                    let i = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                    let (t, b) = common::ray_triangle(camera.position, d, i.map(|k| now[k]))?;
                    Some((t, i, b))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((t, i, b)) = hit else { continue };
            let p = camera.position + d * t;
            let q = before[i[0]] * b.x + before[i[1]] * b.y + before[i[2]] * b.z;
            let want = project(q) - project(p);
            let k = (y * size.0 + x) as usize;
            let got = Vec2::new(on[k][0], on[k][1]);
            errors.push((got - want).length());
            moving += usize::from(want.length() > 0.5);
            off_max = off_max.max(Vec2::new(off[k][0], off[k][1]).length());
        }
    }
    errors.sort_by(f32::total_cmp);
    let n = errors.len().max(1);
    let within = errors.iter().filter(|&&e| e < 0.05).count() as f32 / n as f32;
    let at = |q: usize| errors.get(q).copied().unwrap_or(f32::INFINITY);
    (
        errors.len(),
        moving,
        at(n / 2),
        at(n * 9 / 10),
        within,
        off_max,
    )
}

/// Issue #22: skinned vertices' motion vectors carry the deformation: the
/// Fox walking in place (its transform still) against the CPU twin
/// ([`deformation_motion`]). With `deform_motion` off (the object's
/// transform only, as before) the fox's pixels have no motion.
#[test]
fn skinned_motion_vectors_match_the_previous_pose() {
    let mut scene = Scene::from_gltf(&common::gltf_sample("Fox")).unwrap();
    scene.set_animation(Some("Walk")).unwrap();
    let camera = gltf::orbit_camera(&scene.bounds, 90.0, 10.0, None, 40.0);
    let a = animated(&scene)[0].clone();
    let object = &scene.objects[0];
    let sources = &a.skin.as_ref().unwrap().1;
    let posed = |t: f32| -> Vec<Vec3> {
        let (joints, model) = (a.joints_at(t), object.transform_at(t));
        (sources.iter())
            .map(|v| model.transform_point3(Vec3::from(skin_vertex(v, &joints).0)))
            .collect()
    };
    let indices = &scene.meshes[object.mesh].indices;
    let (n, moving, median, p90, within, off_max) =
        deformation_motion(&scene, &camera, (0.4, 0.4 + 1.0 / 15.0), indices, posed);
    eprintln!(
        "fox: {n} px, {moving} moving > 0.5 px; |GPU - CPU| median {median:.4} px, 90th percentile {p90:.4} px, {:.1}% within 0.05 px; deform motion off: max {off_max:.4} px",
        100.0 * within
    );
    assert!(n > 500 && moving > 100, "{n} fox px, {moving} moving");
    // Measured 2026-12-06 on lavapipe: 801 px, 480 moving; median 0.0002 px,
    // 99.8 % within 0.05 px (the rest: triangle edges where the pixel's
    // centre falls on the other side; Rg16Float storage).
    assert!(
        median < 0.01 && within > 0.97,
        "median {median}, within {within}"
    );
    assert!(
        off_max < 1e-3,
        "without deformation motion the fox is still: {off_max}"
    );
}

/// Morphed vertices likewise: SimpleMorph between two of its keys (the
/// node still) against the CPU morph at t0 and t1.
#[test]
fn morphed_motion_vectors_match_the_previous_shape() {
    let scene = Scene::from_gltf(&common::gltf_sample("SimpleMorph")).unwrap();
    let camera = gltf::orbit_camera(&scene.bounds, 0.0, 0.0, None, 40.0);
    let a = animated(&scene)[0].clone();
    let object = &scene.objects[0];
    let mesh = &scene.meshes[object.mesh];
    let posed = |t: f32| -> Vec<Vec3> {
        let mut v = mesh.vertices.clone();
        a.morph.as_ref().unwrap().apply(&mut v, &a.weights_at(t));
        let model = object.transform_at(t);
        v.iter()
            .map(|v| model.transform_point3(Vec3::from(v.position)))
            .collect()
    };
    let (n, moving, median, p90, within, off_max) =
        deformation_motion(&scene, &camera, (1.4, 1.5), &mesh.indices, posed);
    eprintln!(
        "SimpleMorph: {n} px, {moving} moving > 0.5 px; |GPU - CPU| median {median:.4} px, 90th percentile {p90:.4} px, {:.1}% within 0.05 px; deform motion off: max {off_max:.4} px",
        100.0 * within
    );
    assert!(n > 500 && moving > 100, "{n} px, {moving} moving");
    assert!(
        median < 0.01 && within > 0.97,
        "median {median}, within {within}"
    );
    assert!(
        off_max < 1e-3,
        "without deformation motion the shape is still: {off_max}"
    );
}
