//! V4 ambient-occlusion volumes (issue #18; Far Cry 4's vegetation talk,
//! `seeds/000_...`): per tree, a grid of sky visibility over its box and
//! the ground under it, baked from orthographic shadow maps of the LOD0
//! tree (trunk, and leaf cards alpha-tested with the shader's pattern) in
//! [`DIRECTIONS`] directions spread cosine-weighted over the upper
//! hemisphere. A voxel's value is the fraction of those maps in which
//! nothing lies between it and the sky: the cosine-weighted visibility a
//! surface facing up sees, the quantity the frame's sky occlusion scales
//! the sky light by. Reference: rays traced against the same triangles
//! ([`traced_visibility`]). Math and figures: `docs/techniques/V4.md`.

use std::path::{Path, PathBuf};

use glam::{UVec3, Vec3};

use super::impostor::{capture_meshes, view, view_basis};
use super::{Species, TreeModel};
use crate::scene::{Aabb, Mesh};

/// Shadow maps baked per tree (the talk's 32).
pub const DIRECTIONS: usize = 32;
/// Texels along a shadow map's edge.
pub const MAP_SIZE: usize = 256;
/// Voxels along the volume's longest edge (the talk: 16³ to 64³).
pub const VOXELS: u32 = 32;

/// `n` directions over the upper hemisphere, cosine-weighted with equal
/// weights: sample k at u = (k + ½) / n, elevation sin θ = √(1 − u) ... the
/// Hammersley-style spiral (azimuth k times the golden angle), so
/// E[visibility] over them estimates ∫ V cos θ dω / π.
pub fn hemisphere_directions(n: usize) -> Vec<Vec3> {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    (0..n)
        .map(|k| {
            let u = (k as f32 + 0.5) / n as f32;
            let r = u.sqrt();
            let phi = golden * k as f32;
            Vec3::new(r * phi.cos(), (1.0 - u).sqrt(), r * phi.sin())
        })
        .collect()
}

/// A tree's occlusion volume: `res` voxels over `bounds` (tree space),
/// each the sky visibility at its centre in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct AoVolume {
    /// The box the voxels cover: the tree's, widened, down to the ground.
    pub bounds: Aabb,
    /// Voxels per axis.
    pub res: UVec3,
    /// Visibility per voxel, x fastest, then y, then z.
    pub visibility: Vec<f32>,
}

impl AoVolume {
    /// Centre of voxel (x, y, z).
    pub fn voxel_centre(&self, v: UVec3) -> Vec3 {
        let size = self.bounds.extent() / self.res.as_vec3();
        self.bounds.min + (v.as_vec3() + 0.5) * size
    }

    /// Trilinear visibility at `p` (tree space), clamped to the box (the
    /// edge voxels hold beyond it).
    pub fn sample(&self, p: Vec3) -> f32 {
        let size = self.bounds.extent() / self.res.as_vec3();
        let max = (self.res - 1).as_vec3();
        let g = ((p - self.bounds.min) / size - 0.5).clamp(Vec3::ZERO, max);
        let i = g.floor().as_uvec3().min(self.res - 1);
        let f = g - i.as_vec3();
        let at = |x: u32, y: u32, z: u32| {
            let q = UVec3::new(x, y, z).min(self.res - 1);
            self.visibility[((q.z * self.res.y + q.y) * self.res.x + q.x) as usize]
        };
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let plane = |z: u32| {
            let y0 = lerp(at(i.x, i.y, z), at(i.x + 1, i.y, z), f.x);
            let y1 = lerp(at(i.x, i.y + 1, z), at(i.x + 1, i.y + 1, z), f.x);
            lerp(y0, y1, f.y)
        };
        lerp(plane(i.z), plane(i.z + 1), f.z)
    }
}

/// Width of the fade to 1 at the box's side and top faces, as a fraction
/// of the box along each axis: the frame multiplies [`AoVolume::factor`],
/// so no seam shows where a box ends (the bottom face lies under the
/// ground and does not fade).
pub const EDGE_FADE: f32 = 0.15;

impl AoVolume {
    /// What the frame multiplies the sky light by at `p` (tree space):
    /// [`Self::sample`] faded to 1 toward the side and top faces
    /// ([`EDGE_FADE`]), 1 outside the box. Twin of `passes/tree_ao/decal.wgsl`.
    pub fn factor(&self, p: Vec3) -> f32 {
        let u = (p - self.bounds.min) / self.bounds.extent().max(Vec3::splat(1e-6));
        if u.min_element() < 0.0 || u.max_element() > 1.0 {
            return 1.0;
        }
        let edge = (u.x.min(1.0 - u.x)).min(u.z.min(1.0 - u.z)).min(1.0 - u.y);
        let t = (edge / EDGE_FADE).clamp(0.0, 1.0);
        let fade = t * t * (3.0 - 2.0 * t);
        1.0 + (self.sample(p) - 1.0) * fade
    }
}

