//! CPU twin of `deferred.wgsl`: the same shading, term by term, for
//! GPU-versus-CPU tests.

use glam::{Vec2, Vec3};

use crate::math::brdf::{
    Material, brdf_cos, env_brdf_approx, perceptual_roughness_from_glossiness,
    surface_from_material,
};
use crate::math::sh::Sh9Rgb;
use crate::passes::envmap::reference::{CubeMip, m4_reflection_normal, sample_lod};

/// The filtered environment cube and the DFG table (L4), as the lighting
/// pass samples them.
#[derive(Clone, Debug)]
pub struct EnvironmentSpecular {
    /// Filtered mips; mip m holds perceptual roughness m / (len - 1).
    pub filtered: Vec<CubeMip>,
    /// DFG table (A, B), `dfg_size`² texels: x = n.v, y = roughness.
    pub dfg: Vec<Vec2>,
    /// Edge of the square DFG table (texels), so `dfg.len() == dfg_size²`.
    pub dfg_size: usize,
}

impl EnvironmentSpecular {
    /// Bilinear (A, B) at texel-centre coordinates, clamped like the GPU sampler.
    pub fn dfg_at(&self, n_o_v: f32, roughness: f32) -> Vec2 {
        let n = self.dfg_size;
        let p = Vec2::new(n_o_v, roughness) * n as f32 - 0.5;
        let p0 = p.floor();
        let f = p - p0;
        let at = |x: f32, y: f32| {
            let x = (x.max(0.0) as usize).min(n - 1);
            let y = (y.max(0.0) as usize).min(n - 1);
            self.dfg[y * n + x]
        };
        let top = at(p0.x, p0.y).lerp(at(p0.x + 1.0, p0.y), f.x);
        let bottom = at(p0.x, p0.y + 1.0).lerp(at(p0.x + 1.0, p0.y + 1.0), f.x);
        top.lerp(bottom, f.y)
    }
}

/// What `Lighting` holds on the GPU.
#[derive(Clone, Debug)]
pub struct LightingParams {
    /// World-space unit vector towards the sun.
    pub sun_direction: Vec3,
    /// Sun illuminance at the ground, linear RGB (klux).
    pub sun_illuminance: Vec3,
    /// Sky irradiance E(n) as RGB SH9 (klux): ambient diffuse along the
    /// normal (the bent normal with L2), ambient specular along the
    /// reflection vector when `environment` is `None`.
    pub sky_irradiance: Sh9Rgb,
    /// Ambient specular from the filtered cube (`ENV_SPECULAR`); `None`: SH
    /// along the reflection vector with the fitted DFG.
    pub environment: Option<EnvironmentSpecular>,
    /// R4: the sun sees Burley's remapped roughness in V
    /// ([`crate::math::brdf::visibility_remap`]; `sun_illuminance.w` on the GPU).
    pub visibility_remap: bool,
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
    shade_sky_occluded(m, ao, t, b, n, v, light, sun_visibility, None)
}

/// [`shade`] with the `SKY_OCCLUSION` permutation (L2): `sky_vis` is the
/// pixel's faded SH2 visibility (`passes/skyocc/reference.rs`); the sky
/// irradiance is taken along the bent normal and, with ambient specular,
/// scaled by the cosine-convolved visibility along it.
#[allow(clippy::too_many_arguments)]
pub fn shade_sky_occluded(
    m: &Material,
    ao_in: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    light: &LightingParams,
    sun_visibility: f32,
    sky_vis: Option<glam::Vec4>,
) -> Vec3 {
    use crate::passes::skyocc::reference::{bent_normal_from_sh_visibility, sh2_visibility_cosine};
    let s = surface_from_material(m);
    let l = light.sun_direction;
    let s_direct = if light.visibility_remap {
        crate::math::brdf::visibility_remap(s)
    } else {
        s
    };
    let mut c = brdf_cos(&s_direct, t, b, n, v, l) * light.sun_illuminance * sun_visibility;
    let n_o_v = n.dot(v).max(1e-4);
    let (ao, n_sky) = match sky_vis {
        Some(sh) => {
            let bent = bent_normal_from_sh_visibility(n, sh);
            (ao_in * sh2_visibility_cosine(sh, bent), bent)
        }
        None => (ao_in, n),
    };
    let e_n = light.sky_irradiance.eval(n_sky).max(Vec3::ZERO);
    let roughness = perceptual_roughness_from_glossiness(m.glossiness);
    if let Some(env) = &light.environment {
        let n_r = m4_reflection_normal(n, b, v, m.anisotropy);
        let r = (2.0 * n_r.dot(v)) * n_r - v;
        let lod = roughness * (env.filtered.len() - 1) as f32;
        let ab = env.dfg_at(n_o_v, roughness);
        let ratio = ambient_luminance_ratio(&light.sky_irradiance, n, sky_vis);
        c +=
            sample_lod(&env.filtered, r, lod) * (s.f0 * ab.x + Vec3::splat(ab.y)) * (ao_in * ratio);
    } else {
        let r = (2.0 * n.dot(v)) * n - v;
        let e_r = light.sky_irradiance.eval(r).max(Vec3::ZERO);
        c += env_brdf_approx(s.f0, roughness, n_o_v) * e_r * (ao / std::f32::consts::PI);
    }
    c += s.diffuse_albedo * e_n * (ao / std::f32::consts::PI);
    c
}

