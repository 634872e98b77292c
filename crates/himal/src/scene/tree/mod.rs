//! V1 trees (issue #18, part 1; Far Cry 4's vegetation talk,
//! `seeds/000_...`, `002_...`): a deterministic procedural generator of
//! two species, a conifer like the talk's larch and a broadleaf like its
//! rosewood, and their LODs. Trunk and branches are tapered generalized
//! cylinders ([`Limb`]); leaves are alpha-tested cards grouped in clusters
//! ([`Cluster`]). Leaf LODs keep the clusters most visible from 9
//! viewpoints at 12 distances ([`visibility`]), enlarged so the crown's
//! coverage stays; trunk LODs reduce radial and segment counts.
//! Method and figures: `docs/techniques/V1.md`.
//!
//! Card vertices follow the vegetation conventions (`vegetation.rs`: `uv.x`
//! = pattern seed + 0..1, `uv.y` = 0..1); the cluster's random tint in
//! [0, 1] is mixed into the vertex colour between the leaf material and
//! the tint colour (V5). Every trunk and card vertex carries `uv1 = [bone,
//! weight]` (V2 wind, [`rig`]).

pub mod ao;
pub mod bake;
pub mod impostor;
pub mod impostor_level;
pub mod rig;
pub mod visibility;

use std::ops::Range;

use glam::Vec3;

use super::lod::Level;
use super::noise::{hash_lattice, hash_to_unit};
use super::primitives::MeshBuilder;
use super::vegetation::Rng;
use super::{MaterialDesc, Mesh};

pub use bake::LeafLods;
pub use visibility::{DISTANCES, VIEWPOINTS, VisibilityTable};

/// Name prefix of trunk meshes (`--vegetation off` finds trunks by it).
pub const TRUNK_PREFIX: &str = "tree-trunk/";

/// Levels per tree part: LOD0 and two reductions (the leaves' impostor
/// level comes after them: `impostor_level`).
pub const LEVELS: usize = 3;

/// Tree species.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Species {
    /// Conifer: straight trunk, whorls of drooping branches, needle clusters.
    Larch,
    /// Broadleaf: forked trunk, spreading crown, leaf clusters.
    Rosewood,
}

impl Species {
    /// Every species, in file-name order.
    pub const ALL: [Species; 2] = [Species::Larch, Species::Rosewood];

    /// The scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Species::Larch => "larch",
            Species::Rosewood => "rosewood",
        }
    }

    /// The species a scene file names.
    pub fn parse(name: &str) -> Option<Species> {
        Species::ALL.into_iter().find(|s| s.name() == name)
    }

    /// Fraction of the clusters LOD0, LOD1 and LOD2 keep: the talk's leaf
    /// vertex ratios (larch 44,574 / 5,465 / 846, rosewood 169,076 /
    /// 45,025 / 10,170).
    pub fn keep(self) -> [f32; LEVELS] {
        match self {
            Species::Larch => [1.0, 0.125, 0.02],
            Species::Rosewood => [1.0, 0.27, 0.06],
        }
    }
}

/// A tapered generalized cylinder along a polyline: a ring of `radial`
/// vertices around each point, radius per point.
#[derive(Clone, Debug, PartialEq)]
pub struct Limb {
    /// Centre line, root first.
    pub points: Vec<Vec3>,
    /// Radius at each point (m).
    pub radii: Vec<f32>,
    /// Vertices around at LOD0.
    pub radial: u32,
}

/// One square alpha-tested leaf card.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Card {
    /// Centre (m, tree space).
    pub centre: Vec3,
    /// Unit edge directions (u across, v along).
    pub u: Vec3,
    /// See `u`.
    pub v: Vec3,
    /// Shading normal: the crown's outward normal, tilted up (both faces).
    pub normal: Vec3,
    /// Edge length (m).
    pub size: f32,
    /// Alpha pattern seed (`uv.x` integer part).
    pub pattern: f32,
    /// Index of its cluster.
    pub cluster: u32,
}

