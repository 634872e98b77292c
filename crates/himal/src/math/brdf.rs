//! M1/M2: the Far Cry 4 material model (McAuley, GDC 2015), CPU twin of
//! `shaders/brdf.wgsl`.
//!
//! Anisotropic GGX D (Burley 2012), height-correlated anisotropic Smith
//! visibility (Heitz 2014), Schlick Fresnel, Lambertian diffuse. Parameters
//! are the talk's, all in \[0,1\]: glossiness (= smoothness), reflectance
//! (= F0 of a dielectric, taken literally), metallic, anisotropy.
//! Equations and measured properties: `docs/techniques/M1.md`, `M2.md`.
//!
//! Vectors `t, b, n` are a right-handed orthonormal shading frame (tangent
//! = the anisotropy's x direction), `v` points to the eye, `l` to the light.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Smallest alpha (= roughness^2) handed to D and V.
///
/// Glossiness 1 would give alpha 0: a delta D (0/0 at the peak). 0.002 is
/// Filament's floor (perceptual roughness 0.045^2 ~= 0.002): the D peak
/// 1/(pi alpha^2) ~= 8e4 and the largest intermediate, (h.t/alpha)^4 ~= 6e12,
/// stay far inside f32, and the highlight of a 1-pixel sun is still sharp.
pub const MIN_ALPHA: f32 = 0.002;

/// Floor for n.v: a normal-mapped normal can face away from the eye; such
/// pixels are shaded as grazing instead of returning NaN or black.
pub const MIN_N_O_V: f32 = 1e-4;

/// Perceptual roughness of the talk's glossiness (its name for smoothness).
pub fn perceptual_roughness_from_glossiness(glossiness: f32) -> f32 {
    1.0 - glossiness.clamp(0.0, 1.0)
}

/// GGX alpha = perceptual_roughness^2 (Burley 2012), floored at [`MIN_ALPHA`].
pub fn alpha_from_glossiness(glossiness: f32) -> f32 {
    let r = perceptual_roughness_from_glossiness(glossiness);
    (r * r).max(MIN_ALPHA)
}

/// Burley 2012 anisotropic alphas: aspect = sqrt(1 - 0.9 anisotropy),
/// alpha_x = alpha / aspect along the tangent, alpha_y = alpha * aspect along
/// the binormal. Both are floored at [`MIN_ALPHA`] (only alpha_y can reach it).
pub fn alpha_xy(glossiness: f32, anisotropy: f32) -> Vec2 {
    let alpha = alpha_from_glossiness(glossiness);
    let aspect = (1.0 - 0.9 * anisotropy.clamp(0.0, 1.0)).sqrt();
    Vec2::new(alpha / aspect, alpha * aspect).max(Vec2::splat(MIN_ALPHA))
}

/// The talk's material parameters, each in \[0,1\] (albedo per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base colour, linear RGB in \[0,1\]: diffuse albedo of the dielectric part, F0 of the metallic part.
    pub albedo: Vec3,
    /// Smoothness in \[0,1\]; perceptual roughness = 1 - glossiness.
    pub glossiness: f32,
    /// Specular reflectance at normal incidence of the dielectric part:
    /// F0 = reflectance literally (glTF's dielectric F0 = 0.04 is 0.04 here).
    pub reflectance: f32,
    /// Metalness in \[0,1\]: blends the dielectric and metallic responses (M2).
    pub metallic: f32,
    /// Stretch of the highlight along the tangent in \[0,1\] (0 = isotropic), see [`alpha_xy`].
    pub anisotropy: f32,
}

/// What the BRDF consumes, after M2's metallic blend.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Lambertian albedo, linear RGB: `albedo * (1 - metallic)`.
    pub diffuse_albedo: Vec3,
    /// Fresnel reflectance at normal incidence, linear RGB.
    pub f0: Vec3,
    /// (alpha_x, alpha_y) along (tangent, binormal).
    pub alpha: Vec2,
    /// The alphas of the visibility term V: `alpha`, or Burley's remap of
    /// them for analytic lights (R4, [`visibility_remap`]).
    pub alpha_v: Vec2,
}

