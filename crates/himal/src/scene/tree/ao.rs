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

use glam::{UVec3, Vec3};

use super::TreeModel;
use super::impostor::{capture_meshes, view, view_basis};
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