impl Card {
    /// Corners (counter-clockwise seen from `u x v`) and their UVs, the
    /// card scaled by `s` about `pivot` (LOD compensation).
    pub fn corners(&self, pivot: Vec3, s: f32) -> [(Vec3, [f32; 2]); 4] {
        let c = pivot + (self.centre - pivot) * s;
        let h = 0.5 * self.size * s;
        let (u, v, p) = (self.u * h, self.v * h, self.pattern);
        [
            (c - u - v, [p, 0.0]),
            (c + u - v, [p + 1.0, 0.0]),
            (c + u + v, [p + 1.0, 1.0]),
            (c - u + v, [p, 1.0]),
        ]
    }
}

/// A group of cards hanging together (a needle tuft, a leaf spray): the
/// unit the LODs keep or drop.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Centre (m).
    pub centre: Vec3,
    /// Its cards in [`TreeModel::cards`].
    pub cards: Range<usize>,
    /// Random tint in [0, 1] (V5).
    pub tint: f32,
}

/// A generated tree, before meshing.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeModel {
    /// The species generated.
    pub species: Species,
    /// Trunk first, then branches.
    pub limbs: Vec<Limb>,
    /// Every leaf card, cluster by cluster.
    pub cards: Vec<Card>,
    /// The leaf clusters.
    pub clusters: Vec<Cluster>,
    /// Centre of the crown (bounding sphere of the cards).
    pub crown_centre: Vec3,
    /// Radius of the crown's bounding sphere.
    pub crown_radius: f32,
}

/// Generates a tree of `species` from `seed` (same seed, same tree, bit for
/// bit). `detail` in (0, 1] scales the cards per cluster (1: the full tree;
/// tests use less).
pub fn generate(species: Species, seed: u32, detail: f32) -> TreeModel {
    let mut g = Gen {
        rng: Rng::new(seed, 0x72EE),
        seed,
        limbs: Vec::new(),
        cards: Vec::new(),
        clusters: Vec::new(),
        detail: detail.clamp(0.01, 1.0),
    };
    match species {
        Species::Larch => g.larch(),
        Species::Rosewood => g.rosewood(),
    }
    let (crown_centre, crown_radius) = bounding_sphere(g.cards.iter().map(|c| c.centre));
    let mut model = TreeModel {
        species,
        limbs: g.limbs,
        cards: g.cards,
        clusters: g.clusters,
        crown_centre,
        crown_radius: crown_radius + 0.5,
    };
    // Shade the crown as one mass: the normal leaves its centre, a little up.
    for c in &mut model.cards {
        let out = ((c.centre - crown_centre) / Vec3::new(1.0, 1.4, 1.0)).normalize_or(Vec3::Y);
        c.normal = (out + 0.3 * Vec3::Y).normalize();
    }
    model
}

/// Centre and radius of a sphere around `points` (box centre, farthest point).
fn bounding_sphere(points: impl Iterator<Item = Vec3> + Clone) -> (Vec3, f32) {
    let b = super::Aabb::from_points(points.clone());
    if b.is_empty() {
        return (Vec3::ZERO, 1.0);
    }
    let c = b.center();
    let r = points.map(|p| p.distance(c)).fold(0.0f32, f32::max);
    (c, r.max(0.1))
}

struct Gen {
    rng: Rng,
    seed: u32,
    limbs: Vec<Limb>,
    cards: Vec<Card>,
    clusters: Vec<Cluster>,
    detail: f32,
}

impl Gen {
    fn r(&mut self) -> f32 {
        self.rng.next()
    }