/// `a (1 - s) + b s`: exact at both ends (s = 0 gives a, s = 1 gives b), like
/// WGSL `mix`; the `a + (b - a) s` form can miss `b` by an ulp.
fn lerp_exact(a: Vec3, b: Vec3, s: f32) -> Vec3 {
    a * (1.0 - s) + b * s
}

/// M2: `specularReflectance = lerp(reflectance, albedo, metallic);
/// albedo *= 1 - metallic`.
pub fn surface_from_material(m: &Material) -> Surface {
    let alpha = alpha_xy(m.glossiness, m.anisotropy);
    Surface {
        diffuse_albedo: m.albedo * (1.0 - m.metallic),
        f0: lerp_exact(Vec3::splat(m.reflectance), m.albedo, m.metallic),
        alpha,
        alpha_v: alpha,
    }
}

/// R4 (Burley 2012, sec. 5.6; Ryse): the visibility term of analytic
/// lights sees the remapped roughness alpha_g = ((1 + r) / 2)^2 with r the
/// perceptual roughness, which lowers rough surfaces' specular gain at
/// grazing light. Anisotropic alphas keep their aspect: both scale by
/// alpha_g / alpha of their geometric mean. D, F and image-based light keep
/// the material's alphas (docs/techniques/R4.md).
pub fn visibility_remap(s: Surface) -> Surface {
    let alpha = (s.alpha.x * s.alpha.y).sqrt();
    let r = alpha.sqrt();
    let alpha_g = (0.5 + 0.5 * r) * (0.5 + 0.5 * r);
    Surface {
        alpha_v: s.alpha * (alpha_g / alpha),
        ..s
    }
}

/// Anisotropic GGX normal distribution (Burley 2012, eq. 13):
/// D = 1 / (pi ax ay ((h.t/ax)^2 + (h.b/ay)^2 + (h.n)^2)^2).
pub fn d_ggx_aniso(n_o_h: f32, t_o_h: f32, b_o_h: f32, alpha_x: f32, alpha_y: f32) -> f32 {
    let tx = t_o_h / alpha_x;
    let by = b_o_h / alpha_y;
    let d = tx * tx + by * by + n_o_h * n_o_h;
    1.0 / (PI * alpha_x * alpha_y * d * d)
}

/// Smith Lambda for anisotropic GGX (Heitz 2014, eq. 86):
/// (-1 + sqrt(1 + (ax^2 (w.t)^2 + ay^2 (w.b)^2) / (w.n)^2)) / 2.
pub fn lambda_ggx_aniso(n_o_w: f32, t_o_w: f32, b_o_w: f32, alpha_x: f32, alpha_y: f32) -> f32 {
    let a2_tan2 = ((alpha_x * t_o_w).powi(2) + (alpha_y * b_o_w).powi(2)) / (n_o_w * n_o_w);
    0.5 * ((1.0 + a2_tan2).sqrt() - 1.0)
}

/// Smith masking G1 = 1 / (1 + Lambda) (Heitz 2014, eq. 43).
pub fn g1_smith_ggx_aniso(n_o_w: f32, t_o_w: f32, b_o_w: f32, alpha_x: f32, alpha_y: f32) -> f32 {
    1.0 / (1.0 + lambda_ggx_aniso(n_o_w, t_o_w, b_o_w, alpha_x, alpha_y))
}

/// Height-correlated anisotropic Smith visibility V = G2 / (4 n.v n.l) with
/// G2 = 1 / (1 + Lambda(v) + Lambda(l)) (Heitz 2014, eq. 99), in the
/// division-free form 0.5 / (n.l |(ax t.v, ay b.v, n.v)| + n.v |(ax t.l, ay b.l, n.l)|).
/// Needs n.v > 0 and n.l > 0 (not both zero).
#[allow(clippy::too_many_arguments)]
pub fn v_smith_ggx_correlated_aniso(
    n_o_v: f32,
    n_o_l: f32,
    t_o_v: f32,
    b_o_v: f32,
    t_o_l: f32,
    b_o_l: f32,
    alpha_x: f32,
    alpha_y: f32,
) -> f32 {
    let lambda_v = Vec3::new(alpha_x * t_o_v, alpha_y * b_o_v, n_o_v).length();
    let lambda_l = Vec3::new(alpha_x * t_o_l, alpha_y * b_o_l, n_o_l).length();
    0.5 / (n_o_l * lambda_v + n_o_v * lambda_l)
}

