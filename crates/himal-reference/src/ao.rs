//! Ray-traced ambient occlusion of analytic scenes (planes, spheres, boxes),
//! the ground truth for himal's screen-space AO (TECHNIQUES O1).
//!
//! Definition (the one HBAO approximates, with its falloff):
//! `AO(p) = 1 - (1/pi) * integral over the hemisphere of n of
//!  V(w) W(t(w) / R) cos(theta) dw`, where `t(w)` is the distance to the first
//! hit along `w`, `V` is 1 when something is hit within `R`, and
//! `W(r) = 1 - r^2`. Sampled with cosine-weighted Hammersley directions, so
//! the estimator is `1 - mean(W)`.

use glam::Vec3;

use crate::integrate::hammersley;

/// A primitive of an analytic scene.
#[derive(Clone, Copy, Debug)]
pub enum Shape {
    /// Infinite plane `dot(normal, x) = offset`, one-sided (normal up).
    Plane {
        normal: Vec3,
        offset: f32,
    },
    Sphere {
        centre: Vec3,
        radius: f32,
    },
    /// Axis-aligned box.
    Box {
        min: Vec3,
        max: Vec3,
    },
}

/// The nearest hit of a ray: distance and unit normal facing the ray origin's side.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub normal: Vec3,
}

impl Shape {
    /// First hit of `origin + t dir` with `t > t_min`.
    pub fn intersect(&self, origin: Vec3, dir: Vec3, t_min: f32) -> Option<Hit> {
        match *self {
            Shape::Plane { normal, offset } => {
                let denom = normal.dot(dir);
                if denom.abs() < 1e-12 {
                    return None;
                }
                let t = (offset - normal.dot(origin)) / denom;
                (t > t_min).then_some(Hit {
                    t,
                    normal: if denom < 0.0 { normal } else { -normal },
                })
            }
            Shape::Sphere { centre, radius } => {
                let oc = origin - centre;
                let b = oc.dot(dir);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                [-b - s, -b + s]
                    .into_iter()
                    .find(|&t| t > t_min)
                    .map(|t| Hit {
                        t,
                        normal: (origin + dir * t - centre) / radius,
                    })
            }
            Shape::Box { min, max } => {
                let inv = dir.recip();
                let t0 = (min - origin) * inv;
                let t1 = (max - origin) * inv;
                let near = t0.min(t1);
                let far = t0.max(t1);
                let t_near = near.max_element();
                let t_far = far.min_element();
                if t_near > t_far || t_far <= t_min {
                    return None;
                }
                let (t, faces) = if t_near > t_min {
                    (t_near, near)
                } else {
                    (t_far, far)
                };
                let axis = if faces.x == t {
                    0
                } else if faces.y == t {
                    1
                } else {
                    2
                };
                let mut normal = Vec3::ZERO;
                normal[axis] = -dir[axis].signum();
                Some(Hit { t, normal })
            }
        }
    }
}

/// The nearest hit over all shapes.
pub fn trace(shapes: &[Shape], origin: Vec3, dir: Vec3, t_min: f32) -> Option<Hit> {
    trace_index(shapes, origin, dir, t_min).map(|(_, hit)| hit)
}

/// The nearest hit over `shapes` and the index of the shape hit.
pub fn trace_index(shapes: &[Shape], origin: Vec3, dir: Vec3, t_min: f32) -> Option<(usize, Hit)> {
    shapes
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.intersect(origin, dir, t_min).map(|h| (k, h)))
        .min_by(|a, b| a.1.t.total_cmp(&b.1.t))
}

/// Orthonormal tangent and bitangent of `n` (Duff et al. 2017).
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted direction `i` of `samples` about `n` (Hammersley points).
fn cosine_direction(n: Vec3, i: u32, samples: u32) -> Vec3 {
    let (t, b) = basis(n);
    let u = hammersley(i, samples);
    let r = u.x.sqrt();
    let phi = std::f32::consts::TAU * u.y;
    let local = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt());
    (t * local.x + b * local.y + n * local.z).normalize()
}

/// Ray-traced AO at `p` with normal `n`, radius `radius`, `samples` cosine-weighted rays.
pub fn ambient_occlusion(shapes: &[Shape], p: Vec3, n: Vec3, radius: f32, samples: u32) -> f32 {
    let origin = p + n * 1e-4;
    let mut occlusion = 0.0f64;
    for i in 0..samples {
        let dir = cosine_direction(n, i, samples);
        if let Some(hit) = trace(shapes, origin, dir, 0.0)
            && hit.t < radius
        {
            let rr = hit.t / radius;
            occlusion += (1.0 - rr * rr) as f64;
        }
    }
    (1.0 - occlusion / samples as f64) as f32
}

