//! glTF skins and animations (glTF 2.0 3.7.3, 3.11): the node tree kept
//! for playback, keyframe sampling, joint matrices, and the skinning math
//! that `passes/skin` runs on the GPU (its CPU twin is [`skin_vertex`]).
//! Equations and conventions: docs/gltf.md, "Animation and skinning".

use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Quat, Vec3, Vec4};

use super::buffers::GltfContext;
use crate::scene::{Aabb, SceneError};

/// Largest accepted keyframe count per channel (and joints per skin).
const MAX_KEYS: usize = 1 << 20;
/// Times the swept bounds sample each clip at (plus every keyframe time of
/// short clips).
const BOUND_SAMPLES: usize = 64;

/// A node's local transform as translation, rotation, scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Metres in the parent's frame.
    pub translation: Vec3,
    /// Unit quaternion.
    pub rotation: Quat,
    /// Per-axis scale.
    pub scale: Vec3,
}

impl Trs {
    /// T · R · S.
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// One node of the file's hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct RigNode {
    /// The node's name in the file (`node<i>` when it has none).
    pub name: String,
    /// The parent node; `None` for roots.
    pub parent: Option<usize>,
    /// The node's own matrix (kept exact where no channel animates it).
    pub rest: Mat4,
    /// `rest` as TRS: what channels override.
    pub rest_trs: Trs,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The node's translation (a vector key).
    Translation,
    /// The node's rotation (a quaternion key).
    Rotation,
    /// The node's scale (a vector key).
    Scale,
    /// The weight of morph target k of the node's mesh (a scalar key in x).
    Weight(u32),
}

/// Keyframe interpolation (glTF 2.0 3.11.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Each key's value holds until the next key.
    Step,
    /// Linear between keys (slerp for rotations).
    Linear,
    /// Hermite spline; each key holds (in-tangent, value, out-tangent).
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// Index of the animated node in [`Rig::nodes`].
    pub node: usize,
    /// The property animated.
    pub target: Target,
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// Ascending key times in seconds.
    pub times: Vec<f32>,
    /// One value per key (three for cubic splines); xyz for translation and
    /// scale, a quaternion (xyzw) for rotation.
    pub values: Vec<Vec4>,
}

impl Channel {
    /// The channel's value at `t` seconds (held before the first and after
    /// the last key).
    pub fn sample(&self, t: f32) -> Vec4 {
        let (times, cubic) = (
            &self.times,
            self.interpolation == Interpolation::CubicSpline,
        );
        let value = |k: usize| {
            if cubic {
                self.values[3 * k + 1]
            } else {
                self.values[k]
            }
        };
        let last = times.len() - 1;
        if t <= times[0] || last == 0 {
            return value(0);
        }
        if t >= times[last] {
            return value(last);
        }
        // times[k] <= t < times[k + 1]
        let k = times.partition_point(|&x| x <= t) - 1;
        let dt = times[k + 1] - times[k];
        let s = if dt > 0.0 { (t - times[k]) / dt } else { 0.0 };
        let rotation = self.target == Target::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => {
                let (a, b) = (Quat::from_vec4(value(k)), Quat::from_vec4(value(k + 1)));
                Vec4::from(a.normalize().slerp(b.normalize(), s))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                // p(s) = (2s³-3s²+1)v_k + (s³-2s²+s)dt·b_k + (-2s³+3s²)v_k+1 + (s³-s²)dt·a_k+1
                let (s2, s3) = (s * s, s * s * s);
                let out_tangent = self.values[3 * k + 2];
                let in_tangent = self.values[3 * (k + 1)];
                let p = value(k) * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + out_tangent * (dt * (s3 - 2.0 * s2 + s))
                    + value(k + 1) * (-2.0 * s3 + 3.0 * s2)
                    + in_tangent * (dt * (s3 - s2));
                if rotation { p.normalize_or(Vec4::W) } else { p }
            }
        }
    }
}

/// A named animation.
#[derive(Clone, Debug, PartialEq)]
pub struct Clip {
    /// The clip's name in the file (`animation<i>` when it has none).
    pub name: String,
    /// The last key time of any channel (seconds); playback loops over it.
    pub duration: f32,
    /// What the clip animates, one channel per node property.
    pub channels: Vec<Channel>,
}