    /// `r` in [lo, hi).
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.r()
    }

    fn limb(&mut self, points: Vec<Vec3>, radii: Vec<f32>, radial: u32) {
        self.limbs.push(Limb {
            points,
            radii,
            radial,
        });
    }

    /// A cluster of `cards` cards of edge `size`, centres uniform in a ball
    /// of `radius` around `centre`, facing random directions biased to `up`.
    fn cluster(&mut self, centre: Vec3, radius: f32, cards: u32, size: f32, up: f32) {
        let n = ((cards as f32 * self.detail).round() as u32).max(2);
        let id = self.clusters.len() as u32;
        let start = self.cards.len();
        for _ in 0..n {
            let q = loop {
                let q = Vec3::new(self.r(), self.r(), self.r()) * 2.0 - 1.0;
                if q.length_squared() <= 1.0 {
                    break q;
                }
            };
            let z = (self.r() * 2.0 - 1.0 + up).clamp(-1.0, 1.0);
            let az = self.r() * std::f32::consts::TAU;
            let rr = (1.0 - z * z).max(0.0).sqrt();
            let facing = Vec3::new(rr * az.cos(), z, rr * az.sin());
            let (t0, b0) = facing.any_orthonormal_pair();
            let spin = self.r() * std::f32::consts::TAU;
            let u = t0 * spin.cos() + b0 * spin.sin();
            let v = facing.cross(u);
            let pattern = self.rng.pattern_seed();
            let s = size * self.range(0.8, 1.2);
            self.cards.push(Card {
                centre: centre + q * radius,
                u,
                v,
                normal: facing,
                size: s,
                pattern,
                cluster: id,
            });
        }
        let tint = hash_to_unit(hash_lattice(self.seed, id as i32, 0x7157));
        self.clusters.push(Cluster {
            centre,
            cards: start..self.cards.len(),
            tint,
        });
    }

    /// Larch: an 18 m straight trunk; 14 whorls of 5 drooping branches,
    /// shorter toward the top (a cone); needle clusters along each branch.
    fn larch(&mut self) {
        let h = self.range(16.0, 19.0);
        let n = 40;
        let lean = Vec3::new(self.range(-0.3, 0.3), 0.0, self.range(-0.3, 0.3));
        let trunk: Vec<Vec3> = (0..n)
            .map(|i| {
                let t = i as f32 / (n - 1) as f32;
                Vec3::new(0.0, h * t, 0.0) + lean * t * t
            })
            .collect();
        let radii = (0..n)
            .map(|i| 0.03 + 0.27 * (1.0 - i as f32 / (n - 1) as f32).powf(0.9))
            .collect();
        self.limb(trunk.clone(), radii, 16);
        let whorls = 14;
        for w in 0..whorls {
            let tw = w as f32 / (whorls - 1) as f32;
            let y = h * (0.22 + 0.74 * tw) + self.range(-0.2, 0.2);
            let base = Vec3::new(0.0, y, 0.0) + lean * (y / h).powi(2);
            let yaw0 = self.r() * std::f32::consts::TAU;
            for k in 0..5 {
                let yaw = yaw0 + k as f32 * std::f32::consts::TAU / 5.0 + self.range(-0.3, 0.3);
                let dir = Vec3::new(yaw.cos(), 0.0, yaw.sin());
                let len = (0.3 * h * (1.0 - tw).powf(0.9) + 0.6) * self.range(0.85, 1.1);
                let droop = self.range(0.25, 0.45);
                let m = 8;
                let pts: Vec<Vec3> = (0..m)
                    .map(|i| {
                        let s = i as f32 / (m - 1) as f32;
                        base + dir * len * s + Vec3::Y * len * (0.15 * s - droop * s * s)
                    })
                    .collect();
                let r0 = 0.02 + 0.012 * len;
                let radii = (0..m)
                    .map(|i| r0 * (1.0 - 0.8 * i as f32 / (m - 1) as f32))
                    .collect();
                self.limb(pts.clone(), radii, 7);
                // Needle tufts from a third of the way out to the tip.
                let tufts = 5;
                for c in 0..tufts {
                    let s = 0.3 + 0.7 * (c as f32 + self.r()) / tufts as f32;
                    let i = (s * (m - 1) as f32).min((m - 1) as f32);
                    let (i0, f) = (i.floor() as usize, i.fract());
                    let p = pts[i0].lerp(pts[(i0 + 1).min(m - 1)], f);
                    let jitter = Vec3::new(self.r(), self.r(), self.r()) * 0.3 - 0.15;
                    let radius = 0.3 + 0.15 * (1.0 - tw);
                    self.cluster(p + jitter - Vec3::Y * 0.1, radius, 32, 0.34, -0.2);
                }
            }
        }
    }

    /// Rosewood: a 4 m bole forking into three limbs that fork again; ten
    /// side branches per upper limb spread a wide crown of leaf sprays.
    fn rosewood(&mut self) {
        let h = self.range(11.0, 13.0);
        let bole = h * 0.33;
        let n = 16;
        let pts: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(0.0, bole * i as f32 / (n - 1) as f32, 0.0))
            .collect();
        let radii = (0..n)
            .map(|i| 0.34 - 0.08 * i as f32 / (n - 1) as f32)
            .collect();
        self.limb(pts, radii, 12);
        let fork = Vec3::new(0.0, bole, 0.0);
        let yaw0 = self.r() * std::f32::consts::TAU;
        for k in 0..3 {
            let yaw = yaw0 + k as f32 * std::f32::consts::TAU / 3.0 + self.range(-0.25, 0.25);
            let out = Vec3::new(yaw.cos(), 0.0, yaw.sin());
            let dir = (out * 0.7 + Vec3::Y).normalize();
            let len = h * self.range(0.3, 0.36);
            let end = self.bent_limb(fork, dir, len, 0.2, 0.13, 10, 9);
            for j in 0..2 {
                let side = out.cross(Vec3::Y) * if j == 0 { 1.0 } else { -1.0 };
                let dir2 = (out * 0.8 + side * 0.6 + Vec3::Y * 0.9).normalize();
                let len2 = h * self.range(0.3, 0.36);
                let tip = self.bent_limb(end, dir2, len2, 0.12, 0.03, 9, 8);
                let hub = end;
                for b in 0..10 {
                    let s = 0.2 + 0.8 * (b as f32 + self.r()) / 10.0;
                    let from = hub.lerp(tip, s);
                    let a = self.r() * std::f32::consts::TAU;
                    let d =
                        (Vec3::new(a.cos(), 0.0, a.sin()) + out * 0.8 + Vec3::Y * 0.3).normalize();
                    let l3 = self.range(1.6, 2.6);
                    let twig_end = self.bent_limb(from, d, l3, 0.045, 0.012, 6, 6);
                    // Leaf sprays along the side branch and around its tip.
                    for c in 0..6 {
                        let s3 = 0.3 + 0.7 * (c as f32 + self.r()) / 6.0;
                        let p = from.lerp(twig_end, s3);
                        let jitter = Vec3::new(self.r(), self.r(), self.r()) * 0.8 - 0.4;
                        self.cluster(p + jitter, 0.5, 105, 0.24, 0.3);
                    }
                }
                for _ in 0..6 {
                    let jitter = Vec3::new(self.r(), self.r(), self.r()) * 1.2 - 0.6;
                    self.cluster(tip + jitter, 0.5, 105, 0.24, 0.3);
                }
            }
        }
    }

    /// A limb from `from` along `dir` curving up a little, tapering from
    /// `r0` to `r1`; returns its tip.
    #[allow(clippy::too_many_arguments)]
    fn bent_limb(
        &mut self,
        from: Vec3,
        dir: Vec3,
        len: f32,
        r0: f32,
        r1: f32,
        points: usize,
        radial: u32,
    ) -> Vec3 {
        let bend = Vec3::new(self.range(-0.15, 0.15), 0.12, self.range(-0.15, 0.15));
        let pts: Vec<Vec3> = (0..points)
            .map(|i| {
                let s = i as f32 / (points - 1) as f32;
                from + dir * len * s + bend * len * s * s
            })
            .collect();
        let radii = (0..points)
            .map(|i| r0 + (r1 - r0) * i as f32 / (points - 1) as f32)
            .collect();
        let tip = pts[points - 1];
        self.limb(pts, radii, radial);
        tip
    }
}

