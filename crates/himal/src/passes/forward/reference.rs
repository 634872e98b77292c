//! CPU twin of `shaders/forward.wgsl` (`forward_shade_premultiplied`) and
//! of premultiplied "over" blending, for GPU-versus-CPU tests.

use glam::{Vec2, Vec3, Vec4};

use crate::math::brdf::{Surface, brdf_cos};
use crate::math::sh::Sh9Rgb;

/// The light a forward fragment receives (what `Lighting` and the caller's
/// samples of the filtered cube and DFG table give the shader).
#[derive(Clone, Debug)]
pub struct ForwardLight {
    pub sun_direction: Vec3,
    pub sun_illuminance: Vec3,
    /// Irradiance SH9 (`sh9_eval` gives E(n)).
    pub sky_irradiance: Sh9Rgb,
    /// Filtered-cube radiance along the (M4) reflection vector.
    pub prefiltered: Vec3,
    /// DFG table (A, B) at (n.v, roughness).
    pub dfg: Vec2,
}

/// Premultiplied (radiance × alpha, alpha) of a fragment with surface `s`,
/// right-handed frame (t, b, n), view vector `v`, ambient occlusion `ao`,
/// emission `emissive` (radiance) and coverage `alpha` (clamped to [0, 1]).
#[allow(clippy::too_many_arguments)]
pub fn forward_shade_premultiplied(
    s: &Surface,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    light: &ForwardLight,
    ao: f32,
    emissive: Vec3,
    alpha: f32,
) -> Vec4 {
    let mut c = brdf_cos(s, t, b, n, v, light.sun_direction) * light.sun_illuminance;
    c += light.prefiltered * (s.f0 * light.dfg.x + Vec3::splat(light.dfg.y)) * ao;
    let e_n = light.sky_irradiance.eval(n).max(Vec3::ZERO);
    c += s.diffuse_albedo * e_n * (ao / std::f32::consts::PI);
    c += emissive;
    let a = alpha.clamp(0.0, 1.0);
    (c * a).extend(a)
}

/// Premultiplied `src` over `dst` (blend One, OneMinusSrcAlpha).
pub fn over(src: Vec4, dst: Vec4) -> Vec4 {
    src + dst * (1.0 - src.w)
}