/// L3 normalisation of the environment cube, which was lit by the open sky:
/// luminance (not colour) of the pixel's sky ambient — SH irradiance along
/// the bent normal times the SH2 visibility — over the open sky's along `n`,
/// clamped to [0, 1]. 1 without sky occlusion.
pub fn ambient_luminance_ratio(
    sky: &crate::math::sh::Sh9Rgb,
    n: Vec3,
    sky_vis: Option<glam::Vec4>,
) -> f32 {
    use crate::passes::post::reference::luminance;
    use crate::passes::skyocc::reference::{bent_normal_from_sh_visibility, sh2_visibility_cosine};
    let Some(sh) = sky_vis else {
        return 1.0;
    };
    let bent = bent_normal_from_sh_visibility(n, sh);
    let e_n = sky.eval(bent).max(Vec3::ZERO) * sh2_visibility_cosine(sh, bent);
    let e_open = sky.eval(n).max(Vec3::ZERO);
    (luminance(e_n) / luminance(e_open).max(1e-9)).clamp(0.0, 1.0)
}

/// `local_light_falloff`: windowed inverse square, 1/d² · (1 − (d/range)⁴)².
pub fn local_light_falloff(d: f32, range: f32) -> f32 {
    let x = d / range;
    let window = (1.0 - x.powi(4)).clamp(0.0, 1.0);
    window * window / (d * d).max(1e-4)
}

