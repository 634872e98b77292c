//! CPU twin of `shaders/forward.wgsl` (`forward_shade_premultiplied`), of
//! premultiplied "over" blending and of `shaders/layers.wgsl` (clearcoat
//! and sheen, [`layers_shade`]), for GPU-versus-CPU tests.

use std::f32::consts::PI;

use glam::{Vec2, Vec3, Vec4};

use crate::math::brdf::{
    MIN_ALPHA, MIN_N_O_V, Surface, alpha_from_glossiness, brdf_cos_f90, d_ggx_aniso, f_schlick,
    specular_cos_f90, v_smith_ggx_correlated_aniso,
};
use crate::math::sh::Sh9Rgb;

/// The light a forward fragment receives (what `Lighting` and the caller's
/// samples of the filtered cube and DFG table give the shader).
#[derive(Clone, Debug)]
pub struct ForwardLight {
    /// World-space unit vector towards the sun.
    pub sun_direction: Vec3,
    /// Sun illuminance, linear RGB (klux), times its shadow where the
    /// caller applies one.
    pub sun_illuminance: Vec3,
    /// Irradiance SH9 (`sh9_eval` gives E(n)).
    pub sky_irradiance: Sh9Rgb,
    /// Filtered-cube radiance along the (M4) reflection vector.
    pub prefiltered: Vec3,
    /// DFG table (A, B) at (n.v, roughness).
    pub dfg: Vec2,
}

/// Premultiplied (radiance × alpha, alpha) of a fragment with surface `s`
/// and Schlick F90 `f90` (below 1 for a KHR_materials_specular dielectric),
/// right-handed frame (t, b, n), view vector `v`, ambient occlusion `ao`
/// (times the ambient lights' multiplier, per channel),
/// emission `emissive` (radiance), the local lights' reflected radiance
/// `local` (see [`local_radiance`]) and coverage `alpha` (clamped to [0, 1]).
#[allow(clippy::too_many_arguments)]
pub fn forward_shade_premultiplied(
    s: &Surface,
    f90: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    light: &ForwardLight,
    ao: Vec3,
    emissive: Vec3,
    local: Vec3,
    alpha: f32,
) -> Vec4 {
    let mut c = brdf_cos_f90(s, f90, t, b, n, v, light.sun_direction) * light.sun_illuminance;
    c += light.prefiltered * (s.f0 * light.dfg.x + Vec3::splat(f90 * light.dfg.y)) * ao;
    let e_n = light.sky_irradiance.eval(n).max(Vec3::ZERO);
    c += s.diffuse_albedo * e_n * (ao / PI);
    c += emissive + local;
    let a = alpha.clamp(0.0, 1.0);
    (c * a).extend(a)
}

/// The local lights' reflected radiance at a `forward.blend` fragment
/// (twin of `blend_local` in passes/forward/forward.wgsl): the sum over
/// `lights` of (unit direction to the light, its illuminance × shadow
/// visibility) of the BRDF × cosine with Schlick F90 `f90`.
#[allow(clippy::too_many_arguments)]
pub fn local_radiance(
    s: &Surface,
    f90: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    lights: &[(Vec3, Vec3)],
) -> Vec3 {
    lights
        .iter()
        .map(|&(dir, e)| brdf_cos_f90(s, f90, t, b, n, v, dir) * e)
        .sum()
}

/// A premultiplied `forward.blend` fragment `c` seen through the frame's
/// aerial perspective (L_in, T) (twin of fs_blend's FOG branch): the layer's
/// share of "over", (c.rgb T + L_in (1 − T) c.a, c.a).
pub fn fog_premultiplied(c: Vec4, (inscatter, transmittance): (Vec3, f32)) -> Vec4 {
    (c.truncate() * transmittance + inscatter * ((1.0 - transmittance) * c.w)).extend(c.w)
}