/// A skin: its joints (node indices) and their inverse bind matrices.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    /// The joints' node indices, in the order JOINTS_0 indexes them.
    pub joints: Vec<usize>,
    /// IBM_i: bind pose to joint i's space, one per joint.
    pub inverse_bind: Vec<Mat4>,
}

/// The file's node tree, skins and clips: everything playback needs.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Every node of the file, in file order (channels and joints index it).
    pub nodes: Vec<RigNode>,
    /// The file's skins, in file order.
    pub skins: Vec<Skin>,
    /// The file's animations, in file order.
    pub clips: Vec<Clip>,
    /// Node indices, parents before children.
    order: Vec<usize>,
    /// The last pose computed: every object of the rig asks for the same
    /// (clip, time) in a frame, which is then computed once.
    cache: PoseCache,
}

/// (clip, time bits, pose).
type CachedPose = (Option<usize>, u32, Arc<Vec<Mat4>>);

/// The last (clip, time, pose) of a rig. Not part of its value: clones
/// start empty, and equality ignores it.
#[derive(Default)]
struct PoseCache {
    last: std::sync::Mutex<Option<CachedPose>>,
    computed: std::sync::atomic::AtomicU64,
}

impl Clone for PoseCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl PartialEq for PoseCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for PoseCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PoseCache")
    }
}

impl Rig {
    /// The index of the clip called `name`.
    pub fn clip(&self, name: &str) -> Option<usize> {
        self.clips.iter().position(|c| c.name == name)
    }

    /// Local transforms of every node under clip `clip` at `t` seconds
    /// (looped over the clip's duration).
    fn locals(&self, clip: Option<usize>, t: f32) -> Vec<Mat4> {
        let mut locals: Vec<Mat4> = self.nodes.iter().map(|n| n.rest).collect();
        let Some(clip) = clip.and_then(|c| self.clips.get(c)) else {
            return locals;
        };
        let t = if clip.duration > 0.0 {
            t.rem_euclid(clip.duration)
        } else {
            0.0
        };
        let mut trs: Vec<Option<Trs>> = vec![None; self.nodes.len()];
        for ch in &clip.channels {
            if let Target::Weight(_) = ch.target {
                continue;
            }
            let v = ch.sample(t);
            let n = trs[ch.node].get_or_insert(self.nodes[ch.node].rest_trs);
            match ch.target {
                Target::Translation => n.translation = v.truncate(),
                Target::Rotation => n.rotation = Quat::from_vec4(v).normalize(),
                Target::Scale => n.scale = v.truncate(),
                Target::Weight(_) => {}
            }
        }
        for (l, trs) in locals.iter_mut().zip(trs) {
            if let Some(trs) = trs {
                *l = trs.matrix();
            }
        }
        locals
    }

    /// The morph weights of node `node`'s mesh under `clip` at `t` (looped
    /// as the pose): `defaults` with the clip's weight channels on the node
    /// sampled over them.
    pub fn weights(&self, clip: Option<usize>, t: f32, node: usize, defaults: &[f32]) -> Vec<f32> {
        let mut w = defaults.to_vec();
        let Some(clip) = clip.and_then(|c| self.clips.get(c)) else {
            return w;
        };
        let t = if clip.duration > 0.0 {
            t.rem_euclid(clip.duration)
        } else {
            0.0
        };
        for ch in clip.channels.iter().filter(|c| c.node == node) {
            if let Target::Weight(k) = ch.target
                && let Some(slot) = w.get_mut(k as usize)
            {
                *slot = ch.sample(t).x;
            }
        }
        w
    }

    /// Whether a clip animates the morph weights of node `node`.
    pub fn animates_weights(&self, node: usize) -> bool {
        (self.clips.iter().flat_map(|c| &c.channels))
            .any(|ch| ch.node == node && matches!(ch.target, Target::Weight(_)))
    }

