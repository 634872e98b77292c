//! Morph targets kept for animated weights (glTF 2.0 3.7.2.2, 3.11): the
//! un-morphed attributes and each target's deltas per drawn vertex, and
//! the morph itself, P = P0 + Σ wᵢ ΔPᵢ (normals and tangents alike, then
//! normalised). `gpu_scene` morphs the animated meshes with it each frame;
//! docs/gltf.md, "Animation and skinning".

use glam::Vec3;

use crate::scene::{Aabb, Vertex};

/// One target's deltas per drawn vertex (empty: the target has none).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// POSITION deltas.
    pub positions: Vec<[f32; 3]>,
    /// NORMAL deltas (empty where the file gives none).
    pub normals: Vec<[f32; 3]>,
    /// TANGENT deltas (empty where the file gives none).
    pub tangents: Vec<[f32; 3]>,
}

/// A mesh's morph targets, indexed like its vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTargets {
    /// The mesh's default weights (missing ones 0), one per target.
    pub defaults: Vec<f32>,
    /// Un-morphed positions.
    pub positions: Vec<[f32; 3]>,
    /// Un-morphed normals; `None` when the file has none (the drawn normals
    /// are then flat ones of the default shape and are not morphed).
    pub normals: Option<Vec<[f32; 3]>>,
    /// Un-morphed tangents (xyz); `None` when generated (MikkTSpace): the
    /// drawn tangent is then only made orthogonal to the morphed normal.
    pub tangents: Option<Vec<[f32; 3]>>,
    /// The targets, in file order.
    pub targets: Vec<MorphTarget>,
}

impl MorphTargets {
    /// Writes the shape at `weights` (one per target; missing ones 0) into
    /// `vertices` (the mesh's vertices, same order): positions, and normals
    /// and tangents where the file gives them; the tangent is made
    /// orthogonal to the normal again and normalised, its handedness kept.
    pub fn apply(&self, vertices: &mut [Vertex], weights: &[f32]) {
        let w = |k: usize| weights.get(k).copied().unwrap_or(0.0);
        let sum = |base: [f32; 3], i: usize, of: fn(&MorphTarget) -> &Vec<[f32; 3]>| {
            let mut v = Vec3::from(base);
            for (k, t) in self.targets.iter().enumerate() {
                if let Some(d) = of(t).get(i)
                    && w(k) != 0.0
                {
                    v += w(k) * Vec3::from(*d);
                }
            }
            v
        };
        for (i, v) in vertices.iter_mut().enumerate() {
            if let Some(p) = self.positions.get(i) {
                v.position = sum(*p, i, |t| &t.positions).to_array();
            }
            if let Some(n) = self.normals.as_ref().and_then(|n| n.get(i)) {
                v.normal = sum(*n, i, |t| &t.normals).normalize_or(Vec3::Y).to_array();
            }
            let n = Vec3::from(v.normal);
            let t = match self.tangents.as_ref().and_then(|t| t.get(i)) {
                Some(t) => sum(*t, i, |t| &t.tangents),
                None => Vec3::from_slice(&v.tangent[..3]),
            };
            let t = (t - n * n.dot(t))
                .try_normalize()
                .unwrap_or_else(|| n.any_orthonormal_vector());
            v.tangent[..3].copy_from_slice(&t.to_array());
        }
    }

    /// Bounds of the positions for every weight vector whose weight k lies
    /// in `ranges[k]` (min, max; missing ones the default): per vertex and
    /// axis the extremes of each target's term, so exact for weights that
    /// only move between their key values (LINEAR, STEP).
    pub fn bounds(&self, ranges: &[(f32, f32)]) -> Aabb {
        let range = |k: usize| {
            ranges
                .get(k)
                .copied()
                .unwrap_or((self.defaults[k], self.defaults[k]))
        };
        Aabb::from_points(self.positions.iter().enumerate().flat_map(|(i, p)| {
            let (mut lo, mut hi) = (Vec3::from(*p), Vec3::from(*p));
            for (k, t) in self.targets.iter().enumerate() {
                if let Some(d) = t.positions.get(i) {
                    let (a, b) = range(k);
                    let (da, db) = (a * Vec3::from(*d), b * Vec3::from(*d));
                    lo += da.min(db);
                    hi += da.max(db);
                }
            }
            [lo, hi]
        }))
    }
}
