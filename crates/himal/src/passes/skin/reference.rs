//! CPU twin of `skin.wgsl`: every source vertex morphed
//! ([`crate::scene::gltf::MorphTargets::vertex`]) then skinned
//! ([`crate::scene::gltf::skin_vertex`]).

use glam::Mat4;

use crate::scene::Vertex;
use crate::scene::gltf::{Animated, SkinVertex, skin_vertex};

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

/// The (position, normal, tangent) `skin.wgsl` writes for the object `a`
/// deforms at `time`: its mesh's vertices (`drawn`, as uploaded) morphed to
/// its weights at `time` where it has targets, then skinned by its joints
/// at `time` where it has a skin.
pub fn deform(a: &Animated, drawn: &[Vertex], time: f32) -> Vec<([f32; 3], [f32; 3], [f32; 4])> {
    let sources: Vec<SkinVertex> = match &a.skin {
        Some((_, bind)) => bind.to_vec(),
        None => drawn.iter().map(SkinVertex::unskinned).collect(),
    };
    let sources = match &a.morph {
        Some(m) => m.morph_skin(&sources, &a.weights_at(time)),
        None => sources,
    };
    skin(&sources, &a.joints_at(time))
}
