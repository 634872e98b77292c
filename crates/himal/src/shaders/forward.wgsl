// Forward shading of one fragment (passes/forward, issue #8): the deferred
// pass's sun, SH sky and environment-specular terms for one surface point,
// plus emission, premultiplied by alpha. `f90`: Schlick's F90 (below 1 for
// a KHR_materials_specular dielectric). The caller samples the filtered
// cube (`prefiltered`) and the DFG table (`dfg` = (A, B)). The sun is
// unshadowed: the shadow mask holds the opaque surface behind. CPU twin:
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
        prefiltered: vec3f, dfg: vec2f, ao: f32, emissive: vec3f, alpha: f32) -> vec4f {
    var c = brdf_cos_f90(s, f90, t, b, n, v, sun_direction) * sun_illuminance;
    // Radiance (kcd/m^2): no 1/pi, unlike the irradiance term below.
    c += prefiltered * (s.f0 * dfg.x + f90 * dfg.y) * ao;
    let e_n = max(sh9_eval(sky_irradiance, n), vec3f(0.0));
    c += s.diffuse_albedo * e_n * (ao / PI);
    c += emissive;
    let a = saturate(alpha);
    return vec4f(c * a, a);
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
