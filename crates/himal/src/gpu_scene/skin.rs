//! The scene's deformed meshes on the GPU (skinned, morphed, or both):
//! bind-pose vertices with joints and weights, morph targets' deltas
//! (uploaded once), the joint matrices and morph weights (rewritten per
//! frame: O(joints + targets) per mesh, not per vertex), and the deformed
//! vertices `passes/skin` writes and copies into the scene's vertex
//! buffer, where the deformed meshes lie together from `first_vertex` on.

use wgpu::util::DeviceExt;

use crate::scene::Vertex;
use crate::scene::gltf::{Animated, SkinVertex};

/// One deformed object: its rig binding, its first joint in `joints` and
/// its first weight in `weights`.
#[derive(Clone, Debug)]
pub struct SkinJob {
    /// The object's rig binding: its clip, skin and morph targets.
    pub animated: Animated,
    /// Offset of its joints in [`SkinGpu::joints`].
    pub first_joint: u32,
    /// Joints of its skin (0: not skinned).
    pub joint_count: u32,
    /// Offset of its weights in [`SkinGpu::weights`] (the frame's, then
    /// the previous frame's).
    pub first_weight: u32,
    /// Its morph targets (0: not morphed).
    pub target_count: u32,
}

/// Buffers of `passes/skin` for every deformed mesh of one uploaded scene.
pub struct SkinGpu {
    /// [`SkinVertex`] per deformed vertex, joints offset to `joints`
    /// (morphed ones: their un-morphed base; only morphed: no weight).
    pub sources: wgpu::Buffer,
    /// Per deformed vertex (first delta, targets, first weight, 0) as u32
    /// bits, then the deltas ([`crate::scene::gltf::MorphTargets::gpu_deltas`]).
    pub morph: wgpu::Buffer,
    /// Per morphed job: its weights at the frame's time, then the previous.
    pub weights: wgpu::Buffer,
    /// One mat4x4 per joint of every job.
    pub joints: wgpu::Buffer,
    /// The skinned vertices ([`Vertex`] layout; uv, colour and surface from
    /// the upload, position, normal and tangent from the skin pass).
    pub skinned: wgpu::Buffer,
    /// Uniform: (vertex count, 0, 0, 0).
    pub params: wgpu::Buffer,
    /// The joint matrices at the previous frame's time (the skin pass
    /// writes the previous positions into `SceneGpu::deform`).
    pub prev_joints: wgpu::Buffer,
    /// Skinned vertices of all jobs.
    pub vertex_count: u32,
    /// The first skinned vertex in the scene's vertex buffer.
    pub first_vertex: u32,
    /// The skinned objects, in the order of their vertices and joints.
    pub jobs: Vec<SkinJob>,
}

impl SkinGpu {
    /// `sources`, `morph` (the `morph` buffer's contents) and `rest` (the
    /// same vertices as drawn at upload) of every job in order.
    pub fn new(
        device: &wgpu::Device,
        jobs: Vec<SkinJob>,
        (sources, morph): (&[SkinVertex], &[[f32; 4]]),
        rest: &[Vertex],
        first_vertex: u32,
    ) -> Self {
        let joint_count: u32 = jobs.iter().map(|j| j.joint_count).sum();
        let weight_count: u32 = jobs.iter().map(|j| 2 * j.target_count).sum();
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let count = [sources.len() as u32, 0, 0, 0];
        use wgpu::BufferUsages as U;
        let joint_bytes = vec![0u8; joint_count.max(1) as usize * 64];
        SkinGpu {
            sources: init("skin.sources", bytemuck::cast_slice(sources), U::STORAGE),
            joints: init("skin.joints", &joint_bytes, U::STORAGE | U::COPY_DST),
            prev_joints: init("skin.prev_joints", &joint_bytes, U::STORAGE | U::COPY_DST),
            morph: init("skin.morph", bytemuck::cast_slice(morph), U::STORAGE),
            weights: init(
                "skin.weights",
                &vec![0u8; weight_count.max(1) as usize * 4],
                U::STORAGE | U::COPY_DST,
            ),
            skinned: init(
                "skin.skinned",
                bytemuck::cast_slice(rest),
                U::STORAGE | U::COPY_SRC,
            ),
            params: init("skin.params", bytemuck::cast_slice(&count), U::UNIFORM),
            vertex_count: sources.len() as u32,
            first_vertex,
            jobs,
        }
    }

    /// Every job's joint matrices at `time` (s), in `joints` order.
    pub fn joint_matrices(&self, time: f32) -> Vec<glam::Mat4> {
        (self.jobs.iter())
            .flat_map(|j| j.animated.joints_at(time))
            .collect()
    }

    /// Every morphed job's weights at `time` then at `prev_time`, in
    /// `weights` order.
    pub fn morph_weights(&self, time: f32, prev_time: f32) -> Vec<f32> {
        let mut out = Vec::new();
        for j in self.jobs.iter().filter(|j| j.target_count > 0) {
            for t in [time, prev_time] {
                let mut w = j.animated.weights_at(t);
                w.resize(j.target_count as usize, 0.0);
                out.extend(w);
            }
        }
        out
    }

    /// Writes the joint matrices and morph weights at `time` and at the
    /// previous frame's `prev_time`.
    pub fn update(&self, queue: &wgpu::Queue, time: f32, prev_time: f32) {
        let m = self.joint_matrices(time);
        if !m.is_empty() {
            queue.write_buffer(&self.joints, 0, bytemuck::cast_slice(&m));
            let m = self.joint_matrices(prev_time);
            queue.write_buffer(&self.prev_joints, 0, bytemuck::cast_slice(&m));
        }
        let w = self.morph_weights(time, prev_time);
        if !w.is_empty() {
            queue.write_buffer(&self.weights, 0, bytemuck::cast_slice(&w));
        }
    }
}

/// Element 0 of a `deform_prev` buffer (`shaders/deform.wgsl`): the first
/// deformed vertex and their count, as u32 bits.
pub fn deform_header(first_vertex: u32, count: u32) -> [f32; 4] {
    [
        f32::from_bits(first_vertex),
        f32::from_bits(count),
        0.0,
        0.0,
    ]
}
