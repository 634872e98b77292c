// M1/M2: Far Cry 4 material model (McAuley, GDC 2015). GPU twin of
// src/math/brdf.rs (same names, same equations; see docs/techniques/M1.md).
// Anisotropic GGX D (Burley 2012), height-correlated anisotropic Smith V
// (Heitz 2014), Schlick F, Lambert diffuse. t, b, n: right-handed orthonormal
// shading frame (t = anisotropy x); v to the eye, l to the light.
#import math

// alpha floor: glossiness 1 would make D a delta (see MIN_ALPHA in brdf.rs).
const BRDF_MIN_ALPHA: f32 = 0.002;
// n.v floor: normal-mapped normals facing away shade as grazing.
const BRDF_MIN_N_O_V: f32 = 1e-4;

struct Surface {
    diffuse_albedo: vec3f,
    f0: vec3f,
    // (alpha_x, alpha_y) along (tangent, binormal)
    alpha: vec2f,
    // the alphas of the visibility term: alpha, or R4's remap (analytic lights)
    alpha_v: vec2f,
}

fn perceptual_roughness_from_glossiness(glossiness: f32) -> f32 {
    return 1.0 - saturate(glossiness);
}

fn alpha_from_glossiness(glossiness: f32) -> f32 {
    let r = perceptual_roughness_from_glossiness(glossiness);
    return max(r * r, BRDF_MIN_ALPHA);
}

// Burley 2012: aspect = sqrt(1 - 0.9 anisotropy); (alpha / aspect, alpha * aspect).
fn alpha_xy(glossiness: f32, anisotropy: f32) -> vec2f {
    let alpha = alpha_from_glossiness(glossiness);
    let aspect = sqrt(1.0 - 0.9 * saturate(anisotropy));
    return max(vec2f(alpha / aspect, alpha * aspect), vec2f(BRDF_MIN_ALPHA));
}

// M2: specularReflectance = lerp(reflectance, albedo, metallic);
// albedo *= 1 - metallic. F0 = reflectance literally.
fn surface_from_material(albedo: vec3f, glossiness: f32, reflectance: f32, metallic: f32, anisotropy: f32) -> Surface {
    let alpha = alpha_xy(glossiness, anisotropy);
    return Surface(albedo * (1.0 - metallic), mix(vec3f(reflectance), albedo, metallic), alpha, alpha);
}

// R4 (Burley 2012): V of analytic lights sees alpha_g = ((1 + r) / 2)^2,
// r the perceptual roughness of the alphas' geometric mean; aspect kept.
fn visibility_remap(s: Surface) -> Surface {
    let alpha = sqrt(s.alpha.x * s.alpha.y);
    let r = sqrt(alpha);
    let alpha_g = (0.5 + 0.5 * r) * (0.5 + 0.5 * r);
    return Surface(s.diffuse_albedo, s.f0, s.alpha, s.alpha * (alpha_g / alpha));
}

// The surface analytic lights see: R4's remap when `remap` > 0.5 (the
// lighting constant's sun_illuminance.w).
fn analytic_surface(s: Surface, remap: f32) -> Surface {
    if remap > 0.5 {
        return visibility_remap(s);
    }
    return s;
}