/// Radial and segment step of trunk level `l`: LOD1 halves the vertices
/// around and takes every second ring, LOD2 a quarter and every fourth.
fn limb_detail(limb: &Limb, level: usize) -> (u32, usize) {
    let radial = (limb.radial >> level).max(3);
    (radial, 1 << level)
}

/// Appends the tube of `limb` at `level` to `b`; UVs in metres (u around,
/// v along); `uv1` its bone and weight (`hang`: [`rig::Rig::limbs`]).
fn limb_mesh(b: &mut MeshBuilder, limb: &Limb, level: usize, rig: &rig::Rig, hang: (u32, Vec3)) {
    let (radial, step) = limb_detail(limb, level);
    let n = limb.points.len();
    if n < 2 {
        return;
    }
    let mut rings: Vec<usize> = (0..n).step_by(step).collect();
    if rings.last() != Some(&(n - 1)) {
        rings.push(n - 1);
    }
    // Parallel-transported frame along the curve (no twist).
    let tangent_at = |i: usize| {
        let a = limb.points[i.saturating_sub(1)];
        let c = limb.points[(i + 1).min(n - 1)];
        (c - a).normalize_or(Vec3::Y)
    };
    let mut normal = tangent_at(0).any_orthonormal_vector();
    let mut first_rows = Vec::new();
    let mut along = 0.0;
    let mut last = limb.points[0];
    for &i in &rings {
        let t = tangent_at(i);
        normal = (normal - t * normal.dot(t)).normalize_or(t.any_orthonormal_vector());
        let binormal = t.cross(normal);
        along += limb.points[i].distance(last);
        last = limb.points[i];
        let r = limb.radii[i];
        let first = b.vertex_count();
        for k in 0..=radial {
            let a = k as f32 / radial as f32 * std::f32::consts::TAU;
            let out = normal * a.cos() + binormal * a.sin();
            let around = t.cross(out);
            let p = limb.points[i] + out * r;
            let v = b.vertex(p, out, around, [a * r.max(0.05), along]);
            b.set_uv1(v, rig.uv1(hang, p));
        }
        first_rows.push(first);
    }
    for w in first_rows.windows(2) {
        let (a0, a1) = (w[0], w[1]);
        for k in 0..radial {
            // Counter-clockwise seen from outside.
            b.triangle(a0 + k, a0 + k + 1, a1 + k);
            b.triangle(a0 + k + 1, a1 + k + 1, a1 + k);
        }
    }
}

