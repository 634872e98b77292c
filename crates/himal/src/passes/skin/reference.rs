//! CPU twin of `skin.wgsl`: every source vertex through
//! [`crate::scene::gltf::skin_vertex`].

use glam::Mat4;

use crate::scene::gltf::{SkinVertex, skin_vertex};

/// The previous frame's position of each of `sources` under the previous
/// time's `prev_joints` (what `skin.wgsl` writes into `prev` after the header).
pub fn prev_positions(sources: &[SkinVertex], prev_joints: &[Mat4]) -> Vec<[f32; 3]> {
    sources
        .iter()
        .map(|v| skin_vertex(v, prev_joints).0)
        .collect()
}

/// Skinned (position, normal, tangent) of each of `sources` under `joints`
/// (the scene's joint buffer: sources' joints index it directly).
pub fn skin(sources: &[SkinVertex], joints: &[Mat4]) -> Vec<([f32; 3], [f32; 3], [f32; 4])> {
    sources.iter().map(|v| skin_vertex(v, joints)).collect()
}