/// Schlick 1994: F = f0 + (f90 - f0) (1 - v.h)^5.
pub fn f_schlick(f0: Vec3, f90: f32, v_o_h: f32) -> Vec3 {
    let fc = (1.0 - v_o_h.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::splat(f90) - f0) * fc
}

/// Lambert: albedo / pi.
pub fn diffuse_lambert(diffuse_albedo: Vec3) -> Vec3 {
    diffuse_albedo * (1.0 / PI)
}

/// The dot products one BRDF evaluation needs, with the robustness rules
/// applied once: `None` when l is at or below the horizon.
struct Geometry {
    n_o_v: f32,
    n_o_l: f32,
    n_o_h: f32,
    v_o_h: f32,
    t_o_v: f32,
    b_o_v: f32,
    t_o_l: f32,
    b_o_l: f32,
    t_o_h: f32,
    b_o_h: f32,
}

fn geometry(t: Vec3, b: Vec3, n: Vec3, v: Vec3, l: Vec3) -> Option<Geometry> {
    let n_o_l = n.dot(l);
    if n_o_l <= 0.0 || n_o_l.is_nan() {
        return None;
    }
    // v = -l (only possible with v below the horizon) has no half vector.
    let h = (v + l).try_normalize().unwrap_or(n);
    Some(Geometry {
        n_o_v: n.dot(v).max(MIN_N_O_V),
        n_o_l,
        n_o_h: n.dot(h),
        v_o_h: v.dot(h).clamp(0.0, 1.0),
        t_o_v: t.dot(v),
        b_o_v: b.dot(v),
        t_o_l: t.dot(l),
        b_o_l: b.dot(l),
        t_o_h: t.dot(h),
        b_o_h: b.dot(h),
    })
}

fn specular_of(s: &Surface, f90: f32, g: &Geometry) -> Vec3 {
    // Back-facing microfacets (only when v is below the horizon) carry no D.
    if g.n_o_h <= 0.0 {
        return Vec3::ZERO;
    }
    let d = d_ggx_aniso(g.n_o_h, g.t_o_h, g.b_o_h, s.alpha.x, s.alpha.y);
    let vis = v_smith_ggx_correlated_aniso(
        g.n_o_v,
        g.n_o_l,
        g.t_o_v,
        g.b_o_v,
        g.t_o_l,
        g.b_o_l,
        s.alpha_v.x,
        s.alpha_v.y,
    );
    f_schlick(s.f0, f90, g.v_o_h) * (d * vis)
}

/// The BRDF f(v, l) (no cosine): Lambert + D V F. Zero for l below the horizon.
pub fn brdf(s: &Surface, t: Vec3, b: Vec3, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    match geometry(t, b, n, v, l) {
        Some(g) => diffuse_lambert(s.diffuse_albedo) + specular_of(s, 1.0, &g),
        None => Vec3::ZERO,
    }
}

/// f(v, l) max(n.l, 0): what a light of unit irradiance reflects to the eye.
pub fn brdf_cos(s: &Surface, t: Vec3, b: Vec3, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    brdf_cos_f90(s, 1.0, t, b, n, v, l)
}

/// [`brdf_cos`] with Schlick's F90 = `f90` (KHR_materials_specular's
/// dielectric; 1 elsewhere).
pub fn brdf_cos_f90(s: &Surface, f90: f32, t: Vec3, b: Vec3, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    match geometry(t, b, n, v, l) {
        Some(g) => (diffuse_lambert(s.diffuse_albedo) + specular_of(s, f90, &g)) * g.n_o_l,
        None => Vec3::ZERO,
    }
}

