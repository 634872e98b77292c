//! Ray queries against a scene's opaque triangles on the CPU, for offline
//! bakes (L5 probes) and their references. A compressed wide BVH (obvhs),
//! built serially so the same scene gives the same tree and the same hits.
//!
//! Foliage cards are left out (alpha-tested: a card's bounding triangle
//! would block far more than its leaves), and so are moving and animated
//! objects (what is baked must stay put).

use glam::{Mat3, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;

use super::{Aabb, Scene};

/// What a ray found: distance, the face normal turned towards the ray's
/// origin, and the surface's linear albedo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Distance along the ray.
    pub t: f32,
    /// Unit face normal on the ray's side.
    pub normal: Vec3,
    /// Linear albedo (the triangle's mean vertex colour).
    pub albedo: Vec3,
    /// The triangle belongs to terrain (`Object::ground`).
    pub ground: bool,
    /// The ray arrived from behind the surface (against its mesh normals):
    /// the origin is inside a closed object.
    pub backface: bool,
}

/// Triangles with a per-triangle albedo and ground flag, in a BVH.
pub struct RayScene {
    tris: Vec<Triangle>,
    /// Outward direction per triangle (its vertex normals' mean).
    outward: Vec<Vec3>,
    albedo: Vec<Vec3>,
    ground: Vec<bool>,
    /// Built on the first ray: a bake whose cells are all cached only
    /// hashes the triangles.
    bvh: std::sync::OnceLock<Option<CwBvh>>,
    bounds: Aabb,
}

impl RayScene {
    /// The opaque, still, non-foliage triangles of `scene` whose bounds overlap
    /// `region` (all of them for `None`).
    pub fn from_scene(scene: &Scene, region: Option<&Aabb>) -> RayScene {
        let mut tris = Vec::new();
        let mut outward = Vec::new();
        let mut albedo = Vec::new();
        let mut ground = Vec::new();
        let still = |o: &&super::Object| o.foliage.is_none() && o.motion.is_none();
        for object in scene.objects.iter().filter(still) {
            let Some(mesh) = scene.meshes.get(object.mesh) else {
                continue;
            };
            let m = object.transform;
            let normal_m = glam::Mat3::from_mat4(m).inverse().transpose();
            if let Some(r) = region
                && !mesh.bounds.transform(&m).overlaps(r)
            {
                continue;
            }
            let world = |i: u32| m.transform_point3(Vec3::from(mesh.vertices[i as usize].position));
            for t in mesh.indices.chunks_exact(3) {
                let [a, b, c] = [world(t[0]), world(t[1]), world(t[2])];
                if let Some(r) = region
                    && !Aabb::from_points([a, b, c]).overlaps(r)
                {
                    continue;
                }
                let colour = t
                    .iter()
                    .map(|&i| Vec3::from_slice(&mesh.vertices[i as usize].color[..3]))
                    .sum::<Vec3>()
                    / 3.0;
                tris.push(Triangle {
                    v0: a.into(),
                    v1: b.into(),
                    v2: c.into(),
                });
                let n: Vec3 = t
                    .iter()
                    .map(|&i| Vec3::from(mesh.vertices[i as usize].normal))
                    .sum();
                outward.push((normal_m * n).normalize_or_zero());
                albedo.push(colour);
                ground.push(object.ground);
            }
        }
        RayScene::new(tris, outward, albedo, ground)
    }

