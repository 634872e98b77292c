//! glTF meshes whose morph weights a clip animates: morphed on the CPU to
//! the frame's weights ([`crate::scene::gltf::MorphTargets::apply`]) and
//! written over their range of the scene's vertex buffer by
//! `SceneGpu::update_objects`, only when the weights changed; their
//! positions at the previous frame's time likewise into `SceneGpu::deform`
//! (motion vectors, `shaders/deform.wgsl`). O(vertices ×
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
    /// The weights last written: of the shape and of the previous
    /// positions (`None`: none yet).
    pub written: std::sync::Mutex<[Option<Vec<f32>>; 2]>,
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

    /// Writes the shape at `time` into `vertices`, and its positions at
    /// the previous frame's `prev_time` into `deform` (`SceneGpu::deform`,
    /// for motion vectors), each when its weights differ from the last
    /// written.
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        (vertices, deform): (&wgpu::Buffer, &wgpu::Buffer),
        (time, prev_time): (f32, f32),
    ) {
        let mut written = match self.written.lock() {
            Ok(w) => w,
            Err(poisoned) => poisoned.into_inner(),
        };
        let weights = self.animated.weights_at(time);
        if written[0].as_ref() != Some(&weights) {
            let v = self.vertices_at(time);
            let offset = self.first_vertex as u64 * std::mem::size_of::<Vertex>() as u64;
            queue.write_buffer(vertices, offset, bytemuck::cast_slice(&v));
            written[0] = Some(weights);
        }
        let weights = self.animated.weights_at(prev_time);
        if written[1].as_ref() != Some(&weights) {
            let prev: Vec<[f32; 4]> = (self.vertices_at(prev_time).iter())
                .map(|v| [v.position[0], v.position[1], v.position[2], 1.0])
                .collect();
            // After the header: element 1 + vertex (the deformed range starts at 0).
            let offset = (1 + self.first_vertex as u64) * 16;
            queue.write_buffer(deform, offset, bytemuck::cast_slice(&prev));
            written[1] = Some(weights);
        }
    }
}
