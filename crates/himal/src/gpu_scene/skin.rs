//! The scene's skinned meshes on the GPU: bind-pose vertices with joints
//! and weights, the joint matrices (rewritten per frame), and the skinned
//! vertices `passes/skin` writes and copies into the scene's vertex buffer,
//! where the skinned meshes lie together from `first_vertex` on.

use wgpu::util::DeviceExt;

use crate::scene::Vertex;
use crate::scene::gltf::{Animated, SkinVertex};

/// One skinned object: its rig binding and its first joint in `joints`.
#[derive(Clone, Debug)]
pub struct SkinJob {
    /// The object's rig binding: its clip and skin.
    pub animated: Animated,
    /// Offset of its joints in [`SkinGpu::joints`].
    pub first_joint: u32,
    /// Joints of its skin.
    pub joint_count: u32,
}

/// Buffers of `passes/skin` for every skinned mesh of one uploaded scene.
pub struct SkinGpu {
    /// [`SkinVertex`] per skinned vertex, joints offset to `joints`.
    pub sources: wgpu::Buffer,
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
    /// `sources` and `rest` (the same vertices as drawn at upload) of every
    /// job in order.
    pub fn new(
        device: &wgpu::Device,
        jobs: Vec<SkinJob>,
        sources: &[SkinVertex],
        rest: &[Vertex],
        first_vertex: u32,
    ) -> Self {
        let joint_count: u32 = jobs.iter().map(|j| j.joint_count).sum();
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

    /// Writes the joint matrices at `time` and at the previous frame's `prev_time`.
    pub fn update(&self, queue: &wgpu::Queue, time: f32, prev_time: f32) {
        let m = self.joint_matrices(time);
        queue.write_buffer(&self.joints, 0, bytemuck::cast_slice(&m));
        let m = self.joint_matrices(prev_time);
        queue.write_buffer(&self.prev_joints, 0, bytemuck::cast_slice(&m));
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