/// Appends the cards of `clusters` (each scaled by `s` about its centre) to `b`.
fn cards_mesh(
    b: &mut MeshBuilder,
    model: &TreeModel,
    clusters: &[usize],
    s: f32,
    colors: (Vec3, Vec3),
    alpha: f32,
    rig: &rig::Rig,
) {
    for &ci in clusters {
        let cl = &model.clusters[ci];
        let color = colors.0.lerp(colors.1, cl.tint);
        for card in &model.cards[cl.cards.clone()] {
            let tangent = (card.u - card.normal * card.normal.dot(card.u))
                .normalize_or(card.normal.any_orthonormal_vector());
            let i = card.corners(cl.centre, s).map(|(p, uv)| {
                let i = b.vertex(p, card.normal, tangent, uv);
                b.set_uv1(i, rig.uv1(rig.clusters[ci], p));
                b.set_color(i, [color.x, color.y, color.z, alpha]);
                i
            });
            b.triangle(i[0], i[1], i[2]);
            b.triangle(i[0], i[2], i[3]);
        }
    }
}

/// A tree's two meshes with their levels, and what each level holds.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeMeshes {
    /// Trunk and branches (opaque); `levels` holds LOD1 and LOD2.
    pub trunk: Mesh,
    /// Leaf cards (alpha-tested); `levels` holds LOD1 and LOD2.
    pub leaves: Mesh,
    /// Vertices of each level (trunk, leaves).
    pub vertices: [[usize; LEVELS]; 2],
    /// Clusters each leaf level keeps.
    pub clusters: [usize; LEVELS],
    /// Scale of the kept clusters per leaf level (coverage compensation).
    pub card_scale: [f32; LEVELS],
    /// V2: the bones both meshes hang on.
    pub rig: rig::Rig,
}

/// Meshes `model`: levels over one vertex buffer per part (each level's
/// vertices appended after the previous one's; `Mesh::levels` index them).
/// Leaf level `l` keeps the `keep[l]` fraction of clusters ranked by
/// visibility, scaled by `lods.card_scale[l]` ([`LeafLods::new`]).
pub fn meshes(
    model: &TreeModel,
    lods: &LeafLods,
    name: &str,
    bark: &MaterialDesc,
    leaves: &MaterialDesc,
    tint: Vec3,
) -> TreeMeshes {
    let kept = std::array::from_fn(|level| lods.kept(model, level));
    meshes_keeping(model, &kept, lods.card_scale, name, bark, leaves, tint)
}