/// The box a tree's volume covers: the LOD0 meshes' bounds widened by a
/// quarter of the crown's horizontal radius on each side (the ground
/// under the crown's edge), from 0.25 m below the ground to 0.5 m above
/// the top.
pub fn volume_bounds(meshes: &(Mesh, Mesh)) -> Aabb {
    let b = meshes.0.bounds.union(&meshes.1.bounds);
    let reach = 0.25 * (b.max.x - b.min.x).max(b.max.z - b.min.z) * 0.5;
    Aabb::new(
        Vec3::new(b.min.x - reach, b.min.y.min(0.0) - 0.25, b.min.z - reach),
        Vec3::new(b.max.x + reach, b.max.y + 0.5, b.max.z + reach),
    )
}

/// Voxels per axis for `bounds`: [`VOXELS`] along the longest edge, the
/// others in proportion (at least 4).
pub fn volume_res(bounds: &Aabb) -> UVec3 {
    let e = bounds.extent();
    let per_m = VOXELS as f32 / e.max_element();
    (e * per_m)
        .ceil()
        .as_uvec3()
        .clamp(UVec3::splat(4), UVec3::splat(VOXELS))
}

/// Bakes `model`'s volume: for each of [`DIRECTIONS`] directions d, the
/// LOD0 tree rasterised orthographically along −d ([`view`], the
/// impostor captures' rasteriser: depth test, cards alpha-tested) over the
/// volume's bounding sphere at [`MAP_SIZE`]²; a voxel centre p sees the
/// sky along d when no surface's depth toward d exceeds its own by more
/// than the bias (one and a half voxels: the voxel's own leaf does not
/// shadow it). Directions are spread over threads; the result does not
/// depend on how.
pub fn bake_volume(model: &TreeModel) -> AoVolume {
    let meshes = capture_meshes(model);
    let bounds = volume_bounds(&meshes);
    let res = volume_res(&bounds);
    let centre = bounds.center();
    let radius = 0.5 * bounds.extent().length();
    let voxel = bounds.extent() / res.as_vec3();
    let bias = 1.5 * voxel.max_element() / radius;
    let dirs = hemisphere_directions(DIRECTIONS);
    let count = (res.x * res.y * res.z) as usize;
    let centres: Vec<Vec3> = (0..count)
        .map(|i| {
            let i = i as u32;
            let v = UVec3::new(i % res.x, (i / res.x) % res.y, i / (res.x * res.y));
            bounds.min + (v.as_vec3() + 0.5) * voxel
        })
        .collect();
    let lit_per_dir: Vec<Vec<bool>> = std::thread::scope(|s| {
        let handles: Vec<_> = (dirs.iter())
            .map(|&d| {
                let (meshes, centres) = (&meshes, &centres);
                s.spawn(move || {
                    let map = view(meshes, centre, radius, d, MAP_SIZE);
                    let basis = view_basis(d);
                    let n = MAP_SIZE as f32;
                    (centres.iter())
                        .map(|&p| {
                            let q = (p - centre) / radius;
                            let x = ((q.dot(basis[0]) * 0.5 + 0.5) * n).floor();
                            let y = ((0.5 - q.dot(basis[1]) * 0.5) * n).floor();
                            let px = (y.clamp(0.0, n - 1.0) as usize) * MAP_SIZE
                                + x.clamp(0.0, n - 1.0) as usize;
                            map[px].depth <= q.dot(basis[2]) + bias
                        })
                        .collect()
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("AO bake thread"))
            .collect()
    });
    let visibility = (0..count)
        .map(|i| lit_per_dir.iter().filter(|l| l[i]).count() as f32 / dirs.len() as f32)
        .collect();
    AoVolume {
        bounds,
        res,
        visibility,
    }
}

const MAGIC: &[u8; 4] = b"HAOV";
const VERSION: u32 = 1;

/// The volume file of tree (`species`, `seed`) under `dir`.
pub fn cache_file(dir: &Path, species: Species, seed: u32) -> PathBuf {
    dir.join("trees")
        .join(format!("{}-{seed}.himal-ao", species.name()))
}

/// File: magic `HAOV`, version, the impostor's fingerprint (cards and
/// limbs: what the maps see), voxels per axis, the box, then one f32
/// visibility per voxel (x fastest), all little-endian.
pub fn encode(model: &TreeModel, v: &AoVolume) -> Vec<u8> {
    let mut out = Vec::with_capacity(52 + 4 * v.visibility.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&super::impostor::fingerprint(model).to_le_bytes());
    for r in v.res.to_array() {
        out.extend_from_slice(&r.to_le_bytes());
    }
    let corners = v
        .bounds
        .min
        .to_array()
        .into_iter()
        .chain(v.bounds.max.to_array());
    for x in corners.chain(v.visibility.iter().copied()) {
        out.extend_from_slice(&x.to_le_bytes());
    }
    out
}

/// The file's volume, if it is whole and made for `model`.
pub fn decode(model: &TreeModel, bytes: &[u8]) -> Option<AoVolume> {
    let word = |at: usize| -> Option<[u8; 4]> { bytes.get(at..at + 4)?.try_into().ok() };
    if bytes.get(..4)? != MAGIC
        || u32::from_le_bytes(word(4)?) != VERSION
        || u64::from_le_bytes(bytes.get(8..16)?.try_into().ok()?)
            != super::impostor::fingerprint(model)
    {
        return None;
    }
    let u = |i: usize| word(16 + 4 * i).map(u32::from_le_bytes);
    let res = UVec3::new(u(0)?, u(1)?, u(2)?);
    if res.min_element() < 2 || res.max_element() > VOXELS {
        return None;
    }
    let count = (res.x * res.y * res.z) as usize;
    if bytes.len() != 52 + 4 * count {
        return None;
    }
    let f = |i: usize| word(28 + 4 * i).map(f32::from_le_bytes);
    let min = Vec3::new(f(0)?, f(1)?, f(2)?);
    let max = Vec3::new(f(3)?, f(4)?, f(5)?);
    let visibility = (0..count).map(|i| f(6 + i)).collect::<Option<Vec<f32>>>()?;
    let sane = min.is_finite() && max.is_finite() && max.cmpgt(min).all();
    (sane && visibility.iter().all(|v| (0.0..=1.0).contains(v))).then(|| AoVolume {
        bounds: Aabb::new(min, max),
        res,
        visibility,
    })
}

/// Reads tree (`model.species`, `seed`)'s volume from `dir`, or bakes and
/// writes it (a damaged or stale file is reported with its path and baked
/// again); the flag is true when read from the cache.
pub fn load_or_bake_in(dir: &Path, model: &TreeModel, seed: u32) -> (AoVolume, bool) {
    let path = cache_file(dir, model.species, seed);
    match std::fs::read(&path) {
        Ok(bytes) => match decode(model, &bytes) {
            Some(v) => return (v, true),
            None => log::warn!(
                "tree AO cache {}: damaged or made for another tree; baking it again",
                path.display()
            ),
        },
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => log::warn!("tree AO cache {}: {e}; baking it again", path.display()),
    }
    let v = bake_volume(model);
    let written = std::fs::create_dir_all(path.parent().unwrap_or(dir))
        .and_then(|_| std::fs::write(&path, encode(model, &v)));
    if let Err(e) = written {
        log::warn!("tree AO cache {}: {e} (baked in memory)", path.display());
    }
    (v, false)
}

/// The volume of tree (`species`, `seed`) through the tree cache
/// ([`super::bake::cache_dir`]), or baked in memory without one; once per
/// process ([`super::bake::Memo`]).
pub fn cached(model: &TreeModel, seed: u32) -> std::sync::Arc<AoVolume> {
    static MEMO: super::bake::Memo<AoVolume> = super::bake::Memo::new();
    MEMO.get_or(model, seed, || match super::bake::cache_dir() {
        Some(dir) => load_or_bake_in(&dir, model, seed).0,
        None => bake_volume(model),
    })
}

/// The reference: sky visibility at `p` by `rays` cosine-weighted rays
/// ([`hemisphere_directions`]) traced against `model`'s LOD0 triangles,
/// leaf cards alpha-tested at the hit (`vegetation::leaves_alpha`), from
/// `offset` metres along each ray (off the surface `p` lies on).
pub fn traced_visibility(tracer: &TreeTracer, p: Vec3, rays: usize, offset: f32) -> f32 {
    let dirs = hemisphere_directions(rays);
    let open = (dirs.iter())
        .filter(|&&d| tracer.unoccluded(p + d * offset, d))
        .count();
    open as f32 / rays as f32
}

/// A tree's LOD0 triangles in a BVH for [`traced_visibility`].
pub struct TreeTracer {
    scene: crate::scene::raycast::RayScene,
    /// Per triangle: the leaf card's uv at its corners (`None`: bark).
    uvs: Vec<Option<[[f32; 2]; 3]>>,
}

impl TreeTracer {
    /// `model`'s trunk and every card, as the volume's maps see them.
    pub fn new(model: &TreeModel) -> Self {
        let (trunk, leaves) = capture_meshes(model);
        let mut list = Vec::new();
        let mut uvs = Vec::new();
        for (mesh, leaf) in [(&trunk, false), (&leaves, true)] {
            for tri in mesh.indices.chunks_exact(3) {
                let v = [0, 1, 2].map(|i| &mesh.vertices[tri[i] as usize]);
                list.push((v.map(|v| Vec3::from(v.position)), Vec3::ONE, false));
                uvs.push(leaf.then(|| v.map(|v| v.uv)));
            }
        }
        Self {
            scene: crate::scene::raycast::RayScene::from_triangles(&list),
            uvs,
        }
    }

    /// True when a ray from `origin` along `dir` leaves the tree: bark
    /// blocks, a card blocks where its leaf pattern is opaque.
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3) -> bool {
        let blocks = |prim: usize, b: [f32; 3]| match self.uvs[prim] {
            None => true,
            Some(uv) => {
                let pattern = uv[0][0].floor();
                let at = |k: usize| b[0] * uv[0][k] + b[1] * uv[1][k] + b[2] * uv[2][k];
                let u = (at(0) - pattern).clamp(0.0, 0.9999);
                crate::scene::vegetation::leaves_alpha([pattern + u, at(1)]) >= 0.5
            }
        };
        self.scene
            .unoccluded_where(origin, dir, 0.0, f32::INFINITY, blocks)
    }
}

#[cfg(test)]
mod tests {
    use super::super::generate;
    use super::*;

    /// The cache: same bytes from two bakes, a round trip, other trees and
    /// damaged files refused (and baked again through `load_or_bake_in`).
    #[test]
    fn cache_round_trips_and_rebakes_damaged_files() {
        let model = generate(Species::Larch, 2, 0.1);
        let v = bake_volume(&model);
        let bytes = encode(&model, &v);
        assert_eq!(bytes, encode(&model, &bake_volume(&model)), "deterministic");
        assert_eq!(decode(&model, &bytes), Some(v.clone()));
        assert_eq!(decode(&generate(Species::Larch, 3, 0.1), &bytes), None);
        assert_eq!(decode(&model, &bytes[..bytes.len() - 1]), None);
        let mut nan = bytes.clone();
        let at = nan.len() - 4;
        nan[at..].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(decode(&model, &nan), None);
        let dir = std::env::temp_dir().join(format!("himal-ao-cache-{}", std::process::id()));
        let (a, read) = load_or_bake_in(&dir, &model, 2);
        assert!(!read && a == v);
        let path = cache_file(&dir, Species::Larch, 2);
        assert_eq!(std::fs::read(&path).ok(), Some(bytes.clone()));
        let (b, read) = load_or_bake_in(&dir, &model, 2);
        assert!(read && b == v);
        std::fs::write(&path, &bytes[..100]).expect("truncate");
        let (c, read) = load_or_bake_in(&dir, &model, 2);
        assert!(!read && c == v, "a damaged file is baked again");
        assert_eq!(std::fs::read(&path).ok(), Some(bytes), "and rewritten");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// The factor fades to 1 at the side and top faces and is the volume's
    /// sample inside the fade.
    #[test]
    fn factor_fades_to_one_at_the_faces() {
        let v = AoVolume {
            bounds: Aabb::new(Vec3::ZERO, Vec3::splat(10.0)),
            res: UVec3::splat(4),
            visibility: vec![0.5; 64],
        };
        assert_eq!(v.factor(Vec3::new(5.0, 5.0, 5.0)), 0.5);
        assert_eq!(v.factor(Vec3::new(0.0, 5.0, 5.0)), 1.0);
        assert_eq!(v.factor(Vec3::new(5.0, 10.0, 5.0)), 1.0);
        assert_eq!(
            v.factor(Vec3::new(5.0, 0.0, 5.0)),
            0.5,
            "no fade at the bottom"
        );
        assert_eq!(v.factor(Vec3::new(-1.0, 5.0, 5.0)), 1.0);
        let half = v.factor(Vec3::new(0.75, 5.0, 5.0));
        assert!((half - 0.75).abs() < 1e-6, "{half}");
    }
}
