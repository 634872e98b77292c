//! V1's offline leaf-cluster visibility (the talk's method): the crown is
//! rasterised on the CPU, a z-buffer of cluster ids with the cards' alpha
//! pattern, from 9 viewpoints (8 around, 15 degrees up, and the top) at 12
//! distances. A cluster's visibility from one view is the fraction of the
//! pixels its alpha-passing fragments touch where it wins the depth test
//! (hidden by other clusters only: its own overlapping cards count once);
//! its score is the mean over the 108 views. LODs keep the highest scores. Deterministic: same
//! model, same table, on any thread count.

use glam::Vec3;

use super::TreeModel;

/// Viewpoints: 8 around and one above.
pub const VIEWPOINTS: usize = 9;
/// Distances per viewpoint.
pub const DISTANCES: usize = 12;
/// Raster edge (pixels); the nearest distance fits the crown in it.
pub const RESOLUTION: usize = 128;
/// Elevation of the 8 side viewpoints (degrees).
const SIDE_ELEVATION_DEG: f32 = 15.0;
/// Nearest distance (crown radii) and the ratio between distances: 2 R to 2 R * 1.4^11 = 81 R.
const NEAREST: f32 = 2.0;
const RATIO: f32 = 1.4;
/// The distance index whose coverage LODs match (7.7 crown radii, ~33 px across).
const COVERAGE_DISTANCE: usize = 4;

/// Unit directions from the crown toward the 9 viewpoints.
pub fn viewpoints() -> [Vec3; VIEWPOINTS] {
    let e = SIDE_ELEVATION_DEG.to_radians();
    std::array::from_fn(|i| {
        if i == 8 {
            Vec3::Y
        } else {
            let a = i as f32 * std::f32::consts::TAU / 8.0;
            Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin())
        }
    })
}

/// Distances (in crown radii) of the 12 rings.
pub fn distances() -> [f32; DISTANCES] {
    std::array::from_fn(|k| NEAREST * RATIO.powi(k as i32))
}

/// Per cluster, per view and distance: the visible fraction of its fragments.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityTable {
    /// Number of clusters.
    pub clusters: usize,
    /// `fraction[(c * VIEWPOINTS + v) * DISTANCES + d]`, in [0, 1]; 0 where
    /// the cluster has no fragment (sub-pixel, or cut away by its pattern).
    pub fraction: Vec<f32>,
    /// Mean fraction over the 108 views, per cluster.
    pub score: Vec<f32>,
}

impl VisibilityTable {
    /// Cluster indices, most visible first (ties by index: deterministic).
    pub fn ranking(&self) -> Vec<usize> {
        rank(&self.score)
    }
}

/// Indices of `score`, highest first (ties by index: deterministic).
pub fn rank(score: &[f32]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..score.len()).collect();
    order.sort_by(|&a, &b| score[b].total_cmp(&score[a]).then(a.cmp(&b)));
    order
}

/// One view: crown centre `c`, radius `r`, seen from direction `dir` at
/// `k` radii through a square frustum the crown fills at 2 r.
#[derive(Clone, Copy)]
struct View {
    eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    /// 1 / tan(half field of view).
    focal: f32,
}

fn view(model: &TreeModel, dir: Vec3, k: f32) -> View {
    let (c, r) = (model.crown_centre, model.crown_radius);
    let forward = -dir;
    let up0 = if dir.y > 0.99 { Vec3::Z } else { Vec3::Y };
    let right = forward.cross(up0).normalize();
    let half = (1.0 / NEAREST).asin();
    View {
        eye: c + dir * r * k,
        right,
        up: right.cross(forward),
        forward,
        focal: 1.0 / half.tan(),
    }
}

impl View {
    /// Pixel position (x right, y down) and 1 / depth (affine in screen space).
    fn project(&self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        let z = d.dot(self.forward).max(1e-4);
        let n = RESOLUTION as f32;
        let x = d.dot(self.right) / z * self.focal;
        let y = d.dot(self.up) / z * self.focal;
        Vec3::new((x * 0.5 + 0.5) * n, (0.5 - y * 0.5) * n, 1.0 / z)
    }
}

/// A z-buffer of cluster ids.
struct Raster {
    depth: Vec<f32>,
    id: Vec<u32>,
    /// The last cluster whose fragment touched each pixel: a cluster's
    /// pixels count once, so its own overlapping cards do not hide it.
    stamp: Vec<u32>,
}

const NONE: u32 = u32::MAX;

impl Raster {
    fn new() -> Self {
        Raster {
            depth: vec![f32::INFINITY; RESOLUTION * RESOLUTION],
            id: vec![NONE; RESOLUTION * RESOLUTION],
            stamp: vec![NONE; RESOLUTION * RESOLUTION],
        }
    }