    /// Per morph target of node `node` (`defaults` gives their count and
    /// the values of unanimated ones): the least and greatest weight of any
    /// key value of any clip, with the default (the rest pose).
    pub fn weight_ranges(&self, node: usize, defaults: &[f32]) -> Vec<(f32, f32)> {
        let mut r: Vec<(f32, f32)> = defaults.iter().map(|&d| (d, d)).collect();
        for ch in self.clips.iter().flat_map(|c| &c.channels) {
            if let (true, Target::Weight(k)) = (ch.node == node, ch.target)
                && let Some((lo, hi)) = r.get_mut(k as usize)
            {
                for v in &ch.values {
                    (*lo, *hi) = (lo.min(v.x), hi.max(v.x));
                }
            }
        }
        r
    }

    /// World (file space) transforms of every node under `clip` at `t`.
    pub fn pose(&self, clip: Option<usize>, t: f32) -> Vec<Mat4> {
        let mut world = self.locals(clip, t);
        for &n in &self.order {
            if let Some(p) = self.nodes[n].parent {
                world[n] = world[p] * world[n];
            }
        }
        world
    }

    /// [`Rig::pose`] through the rig's cache of the last pose: the objects
    /// of one rig share one evaluation per frame (O(nodes + channels), not
    /// that per object).
    pub fn pose_shared(&self, clip: Option<usize>, t: f32) -> Arc<Vec<Mat4>> {
        let key = (clip, t.to_bits());
        let mut last = match self.cache.last.lock() {
            Ok(l) => l,
            // A panic while holding it left at worst a stale entry: recompute.
            Err(poisoned) => poisoned.into_inner(),
        };
        if let Some((c, bits, pose)) = last.as_ref()
            && (*c, *bits) == key
        {
            return pose.clone();
        }
        let pose = Arc::new(self.pose(clip, t));
        self.cache
            .computed
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        *last = Some((clip, key.1, pose.clone()));
        pose
    }

    /// How many poses [`Rig::pose_shared`] computed (tests: once per time).
    pub fn poses_computed(&self) -> u64 {
        self.cache
            .computed
            .load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Joint matrices of skin `skin` in pose `pose` ([`Rig::pose`]):
    /// J_i = W(joint_i) · IBM_i.
    pub fn joint_matrices(&self, skin: usize, pose: &[Mat4]) -> Vec<Mat4> {
        let s = &self.skins[skin];
        (s.joints.iter().zip(&s.inverse_bind))
            .map(|(&j, ibm)| pose[j] * *ibm)
            .collect()
    }

    /// Times to sample for bounds over every clip: evenly spaced and every
    /// key time of the clip.
    fn sample_times(&self) -> Vec<(Option<usize>, f32)> {
        let mut out = vec![(None, 0.0)];
        for (c, clip) in self.clips.iter().enumerate() {
            out.extend(
                (0..=BOUND_SAMPLES)
                    .map(|i| (Some(c), clip.duration * i as f32 / BOUND_SAMPLES as f32)),
            );
            let keys = clip.channels.iter().flat_map(|ch| ch.times.iter().copied());
            out.extend(keys.take(4 * BOUND_SAMPLES).map(|t| (Some(c), t)));
        }
        out
    }
}

/// A skinned mesh vertex in its bind pose, as `passes/skin` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SkinVertex {
    /// xyz: bind-pose position; w: the output vertex (u32 bits, set at upload).
    pub position: [f32; 4],
    /// xyz: bind-pose normal; w: 0.
    pub normal: [f32; 4],
    /// xyz: tangent, w: handedness.
    pub tangent: [f32; 4],
    /// Sum 1.
    pub weights: [f32; 4],
    /// Indices into the skin's joints (offset to the scene's joint buffer at upload).
    pub joints: [u32; 4],
}

impl SkinVertex {
    /// Drawn vertex `v` with no joint weight: [`skin_vertex`] leaves it in
    /// place (the meshes `passes/skin` only morphs).
    pub fn unskinned(v: &crate::scene::Vertex) -> Self {
        SkinVertex {
            position: [v.position[0], v.position[1], v.position[2], 0.0],
            normal: [v.normal[0], v.normal[1], v.normal[2], 0.0],
            tangent: v.tangent,
            weights: [0.0; 4],
            joints: [0; 4],
        }
    }
}