/// KHR_materials_transmission's BTDF roughness: `roughness` (perceptual
/// or alpha) × clamp(2 ior − 2, 0, 1). Twin of `transmission_roughness`
/// in shaders/forward.wgsl.
pub fn transmission_roughness(roughness: f32, ior: f32) -> f32 {
    roughness * (2.0 * ior - 2.0).clamp(0.0, 1.0)
}

/// The mip of the opaque scene's chain sampled behind a transmissive
/// surface on a `width`-pixel screen: log2(width) × the BTDF's roughness.
pub fn transmission_lod(roughness: f32, ior: f32, width: f32) -> f32 {
    width.log2() * transmission_roughness(roughness, ior)
}

/// KHR_materials_volume's Beer–Lambert transmittance over `distance`:
/// colour^(distance / attenuation distance); `inv_distance` = 1 / the
/// attenuation distance, 0 for none.
pub fn volume_attenuation(distance: f32, inv_distance: f32, colour: Vec3) -> Vec3 {
    if inv_distance <= 0.0 {
        return Vec3::ONE;
    }
    let ln = colour.max(Vec3::splat(1e-6)).to_array().map(f32::ln);
    (Vec3::from_array(ln) * (distance * inv_distance)).exp()
}

/// The sun through a transmissive surface: (1 − F) D V n.l′ toward the sun
/// direction `l` mirrored through the surface's plane.
#[allow(clippy::too_many_arguments)]
pub fn transmission_sun_cos(
    f0: Vec3,
    f90: f32,
    alpha_t: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    l: Vec3,
) -> Vec3 {
    let l_m = l - 2.0 * n.dot(l) * n;
    let n_o_l = n.dot(l_m);
    if n_o_l.is_nan() || n_o_l <= 0.0 {
        return Vec3::ZERO;
    }
    let hv = v + l_m;
    let h = if hv.length_squared() > 1e-30 {
        hv.normalize()
    } else {
        n
    };
    let n_o_h = n.dot(h);
    if n_o_h <= 0.0 {
        return Vec3::ZERO;
    }
    let n_o_v = n.dot(v).max(MIN_N_O_V);
    let a = alpha_t.max(MIN_ALPHA);
    let d = d_ggx_aniso(n_o_h, t.dot(h), b.dot(h), a, a);
    let vis = v_smith_ggx_correlated_aniso(
        n_o_v,
        n_o_l,
        t.dot(v),
        b.dot(v),
        t.dot(l_m),
        b.dot(l_m),
        a,
        a,
    );
    (Vec3::ONE - f_schlick(f0, f90, v.dot(h))) * (d * vis * n_o_l)
}

/// What light reaches a transmissive fragment from behind.
#[derive(Clone, Debug)]
pub struct TransmittedLight {
    /// The opaque scene's radiance at the refracted exit point (the mip chain's sample).
    pub behind: Vec3,
    /// The volume's transmittance along the refracted path.
    pub transmittance: Vec3,
}

/// Radiance transmitted toward the eye by a surface with Fresnel (`f0`,
/// `f90`), split-sum table sample `dfg`, transmitted albedo `t_albedo`
/// (transmission × the dielectric's base colour) and BTDF alpha `alpha_t`:
/// t_albedo × transmittance × (behind × (1 − f0 A − f90 B) + sun lobe).
/// Twin of `transmitted_radiance` in shaders/forward.wgsl.
#[allow(clippy::too_many_arguments)]
pub fn transmitted_radiance(
    f0: Vec3,
    f90: f32,
    dfg: Vec2,
    t_albedo: Vec3,
    light: &TransmittedLight,
    alpha_t: f32,
    (t, b, n): (Vec3, Vec3, Vec3),
    v: Vec3,
    sun_direction: Vec3,
    sun_illuminance: Vec3,
) -> Vec3 {
    let through = light.behind * (Vec3::ONE - (f0 * dfg.x + Vec3::splat(f90 * dfg.y)));
    let sun = transmission_sun_cos(f0, f90, alpha_t, t, b, n, v, sun_direction) * sun_illuminance;
    t_albedo * light.transmittance * (through + sun)
}

