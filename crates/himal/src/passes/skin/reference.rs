//! CPU twin of `skin.wgsl`: every source vertex through
//! [`crate::scene::gltf::skin_vertex`].

use glam::Mat4;

use crate::scene::gltf::{SkinVertex, skin_vertex};

/// Skinned (position, normal, tangent) of each of `sources` under `joints`
/// (the scene's joint buffer: sources' joints index it directly).
pub fn skin(sources: &[SkinVertex], joints: &[Mat4]) -> Vec<([f32; 3], [f32; 3], [f32; 4])> {
    sources.iter().map(|v| skin_vertex(v, joints)).collect()
}
