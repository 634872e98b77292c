//! Morph targets kept for animated weights (glTF 2.0 3.7.2.2, 3.11): the
//! un-morphed attributes and each target's deltas per drawn vertex, and
//! the morph itself, P = P0 + Σ wᵢ ΔPᵢ (normals and tangents alike, then
//! normalised). The CPU twin of the GPU morph in `passes/skin/skin.wgsl`
//! (which reads [`MorphTargets::gpu_deltas`]); docs/gltf.md, "Animation
//! and skinning".

use glam::Vec3;

use super::SkinVertex;
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
        for (i, v) in vertices.iter_mut().enumerate() {
            let t = [v.tangent[0], v.tangent[1], v.tangent[2]];
            let (p, n, t) = self.vertex(i, weights, (v.position, v.normal, t));
            (v.position, v.normal) = (p, n);
            v.tangent[..3].copy_from_slice(&t);
        }
    }

    /// Vertex `i` at `weights` from its drawn (position, normal, tangent
    /// xyz), which stand in for the attributes the file does not give.
    pub fn vertex(
        &self,
        i: usize,
        weights: &[f32],
        (p, n, t): ([f32; 3], [f32; 3], [f32; 3]),
    ) -> ([f32; 3], [f32; 3], [f32; 3]) {
        let w = |k: usize| weights.get(k).copied().unwrap_or(0.0);
        let sum = |base: [f32; 3], of: fn(&MorphTarget) -> &Vec<[f32; 3]>| {
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
        let p = match self.positions.get(i) {
            Some(p0) => sum(*p0, |t| &t.positions).to_array(),
            None => p,
        };
        let n = match self.normals.as_ref().and_then(|n| n.get(i)) {
            Some(n0) => sum(*n0, |t| &t.normals).normalize_or(Vec3::Y),
            None => Vec3::from(n),
        };
        let t = match self.tangents.as_ref().and_then(|t| t.get(i)) {
            Some(t0) => sum(*t0, |t| &t.tangents),
            None => Vec3::from(t),
        };
        let t = (t - n * n.dot(t))
            .try_normalize()
            .unwrap_or_else(|| n.any_orthonormal_vector());
        (p, n.to_array(), t.to_array())
    }

    /// Skin vertices `bind` (this mesh's, same order) morphed to `weights`
    /// before skinning (glTF 2.0: morph, then skin).
    pub fn morph_skin(&self, bind: &[SkinVertex], weights: &[f32]) -> Vec<SkinVertex> {
        (bind.iter().enumerate())
            .map(|(i, s)| {
                let v3 = |v: &[f32; 4]| [v[0], v[1], v[2]];
                let (p, n, t) =
                    self.vertex(i, weights, (v3(&s.position), v3(&s.normal), v3(&s.tangent)));
                SkinVertex {
                    position: [p[0], p[1], p[2], s.position[3]],
                    normal: [n[0], n[1], n[2], s.normal[3]],
                    tangent: [t[0], t[1], t[2], s.tangent[3]],
                    ..*s
                }
            })
            .collect()
    }

    /// The un-morphed base of vertex `i` where the file gives it, else the
    /// drawn `(p, n, t)`: what `skin.wgsl` starts from.
    pub fn base(
        &self,
        i: usize,
        (p, n, t): ([f32; 3], [f32; 3], [f32; 3]),
    ) -> ([f32; 3], [f32; 3], [f32; 3]) {
        let get = |v: Option<&Vec<[f32; 3]>>, d| v.and_then(|v| v.get(i).copied()).unwrap_or(d);
        (
            get(Some(&self.positions), p),
            get(self.normals.as_ref(), n),
            get(self.tangents.as_ref(), t),
        )
    }

    /// Vertex `i`'s deltas for `skin.wgsl`: per target (position, normal,
    /// tangent) as vec4 (w 0), zero where the file gives none (the same sum
    /// as [`MorphTargets::vertex`]: a zero term adds nothing).
    pub fn gpu_deltas(&self, i: usize, out: &mut Vec<[f32; 4]>) {
        let get = |v: &Vec<[f32; 3]>| {
            let d = v.get(i).copied().unwrap_or([0.0; 3]);
            [d[0], d[1], d[2], 0.0]
        };
        for t in &self.targets {
            let n = if self.normals.is_some() {
                get(&t.normals)
            } else {
                [0.0; 4]
            };
            let tn = if self.tangents.is_some() {
                get(&t.tangents)
            } else {
                [0.0; 4]
            };
            out.extend([get(&t.positions), n, tn]);
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