/// Premultiplied `src` over `dst` (blend One, OneMinusSrcAlpha).
pub fn over(src: Vec4, dst: Vec4) -> Vec4 {
    src + dst * (1.0 - src.w)
}

/// Sheen roughness floor (the Charlie exponent 1/alpha stays finite); twin
/// of `SHEEN_MIN_ROUGHNESS` in shaders/layers.wgsl.
pub const SHEEN_MIN_ROUGHNESS: f32 = 0.07;

/// Charlie sheen distribution (Estevez & Kulla 2017):
/// D = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi).
pub fn d_charlie(alpha: f32, n_o_h: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - n_o_h * n_o_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) / (2.0 * PI)
}

/// Estevez & Kulla 2017's fit of the Charlie lobe's Λ: the exponent
/// L(x) = a / (1 + b x^c) + d x + e, coefficients blended between the
/// paper's rows for alpha = 0 and 1 by (1 − alpha)².
fn charlie_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |at1: f32, at0: f32| at1 * (1.0 - t) + at0 * t;
    let (a, b, c) = (
        mix(21.5473, 25.3245),
        mix(3.82987, 3.32435),
        mix(0.19823, 0.16801),
    );
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// Λ(cos θ) of the Charlie lobe (Estevez & Kulla 2017, eq. 3 and its
/// mirror for cos θ ≥ 0.5).
pub fn charlie_lambda(cos_theta: f32, alpha: f32) -> f32 {
    if cos_theta < 0.5 {
        charlie_l(cos_theta, alpha).exp()
    } else {
        (2.0 * charlie_l(0.5, alpha) - charlie_l(1.0 - cos_theta, alpha)).exp()
    }
}

/// Charlie visibility 1 / ((1 + Λ(v) + Λ(l)) 4 n.v n.l), at most 1 (as
/// the Khronos sample viewer clamps it).
pub fn v_charlie(n_o_v: f32, n_o_l: f32, alpha: f32) -> f32 {
    let g = 1.0 + charlie_lambda(n_o_v, alpha) + charlie_lambda(n_o_l, alpha);
    (1.0 / (g * 4.0 * n_o_v * n_o_l)).clamp(0.0, 1.0)
}

/// alpha = r² of a sheen roughness, floored.
pub fn sheen_alpha(perceptual_roughness: f32) -> f32 {
    let r = perceptual_roughness.max(SHEEN_MIN_ROUGHNESS);
    r * r
}

/// The sheen lobe times n.l toward `l` (colour 1).
pub fn sheen_cos(perceptual_roughness: f32, n: Vec3, v: Vec3, l: Vec3) -> f32 {
    let n_o_l = n.dot(l);
    if n_o_l.is_nan() || n_o_l <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize();
    let n_o_v = n.dot(v).max(MIN_N_O_V);
    let alpha = sheen_alpha(perceptual_roughness);
    d_charlie(alpha, n.dot(h)) * v_charlie(n_o_v, n_o_l, alpha) * n_o_l
}

/// Directional albedo of the sheen lobe, E(n.v) = ∫ D V (n.l) dω_l over the
/// hemisphere (colour 1), by the midpoint rule in (θ_l, φ_l): 96 × 96
/// cells, φ over half the circle (the lobe is symmetric about the plane of
/// n and v). Measured against 4x finer grids in the tests.
pub fn sheen_albedo(n_o_v: f32, perceptual_roughness: f32, cells: usize) -> f32 {
    let n_o_v = n_o_v.clamp(MIN_N_O_V, 1.0);
    let v = Vec3::new((1.0 - n_o_v * n_o_v).sqrt(), 0.0, n_o_v);
    let (d_theta, d_phi) = (0.5 * PI / cells as f32, PI / cells as f32);
    let mut e = 0.0f64;
    for i in 0..cells {
        let theta = (i as f32 + 0.5) * d_theta;
        let (sin_t, cos_t) = theta.sin_cos();
        for j in 0..cells {
            let phi = (j as f32 + 0.5) * d_phi;
            let l = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
            e += (sheen_cos(perceptual_roughness, Vec3::Z, v, l) * sin_t) as f64;
        }
    }
    (2.0 * e * (d_theta * d_phi) as f64) as f32
}

