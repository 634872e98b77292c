//! One-bounce indirect irradiance by Monte Carlo path tracing: the ground
//! truth for himal's L5 radiance-transfer probes.
//!
//! At a point p with normal n:
//!   E(p, n) = integral over the hemisphere of n of L_b(w) cos(theta) dw,
//!   L_b(w)  = rho(x) / pi * ( E_sun V(x, l) max(n_x . l, 0)
//!                             + integral of L_sky(w') V(x, w') max(n_x . w', 0) dw' )
//! where x is the first surface along w. The sun is a directional light
//! with its true direction and a shadow ray; the sky is its full radiance
//! function (no SH); rays that escape contribute nothing. Unlike the bake,
//! nothing here goes through SH, and the point is the point itself (not a
//! probe 8 m away, 2 m above the ground).

use glam::{DVec3, Vec3};

use crate::integrate::hammersley;

/// What a ray found: distance, the unit normal facing the ray's origin, albedo.
#[derive(Clone, Copy, Debug)]
pub struct Found {
    pub t: f32,
    pub normal: Vec3,
    pub albedo: Vec3,
}

/// The scene's surfaces, as the caller's ray caster sees them.
pub trait Surfaces: Sync {
    /// Nearest surface along unit `dir` from `origin`.
    fn nearest(&self, origin: Vec3, dir: Vec3) -> Option<Found>;
    /// True where nothing lies along unit `dir` from `origin`.
    fn clear(&self, origin: Vec3, dir: Vec3) -> bool;
}

/// One lighting condition: the sky's radiance per direction and the sun.
pub struct Light<'a> {
    pub sky: &'a (dyn Fn(Vec3) -> Vec3 + Sync),
    pub to_sun: Vec3,
    pub sun_illuminance: Vec3,
}

/// Sample counts: cosine-distributed primary rays from the point, and
/// sky rays from each surface they hit.
#[derive(Clone, Copy, Debug)]
pub struct Samples {
    pub primary: u32,
    pub sky: u32,
}

fn basis(n: Vec3) -> (Vec3, Vec3) {
    // Hughes-Moeller: a vector orthogonal to n from its smallest component.
    let a = if n.x.abs() < n.y.abs().min(n.z.abs()) {
        Vec3::new(0.0, -n.z, n.y)
    } else if n.y.abs() < n.z.abs() {
        Vec3::new(-n.z, 0.0, n.x)
    } else {
        Vec3::new(-n.y, n.x, 0.0)
    }
    .normalize();
    (a, n.cross(a))
}

fn cosine_dir(n: Vec3, u: glam::Vec2) -> Vec3 {
    let (a, b) = basis(n);
    let phi = std::f32::consts::TAU * u.x;
    let r = u.y.sqrt();
    (a * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.y).max(0.0).sqrt()).normalize()
}

/// Indirect irradiance at `p` for normal `n` under each of `lights`
/// (the same paths serve every light, so their differences are not noise).
pub fn one_bounce_irradiance(
    surfaces: &dyn Surfaces,
    p: Vec3,
    n: Vec3,
    lights: &[Light],
    samples: Samples,
    seed: u32,
) -> Vec<Vec3> {
    let mut sum = vec![DVec3::ZERO; lights.len()];
    let origin = p + n * 1e-3;
    // A per-point rotation (Cranley-Patterson) so neighbours do not share a pattern.
    let rot = hammersley(seed % 1021, 1021);
    for k in 0..samples.primary {
        let u = (hammersley(k, samples.primary) + rot).fract();
        let w = cosine_dir(n, u);
        let Some(hit) = surfaces.nearest(origin, w) else {
            continue;
        };
        let x = origin + w * hit.t + hit.normal * 1e-3;
        // Sky visibility per direction, shared by every light.
        let mut visible = Vec::with_capacity(samples.sky as usize);
        let spin = hammersley((k * 7 + seed) % 509, 509);
        for m in 0..samples.sky {
            let d = cosine_dir(hit.normal, (hammersley(m, samples.sky) + spin).fract());
            if surfaces.clear(x, d) {
                visible.push(d);
            }
        }
        for (s, light) in sum.iter_mut().zip(lights) {
            let cos_sun = hit.normal.dot(light.to_sun);
            let sun = if light.to_sun.y > 0.0 && cos_sun > 0.0 && surfaces.clear(x, light.to_sun) {
                light.sun_illuminance * cos_sun
            } else {
                Vec3::ZERO
            };
            // Cosine-distributed sky rays: integral = pi / M * sum of L_sky.
            let sky: Vec3 = visible.iter().map(|&d| (light.sky)(d)).sum::<Vec3>()
                * (std::f32::consts::PI / samples.sky.max(1) as f32);
            // L_b = rho / pi * E(x); cosine-distributed primaries: E = pi / N * sum L_b.
            *s += (hit.albedo * (sun + sky)).as_dvec3();
        }
    }
    sum.iter()
        .map(|s| (*s / samples.primary.max(1) as f64).as_vec3())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A floor (y = 0) and an infinite wall x = 1 facing -x, both albedo 0.5.
    struct Corner;

    impl Surfaces for Corner {
        fn nearest(&self, o: Vec3, d: Vec3) -> Option<Found> {
            let floor = (d.y < 0.0).then(|| -o.y / d.y).filter(|t| *t > 0.0);
            let wall = (d.x > 0.0).then(|| (1.0 - o.x) / d.x).filter(|t| *t > 0.0);
            match (floor, wall) {
                (Some(f), Some(w)) if w < f => Some(Found {
                    t: w,
                    normal: -Vec3::X,
                    albedo: Vec3::splat(0.5),
                }),
                (Some(f), _) => Some(Found {
                    t: f,
                    normal: Vec3::Y,
                    albedo: Vec3::splat(0.5),
                }),
                (None, Some(w)) => Some(Found {
                    t: w,
                    normal: -Vec3::X,
                    albedo: Vec3::splat(0.5),
                }),
                _ => None,
            }
        }
        fn clear(&self, o: Vec3, d: Vec3) -> bool {
            self.nearest(o, d).is_none()
        }
    }

    #[test]
    fn a_lit_infinite_wall_gives_a_floor_point_at_its_foot_half_its_radiosity() {
        // Sun straight along -x onto the wall (cos 1), no sky: the wall's
        // radiance is rho E / pi everywhere; a floor point at the wall's foot
        // sees it over half its hemisphere, where the cosine integral is pi/2:
        // E = rho E_sun / pi * pi / 2 = rho E_sun / 2.
        let sky = |_: Vec3| Vec3::ZERO;
        let light = Light {
            sky: &sky,
            to_sun: Vec3::new(-1.0, 1e-4, 0.0).normalize(),
            sun_illuminance: Vec3::ONE,
        };
        let e = one_bounce_irradiance(
            &Corner,
            Vec3::new(1.0 - 1e-3, 0.0, 0.0),
            Vec3::Y,
            &[light],
            Samples {
                primary: 4096,
                sky: 1,
            },
            3,
        );
        assert!((e[0].x - 0.25).abs() < 0.01, "{}", e[0].x);
    }
}