    /// Triangles given as corner triples (counter-clockwise seen from
    /// outside), each with its albedo and ground flag.
    pub fn from_triangles(list: &[([Vec3; 3], Vec3, bool)]) -> RayScene {
        let outward = list
            .iter()
            .map(|(v, _, _)| (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero())
            .collect();
        let tris = list
            .iter()
            .map(|(v, _, _)| Triangle {
                v0: v[0].into(),
                v1: v[1].into(),
                v2: v[2].into(),
            })
            .collect();
        RayScene::new(
            tris,
            outward,
            list.iter().map(|t| t.1).collect(),
            list.iter().map(|t| t.2).collect(),
        )
    }

    fn new(
        tris: Vec<Triangle>,
        outward: Vec<Vec3>,
        albedo: Vec<Vec3>,
        ground: Vec<bool>,
    ) -> RayScene {
        let bounds =
            Aabb::from_points(tris.iter().flat_map(|t| [t.v0, t.v1, t.v2]).map(Vec3::from));
        RayScene {
            tris,
            outward,
            albedo,
            ground,
            bvh: std::sync::OnceLock::new(),
            bounds,
        }
    }

    fn bvh(&self) -> Option<&CwBvh> {
        self.bvh
            .get_or_init(|| {
                (!self.tris.is_empty()).then(|| {
                    build_cwbvh_from_tris(
                        &self.tris,
                        BvhBuildParams::medium_build(),
                        &mut std::time::Duration::default(),
                    )
                })
            })
            .as_ref()
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// No triangle at all.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// A hash of the triangles, their albedo and ground flags (cache keys).
    pub fn fingerprint(&self) -> u32 {
        let mut h = crc32fast::Hasher::new();
        for (t, (a, g)) in self.tris.iter().zip(self.albedo.iter().zip(&self.ground)) {
            for v in [t.v0, t.v1, t.v2] {
                h.update(bytemuck::cast_slice(&v.to_array()));
            }
            h.update(bytemuck::cast_slice(&a.to_array()));
            h.update(&[*g as u8]);
        }
        h.finalize()
    }

    /// Bounds of every triangle.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Nearest hit along `dir` (unit) within (t_min, t_max).
    pub fn trace(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        self.trace_filtered(origin, dir, t_min, t_max, |_| true)
    }

    /// Nearest hit on terrain only (probe heights follow the ground, not roofs).
    pub fn trace_ground(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<SurfaceHit> {
        self.trace_filtered(origin, dir, 0.0, t_max, |i| self.ground[i])
    }

    fn trace_filtered(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        keep: impl Fn(usize) -> bool,
    ) -> Option<SurfaceHit> {
        let bvh = self.bvh()?;
        let ray = Ray::new(Vec3A::from(origin), off_axis(dir), t_min, t_max);
        let mut hit = RayHit::none();
        let found = bvh.ray_traverse(ray, &mut hit, |ray, id| {
            let prim = bvh.primitive_indices[id] as usize;
            if keep(prim) {
                intersect(&self.tris[prim], ray)
            } else {
                f32::INFINITY
            }
        });
        if !found {
            return None;
        }
        let prim = bvh.primitive_indices[hit.primitive_id as usize] as usize;
        let n = Vec3::from(self.tris[prim].compute_normal()).normalize_or(Vec3::Y);
        Some(SurfaceHit {
            t: hit.t,
            normal: if n.dot(dir) > 0.0 { -n } else { n },
            albedo: self.albedo[prim],
            ground: self.ground[prim],
            backface: self.outward[prim].dot(dir) > 0.0,
        })
    }

    /// True where nothing lies along `dir` within (t_min, t_max).
    pub fn unoccluded(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        let Some(bvh) = self.bvh() else {
            return true;
        };
        let ray = Ray::new(Vec3A::from(origin), off_axis(dir), t_min, t_max);
        bvh.ray_traverse_miss(ray, |ray, id| {
            intersect(&self.tris[bvh.primitive_indices[id] as usize], ray)
        })
    }
}

impl RayScene {
    /// True where no triangle that `blocks` (given its index, in the
    /// order the scene was made, and the hit's barycentrics) lies along
    /// `dir` within (t_min, t_max): alpha-tested cards let rays through
    /// their holes.
    pub fn unoccluded_where(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        blocks: impl Fn(usize, [f32; 3]) -> bool,
    ) -> bool {
        let Some(bvh) = self.bvh() else {
            return true;
        };
        let ray = Ray::new(Vec3A::from(origin), off_axis(dir), t_min, t_max);
        bvh.ray_traverse_miss(ray, |ray, id| {
            let prim = bvh.primitive_indices[id] as usize;
            match intersect_bary(&self.tris[prim], ray) {
                Some((t, b)) if blocks(prim, b) => t,
                _ => f32::INFINITY,
            }
        })
    }
}

/// The direction with no component exactly zero: obvhs's wide-node test
/// misses everything along a zero component (a ray straight down finds no
/// ground). 1e-6 turns the ray by a microradian.
fn off_axis(dir: Vec3) -> Vec3A {
    let nudge = |c: f32| {
        if c.abs() < 1e-6 {
            1e-6f32.copysign(c)
        } else {
            c
        }
    };
    Vec3A::new(nudge(dir.x), nudge(dir.y), nudge(dir.z))
}

/// Möller-Trumbore, two-sided, with edges inclusive (obvhs's own test
/// rejects a barycentric of -0.0, so a ray straight down a shared edge or
/// vertex of a terrain grid, where probes stand, hits neither triangle).
fn intersect(tri: &Triangle, ray: &Ray) -> f32 {
    intersect_bary(tri, ray).map_or(f32::INFINITY, |(t, _)| t)
}

/// [`intersect`] with the hit's barycentrics (weights of v0, v1, v2).
fn intersect_bary(tri: &Triangle, ray: &Ray) -> Option<(f32, [f32; 3])> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = ray.direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let s = ray.origin - tri.v0;
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = ray.direction.dot(q) * inv;
    const EDGE: f32 = -1e-6;
    if u < EDGE || v < EDGE || u + v > 1.0 - EDGE {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t >= ray.tmin && t <= ray.tmax).then_some((t, [1.0 - u - v, u, v]))
}

/// An orthonormal frame whose third column is `n` (Frisvad-style branchless
/// construction by Duff et al. 2017), for turning z-up samples about `n`.
pub fn frame_about(n: Vec3) -> Mat3 {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    Mat3::from_cols(t, bt, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(y: f32, half: f32, albedo: Vec3) -> Vec<([Vec3; 3], Vec3, bool)> {
        let p = |x: f32, z: f32| Vec3::new(x, y, z);
        vec![
            (
                [p(-half, -half), p(half, -half), p(half, half)],
                albedo,
                true,
            ),
            (
                [p(-half, -half), p(half, half), p(-half, half)],
                albedo,
                true,
            ),
        ]
    }

    #[test]
    fn hits_the_nearest_surface_with_its_albedo_and_a_facing_normal() {
        let mut tris = quad(0.0, 10.0, Vec3::splat(0.2));
        tris.extend(
            quad(5.0, 1.0, Vec3::X)
                .into_iter()
                .map(|(v, a, _)| (v, a, false)),
        );
        let s = RayScene::from_triangles(&tris);
        let down = s
            .trace(Vec3::new(0.0, 10.0, 0.0), -Vec3::Y, 0.0, 100.0)
            .unwrap();
        assert!((down.t - 5.0).abs() < 1e-4);
        assert_eq!(down.albedo, Vec3::X);
        assert!(down.normal.abs_diff_eq(Vec3::Y, 1e-5));
        let ground = s
            .trace_ground(Vec3::new(0.0, 10.0, 0.0), -Vec3::Y, 100.0)
            .unwrap();
        assert!((ground.t - 10.0).abs() < 1e-4 && ground.ground);
        let up = s
            .trace(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 0.0, 100.0)
            .unwrap();
        assert!(
            up.normal.abs_diff_eq(-Vec3::Y, 1e-5),
            "normal faces the ray"
        );
        assert!(!s.unoccluded(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 0.0, 100.0));
        assert!(s.unoccluded(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 0.0, 2.5));
        assert!(s.unoccluded(Vec3::new(5.0, 2.0, 0.0), Vec3::Y, 0.0, 100.0));
    }

    #[test]
    fn frame_about_is_orthonormal_with_n_as_z() {
        for n in [Vec3::Y, -Vec3::Z, Vec3::new(0.3, -0.8, 0.52).normalize()] {
            let f = frame_about(n);
            assert!(f.z_axis.abs_diff_eq(n, 1e-6));
            assert!((f.x_axis.dot(f.y_axis)).abs() < 1e-5);
            assert!((f.x_axis.length() - 1.0).abs() < 1e-5);
            assert!((f.x_axis.cross(f.y_axis)).abs_diff_eq(n, 1e-5));
        }
    }
}