// Isotropic GGX D = a^2 / (pi ((h.n)^2 (a^2 - 1) + 1)^2): the environment
// filter's pdf (passes/envmap/filter.wgsl; twin: envmap/reference.rs `d_ggx`).
// Not d_ggx_aniso(alpha, alpha): the same value, other rounding.
fn d_ggx(n_o_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_o_h * n_o_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// D = 1 / (pi ax ay ((h.t/ax)^2 + (h.b/ay)^2 + (h.n)^2)^2)
fn d_ggx_aniso(n_o_h: f32, t_o_h: f32, b_o_h: f32, alpha_x: f32, alpha_y: f32) -> f32 {
    let tx = t_o_h / alpha_x;
    let by = b_o_h / alpha_y;
    let d = tx * tx + by * by + n_o_h * n_o_h;
    return 1.0 / (PI * alpha_x * alpha_y * d * d);
}

// V = G2 / (4 n.v n.l), G2 = 1 / (1 + Lambda(v) + Lambda(l)); needs n.v, n.l > 0.
fn v_smith_ggx_correlated_aniso(n_o_v: f32, n_o_l: f32, t_o_v: f32, b_o_v: f32, t_o_l: f32, b_o_l: f32, alpha_x: f32, alpha_y: f32) -> f32 {
    let lambda_v = length(vec3f(alpha_x * t_o_v, alpha_y * b_o_v, n_o_v));
    let lambda_l = length(vec3f(alpha_x * t_o_l, alpha_y * b_o_l, n_o_l));
    return 0.5 / (n_o_l * lambda_v + n_o_v * lambda_l);
}

fn f_schlick(f0: vec3f, f90: f32, v_o_h: f32) -> vec3f {
    let x = 1.0 - saturate(v_o_h);
    let x2 = x * x;
    return f0 + (vec3f(f90) - f0) * (x2 * x2 * x);
}

fn diffuse_lambert(diffuse_albedo: vec3f) -> vec3f {
    return diffuse_albedo * (1.0 / PI);
}

// D V F n.l with Schlick's F90 = `f90` (KHR_materials_specular; 1
// elsewhere), the same robustness rules as the CPU twin.
fn specular_cos_f90(s: Surface, f90: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    let n_o_l = dot(n, l);
    if !(n_o_l > 0.0) {
        return vec3f(0.0);
    }
    let hv = v + l;
    let h_len2 = dot(hv, hv);
    // v = -l has no half vector (v below the horizon).
    let h = select(n, hv * inverseSqrt(h_len2), h_len2 > 1e-30);
    let n_o_h = dot(n, h);
    if n_o_h <= 0.0 {
        return vec3f(0.0);
    }
    let n_o_v = max(dot(n, v), BRDF_MIN_N_O_V);
    let d = d_ggx_aniso(n_o_h, dot(t, h), dot(b, h), s.alpha.x, s.alpha.y);
    let vis = v_smith_ggx_correlated_aniso(n_o_v, n_o_l, dot(t, v), dot(b, v), dot(t, l), dot(b, l), s.alpha_v.x, s.alpha_v.y);
    return f_schlick(s.f0, f90, saturate(dot(v, h))) * (d * vis * n_o_l);
}

// D V F n.l (F90 = 1).
fn specular_cos(s: Surface, t: vec3f, b: vec3f, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    return specular_cos_f90(s, 1.0, t, b, n, v, l);
}

// (Lambert + D V F) max(n.l, 0), Schlick's F90 = `f90`.
fn brdf_cos_f90(s: Surface, f90: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    let n_o_l = dot(n, l);
    if !(n_o_l > 0.0) {
        return vec3f(0.0);
    }
    return diffuse_lambert(s.diffuse_albedo) * n_o_l + specular_cos_f90(s, f90, t, b, n, v, l);
}

// (Lambert + D V F) max(n.l, 0).
fn brdf_cos(s: Surface, t: vec3f, b: vec3f, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    return brdf_cos_f90(s, 1.0, t, b, n, v, l);
}

// Split-sum DFG fit f0 A + B (rational in roughness and n.v; coefficients
// and error in brdf.rs env_brdf_approx_ab and docs/techniques/M1.md).
fn env_brdf_approx(f0: vec3f, perceptual_roughness: f32, n_o_v: f32) -> vec3f {
    let x = saturate(perceptual_roughness);
    let y = saturate(n_o_v);
    let x2 = x * x;
    let y2 = y * y;
    let xy = x * y;
    let a_num = -0.055383194 + 6.755665 * y + 6.124511 * y2 - 2.5169654 * y2 * y
        - 0.8979223 * x - 10.897606 * xy + 3.5524464 * xy * y
        + 11.994692 * x2 - 7.513965 * x2 * y - 3.8492672 * x2 * x;
    let a_den = 1.0 + 5.220406 * y + 4.354746 * y2 - 1.21989 * x - 9.033067 * xy + 8.828744 * x2;
    let b_num = 0.9446362 - 2.067182 * y + 1.0619216 * y2 - 0.4990199 * x + 0.7222509 * xy - 0.053478025 * x2;
    let b_den = 1.0 + 1.500716 * y + 12.616845 * y2 - 0.8193233 * x - 11.694335 * xy + 13.671154 * x2;
    var ab = max(vec2f(a_num / a_den, b_num / b_den), vec2f(0.0));
    // The fit overshoots A + B = 1 by up to 0.02 near roughness 0.
    ab = ab / max(ab.x + ab.y, 1.0);
    return f0 * ab.x + vec3f(ab.y);
}

// E3 (Toksvig 2004): normal variance sigma^2 from a baked normal map's alpha
// A = sqrt(sigma^2 / (1 + sigma^2)) (gpu_scene/normal_mipmap.wgsl), and back.
fn normal_variance_encode(variance: f32) -> f32 {
    let v = max(variance, 0.0);
    return sqrt(v / (1.0 + v));
}

fn normal_variance_decode(a: f32) -> f32 {
    let a2 = saturate(a) * saturate(a);
    return a2 / max(1.0 - a2, 1e-4);
}

// E3: perceptual roughness r widened by normal variance: alpha'^2 = alpha^2
// + 2 sigma^2 (Toksvig with Blinn-Phong s ~= 2 / alpha^2, alpha = r^2), at most 1.
fn toksvig_roughness(r: f32, variance: f32) -> f32 {
    let r2 = r * r;
    return min(sqrt(sqrt(r2 * r2 + 2.0 * max(variance, 0.0))), 1.0);
}