/// Entries per side of the sheen albedo table.
pub const SHEEN_TABLE_SIZE: usize = 32;

/// E(n.v, roughness) at n.v = i / (size - 1) (columns) and roughness
/// j / (size - 1) (rows), computed once per process; uploaded as the
/// `sheen_albedo` texture of `forward.layers`. Clamped to 1: with the
/// visibility clamped as the sample viewer does, the fitted lobe reflects
/// more than arrives at views within ~5° of grazing and roughness under
/// 0.2 (E(0, 0) = 1.57), which would make the base's weight negative.
pub fn sheen_albedo_table() -> &'static [f32] {
    static TABLE: std::sync::OnceLock<Vec<f32>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let n = SHEEN_TABLE_SIZE;
        let at = |k: usize| k as f32 / (n - 1) as f32;
        (0..n * n)
            .map(|k| sheen_albedo(at(k % n), at(k / n), 96).min(1.0))
            .collect()
    })
}

/// Bilinear lookup in [`sheen_albedo_table`] (twin of `sheen_albedo_lookup`
/// in shaders/layers.wgsl).
pub fn sheen_albedo_lookup(table: &[f32], n_o_v: f32, perceptual_roughness: f32) -> f32 {
    let n = SHEEN_TABLE_SIZE;
    let x = n_o_v.clamp(0.0, 1.0) * (n - 1) as f32;
    let y = perceptual_roughness.clamp(0.0, 1.0) * (n - 1) as f32;
    let (x0, y0) = ((x as usize).min(n - 2), (y as usize).min(n - 2));
    let (fx, fy) = (x - x0 as f32, y - y0 as f32);
    let e = |i: usize, j: usize| table[j * n + i];
    let mix = |a: f32, b: f32, t: f32| a * (1.0 - t) + b * t;
    let top = mix(e(x0, y0), e(x0 + 1, y0), fx);
    let bottom = mix(e(x0, y0 + 1), e(x0 + 1, y0 + 1), fx);
    mix(top, bottom, fy)
}

/// A glTF material's layers at one point (factors times textures).
#[derive(Clone, Copy, Debug)]
pub struct Layers {
    /// Linear sheen colour (0: no sheen).
    pub sheen_color: Vec3,
    /// Sheen perceptual roughness in [0, 1].
    pub sheen_roughness: f32,
    /// Coat intensity in [0, 1] (0: no coat).
    pub clearcoat: f32,
    /// Coat perceptual roughness in [0, 1].
    pub clearcoat_roughness: f32,
    /// KHR_materials_specular's correction of the deferred base: the true
    /// F0 minus the G-buffer's grey one, times 1 − metallic.
    pub base_f0_delta: Vec3,
    /// The true F90 minus the deferred pass's 1, times 1 − metallic.
    pub base_f90_delta: f32,
    /// The base's perceptual roughness.
    pub base_roughness: f32,
}

/// What the layers see (twin of `LayerLight` in shaders/layers.wgsl).
#[derive(Clone, Copy, Debug)]
pub struct LayerLight {
    /// World-space unit vector towards the sun.
    pub sun_direction: Vec3,
    /// Sun illuminance times its shadow.
    pub sun: Vec3,
    /// Filtered environment along the base normal's reflection vector at the sheen roughness.
    pub sheen_env: Vec3,
    /// Filtered environment along the coat normal's reflection vector at the coat roughness.
    pub coat_env: Vec3,
    /// DFG table (A, B) at the coat's (n.v, roughness).
    pub coat_dfg: Vec2,
    /// E(n.v) of the sheen.
    pub sheen_albedo: f32,
    /// Filtered environment along the base normal's reflection vector at the base roughness.
    pub base_env: Vec3,
    /// DFG table (A, B) at the base's (n.v, roughness).
    pub base_dfg: Vec2,
    /// Ambient occlusion in [0, 1] applied to the environment terms (not
    /// the sun).
    pub ao: f32,
}

