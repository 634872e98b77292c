// Layers over the deferred base (KHR_materials_sheen, KHR_materials_clearcoat;
// passes/forward `forward.layers`, docs/gltf.md "Clearcoat and sheen").
// The deferred pass shaded the base; this returns (radiance the layers add,
// 1 - the fraction of the base they let through), blended One,
// OneMinusSrcAlpha: out = layers + base * s_sheen * s_coat. CPU twin:
// passes/forward/reference.rs `layers_shade`.
#import brdf
#import math

// Sheen roughness floor: the Charlie lobe's exponent 1/alpha stays finite.
const SHEEN_MIN_ROUGHNESS: f32 = 0.07;

// Charlie sheen distribution (Estevez & Kulla 2017):
// D = (2 + 1/alpha) sin(theta_h)^(1/alpha) / (2 pi).
fn d_charlie(alpha: f32, n_o_h: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = max(1.0 - n_o_h * n_o_h, 0.0);
    return (2.0 + inv) * pow(sin2, 0.5 * inv) / (2.0 * PI);
}

// Estevez & Kulla 2017's fit of the Charlie lobe's Lambda: the exponent
// L(x) = a / (1 + b x^c) + d x + e, coefficients blended between the
// paper's rows for alpha = 0 and 1 by (1 - alpha)^2.
fn charlie_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = mix(21.5473, 25.3245, t);
    let b = mix(3.82987, 3.32435, t);
    let c = mix(0.19823, 0.16801, t);
    let d = mix(-1.97760, -1.27393, t);
    let e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

fn charlie_lambda(cos_theta: f32, alpha: f32) -> f32 {
    if (cos_theta < 0.5) {
        return exp(charlie_l(cos_theta, alpha));
    }
    return exp(2.0 * charlie_l(0.5, alpha) - charlie_l(1.0 - cos_theta, alpha));
}

// 1 / ((1 + Lambda(v) + Lambda(l)) 4 n.v n.l), at most 1 (as the Khronos
// sample viewer clamps it).
fn v_charlie(n_o_v: f32, n_o_l: f32, alpha: f32) -> f32 {
    let g = 1.0 + charlie_lambda(n_o_v, alpha) + charlie_lambda(n_o_l, alpha);
    return clamp(1.0 / (g * 4.0 * n_o_v * n_o_l), 0.0, 1.0);
}

fn sheen_alpha(perceptual_roughness: f32) -> f32 {
    let r = max(perceptual_roughness, SHEEN_MIN_ROUGHNESS);
    return r * r;
}

// The sheen lobe times n.l toward `l` (colour 1).
fn sheen_cos(perceptual_roughness: f32, n: vec3f, v: vec3f, l: vec3f) -> f32 {
    let n_o_l = dot(n, l);
    if !(n_o_l > 0.0) {
        return 0.0;
    }
    let h = normalize(v + l);
    let n_o_v = max(dot(n, v), BRDF_MIN_N_O_V);
    let alpha = sheen_alpha(perceptual_roughness);
    return d_charlie(alpha, dot(n, h)) * v_charlie(n_o_v, n_o_l, alpha) * n_o_l;
}

struct Layers {
    // linear, times the sheen colour texture
    sheen_color: vec3f,
    sheen_roughness: f32,
    clearcoat: f32,
    clearcoat_roughness: f32,
    // KHR_materials_specular's correction of the deferred base: (1 - metallic)
    // (true F0 - the G-buffer's grey F0), (1 - metallic) (true F90 - 1)
    base_f0_delta: vec3f,
    base_f90_delta: f32,
    base_roughness: f32,
}

// What the layers see: the sun (illuminance times its shadow), the filtered
// environment along each layer's (and the base's) reflection vector, the
// coat's and the base's DFG (A, B), the sheen's directional albedo E(n.v)
// and the ambient occlusion.
struct LayerLight {
    sun_direction: vec3f,
    sun: vec3f,
    sheen_env: vec3f,
    coat_env: vec3f,
    coat_dfg: vec2f,
    sheen_albedo: f32,
    base_env: vec3f,
    base_dfg: vec2f,
    ao: f32,
}

