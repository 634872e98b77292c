//! glTF meshes whose morph weights a clip animates: morphed on the CPU to
//! the frame's weights ([`crate::scene::gltf::MorphTargets::apply`]) and
//! written over their range of the scene's vertex buffer by
//! `SceneGpu::update_objects`, only when the weights changed. O(vertices ×
//! targets) per changed frame; skinned meshes keep their default weights
//! (docs/gltf.md, "Animation and skinning").

use crate::scene::Vertex;
use crate::scene::gltf::Animated;

/// One morphed mesh: the object that animates it and where it lies.
pub struct MorphJob {
    /// The object's rig binding, with its morph targets.
    pub animated: Animated,
    /// The mesh's first vertex in the scene's vertex buffer.
    pub first_vertex: u32,
    /// The mesh's vertices as uploaded (uv, colour, surface kept).
    pub rest: Vec<Vertex>,
    /// The weights last written (`None`: none yet).
    pub written: std::sync::Mutex<Option<Vec<f32>>>,
}

impl MorphJob {
    /// The mesh's vertices at `time` (s).
    pub fn vertices_at(&self, time: f32) -> Vec<Vertex> {
        let mut v = self.rest.clone();
        if let Some(m) = &self.animated.morph {
            m.apply(&mut v, &self.animated.weights_at(time));
        }
        v
    }

    /// Writes the shape at `time` into `vertices` when its weights differ
    /// from the last written.
    pub fn update(&self, queue: &wgpu::Queue, vertices: &wgpu::Buffer, time: f32) {
        let weights = self.animated.weights_at(time);
        let mut written = match self.written.lock() {
            Ok(w) => w,
            Err(poisoned) => poisoned.into_inner(),
        };
        if written.as_ref() == Some(&weights) {
            return;
        }
        let v = self.vertices_at(time);
        let offset = self.first_vertex as u64 * std::mem::size_of::<Vertex>() as u64;
        queue.write_buffer(vertices, offset, bytemuck::cast_slice(&v));
        *written = Some(weights);
    }
}