/// Specular lobe only, times max(n.l, 0).
pub fn specular_cos(s: &Surface, t: Vec3, b: Vec3, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    specular_cos_f90(s, 1.0, t, b, n, v, l)
}

/// [`specular_cos`] with Schlick's F90 = `f90`.
pub fn specular_cos_f90(
    s: &Surface,
    f90: f32,
    t: Vec3,
    b: Vec3,
    n: Vec3,
    v: Vec3,
    l: Vec3,
) -> Vec3 {
    match geometry(t, b, n, v, l) {
        Some(g) => specular_of(s, f90, &g) * g.n_o_l,
        None => Vec3::ZERO,
    }
}

/// Analytic fit of the split-sum DFG term (Karis 2013) for this BRDF:
/// returns f0 A + B (f90 = 1), for the ambient specular until the GPU DFG
/// LUT lands. A and B are rational functions of (perceptual roughness r,
/// n.v): numerators of total degree 3 (A) and 2 (B) over degree-2
/// denominators (positive on \[0,1\]^2), fitted to our own split-sum
/// integrals for n.v in [0.05, 1]. Karis 2014's mobile fit was tried first
/// and misses A by up to 0.36 here (it targets UE4's Schlick-Smith G).
/// Errors against `dfg_reference.txt`: `docs/techniques/M1.md`.
pub fn env_brdf_approx(f0: Vec3, perceptual_roughness: f32, n_o_v: f32) -> Vec3 {
    let (a, b) = env_brdf_approx_ab(perceptual_roughness, n_o_v);
    f0 * a + Vec3::splat(b)
}

/// The split-sum (A, B) of [`env_brdf_approx`]: non-negative, A + B <= 1.
pub fn env_brdf_approx_ab(perceptual_roughness: f32, n_o_v: f32) -> (f32, f32) {
    let x = perceptual_roughness.clamp(0.0, 1.0);
    let y = n_o_v.clamp(0.0, 1.0);
    let (x2, y2, xy) = (x * x, y * y, x * y);
    let a_num = -0.055_383_194 + 6.755_665 * y + 6.124_511 * y2
        - 2.516_965_4 * y2 * y
        - 0.897_922_3 * x
        - 10.897_606 * xy
        + 3.552_446_4 * xy * y
        + 11.994_692 * x2
        - 7.513_965 * x2 * y
        - 3.849_267_2 * x2 * x;
    let a_den =
        1.0 + 5.220_406 * y + 4.354_746 * y2 - 1.219_89 * x - 9.033_067 * xy + 8.828_744 * x2;
    let b_num = 0.944_636_2 - 2.067_182 * y + 1.061_921_6 * y2 - 0.499_019_9 * x + 0.722_250_9 * xy
        - 0.053_478_025 * x2;
    let b_den =
        1.0 + 1.500_716 * y + 12.616_845 * y2 - 0.819_323_3 * x - 11.694_335 * xy + 13.671_154 * x2;
    let (a, b) = ((a_num / a_den).max(0.0), (b_num / b_den).max(0.0));
    // The fit overshoots A + B = 1 (white furnace) by up to 0.02 near r = 0.
    let excess = (a + b).max(1.0);
    (a / excess, b / excess)
}

/// E3 (Toksvig 2004): the normal variance sigma^2 = (1 - |n|) / |n| of a
/// filtered normal of length |n|, stored in a baked normal map's alpha as
/// A = sqrt(sigma^2 / (1 + sigma^2)): 0 stays exactly 0, the 8-bit steps are
/// finest near 0, and any sigma^2 fits below 1 (docs/techniques/E3.md).
pub fn normal_variance_encode(variance: f32) -> f32 {
    let v = variance.max(0.0);
    (v / (1.0 + v)).sqrt()
}

/// Inverse of [`normal_variance_encode`]: sigma^2 = A^2 / (1 - A^2); A = 1
/// (opposite normals averaged to nothing) decodes to 1e4, rough enough.
pub fn normal_variance_decode(a: f32) -> f32 {
    let a2 = a.clamp(0.0, 1.0).powi(2);
    a2 / (1.0 - a2).max(1e-4)
}