/// One-bounce coloured ambient occlusion, the ground truth O5 approximates.
/// Under a uniform sky of radiance L a point sees the sky along open
/// directions and, along blocked ones, a Lambertian surface q of albedo
/// `rho` lit by the same sky, of radiance `rho L AO(q)` (its own ambient
/// occlusion, no further bounce). With the falloff W of
/// [`ambient_occlusion`] blending blocked into open directions, the
/// effective occlusion per channel is
/// `O(p) = mean_i [(1 - W_i) + W_i rho(q_i) AO(q_i)]` over cosine-weighted
/// directions (`rho = 0`: [`ambient_occlusion`]).
///
/// `albedo[k]` is shape k's; `samples` directions at p, `inner` for each
/// hit point's AO.
pub fn one_bounce_occlusion(
    shapes: &[Shape],
    albedo: &[Vec3],
    p: Vec3,
    n: Vec3,
    radius: f32,
    samples: u32,
    inner: u32,
) -> Vec3 {
    let origin = p + n * 1e-4;
    let mut sum = Vec3::ZERO;
    for i in 0..samples {
        let dir = cosine_direction(n, i, samples);
        match trace_index(shapes, origin, dir, 0.0) {
            Some((k, hit)) if hit.t < radius => {
                let rr = hit.t / radius;
                let w = 1.0 - rr * rr;
                let q = origin + dir * hit.t;
                let ao_q = ambient_occlusion(shapes, q, hit.normal, radius, inner);
                sum += Vec3::splat(1.0 - w) + albedo[k] * (w * ao_q);
            }
            _ => sum += Vec3::ONE,
        }
    }
    sum / samples as f32
}

/// Ray-traced directional visibility (O4's ground truth): `1 - mean W(t/R)`
/// over `samples` directions uniform in the cone of half-angle `cone`
/// (radians) around unit `dir`, counting hits within `radius` as in
/// [`ambient_occlusion`]. `cone = 0` is the single ray along `dir`.
pub fn directional_visibility(
    shapes: &[Shape],
    p: Vec3,
    n: Vec3,
    dir: Vec3,
    radius: f32,
    cone: f32,
    samples: u32,
) -> f32 {
    let (t, b) = basis(dir);
    let origin = p + n * 1e-4;
    let cos_max = cone.cos();
    let mut occlusion = 0.0f64;
    for i in 0..samples {
        let u = hammersley(i, samples);
        let cos = 1.0 - u.x * (1.0 - cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u.y;
        let d = (t * (sin * phi.cos()) + b * (sin * phi.sin()) + dir * cos).normalize();
        if let Some(hit) = trace(shapes, origin, d, 0.0)
            && hit.t < radius
        {
            let rr = hit.t / radius;
            occlusion += (1.0 - rr * rr) as f64;
        }
    }
    (1.0 - occlusion / samples as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_plane_is_unoccluded() {
        let ground = [Shape::Plane {
            normal: Vec3::Y,
            offset: 0.0,
        }];
        let ao = ambient_occlusion(&ground, Vec3::ZERO, Vec3::Y, 1.0, 256);
        assert_eq!(ao, 1.0);
    }

    #[test]
    fn inside_a_corner_matches_the_analytic_wall() {
        // A point at the foot of an infinite wall: half the hemisphere sees the
        // wall. The wall x = d seen from the origin with normal +Y: by symmetry of
        // the cosine lobe, the covered fraction with no falloff is 1/2 at d = 0.
        let shapes = [Shape::Box {
            min: Vec3::new(0.0, -10.0, -10.0),
            max: Vec3::new(10.0, 10.0, 10.0),
        }];
        // Radius huge: W ~ 1, so AO -> 1 - 1/2.
        let ao = ambient_occlusion(&shapes, Vec3::new(-1e-3, 0.0, 0.0), Vec3::Y, 1e4, 4096);
        assert!((ao - 0.5).abs() < 0.01, "AO {ao}");
    }

    #[test]
    fn directional_visibility_sees_a_wall() {
        // At the foot of the wall x >= 0: toward it occluded at distance ~0,
        // away from it open.
        let shapes = [Shape::Box {
            min: Vec3::new(0.0, -10.0, -10.0),
            max: Vec3::new(10.0, 10.0, 10.0),
        }];
        let p = Vec3::new(-1e-3, 0.0, 0.0);
        let toward = directional_visibility(
            &shapes,
            p,
            Vec3::Y,
            Vec3::new(1.0, 1.0, 0.0).normalize(),
            1.0,
            0.0,
            1,
        );
        let away = directional_visibility(
            &shapes,
            p,
            Vec3::Y,
            Vec3::new(-1.0, 1.0, 0.0).normalize(),
            1.0,
            0.1,
            64,
        );
        assert!(toward < 0.01 && away == 1.0, "toward {toward}, away {away}");
    }

    #[test]
    fn sphere_and_box_hits_have_outward_normals() {
        let s = Shape::Sphere {
            centre: Vec3::ZERO,
            radius: 1.0,
        };
        let h = s
            .intersect(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, 0.0)
            .expect("hit");
        assert!((h.t - 4.0).abs() < 1e-5 && h.normal.z > 0.99);
        let b = Shape::Box {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let h = b
            .intersect(Vec3::new(5.0, 0.2, 0.1), -Vec3::X, 0.0)
            .expect("hit");
        assert!((h.t - 4.0).abs() < 1e-5 && h.normal.x > 0.99);
    }
}
