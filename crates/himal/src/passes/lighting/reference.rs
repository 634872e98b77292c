//! CPU twin of `deferred.wgsl`: the same shading, term by term, for
//! GPU-versus-CPU tests.

use glam::Vec3;

use crate::math::brdf::{
    Material, brdf_cos, env_brdf_approx, perceptual_roughness_from_glossiness,
    surface_from_material,
};
use crate::math::sh::Sh9Rgb;

/// What `Lighting` holds on the GPU.
#[derive(Clone, Debug)]
pub struct LightingParams {
    pub sun_direction: Vec3,
    pub sun_illuminance: Vec3,
    pub sky_irradiance: Sh9Rgb,
}

/// Outgoing radiance toward `v` of a point with material `m`, material AO
/// `ao` and right-handed frame (t, b, n): sun (times `sun_visibility`) + SH
/// sky, before aerial perspective.
#[allow(clippy::too_many_arguments)]
pub fn shade(
    m: &Material,
    ao: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    light: &LightingParams,
    sun_visibility: f32,
) -> Vec3 {
    let s = surface_from_material(m);
    let l = light.sun_direction;
    let mut c = brdf_cos(&s, t, b, n, v, l) * light.sun_illuminance * sun_visibility;
    let n_o_v = n.dot(v).max(1e-4);
    let r = (2.0 * n.dot(v)) * n - v;
    let e_n = light.sky_irradiance.eval(n).max(Vec3::ZERO);
    let e_r = light.sky_irradiance.eval(r).max(Vec3::ZERO);
    let dfg = env_brdf_approx(
        s.f0,
        perceptual_roughness_from_glossiness(m.glossiness),
        n_o_v,
    );
    c += (s.diffuse_albedo * e_n + dfg * e_r) * (ao / std::f32::consts::PI);
    c
}