/// `spot_cone`: smoothstep from the outer to the inner cosine.
pub fn spot_cone(cos_angle: f32, cos_outer: f32, cos_inner: f32) -> f32 {
    let t = ((cos_angle - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Direction to a local light from `p` and its illuminance there (klux;
/// `intensity` in cd, `color` linear), unshadowed; `None` out of range.
pub fn local_light_illuminance(p: Vec3, light: &crate::scene::LightDesc) -> Option<(Vec3, Vec3)> {
    let to_l = light.position - p;
    let d = to_l.length();
    if d >= light.range || d <= 0.0 {
        return None;
    }
    let l = to_l / d;
    let mut e = light.color * light.intensity * 1e-3 * local_light_falloff(d, light.range);
    if light.kind == crate::scene::LightKind::Spot {
        e *= spot_cone(
            (-l).dot(light.direction),
            light.outer_deg.to_radians().cos(),
            light.inner_deg.to_radians().cos(),
        );
    }
    Some((l, e))
}

/// `shade_local` for one light at `p` (unshadowed, R4 off): BRDF · cos · E.
#[allow(clippy::too_many_arguments)]
pub fn shade_local(
    m: &Material,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    p: Vec3,
    light: &crate::scene::LightDesc,
) -> Vec3 {
    local_light_illuminance(p, light).map_or(Vec3::ZERO, |(l, e)| {
        brdf_cos(&surface_from_material(m), t, b, n, v, l) * e
    })
}

/// V5 (`shaders/leaf.wgsl`): transmitted over reflected diffuse light.
pub const LEAF_TRANSLUCENCY: f32 = 0.6;
/// V5: the share of the view-dependent term (CryEngine's "back view dependency").
pub const LEAF_BACK_VIEW: f32 = 0.5;
/// V5: a leaf's F0 (waxy cuticle, index ~1.42).
pub const LEAF_F0: f32 = 0.03;
/// V5: a leaf's largest glossiness (a broad highlight).
pub const LEAF_GLOSS_MAX: f32 = 0.3;

/// `leaf_material`: `m` with a leaf's glossiness and F0, blended by the leaf amount `f`.
pub fn leaf_material(m: &Material, f: f32) -> Material {
    let lerp = |a: f32, b: f32| a + (b - a) * f;
    Material {
        glossiness: lerp(m.glossiness, m.glossiness.min(LEAF_GLOSS_MAX)),
        reflectance: lerp(m.reflectance, LEAF_F0),
        ..*m
    }
}

/// `leaf_translucency`: radiance toward `v` per unit illuminance from `l`
/// (1/sr) through a leaf of amount `f`:
/// k f albedo / π ((1 − d) max(−n·l, 0) + d saturate(−v·l)⁴).
pub fn leaf_translucency(diffuse_albedo: Vec3, f: f32, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    let back = (-n.dot(l)).max(0.0);
    let t = (-v.dot(l)).clamp(0.0, 1.0);
    let through = (t * t) * (t * t);
    let b = back + (through - back) * LEAF_BACK_VIEW;
    diffuse_albedo * (f * LEAF_TRANSLUCENCY * b / std::f32::consts::PI)
}

/// [`shade`] of a foliage pixel of leaf amount `f` with leaf shading on:
/// the leaf's material ([`leaf_material`]) plus the sun through the leaf.
#[allow(clippy::too_many_arguments)]
pub fn shade_leaf(
    m: &Material,
    f: f32,
    ao: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    light: &LightingParams,
    sun_visibility: f32,
) -> Vec3 {
    let leaf = leaf_material(m, f);
    let through = leaf_translucency(
        surface_from_material(&leaf).diffuse_albedo,
        f,
        n,
        v,
        light.sun_direction,
    );
    shade(&leaf, ao, t, b, n, v, light, sun_visibility)
        + through * light.sun_illuminance * sun_visibility
}

/// [`shade_local`] of a foliage pixel of leaf amount `f` with leaf shading
/// on: the leaf's material plus the light through the leaf.
#[allow(clippy::too_many_arguments)]
pub fn shade_local_leaf(
    m: &Material,
    f: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    p: Vec3,
    light: &crate::scene::LightDesc,
) -> Vec3 {
    let s = surface_from_material(&leaf_material(m, f));
    local_light_illuminance(p, light).map_or(Vec3::ZERO, |(l, e)| {
        (brdf_cos(&s, t, b, n, v, l) + leaf_translucency(s.diffuse_albedo, f, n, v, l)) * e
    })
}

/// `ambient_light_scale`: the multiplier of ambient light `l` at `p`:
/// `mix(1, factor, smoothstep(t))`, `t = clamp((1 - r) / falloff, 0, 1)`
/// with `r` the distance to the centre in units of the volume (the box's
/// largest |local coordinate| / half-extent, or |p - c| / radius); falloff
/// 0 is a hard edge at r = 1.
pub fn ambient_light_scale(l: &crate::scene::AmbientLightDesc, p: Vec3) -> Vec3 {
    use crate::scene::AmbientShape;
    let d = p - l.position;
    let r = match l.shape {
        AmbientShape::Sphere(radius) => d.length() / radius,
        AmbientShape::Box(half) => {
            let local = glam::Quat::from_rotation_y(l.yaw_deg.to_radians()).inverse() * d;
            (local.abs() / half).max_element()
        }
    };
    let t = if l.falloff > 0.0 {
        ((1.0 - r) / l.falloff).clamp(0.0, 1.0)
    } else if r <= 1.0 {
        1.0
    } else {
        0.0
    };
    let w = t * t * (3.0 - 2.0 * t);
    Vec3::ONE.lerp(l.factor, w)
}

/// `ambient_scale`: the product of every light's multiplier at `p`, what
/// both ambient terms (diffuse and specular) are multiplied by.
pub fn ambient_scale(lights: &[crate::scene::AmbientLightDesc], p: Vec3) -> Vec3 {
    lights
        .iter()
        .take(crate::scene::MAX_AMBIENT_LIGHTS)
        .fold(Vec3::ONE, |s, l| s * ambient_light_scale(l, p))
}

/// Aerial perspective of a surface `dist` metres away seen along `-v`
/// (twin of `shaders/fog.wgsl` `aerial_perspective`): (inscattered
/// radiance L_in, transmittance T); the caller applies c T + L_in (1 − T).
/// `fog` is the lighting constant's (x extinction per metre, y amount, z 1 =
/// inscatter from the sky SH); `preetham`: the Preetham sky's radiance
/// toward −v (used when fog.z is 0).
pub fn aerial_perspective(
    dist: f32,
    v: Vec3,
    fog: glam::Vec4,
    sky_irradiance: &Sh9Rgb,
    preetham: Vec3,
) -> (Vec3, f32) {
    let transmittance = (-fog.x * dist).exp();
    let inscatter = if fog.z > 0.5 {
        let d = (Vec3::new(-v.x, (-v.y).max(0.0), -v.z) + Vec3::new(0.0, 1e-4, 0.0)).normalize();
        sky_irradiance
            .radiance_from_irradiance_eval(d)
            .max(Vec3::ZERO)
            * fog.y
    } else {
        preetham * fog.y
    };
    (inscatter, transmittance)
}
