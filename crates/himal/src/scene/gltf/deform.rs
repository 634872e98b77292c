//! The loader's deformed objects: a skinned mesh's object at its clip's
//! first pose (morphed first where its weights animate), a morphed mesh's
//! shape at t = 0, and an instanced node's own copy at its weights.

use glam::Vec3;

use super::{Animated, MorphTargets, PbrSet, Rig, SkinVertex, animation, skin_vertex};
use crate::scene::{Aabb, Mesh};

/// The object of skinned mesh `mesh` on node `node`: its vertices become
/// the pose at t = 0 of `clip` (what static consumers and the first frame
/// see), its bounds those over every clip; with `morph` (animated weights)
/// each pose is of the vertices morphed to the node's weights first.
pub(super) fn skinned(
    rig: &std::sync::Arc<Rig>,
    (node, skin): (usize, usize),
    clip: Option<usize>,
    (vertices, morph): (Vec<SkinVertex>, Option<std::sync::Arc<MorphTargets>>),
    mesh: &mut Mesh,
) -> Animated {
    let joints = rig.joint_matrices(skin, &rig.pose(clip, 0.0));
    let at_zero = match &morph {
        Some(m) => m.morph_skin(&vertices, &rig.weights(clip, 0.0, node, &m.defaults)),
        None => vertices.clone(),
    };
    for (v, s) in mesh.vertices.iter_mut().zip(&at_zero) {
        (v.position, v.normal, v.tangent) = skin_vertex(s, &joints);
    }
    let swept = animation::swept_skinned(rig, skin, &vertices, morph.as_deref().map(|m| (m, node)));
    mesh.bounds = swept;
    Animated {
        rig: rig.clone(),
        node,
        skin: Some((skin, std::sync::Arc::new(vertices))),
        clip,
        swept,
        morph,
    }
}

/// The loader's per-mesh lists: meshes, their skins, their morph targets.
pub(super) type MeshLists<'a> = (
    &'a mut Vec<Mesh>,
    &'a mut Vec<Option<Vec<SkinVertex>>>,
    &'a mut Vec<Option<std::sync::Arc<MorphTargets>>>,
);

/// A copy of mesh `mesh` (with its skin and morph targets) at a node's own
/// weights `weights` (missing ones 0), which become the copy's defaults;
/// returns the copy's index.
pub(super) fn reweighted_copy(
    weights: &[f32],
    targets: &MorphTargets,
    mesh: usize,
    (meshes, skins, morphs): MeshLists<'_>,
    pbr: &mut PbrSet,
) -> usize {
    let mut t = targets.clone();
    t.defaults = (0..t.targets.len())
        .map(|k| {
            weights
                .get(k)
                .copied()
                .filter(|w| w.is_finite())
                .unwrap_or(0.0)
        })
        .collect();
    let mut copy = meshes[mesh].clone();
    t.apply(&mut copy.vertices, &t.defaults);
    copy.bounds = Aabb::from_points(copy.vertices.iter().map(|v| Vec3::from(v.position)));
    // A skinned copy's bind pose is the reweighted shape.
    let skin = skins[mesh].clone().map(|mut s| {
        for (s, v) in s.iter_mut().zip(&copy.vertices) {
            s.position[..3].copy_from_slice(&v.position);
            s.normal[..3].copy_from_slice(&v.normal);
            s.tangent = v.tangent;
        }
        s
    });
    if let Some(m) = pbr.material_of(mesh) {
        pbr.mesh_material.push((meshes.len(), m));
    }
    meshes.push(copy);
    skins.push(skin);
    morphs.push(Some(std::sync::Arc::new(t)));
    meshes.len() - 1
}

/// Morphed mesh `mesh` on node `node`: its vertices become the shape at
/// t = 0 of `clip`, its bounds those of every weight between the clips'
/// key values ([`MorphTargets::bounds`]).
pub(super) fn morphed(
    rig: &std::sync::Arc<Rig>,
    node: usize,
    clip: Option<usize>,
    morph: &MorphTargets,
    mesh: &mut Mesh,
) {
    morph.apply(
        &mut mesh.vertices,
        &rig.weights(clip, 0.0, node, &morph.defaults),
    );
    mesh.bounds = morph.bounds(&rig.weight_ranges(node, &morph.defaults));
}