/// (radiance the layers add, 1 − the fraction of the base they let
/// through) at base normal `n`, coat normal `n_c`, view `v`: blended One,
/// OneMinusSrcAlpha over the deferred base, out = layers + base s_sheen
/// s_coat, with s_coat = 1 − c F_schlick(0.04, n_c·v) and s_sheen = 1 −
/// max(sheen colour) E(n·v) (KHR_materials_sheen's albedo scaling, view
/// term only: the base is one shaded value). The base itself gains Δ, the
/// specular of a lobe with F0 = `base_f0_delta`, F90 = `base_f90_delta`
/// (Schlick is linear in both) under the sun and the environment
/// (KHR_materials_specular, docs/gltf.md "Specular").
pub fn layers_shade(m: &Layers, n: Vec3, n_c: Vec3, v: Vec3, light: &LayerLight) -> Vec4 {
    let alpha_c = alpha_from_glossiness(1.0 - m.clearcoat_roughness);
    let coat_surface = Surface {
        diffuse_albedo: Vec3::ZERO,
        f0: Vec3::splat(0.04),
        alpha: Vec2::splat(alpha_c),
        alpha_v: Vec2::splat(alpha_c),
    };
    let (t_c, b_c) = n_c.any_orthonormal_pair();
    let n_o_v_c = n_c.dot(v).max(MIN_N_O_V);
    let coat = m.clearcoat
        * (specular_cos_f90(&coat_surface, 1.0, t_c, b_c, n_c, v, light.sun_direction) * light.sun
            + light.coat_env * (0.04 * light.coat_dfg.x + light.coat_dfg.y) * light.ao);
    let s_coat = 1.0 - m.clearcoat * f_schlick(Vec3::splat(0.04), 1.0, n_o_v_c).x;
    let sheen = m.sheen_color
        * (sheen_cos(m.sheen_roughness, n, v, light.sun_direction) * light.sun
            + light.sheen_env * (light.sheen_albedo * light.ao));
    let s_sheen = 1.0 - m.sheen_color.max_element() * light.sheen_albedo;
    let alpha_delta = Vec2::splat(alpha_from_glossiness(1.0 - m.base_roughness));
    let delta_surface = Surface {
        diffuse_albedo: Vec3::ZERO,
        f0: m.base_f0_delta,
        alpha: alpha_delta,
        alpha_v: alpha_delta,
    };
    let (t, b) = n.any_orthonormal_pair();
    let base_delta = specular_cos_f90(
        &delta_surface,
        m.base_f90_delta,
        t,
        b,
        n,
        v,
        light.sun_direction,
    ) * light.sun
        + light.base_env
            * (m.base_f0_delta * light.base_dfg.x
                + Vec3::splat(m.base_f90_delta * light.base_dfg.y))
            * light.ao;
    (sheen * s_coat + coat + base_delta * (s_sheen * s_coat)).extend(1.0 - s_sheen * s_coat)
}

/// KHR_materials_unlit radiance of base colour `base` (linear): as bright
/// as a white Lambertian surface facing the sun, (E_sun + E_sky(l)) / π,
/// its Rec. 709 luminance only, so the colour is the material's.
pub fn unlit_radiance(base: Vec3, light: &ForwardLight) -> Vec3 {
    let e = light.sun_illuminance
        + light
            .sky_irradiance
            .eval(light.sun_direction)
            .max(Vec3::ZERO);
    let luminance = e.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    base * (luminance / PI)
}
