// Forward shading of one fragment (passes/forward, issue #8): the deferred
// pass's sun, SH sky and environment-specular terms for one surface point,
// plus emission, premultiplied by alpha. `f90`: Schlick's F90 (below 1 for
// a KHR_materials_specular dielectric). The caller samples the filtered
// cube (`prefiltered`) and the DFG table (`dfg` = (A, B)) and applies the
// sun's shadow to `sun_illuminance` (forward.blend: the sun's maps at the
// fragment; the shadow mask holds the opaque surface behind). `ao`: the
// occlusion times the ambient lights' RGB multiplier (both ambient terms).
// `local`: the local lights' reflected radiance, added like emission.
// CPU twin:
// passes/forward/reference.rs `forward_shade_premultiplied`.
#import brdf
#import sh
#import math
#import color

// The lighting uniform as the forward passes read it (passes/lighting's
// `lighting` frame constant).
struct Lighting {
    sun_direction: vec4f,
    sun_illuminance: vec4f,
    sky_irradiance: Sh9,
    fog: vec4f,
}

fn forward_shade_premultiplied(s: Surface, f90: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f,
        sun_direction: vec3f, sun_illuminance: vec3f, sky_irradiance: Sh9,
        prefiltered: vec3f, dfg: vec2f, ao: vec3f, emissive: vec3f, local: vec3f, alpha: f32) -> vec4f {
    var c = brdf_cos_f90(s, f90, t, b, n, v, sun_direction) * sun_illuminance;
    // Radiance (kcd/m^2): no 1/pi, unlike the irradiance term below.
    c += prefiltered * (s.f0 * dfg.x + f90 * dfg.y) * ao;
    let e_n = max(sh9_eval(sky_irradiance, n), vec3f(0.0));
    c += s.diffuse_albedo * e_n * (ao / PI);
    c += emissive + local;
    let a = saturate(alpha);
    return vec4f(c * a, a);
}

// A premultiplied fragment `c` through the frame's aerial perspective
// `ap` = (L_in, T) (shaders/fog.wgsl): the layer's share of "over",
// (c.rgb T + L_in (1 - T) c.a, c.a). CPU twin: `fog_premultiplied`.
fn fog_premultiplied(c: vec4f, ap: vec4f) -> vec4f {
    return vec4f(c.rgb * ap.a + ap.rgb * ((1.0 - ap.a) * c.a), c.a);
}

// KHR_materials_unlit: the base colour shown as it is. himal's radiance has
// units (kcd/m^2), so "as it is" means as bright as a white Lambertian
// surface facing the sun would be, (E_sun + E_sky(l)) / pi, its luminance
// only (the colour stays the material's). CPU twin:
// passes/forward/reference.rs `unlit_radiance`.
fn unlit_radiance(base: vec3f, sun_direction: vec3f, sun_illuminance: vec3f, sky_irradiance: Sh9) -> vec3f {
    let e = sun_illuminance + max(sh9_eval(sky_irradiance, sun_direction), vec3f(0.0));
    return base * (luminance(e) / PI);
}

// KHR_materials_transmission (docs/gltf.md "Transmission and volume"): the
// microfacet BTDF's roughness, alpha scaled by clamp(2 ior - 2, 0, 1) (thin
// glass of ior 1 does not blur; Khronos sample viewer's
// applyIorToRoughness). Works on perceptual roughness and on alpha alike.
fn transmission_roughness(roughness: f32, ior: f32) -> f32 {
    return roughness * clamp(2.0 * ior - 2.0, 0.0, 1.0);
}

// The mip of the opaque scene's chain (`levels` mips, the finest as wide as
// the screen) sampled behind a surface: log2(width) x the BTDF's
// perceptual roughness, as the sample viewer does.
fn transmission_lod(roughness: f32, ior: f32, width: f32) -> f32 {
    return log2(width) * transmission_roughness(roughness, ior);
}

// KHR_materials_volume: Beer-Lambert transmittance over `distance` with
// sigma = -ln(colour) / attenuation distance (`inv_distance` = 1 / it; 0:
// no absorption): colour^(distance / attenuation distance).
fn volume_attenuation(distance: f32, inv_distance: f32, colour: vec3f) -> vec3f {
    if (inv_distance <= 0.0) {
        return vec3f(1.0);
    }
    return exp(log(max(colour, vec3f(1e-6))) * (distance * inv_distance));
}

// The sun seen through the surface: the GGX BTDF lobe toward the sun
// mirrored through the surface's plane (the thin-surface model of the
// sample viewer), (1 - F) D V n.l', with the cosine its viewer omits.
fn transmission_sun_cos(f0: vec3f, f90: f32, alpha_t: f32, t: vec3f, b: vec3f, n: vec3f,
        v: vec3f, l: vec3f) -> vec3f {
    let l_m = l - 2.0 * dot(n, l) * n;
    let n_o_l = dot(n, l_m);
    if !(n_o_l > 0.0) {
        return vec3f(0.0);
    }
    let hv = v + l_m;
    let h_len2 = dot(hv, hv);
    let h = select(n, hv * inverseSqrt(h_len2), h_len2 > 1e-30);
    let n_o_h = dot(n, h);
    if n_o_h <= 0.0 {
        return vec3f(0.0);
    }
    let n_o_v = max(dot(n, v), BRDF_MIN_N_O_V);
    let a = max(alpha_t, BRDF_MIN_ALPHA);
    let d = d_ggx(n_o_h, a);
    let vis = v_smith_ggx_correlated_aniso(n_o_v, n_o_l, dot(t, v), dot(b, v), dot(t, l_m), dot(b, l_m), a, a);
    return (vec3f(1.0) - f_schlick(f0, f90, saturate(dot(v, h)))) * (d * vis * n_o_l);
}

// Radiance transmitted toward the eye: `t_albedo` (transmission x the
// dielectric's base colour) x the volume's transmittance x (the opaque
// scene `behind` the surface through (1 - the split-sum specular), plus the
// sun's lobe). CPU twin: passes/forward/reference.rs `transmitted_radiance`.
fn transmitted_radiance(f0: vec3f, f90: f32, dfg: vec2f, t_albedo: vec3f, transmittance: vec3f,
        behind: vec3f, alpha_t: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f,
        sun_direction: vec3f, sun_illuminance: vec3f) -> vec3f {
    let through = behind * (vec3f(1.0) - (f0 * dfg.x + f90 * dfg.y));
    let sun = transmission_sun_cos(f0, f90, alpha_t, t, b, n, v, sun_direction) * sun_illuminance;
    return t_albedo * transmittance * (through + sun);
}