/// [`meshes`] with each leaf level's clusters and card scale given
/// (`kept[0]`: every cluster), e.g. a chain chosen without visibility to
/// compare against (`tests/tree_stability.rs`).
pub fn meshes_keeping(
    model: &TreeModel,
    kept: &[Vec<usize>; LEVELS],
    card_scale: [f32; LEVELS],
    name: &str,
    bark: &MaterialDesc,
    leaves: &MaterialDesc,
    tint: Vec3,
) -> TreeMeshes {
    let rig = rig::rig(model);
    // Trunk.
    let mut trunk_levels: Vec<(Vec<u32>, usize)> = Vec::new();
    let mut b = MeshBuilder::new(bark);
    for level in 0..LEVELS {
        let (v0, i0) = (b.vertex_count(), b.index_count());
        for (limb, &hang) in model.limbs.iter().zip(&rig.limbs) {
            limb_mesh(&mut b, limb, level, &rig, hang);
        }
        trunk_levels.push((b.indices_from(i0), (b.vertex_count() - v0) as usize));
    }
    let trunk_error = |l: usize| {
        // The chord's sagitta of the thickest limb at this level's ring.
        let r = model.limbs.first().map_or(0.0, |t| t.radii[0]);
        let n = model.limbs.first().map_or(3, |t| limb_detail(t, l).0) as f32;
        r * (1.0 - (std::f32::consts::PI / n).cos()) * 2.0
    };
    let trunk = leveled(
        b,
        format!("{TRUNK_PREFIX}{name}"),
        trunk_levels.clone(),
        trunk_error,
    );

    // Leaves.
    let mut b = MeshBuilder::new(leaves);
    let colors = (leaves.albedo, tint);
    let alpha = leaves.vertex_color()[3];
    let mut leaf_levels = Vec::new();
    let mut clusters = [0; LEVELS];
    for level in 0..LEVELS {
        clusters[level] = kept[level].len();
        let (v0, i0) = (b.vertex_count(), b.index_count());
        cards_mesh(
            &mut b,
            model,
            &kept[level],
            card_scale[level],
            colors,
            alpha,
            &rig,
        );
        leaf_levels.push((b.indices_from(i0), (b.vertex_count() - v0) as usize));
    }
    // Visibility, not a geometric error, chooses what a leaf level drops:
    // no error guard, the levels switch at E2's distances l d_1 alone.
    let leaves_mesh = leveled(
        b,
        format!("tree-leaves/{name}"),
        leaf_levels.clone(),
        |_| 0.0,
    );
    TreeMeshes {
        trunk,
        leaves: leaves_mesh,
        vertices: [
            std::array::from_fn(|l| trunk_levels[l].1),
            std::array::from_fn(|l| leaf_levels[l].1),
        ],
        clusters,
        card_scale,
        rig,
    }
}

/// The meshes of tree `species` from `seed` at full detail, as scene files
/// place them: generated, its leaf LODs read from the bake cache (baked
/// and written there on first use, [`bake::load_or_bake`]), meshed.
pub fn cached(
    species: Species,
    seed: u32,
    name: &str,
    bark: &MaterialDesc,
    leaves: &MaterialDesc,
    tint: Vec3,
) -> TreeMeshes {
    let model = generate(species, seed, 1.0);
    let lods = bake::load_or_bake(&model, seed);
    meshes(&model, &lods, name, bark, leaves, tint)
}