/// E3: perceptual roughness `r` widened by normal variance `variance`
/// (Toksvig's 1/s' = 1/s + sigma^2 with Blinn-Phong s ~= 2 / alpha^2,
/// alpha = r^2): alpha'^2 = alpha^2 + 2 sigma^2, r' = (r^4 + 2 sigma^2)^(1/4),
/// at most 1.
pub fn toksvig_roughness(r: f32, variance: f32) -> f32 {
    let r2 = r * r;
    (r2 * r2 + 2.0 * variance.max(0.0)).sqrt().sqrt().min(1.0)
}

/// E3: one level of a normal map's variance chain (docs/techniques/E3.md
/// "The chain"), the level after a `width` x `height` level. `texel(x, y)`
/// gives the source level's RGB (0..1, as sampled: n / 2 + 1/2) and its
/// sigma^2 at any integer texel, the caller wrapping or clamping the edges.
/// Per texel: m = the mean of the four parents' unit normals and sigma^2 =
/// mean(sigma_i^2) plus (1 - |m|) / |m|; `from_level0` (the source is level
/// 0): sigma^2 is instead the spread of the bilinear field of unit normals
/// over the footprint, by two-point Gauss-Legendre on its linear pieces (6
/// x 6 nodes). Returns (m / |m|, or +z where m vanishes; sigma^2) row-major.
/// The twin of `gpu_scene/normal_mipmap.wgsl` and the terrain's detail
/// normal chain both use it.
pub fn next_normal_variance_level(
    width: u32,
    height: u32,
    texel: impl Fn(i32, i32) -> (Vec3, f32),
    from_level0: bool,
) -> Vec<(Vec3, f32)> {
    let (w, h) = ((width / 2).max(1), (height / 2).max(1));
    let unit = |rgb: Vec3| {
        let n = rgb * 2.0 - 1.0;
        let len = n.length();
        if len > 1e-6 { n / len } else { Vec3::Z }
    };
    let spread = |m: Vec3| {
        let len = m.length().max(1e-4);
        (1.0 - len) / len
    };
    // Node k of 0..6 along an axis, from the texel's centre, and its weight:
    // piece k / 2 has centre -1/4, 1/2, 5/4 and half-length 1/4, 1/2, 1/4.
    let node = |k: i32| {
        let half = if k / 2 == 1 { 0.5 } else { 0.25 };
        let side = if k & 1 == 1 { 1.0 } else { -1.0 };
        (
            -0.25 + 0.75 * (k / 2) as f32 + side * half * 0.577_350_27,
            half * 0.5,
        )
    };
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            let (px, py) = (2 * x, 2 * y);
            let (mut m, mut variance) = (Vec3::ZERO, 0.0);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (rgb, v) = texel(px + dx, py + dy);
                m += unit(rgb);
                variance += v;
            }
            m *= 0.25;
            let variance = if from_level0 {
                let mut field = Vec3::ZERO;
                for j in 0..36 {
                    let ((u, wx), (v, wy)) = (node(j % 6), node(j / 6));
                    let (fx, fy) = (u.floor(), v.floor());
                    let (x0, y0) = (px + fx as i32, py + fy as i32);
                    let top = texel(x0, y0).0.lerp(texel(x0 + 1, y0).0, u - fx);
                    let bottom = texel(x0, y0 + 1).0.lerp(texel(x0 + 1, y0 + 1).0, u - fx);
                    field += wx * wy * unit(top.lerp(bottom, v - fy));
                }
                spread(field)
            } else {
                0.25 * variance + spread(m)
            };
            let len = m.length();
            let n = if len > 1e-6 {
                m / len.max(1e-4)
            } else {
                Vec3::Z
            };
            out.push((n, variance));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::sampling::{Pcg32, uniform_sample_sphere};
    use himal_reference::microfacet;

    fn random_frame(rng: &mut Pcg32) -> (Vec3, Vec3, Vec3) {
        let n = uniform_sample_sphere(rng.next_vec2());
        let t = n.cross(uniform_sample_sphere(rng.next_vec2())).normalize();
        (t, n.cross(t), n)
    }

    fn upper(rng: &mut Pcg32, n: Vec3) -> Vec3 {
        let d = uniform_sample_sphere(rng.next_vec2());
        if d.dot(n) < 0.0 { -d } else { d }
    }

    fn material(albedo: Vec3, glossiness: f32, reflectance: f32, metallic: f32) -> Material {
        Material {
            albedo,
            glossiness,
            reflectance,
            metallic,
            anisotropy: 0.0,
        }
    }

    #[test]
    fn metallic_limits_and_exact_lerp() {
        let albedo = Vec3::new(0.95, 0.64, 0.54); // gold-ish
        let dielectric = surface_from_material(&material(albedo, 0.5, 0.04, 0.0));
        assert_eq!(dielectric.f0, Vec3::splat(0.04));
        assert_eq!(dielectric.diffuse_albedo, albedo);
        let metal = surface_from_material(&material(albedo, 0.5, 0.04, 1.0));
        assert_eq!(metal.f0, albedo);
        assert_eq!(metal.diffuse_albedo, Vec3::ZERO);
        // In between: f0 is affine in metallic and diffuse fades linearly.
        for i in 0..=16 {
            let m = i as f32 / 16.0;
            let s = surface_from_material(&material(albedo, 0.5, 0.04, m));
            let expected = Vec3::splat(0.04) + (albedo - Vec3::splat(0.04)) * m;
            assert!(
                (s.f0 - expected).abs().max_element() <= 2.0 * f32::EPSILON,
                "{m}"
            );
            assert!((s.diffuse_albedo - albedo * (1.0 - m)).abs().max_element() <= f32::EPSILON);
        }
    }

    #[test]
    fn glossiness_and_anisotropy_mappings() {
        assert_eq!(perceptual_roughness_from_glossiness(0.25), 0.75);
        assert_eq!(alpha_from_glossiness(0.5), 0.25);
        assert_eq!(alpha_from_glossiness(1.0), MIN_ALPHA);
        assert_eq!(alpha_xy(0.5, 0.0), Vec2::splat(0.25));
        // Burley: aspect = sqrt(1 - 0.9 a); ax ay = alpha^2 while unclamped.
        let a = alpha_xy(0.2, 1.0);
        let aspect = 0.1_f32.sqrt();
        assert!((a.x - 0.64 / aspect).abs() < 1e-6 && (a.y - 0.64 * aspect).abs() < 1e-6);
        assert!((a.x * a.y - 0.64 * 0.64).abs() < 1e-6);
        assert!(alpha_xy(1.0, 1.0).min_element() >= MIN_ALPHA);
    }

    #[test]
    fn reciprocity() {
        let mut rng = Pcg32::new(11);
        let mut worst = 0.0_f32;
        for i in 0..20_000 {
            let (t, b, n) = random_frame(&mut rng);
            let m = Material {
                albedo: Vec3::new(0.8, 0.5, 0.2),
                glossiness: rng.next_f32(),
                reflectance: rng.next_f32(),
                metallic: (i % 3) as f32 * 0.5,
                anisotropy: rng.next_f32(),
            };
            let s = surface_from_material(&m);
            let (v, l) = (upper(&mut rng, n), upper(&mut rng, n));
            if n.dot(v) < 1e-3 || n.dot(l) < 1e-3 {
                continue;
            }
            let (a, c) = (brdf(&s, t, b, n, v, l), brdf(&s, t, b, n, l, v));
            worst = worst.max(((a - c).abs() / a.max(c).max(Vec3::splat(1e-6))).max_element());
        }
        println!("reciprocity: worst relative asymmetry {worst:.2e}");
        // Measured 6.7e-6 on 2026-11-22 (f32 rounding only); threshold 5e-5.
        assert!(worst < 5e-5, "worst relative asymmetry {worst}");
    }

    #[test]
    fn anisotropy_zero_is_isotropic_ggx() {
        let mut rng = Pcg32::new(12);
        let mut worst = 0.0_f64;
        for _ in 0..20_000 {
            let (t, b, n) = random_frame(&mut rng);
            let glossiness = rng.next_f32();
            let s = surface_from_material(&Material {
                albedo: Vec3::ZERO,
                glossiness,
                reflectance: 1.0,
                metallic: 0.0,
                anisotropy: 0.0,
            });
            let (v, l) = (upper(&mut rng, n), upper(&mut rng, n));
            if n.dot(v) < 1e-3 || n.dot(l) < 1e-3 {
                continue;
            }
            let h = (v + l).normalize();
            let alpha = ((1.0 - glossiness as f64).powi(2)).max(MIN_ALPHA as f64);
            let (nv, nl) = (n.dot(v) as f64, n.dot(l) as f64);
            let expected = microfacet::ggx_d(n.dot(h) as f64, alpha)
                * microfacet::ggx_v_height_correlated(nv, nl, alpha);
            // F = 1 with f0 = 1, so the specular is D V.
            let got = brdf(&s, t, b, n, v, l).x as f64;
            worst = worst.max((got / expected - 1.0).abs());
        }
        println!("anisotropy 0 vs isotropic GGX: worst relative error {worst:.2e}");
        // Measured 2.5e-4 on 2026-11-22 (f32 rounding of the dot products vs
        // the f64 theta form); threshold 1e-3.
        assert!(worst < 1e-3, "worst relative error {worst}");
    }

    #[test]
    fn finite_and_non_negative_everywhere() {
        let mut rng = Pcg32::new(13);
        let (t, b, n) = (Vec3::X, Vec3::Y, Vec3::Z);
        let grazing = Vec3::new(1.0, 0.0, 1e-7).normalize();
        let special = [n, -n, Vec3::X, grazing, -grazing, Vec3::new(0.6, 0.8, 0.0)];
        for glossiness in [0.0, 1.0] {
            for anisotropy in [0.0, 1.0] {
                for metallic in [0.0, 1.0] {
                    let s = surface_from_material(&Material {
                        albedo: Vec3::ONE,
                        glossiness,
                        reflectance: 0.04,
                        metallic,
                        anisotropy,
                    });
                    let check = |v: Vec3, l: Vec3| {
                        for f in [brdf_cos(&s, t, b, n, v, l), specular_cos(&s, t, b, n, v, l)] {
                            assert!(
                                f.is_finite() && f.min_element() >= 0.0,
                                "{f} v {v} l {l} s {s:?}"
                            );
                        }
                    };
                    for &v in &special {
                        for &l in &special {
                            check(v, l);
                        }
                    }
                    for _ in 0..5_000 {
                        let v = uniform_sample_sphere(rng.next_vec2());
                        let l = uniform_sample_sphere(rng.next_vec2());
                        // Push some samples to the horizon: z in [-1e-4, 1e-4].
                        let squash = Vec3::new(1.0, 1.0, 1e-4);
                        check(v, l);
                        check(v, v);
                        check(v, -v);
                        check((v * squash).normalize(), (l * squash).normalize());
                    }
                }
            }
        }
    }

    #[test]
    fn env_brdf_approx_stays_physical_everywhere() {
        // Also outside the fitted n.v >= 0.05: 0 <= A, B and A + B <= 1.
        let mut worst_sum = 0.0_f32;
        for i in 0..=200 {
            for j in 0..=200 {
                let (r, n_o_v) = (i as f32 / 200.0, j as f32 / 200.0);
                let (a, b) = env_brdf_approx_ab(r, n_o_v);
                assert!(a >= 0.0 && b >= 0.0, "r {r} nov {n_o_v}: {a} {b}");
                worst_sum = worst_sum.max(a + b);
                let e = env_brdf_approx(Vec3::new(0.04, 0.5, 1.0), r, n_o_v);
                assert!(e.is_finite() && e.x <= e.y && e.y <= e.z);
            }
        }
        println!("env_brdf_approx: max A + B {worst_sum}");
        // Measured 1.0000001 on 2026-11-22; threshold 1 + 1e-5.
        assert!(worst_sum <= 1.0 + 1e-5, "max A + B {worst_sum}");
    }
}