// An isotropic lobe's D V F n.l: any tangent frame around n will do.
fn specular_cos_iso(s: Surface, f90: f32, n: vec3f, v: vec3f, l: vec3f) -> vec3f {
    let up = select(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 1.0, 0.0), abs(n.x) > 0.9);
    let b = normalize(cross(n, up));
    return specular_cos_f90(s, f90, cross(b, n), b, n, v, l);
}

// n: the base's shading normal (sheen), n_c: the coat's.
fn layers_shade(m: Layers, n: vec3f, n_c: vec3f, v: vec3f, light: LayerLight) -> vec4f {
    // The coat: a dielectric GGX lobe (F0 0.04, ior 1.5) on its own normal.
    let alpha_c = alpha_from_glossiness(1.0 - m.clearcoat_roughness);
    let coat_surface = Surface(vec3f(0.0), vec3f(0.04), vec2f(alpha_c), vec2f(alpha_c));
    let n_o_v_c = max(dot(n_c, v), BRDF_MIN_N_O_V);
    let coat = m.clearcoat * (specular_cos_iso(coat_surface, 1.0, n_c, v, light.sun_direction) * light.sun
        + light.coat_env * (0.04 * light.coat_dfg.x + light.coat_dfg.y) * light.ao);
    let s_coat = 1.0 - m.clearcoat * f_schlick(vec3f(0.04), 1.0, n_o_v_c).x;
    // The sheen: Charlie lobe under the sun, E(n.v) of the environment.
    let sheen = m.sheen_color * (sheen_cos(m.sheen_roughness, n, v, light.sun_direction) * light.sun
        + light.sheen_env * (light.sheen_albedo * light.ao));
    let s_sheen = 1.0 - max(m.sheen_color.r, max(m.sheen_color.g, m.sheen_color.b)) * light.sheen_albedo;
    // KHR_materials_specular: the base's specular minus what the deferred
    // pass gave it (Schlick is linear in F0 and F90).
    let alpha_delta = vec2f(alpha_from_glossiness(1.0 - m.base_roughness));
    let delta_surface = Surface(vec3f(0.0), m.base_f0_delta, alpha_delta, alpha_delta);
    let base_delta = specular_cos_iso(delta_surface, m.base_f90_delta, n, v, light.sun_direction) * light.sun
        + light.base_env * (m.base_f0_delta * light.base_dfg.x + m.base_f90_delta * light.base_dfg.y) * light.ao;
    return vec4f(sheen * s_coat + coat + base_delta * (s_sheen * s_coat), 1.0 - s_sheen * s_coat);
}

// The sheen's directional albedo E(n.v, roughness) from its table (rows:
// roughness, columns: n.v, both at i / (size - 1)), bilinear like the CPU
// twin's `sheen_albedo_lookup`.
fn sheen_albedo_lookup(table: texture_2d<f32>, n_o_v: f32, perceptual_roughness: f32) -> f32 {
    let size = vec2i(textureDimensions(table));
    let x = saturate(n_o_v) * f32(size.x - 1);
    let y = saturate(perceptual_roughness) * f32(size.y - 1);
    let x0 = min(i32(x), size.x - 2);
    let y0 = min(i32(y), size.y - 2);
    let fx = x - f32(x0);
    let fy = y - f32(y0);
    let top = mix(textureLoad(table, vec2i(x0, y0), 0).r, textureLoad(table, vec2i(x0 + 1, y0), 0).r, fx);
    let bottom = mix(textureLoad(table, vec2i(x0, y0 + 1), 0).r, textureLoad(table, vec2i(x0 + 1, y0 + 1), 0).r, fx);
    return mix(top, bottom, fy);
}