    /// Draws `clusters`' cards (scaled by `s` about each cluster's centre)
    /// under `m`, alpha-tested, both faces; counts the pixels each cluster's
    /// fragments touch in `fragments` (indexed like `clusters`).
    fn draw(
        &mut self,
        model: &TreeModel,
        clusters: &[usize],
        s: f32,
        m: &View,
        fragments: &mut [u32],
    ) {
        for (slot, &ci) in clusters.iter().enumerate() {
            let cl = &model.clusters[ci];
            for card in &model.cards[cl.cards.clone()] {
                let corners = card.corners(cl.centre, s).map(|(p, uv)| (m.project(p), uv));
                for tri in [[0, 1, 2], [0, 2, 3]] {
                    let [a, b, c] = tri.map(|i| corners[i]);
                    fragments[slot] += self.triangle(a, b, c, slot as u32);
                }
            }
        }
    }

    /// Rasterises one triangle of cluster `id` at pixel centres; returns the
    /// pixels its alpha-passing fragments touch that the cluster had not yet.
    fn triangle(
        &mut self,
        (a, ua): (Vec3, [f32; 2]),
        (b, ub): (Vec3, [f32; 2]),
        (c, uc): (Vec3, [f32; 2]),
        id: u32,
    ) -> u32 {
        let pattern = ua[0];
        let mut count = 0;
        raster(RESOLUTION, [a, b, c], |i, [w0, w1, w2]| {
            // Nearer is larger 1 / depth.
            let z = -(w0 * a.z + w1 * b.z + w2 * c.z);
            let u = (w0 * ua[0] + w1 * ub[0] + w2 * uc[0] - pattern).clamp(0.0, 0.9999);
            let v = w0 * ua[1] + w1 * ub[1] + w2 * uc[1];
            if crate::scene::vegetation::leaves_alpha([pattern + u, v]) < 0.5 {
                return;
            }
            if self.stamp[i] != id {
                self.stamp[i] = id;
                count += 1;
            }
            if z < self.depth[i] {
                self.depth[i] = z;
                self.id[i] = id;
            }
        });
        count
    }

    fn covered(&self) -> usize {
        self.id.iter().filter(|&&i| i != NONE).count()
    }
}

/// Calls `f(pixel, barycentrics)` for the pixel centres of `size`² inside
/// the screen-space triangle (either winding; top-left rule not needed:
/// the depth test keeps one of two equal writes).
pub(super) fn raster(size: usize, [a, b, c]: [Vec3; 3], mut f: impl FnMut(usize, [f32; 3])) {
    let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
    if area.abs() < 1e-12 {
        return;
    }
    let n = size as f32;
    let x0 = (a.x.min(b.x).min(c.x) - 0.5).ceil().max(0.0);
    let x1 = (a.x.max(b.x).max(c.x) - 0.5).floor().min(n - 1.0);
    let y0 = (a.y.min(b.y).min(c.y) - 0.5).ceil().max(0.0);
    let y1 = (a.y.max(b.y).max(c.y) - 0.5).floor().min(n - 1.0);
    if x0 > x1 || y0 > y1 {
        return;
    }
    for py in y0 as usize..=y1 as usize {
        for px in x0 as usize..=x1 as usize {
            let (x, y) = (px as f32 + 0.5, py as f32 + 0.5);
            let w0 = ((b.x - x) * (c.y - y) - (b.y - y) * (c.x - x)) / area;
            let w1 = ((c.x - x) * (a.y - y) - (c.y - y) * (a.x - x)) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 >= 0.0 && w1 >= 0.0 && w2 >= 0.0 {
                f(py * size + px, [w0, w1, w2]);
            }
        }
    }
}

