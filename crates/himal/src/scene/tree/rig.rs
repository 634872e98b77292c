//! V2: a tree's bones for the GPU wind simulation (`passes/vegetation`).
//! Bone 0 is the trunk, bending the whole tree about its root; bones 1..3
//! are the main branches, grouped in three 120-degree sectors around the
//! trunk (the rosewood's three main limbs; the larch's whorls by side).
//! Each limb belongs to the sector of its top-level ancestor (the limb
//! that leaves the trunk), each leaf cluster to its nearest limb's; the
//! weight grows with the distance from that ancestor's root, so every limb
//! stays attached. Baked into the meshes as `uv1 = [bone, weight]`.
//! Equations: `docs/techniques/V2.md`.

use glam::Vec3;

use super::TreeModel;

/// Bones per tree (trunk + three branch sectors).
pub const BONES: usize = 4;

/// One bone at rest (tree space) with its dynamics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bone {
    /// Rotation centre (m).
    pub pivot: Vec3,
    /// Distance over which the weight reaches 1 (m).
    pub length: f32,
    /// Where the bone feels the wind (m).
    pub sample: Vec3,
    /// Equilibrium angle per (m/s)^2 of wind (rad).
    pub gain: f32,
    /// Natural angular frequency (rad/s).
    pub omega: f32,
    /// Damping ratio.
    pub damping: f32,
}

/// A tree's bones and how its parts hang on them.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Trunk, then the three branch sectors.
    pub bones: [Bone; BONES],
    /// Height of the tree (m): the trunk's bend weight is `(y / height)^2`.
    pub height: f32,
    /// Per limb: its bone and the root of its top-level ancestor.
    pub limbs: Vec<(u32, Vec3)>,
    /// Per cluster: its bone and root (its nearest limb's).
    pub clusters: Vec<(u32, Vec3)>,
}

/// The rig of a scene's tree meshes (trunk, leaves: both hang on it).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRig {
    /// Scene mesh indices of the trunk and the leaves.
    pub meshes: [usize; 2],
    /// Their bones.
    pub rig: Rig,
}

/// Largest bend of any bone (rad).
pub const MAX_ANGLE: f32 = 0.35;

impl Rig {
    /// `uv1` of a vertex at `p` hanging from `(bone, root)`.
    pub fn uv1(&self, (bone, root): (u32, Vec3), p: Vec3) -> [f32; 2] {
        if bone == 0 {
            return [0.0, 0.0];
        }
        let l = self.bones[bone as usize].length;
        let w = (p.distance(root) / l).clamp(0.0, 1.0);
        [bone as f32, w * w]
    }
}

/// Nearest point of `model`'s limbs `0..before` to `p`: (limb, distance).
fn nearest_limb(model: &TreeModel, before: usize, p: Vec3) -> (usize, f32) {
    let mut best = (0, f32::INFINITY);
    for (i, l) in model.limbs.iter().enumerate().take(before) {
        for q in &l.points {
            let d = q.distance(p);
            if d < best.1 {
                best = (i, d);
            }
        }
    }
    best
}

/// Whether `p` lies on the trunk's surface or inside it (limb 0, its
/// segments with their radii, a few centimetres of slack).
fn on_trunk(model: &TreeModel, p: Vec3) -> bool {
    let Some(t) = model.limbs.first() else {
        return false;
    };
    t.points.windows(2).zip(&t.radii).any(|(w, &r)| {
        let d = w[1] - w[0];
        let s = ((p - w[0]).dot(d) / d.length_squared().max(1e-12)).clamp(0.0, 1.0);
        p.distance(w[0] + d * s) <= r + 0.05
    })
}