/// The builder's mesh with LOD0's indices and the later levels in `levels`.
fn leveled(
    b: MeshBuilder,
    name: String,
    levels: Vec<(Vec<u32>, usize)>,
    error: impl Fn(usize) -> f32,
) -> Mesh {
    let mut mesh = b.finish(name);
    let mut levels = levels.into_iter();
    mesh.indices = levels.next().map(|l| l.0).unwrap_or_default();
    mesh.levels = levels
        .enumerate()
        .map(|(l, (indices, _))| Level {
            indices,
            error: error(l + 1),
        })
        .collect();
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn generation_is_deterministic_and_seeded() {
        let a = generate(Species::Larch, 3, 0.2);
        assert_eq!(a, generate(Species::Larch, 3, 0.2));
        assert_ne!(a.cards, generate(Species::Larch, 4, 0.2).cards);
        for s in Species::ALL {
            let t = generate(s, 1, 0.2);
            assert!(!t.clusters.is_empty() && !t.limbs.is_empty());
            assert!(t.cards.iter().all(|c| c.centre.is_finite()));
            // Every card belongs to the cluster that lists it.
            for (i, cl) in t.clusters.iter().enumerate() {
                assert!(
                    t.cards[cl.cards.clone()]
                        .iter()
                        .all(|c| c.cluster == i as u32)
                );
            }
            assert_eq!(Species::parse(s.name()), Some(s));
        }
    }

    /// Full trees: vertex counts per level beside the talk's, decreasing,
    /// and each level's clusters the most visible ones.
    #[test]
    fn levels_keep_the_most_visible_clusters() {
        let m = MaterialDesc::default();
        for s in Species::ALL {
            let t0 = std::time::Instant::now();
            let model = generate(s, 1, 1.0);
            let t1 = std::time::Instant::now();
            let table = visibility::table(&model);
            let lods = LeafLods::new(&model, &table);
            let t2 = std::time::Instant::now();
            let meshes = meshes(&model, &lods, s.name(), &m, &m, Vec3::ONE);
            println!(
                "{}: {} clusters, {} cards; trunk vertices {:?}, leaf vertices {:?}, clusters {:?}, \
                 card scale {:?}; generate {:.2} s, visibility and scales {:.2} s, meshes {:.2} s",
                s.name(),
                model.clusters.len(),
                model.cards.len(),
                meshes.vertices[0],
                meshes.vertices[1],
                meshes.clusters,
                meshes.card_scale,
                (t1 - t0).as_secs_f32(),
                (t2 - t1).as_secs_f32(),
                t2.elapsed().as_secs_f32(),
            );
            // E2's first switch at 1280 x 720, 60 degrees, T = 4 px: d_1 = size f / sqrt(T).
            let f = crate::scene::lod::focal_px(60.0, 720);
            let d1 = |m: &Mesh| {
                crate::scene::lod::geometric_mean_area(&m.vertices, &m.indices).sqrt() * f / 2.0
            };
            println!(
                "{}: d_1 at 720p: trunk {:.0} m, leaves {:.0} m",
                s.name(),
                d1(&meshes.trunk),
                d1(&meshes.leaves)
            );
            for part in meshes.vertices {
                assert!(part[0] > part[1] && part[1] > part[2], "{part:?}");
            }
            assert_eq!(meshes.leaves.levels.len(), LEVELS - 1);
            assert!(meshes.card_scale[1] >= 1.0 && meshes.card_scale[2] >= meshes.card_scale[1]);
            // Within each height band, kept clusters score at least as high
            // as every dropped one; every band keeps some at LOD1.
            let bands = bake::height_bands(&model);
            for level in 1..LEVELS {
                let kept = lods.kept(&model, level);
                assert_eq!(kept.len(), meshes.clusters[level]);
                for b in 0..bake::HEIGHT_BANDS {
                    let of = |keep: bool| -> Vec<usize> {
                        (0..model.clusters.len())
                            .filter(|&c| bands[c] == b && kept.contains(&c) == keep)
                            .collect()
                    };
                    let (k, d) = (of(true), of(false));
                    let worst_kept = k
                        .iter()
                        .map(|&c| table.score[c])
                        .fold(f32::INFINITY, f32::min);
                    let best_dropped = d.iter().map(|&c| table.score[c]).fold(0.0, f32::max);
                    assert!(k.is_empty() || worst_kept >= best_dropped, "band {b}");
                    assert!(level > 1 || !k.is_empty(), "band {b} empty at LOD1");
                }
            }
            // Every level indexes its own vertices only.
            let nv = meshes.leaves.vertices.len() as u32;
            assert!(
                meshes
                    .leaves
                    .levels
                    .iter()
                    .all(|l| l.indices.iter().all(|&i| i < nv))
            );
        }
    }
}