/// The visibility table of `model`'s clusters (views spread over threads;
/// the result does not depend on how).
pub fn table(model: &TreeModel) -> VisibilityTable {
    let n = model.clusters.len();
    let all: Vec<usize> = (0..n).collect();
    let dirs = viewpoints();
    let ks = distances();
    // One job per (viewpoint, distance): its fractions for every cluster.
    let job = |j: usize| -> Vec<f32> {
        let m = view(model, dirs[j / DISTANCES], ks[j % DISTANCES]);
        let mut r = Raster::new();
        let mut fragments = vec![0u32; n];
        r.draw(model, &all, 1.0, &m, &mut fragments);
        let mut visible = vec![0u32; n];
        for &id in &r.id {
            if id != NONE {
                visible[id as usize] += 1;
            }
        }
        (0..n)
            .map(|c| {
                if fragments[c] == 0 {
                    0.0
                } else {
                    visible[c] as f32 / fragments[c] as f32
                }
            })
            .collect()
    };
    let jobs = VIEWPOINTS * DISTANCES;
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .clamp(1, 8);
    let mut results: Vec<Vec<f32>> = vec![Vec::new(); jobs];
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let job = &job;
                s.spawn(move || {
                    (t..jobs)
                        .step_by(threads)
                        .map(|j| (j, job(j)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            if let Ok(done) = h.join() {
                for (j, r) in done {
                    results[j] = r;
                }
            }
        }
    });
    let mut fraction = vec![0.0; n * jobs];
    for (j, r) in results.iter().enumerate() {
        for (c, f) in r.iter().enumerate() {
            fraction[c * jobs + j] = *f;
        }
    }
    let score = (0..n)
        .map(|c| fraction[c * jobs..(c + 1) * jobs].iter().sum::<f32>() / jobs as f32)
        .collect();
    VisibilityTable {
        clusters: n,
        fraction,
        score,
    }
}

/// Pixels the `clusters` cover (scaled by `s`), summed over the 9 views at
/// the coverage distance.
pub fn coverage(model: &TreeModel, clusters: &[usize], s: f32) -> usize {
    let k = distances()[COVERAGE_DISTANCE];
    viewpoints()
        .iter()
        .map(|&d| {
            let mut r = Raster::new();
            let mut fragments = vec![0u32; clusters.len()];
            r.draw(model, clusters, s, &view(model, d, k), &mut fragments);
            r.covered()
        })
        .sum()
}

/// Largest compensation scale: the larch's LOD2 keeps 2 % of its clusters.
pub const MAX_CARD_SCALE: f32 = 6.0;

/// The scale (1..=[`MAX_CARD_SCALE`]) of the kept clusters (about their centres) at which
/// they cover what every cluster covers at scale 1 (bisection, 8 steps):
/// the dropped clusters' area goes to the kept ones.
pub fn compensation(model: &TreeModel, kept: &[usize]) -> f32 {
    let all: Vec<usize> = (0..model.clusters.len()).collect();
    let target = coverage(model, &all, 1.0);
    let (mut lo, mut hi) = (1.0f32, MAX_CARD_SCALE);
    if coverage(model, kept, hi) <= target {
        return hi;
    }
    for _ in 0..8 {
        let mid = 0.5 * (lo + hi);
        if coverage(model, kept, mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::super::{Card, Cluster, Species, TreeModel};
    use super::*;

    /// A crown of 26 clusters on a sphere shell and one at its centre.
    fn shell() -> TreeModel {
        let mut cards = Vec::new();
        let mut clusters = Vec::new();
        let mut centres = vec![Vec3::ZERO];
        for i in -1..=1 {
            for j in -1..=1 {
                for k in -1..=1 {
                    if (i, j, k) != (0, 0, 0) {
                        centres.push(Vec3::new(i as f32, j as f32, k as f32).normalize() * 2.0);
                    }
                }
            }
        }
        let mut rng = crate::scene::vegetation::Rng::new(9, 0);
        for (ci, &c) in centres.iter().enumerate() {
            let start = cards.len();
            for _ in 0..60 {
                let q = Vec3::new(rng.next(), rng.next(), rng.next()) * 1.4 - 0.7;
                let f = Vec3::new(rng.next(), rng.next(), rng.next()) * 2.0 - 1.0;
                let f = f.normalize_or(Vec3::Y);
                let (u, v) = f.any_orthonormal_pair();
                cards.push(Card {
                    centre: c + q,
                    u,
                    v,
                    normal: f,
                    size: 0.6,
                    pattern: rng.pattern_seed(),
                    cluster: ci as u32,
                });
            }
            clusters.push(Cluster {
                centre: c,
                cards: start..cards.len(),
                tint: 0.5,
            });
        }
        TreeModel {
            species: Species::Rosewood,
            limbs: Vec::new(),
            cards,
            clusters,
            crown_centre: Vec3::ZERO,
            crown_radius: 3.2,
        }
    }

    #[test]
    fn hidden_cluster_ranks_below_outer_ones() {
        let model = shell();
        let t = table(&model);
        assert_eq!(t, table(&model), "deterministic");
        let inner = t.score[0];
        let outer_min = t.score[1..].iter().copied().fold(f32::INFINITY, f32::min);
        println!("inner {inner:.3}, outer min {outer_min:.3}");
        assert!(inner < outer_min, "inner {inner} outer {outer_min}");
        assert_eq!(*t.ranking().last().unwrap_or(&99), 0);
        // Fewer clusters need a larger scale to cover the same pixels.
        let kept: Vec<usize> = t.ranking()[..8].to_vec();
        let s = compensation(&model, &kept);
        assert!(s > 1.05 && s <= MAX_CARD_SCALE, "{s}");
    }
}