/// The skinned position, normal and tangent of `v` under joint matrices
/// `joints` (the CPU twin of `passes/skin/skin.wgsl`): with
/// M = Σ w_i J\[j_i\], p' = M p, n' = normalize(M⁻ᵀ n) (through the
/// cofactor matrix, sign(det M) kept: exact under non-uniform joint scale),
/// t' = M t made orthogonal to n' and normalised. A vertex with no weight
/// is not skinned (M = I: the morphed-only meshes of the deform pass). A
/// direction M collapses keeps its bind-pose value.
pub fn skin_vertex(v: &SkinVertex, joints: &[Mat4]) -> ([f32; 3], [f32; 3], [f32; 4]) {
    let mut m = Mat4::ZERO;
    for (w, j) in v.weights.iter().zip(v.joints) {
        if *w != 0.0 {
            m += *joints.get(j as usize).unwrap_or(&Mat4::IDENTITY) * *w;
        }
    }
    if v.weights == [0.0; 4] {
        m = Mat4::IDENTITY;
    }
    let p = m.transform_point3(Vec3::from_slice(&v.position[..3]));
    let n = normal_matrix(&m) * Vec3::from_slice(&v.normal[..3]);
    let t = m.transform_vector3(Vec3::from_slice(&v.tangent[..3]));
    let n = n.normalize_or(Vec3::from_slice(&v.normal[..3]));
    // Blended matrices are not rotations: the tangent is made orthogonal to
    // the normal again (the vertex contract).
    let t = (t - n * n.dot(t)).normalize_or(Vec3::from_slice(&v.tangent[..3]));
    (p.to_array(), n.to_array(), [t.x, t.y, t.z, v.tangent[3]])
}

/// det(M)·M⁻ᵀ of the upper 3×3 up to its sign: the cofactor matrix, whose
/// columns are the cross products of M's, times sign(det M) (normals need
/// only the direction, and a singular M keeps one). `skin.wgsl`'s
/// `normal_matrix` is the same.
pub fn normal_matrix(m: &Mat4) -> glam::Mat3 {
    let (a, b, c) = (
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    );
    let sign = if a.dot(b.cross(c)) < 0.0 { -1.0 } else { 1.0 };
    glam::Mat3::from_cols(b.cross(c), c.cross(a), a.cross(b)) * sign
}

/// Bind-pose vertices with their joints and weights, shared by the objects
/// of one skinned mesh.
pub type SkinVertices = Arc<Vec<SkinVertex>>;

/// An object moved by a rig: its node's animated transform, or (skinned)
/// its skin's joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Animated {
    /// The rig of the object's file (shared by its objects).
    pub rig: Arc<Rig>,
    /// The object's node in the rig.
    pub node: usize,
    /// Skinned: the skin and the mesh's bind-pose vertices.
    pub skin: Option<(usize, SkinVertices)>,
    /// The clip played; `None` holds the rest pose.
    pub clip: Option<usize>,
    /// Bounds of the object's mesh over every clip, in file space.
    pub swept: Aabb,
    /// Morph targets whose weights a clip animates: the mesh is morphed
    /// each frame to [`Animated::weights_at`] (on the GPU, `passes/skin`),
    /// before skinning where it is skinned.
    pub morph: Option<Arc<super::MorphTargets>>,
}

impl Animated {
    /// Plays clip `name` (`None`: the rest pose). A rig without that clip
    /// keeps playing its own (scenes mixing files: each plays what it has).
    pub fn play(&mut self, name: Option<&str>) {
        match name {
            None => self.clip = None,
            Some(n) => self.clip = self.rig.clip(n).or(self.clip),
        }
    }

    /// File-space transform of the object at `t`: its node's world
    /// transform; identity for skinned meshes (glTF: a skinned mesh's node
    /// transform is ignored, the joints place it).
    pub fn local_at(&self, t: f32) -> Mat4 {
        if self.skin.is_some() {
            return Mat4::IDENTITY;
        }
        self.rig.pose_shared(self.clip, t)[self.node]
    }

    /// The morph weights at `t` (morphed objects; empty otherwise).
    pub fn weights_at(&self, t: f32) -> Vec<f32> {
        match &self.morph {
            Some(m) => self.rig.weights(self.clip, t, self.node, &m.defaults),
            None => Vec::new(),
        }
    }