/// The rig of `model` (deterministic).
pub fn rig(model: &TreeModel) -> Rig {
    let mut top = model
        .limbs
        .iter()
        .flat_map(|l| &l.points)
        .chain(model.cards.iter().map(|c| &c.centre))
        .fold(1.0f32, |h, p| h.max(p.y));
    top = top.max(1.0);
    // Top-level ancestor of each limb: a limb rooted on the trunk is its own.
    let mut ancestor: Vec<usize> = Vec::with_capacity(model.limbs.len());
    for (i, l) in model.limbs.iter().enumerate() {
        let a = if i == 0 {
            0
        } else {
            let (j, _) = nearest_limb(model, i, l.points[0]);
            if j == 0 || on_trunk(model, l.points[0]) {
                i
            } else {
                ancestor[j]
            }
        };
        ancestor.push(a);
    }
    // Sectors by the azimuth of each top-level limb's tip, from limb 1's.
    let azimuth = |p: Vec3| p.z.atan2(p.x);
    let a0 = model
        .limbs
        .get(1)
        .and_then(|l| l.points.last())
        .map_or(0.0, |&p| azimuth(p));
    let sector = |p: Vec3| {
        let third = std::f32::consts::TAU / 3.0;
        let rel = (azimuth(p) - a0).rem_euclid(std::f32::consts::TAU);
        1 + ((rel / third + 0.5).floor() as u32 % 3)
    };
    let limbs: Vec<(u32, Vec3)> = (0..model.limbs.len())
        .map(|i| {
            if i == 0 {
                return (0, Vec3::ZERO);
            }
            let a = &model.limbs[ancestor[i]];
            let tip = *a.points.last().unwrap_or(&Vec3::ZERO);
            (sector(tip), a.points[0])
        })
        .collect();
    let clusters: Vec<(u32, Vec3)> = model
        .clusters
        .iter()
        .map(|c| {
            let (j, _) = nearest_limb(model, model.limbs.len(), c.centre);
            if j == 0 {
                (sector(c.centre), c.centre)
            } else {
                limbs[j]
            }
        })
        .collect();
    // Per sector: pivot (lowest root), length (farthest point from its
    // root), wind sample (mean cluster centre).
    let mut pivot = [None::<Vec3>; BONES];
    let mut length = [0.5f32; BONES];
    let mut sum = [(Vec3::ZERO, 0u32); BONES];
    for (l, &(b, root)) in model.limbs.iter().zip(&limbs).skip(1) {
        let b = b as usize;
        if pivot[b].is_none_or(|p| root.y < p.y) {
            pivot[b] = Some(root);
        }
        for q in &l.points {
            length[b] = length[b].max(q.distance(root));
        }
    }
    for (c, &(b, root)) in model.clusters.iter().zip(&clusters) {
        let b = b as usize;
        for card in &model.cards[c.cards.clone()] {
            length[b] = length[b].max(card.centre.distance(root) + 0.5 * card.size);
        }
        sum[b].0 += c.centre;
        sum[b].1 += 1;
    }
    let trunk_hz = 0.3 * (15.0 / top).sqrt();
    let trunk = Bone {
        pivot: Vec3::ZERO,
        length: top,
        sample: Vec3::new(0.0, 0.6 * top, 0.0),
        gain: 4.0e-4,
        omega: std::f32::consts::TAU * trunk_hz,
        damping: 0.12,
    };
    let bones = std::array::from_fn(|b| {
        if b == 0 {
            return trunk;
        }
        let p = pivot[b].unwrap_or(Vec3::new(0.0, 0.5 * top, 0.0));
        let sample = if sum[b].1 > 0 {
            sum[b].0 / sum[b].1 as f32
        } else {
            p
        };
        let hz = (0.9 * (6.0 / length[b]).sqrt()).clamp(0.5, 2.0);
        Bone {
            pivot: p,
            length: length[b],
            sample,
            gain: 1.2e-3,
            omega: std::f32::consts::TAU * hz,
            damping: 0.2,
        }
    });
    Rig {
        bones,
        height: top,
        limbs,
        clusters,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::tree::{Species, generate};

    #[test]
    fn every_part_hangs_on_a_bone_and_limbs_stay_attached() {
        for s in Species::ALL {
            let m = generate(s, 2, 0.2);
            let r = rig(&m);
            assert_eq!(r.limbs.len(), m.limbs.len());
            assert_eq!(r.clusters.len(), m.clusters.len());
            // Every sector holds something; weights within [0, 1].
            for b in 1..BONES as u32 {
                assert!(r.limbs.iter().any(|l| l.0 == b), "{s:?} sector {b} empty");
            }
            for (l, &lb) in m.limbs.iter().zip(&r.limbs).skip(1) {
                for p in &l.points {
                    let w = r.uv1(lb, *p)[1];
                    assert!((0.0..=1.0).contains(&w));
                }
                // The root of a top-level limb does not move with its bone.
                if lb.1 == l.points[0] {
                    assert_eq!(r.uv1(lb, l.points[0])[1], 0.0);
                }
            }
            assert_eq!(rig(&m), r);
        }
    }
}