    /// Joint matrices at `t` (skinned objects; empty otherwise).
    pub fn joints_at(&self, t: f32) -> Vec<Mat4> {
        match &self.skin {
            Some((skin, _)) => {
                let pose = self.rig.pose_shared(self.clip, t);
                self.rig.joint_matrices(*skin, &pose)
            }
            None => Vec::new(),
        }
    }
}

/// Bounds of a rigid node's mesh (`mesh` bounds) over every clip.
pub(super) fn swept_rigid(rig: &Rig, node: usize, mesh: &Aabb) -> Aabb {
    (rig.sample_times().into_iter()).fold(Aabb::EMPTY, |b, (c, t)| {
        b.union(&mesh.transform(&rig.pose(c, t)[node]))
    })
}

/// Bounds of a skinned mesh over every clip (and the rest pose); with
/// `morph` (its targets and node) the vertices are morphed to the node's
/// weights at each time first.
pub(super) fn swept_skinned(
    rig: &Rig,
    skin: usize,
    vertices: &[SkinVertex],
    morph: Option<(&super::MorphTargets, usize)>,
) -> Aabb {
    let mut b = Aabb::EMPTY;
    for (c, t) in rig.sample_times() {
        let joints = rig.joint_matrices(skin, &rig.pose(c, t));
        let morphed =
            morph.map(|(m, node)| m.morph_skin(vertices, &rig.weights(c, t, node, &m.defaults)));
        let vertices = morphed.as_deref().unwrap_or(vertices);
        b = b.union(&Aabb::from_points(
            vertices
                .iter()
                .map(|v| Vec3::from(skin_vertex(v, &joints).0)),
        ));
    }
    b
}

/// Reads the file's node tree, skins and clips; `None` when the file has
/// neither skins nor animations. A weights channel becomes one channel per
/// morph target ([`Target::Weight`]).
pub(super) fn read_rig(
    cx: &GltfContext,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Option<Rig>, SceneError> {
    if doc.skins().len() == 0 && doc.animations().len() == 0 {
        return Ok(None);
    }
    let data = |b: gltf::Buffer| buffers.get(b.index()).map(Vec::as_slice);
    let mut nodes: Vec<RigNode> = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            RigNode {
                name: n
                    .name()
                    .map_or_else(|| format!("node{}", n.index()), str::to_string),
                parent: None,
                rest: Mat4::from_cols_array_2d(&n.transform().matrix()),
                rest_trs: Trs {
                    translation: Vec3::from(t),
                    rotation: Quat::from_array(r).normalize(),
                    scale: Vec3::from(s),
                },
            }
        })
        .collect();
    for n in doc.nodes() {
        for c in n.children() {
            if nodes[c.index()].parent.is_some() {
                return Err(cx.invalid(format!("node {} has more than one parent", c.index())));
            }
            nodes[c.index()].parent = Some(n.index());
        }
    }
    let order = parents_first(cx, &nodes)?;

    let mut skins = Vec::new();
    for s in doc.skins() {
        let joints: Vec<usize> = s.joints().map(|j| j.index()).collect();
        if joints.is_empty() || joints.len() > MAX_KEYS {
            return Err(cx.invalid(format!("skin {} has {} joints", s.index(), joints.len())));
        }
        let inverse_bind: Vec<Mat4> = match s.reader(data).read_inverse_bind_matrices() {
            Some(m) => m.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        if inverse_bind.len() != joints.len() || !inverse_bind.iter().all(Mat4::is_finite) {
            return Err(cx.invalid(format!(
                "skin {}: {} finite inverse bind matrices for {} joints expected",
                s.index(),
                inverse_bind.len(),
                joints.len()
            )));
        }
        skins.push(Skin {
            joints,
            inverse_bind,
        });
    }

    let mut clips = Vec::new();
    for a in doc.animations() {
        let name = a
            .name()
            .map_or_else(|| format!("animation{}", a.index()), str::to_string);
        let mut channels = Vec::new();
        for ch in a.channels() {
            use gltf::animation::{Property, util::ReadOutputs};
            let bad = |what: String| cx.invalid(format!("animation \"{name}\": {what}"));
            let target = match ch.target().property() {
                Property::Translation => Target::Translation,
                Property::Rotation => Target::Rotation,
                Property::Scale => Target::Scale,
                Property::MorphTargetWeights => Target::Weight(0),
            };
            let reader = ch.reader(data);
            let times: Vec<f32> = match reader.read_inputs() {
                Some(i) => i.collect(),
                None => return Err(bad("a sampler's input cannot be read".into())),
            };
            let v3 = |v: [f32; 3]| Vec4::new(v[0], v[1], v[2], 0.0);
            let values: Vec<Vec4> = match reader.read_outputs() {
                Some(ReadOutputs::Translations(v)) | Some(ReadOutputs::Scales(v)) => {
                    v.map(v3).collect()
                }
                Some(ReadOutputs::Rotations(r)) => r.into_f32().map(Vec4::from).collect(),
                Some(ReadOutputs::MorphTargetWeights(w)) => {
                    w.into_f32().map(|w| Vec4::new(w, 0.0, 0.0, 0.0)).collect()
                }
                None => return Err(bad("a sampler's output cannot be read".into())),
            };
            let interpolation = match ch.sampler().interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let per_key = if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
            if times.is_empty() || times.len() > MAX_KEYS {
                return Err(bad(format!("a channel has {} keys", times.len())));
            }
            if target == Target::Weight(0) {
                // One channel per morph target: key j's value s (in-tangent,
                // value, out-tangent for cubic splines) of target k is
                // output (j · per_key + s) · n + k.
                let per = times.len() * per_key;
                let n = values.len().checked_div(per).unwrap_or(0);
                if n == 0 || n * per != values.len() || n > MAX_KEYS {
                    return Err(bad(format!(
                        "a weights channel has {} values for {} keys",
                        values.len(),
                        times.len()
                    )));
                }
                if !values.iter().all(|v| v.is_finite()) {
                    return Err(bad("non-finite key values".into()));
                }
                if !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                    return Err(bad("key times must be finite and ascending".into()));
                }
                for k in 0..n {
                    channels.push(Channel {
                        node: ch.target().node().index(),
                        target: Target::Weight(k as u32),
                        interpolation,
                        times: times.clone(),
                        values: values.iter().skip(k).step_by(n).copied().collect(),
                    });
                }
                continue;
            }
            if values.len() != times.len() * per_key {
                return Err(bad(format!(
                    "a channel has {} keys and {} values ({per_key} per key expected)",
                    times.len(),
                    values.len()
                )));
            }
            if !times.iter().all(|t| t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                return Err(bad("key times must be finite and ascending".into()));
            }
            if !values.iter().all(|v| v.is_finite()) {
                return Err(bad("non-finite key values".into()));
            }
            channels.push(Channel {
                node: ch.target().node().index(),
                target,
                interpolation,
                times,
                values,
            });
        }
        let duration = (channels.iter())
            .filter_map(|c| c.times.last().copied())
            .fold(0.0f32, f32::max);
        clips.push(Clip {
            name,
            duration,
            channels,
        });
    }
    Ok(Some(Rig {
        nodes,
        skins,
        clips,
        order,
        cache: PoseCache::default(),
    }))
}

/// Node indices with every parent before its children; a cycle is an error.
fn parents_first(cx: &GltfContext, nodes: &[RigNode]) -> Result<Vec<usize>, SceneError> {
    let mut depth: Vec<Option<usize>> = vec![None; nodes.len()];
    for start in 0..nodes.len() {
        let mut chain = vec![start];
        while let Some(&n) = chain.last() {
            if depth[n].is_some() {
                chain.pop();
                break;
            }
            match nodes[n].parent {
                Some(p) if depth[p].is_none() => {
                    if chain.len() > nodes.len() {
                        return Err(cx.invalid("the node hierarchy has a cycle"));
                    }
                    chain.push(p);
                }
                _ => break,
            }
        }
        // Resolve from the top of the chain down.
        while let Some(n) = chain.pop() {
            depth[n] = Some(nodes[n].parent.and_then(|p| depth[p]).map_or(0, |d| d + 1));
        }
    }
    let mut order: Vec<usize> = (0..nodes.len()).collect();
    order.sort_by_key(|&n| depth[n]);
    Ok(order)
}
