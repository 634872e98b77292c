// lighting.deferred: full-screen deferred shading of the G-buffer (TECHNIQUES M1, M2, L1 foundation).
// Sun: anisotropic GGX + height-correlated Smith + Schlick, Lambert diffuse (brdf.wgsl).
// Sky: third-order SH irradiance; ambient specular from the GGX-filtered sky or
// probe cube along the M4 reflection vector times the GPU DFG table
// (passes/envmap, L3/L4); with ENV_SPECULAR off, the split-sum fit with SH
// along the reflection vector.
// Sun shadow: R of the shadow mask written by shadows.mask (S1-S4).
// Local lights (S3): point and spot lights from `lights`, the same BRDF,
// windowed inverse-square falloff, shadow from their mask channel (G, B, A).
// Aerial perspective: exponential extinction toward the sky colour along the view ray.
// Bindings: view, lighting (uniform Lighting), sky (uniform SkyParams), G-buffer, depth,
// shadow_mask, ao, lights (screen-space AO in .x, passes/ao; 1x1 white when off).
// Sky occlusion (L2, SKY_OCCLUSION): SH2 visibility of the pixel's sector
// (passes/skyocc, shaders/sky_occlusion.wgsl), faded with height above the
// terrain; sky SH irradiance along the bent normal times the cosine-convolved
// SH2 visibility along it; the same visibility scales ambient specular.
// O4 (SSDO): the directional term (ao_dir, shaders/ao.wgsl `ssdo_visibility`)
// along each light's direction scales its diffuse and specular (contact
// shadows, blended by ao_params.ssdo.x); REFLECTION_OCCLUSION scales ambient
// specular by Lagarde's specular occlusion from AO (the constant band) times,
// with SSDO, the directional term along the reflection vector, instead of by AO.
// CPU twin: passes/lighting/reference.rs (`shade`, `shade_sky_occluded`);
// O4 functions: passes/ao/reference.rs `ssdo_visibility`, `specular_occlusion_lagarde`.
// AO colour bleeding (O5, AO_BLEED): the ambient diffuse occlusion raised
// per channel by the low-frequency albedo (ao_bleed, passes/ao/bleed;
// shaders/ao_bleed.wgsl); ambient specular keeps the scalar occlusion.
// Ambient lights (shaders/ambient_lights.wgsl, binding `ambient_lights`):
// both ambient terms times the scene's volumes' multiplier at p.
// Indirect light (L5, INDIRECT): the probes' clip map (shaders/indirect.wgsl,
// passes/indirect) replaces the flat ground bounce of the sky SH.
// V5 leaf shading (lighting.sun_direction.w = 1): foliage pixels (the
// material's blue channel, shaders/gbuffer_material.wgsl) take a leaf's
// glossiness and F0 and add the sun's and local lights' light through the
// leaf (shaders/leaf.wgsl); CPU twin reference.rs `shade_leaf`.
// CPU twin: passes/lighting/reference.rs (`shade`, `shade_sky_occluded`).
#import view
#import ao
#import brdf
#import tangent_frame
#import sh
#import sky
#import fog
#import shadow
#import envmap
#import sky_occlusion
#import ao_bleed
#import ambient_lights
#import indirect
#import color
#import math
#import fullscreen
#import gbuffer_material
#import leaf

struct Lighting {
    // xyz: unit vector towards the sun; w: 1 = V5 leaf shading
    sun_direction: vec4f,
    // rgb: sun illuminance at the ground (klux); w: 1 = R4, Burley's
    // remapped roughness in the visibility term of the sun and local lights
    sun_illuminance: vec4f,
    // sky irradiance E(n) as SH9 (klux)
    sky_irradiance: Sh9,
    // x: extinction per metre, y: amount of aerial perspective (0 = off),
    // z: 1 = inscatter from the sky SH (Bruneton sky), 0 = Preetham;
    // w: 1 = sky light along the bent normal (L2), 0 = along n
    fog: vec4f,
}

// E1 permutations (passes/lighting/mod.rs LightingKey): constant branches.
override SHADOWS: bool = true;
override FOG: bool = true;
override SSAO: bool = true;
override ENV_SPECULAR: bool = true;
override SKY_OCCLUSION: bool = false;
override SSDO: bool = false;
override REFLECTION_OCCLUSION: bool = false;
override AO_BLEED: bool = false;
override INDIRECT: bool = false;
override INDIRECT_VIEW: bool = false;

@group(0) @binding(0) var<uniform> view: View;
// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(1) var<storage, read> lighting: Lighting;
@group(0) @binding(2) var<uniform> sky: SkyParams;
@group(0) @binding(3) var gbuffer_albedo: texture_2d<f32>;
@group(0) @binding(4) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(5) var gbuffer_material: texture_2d<f32>;
@group(0) @binding(6) var depth: texture_depth_2d;
@group(0) @binding(7) var shadow_mask: texture_2d<f32>;
@group(0) @binding(8) var ao: texture_2d<f32>;
@group(0) @binding(9) var<storage, read> lights: LocalLights;
@group(0) @binding(10) var env_specular: texture_cube<f32>;
@group(0) @binding(11) var env_sampler: sampler;
@group(0) @binding(12) var dfg_lut: texture_2d<f32>;
@group(0) @binding(13) var skyocc_table: texture_2d<i32>;
@group(0) @binding(14) var skyocc_vis: texture_2d_array<f32>;
@group(0) @binding(15) var skyocc_heights_load: texture_2d_array<f32>;
@group(0) @binding(16) var skyocc_sampler: sampler;
@group(0) @binding(17) var ao_dir: texture_2d<f32>;
@group(0) @binding(18) var<uniform> ao_params: AoParams;
// O5: quarter-resolution bleed texture (1x1 black when off).
@group(0) @binding(19) var ao_bleed: texture_2d<f32>;
// L5 (INDIRECT): the probes' clip map, one texture per colour channel
// (zeros and a black array when off).
@group(0) @binding(21) var<storage, read> indirect_params: IndirectParams;
@group(0) @binding(22) var indirect_r: texture_2d_array<f32>;
@group(0) @binding(23) var indirect_g: texture_2d_array<f32>;
@group(0) @binding(24) var indirect_b: texture_2d_array<f32>;
@group(0) @binding(25) var indirect_sampler: sampler;

// O4 inputs in view space (unused without SSDO).
struct Ssdo {
    p: vec3f,
    n: vec3f,
    // the directional harmonic (c1, c2)
    c: vec2f,
}

// The directional term along world direction l, blended toward 1 by the strength.
fn ssdo_light(o: Ssdo, l: vec3f) -> f32 {
    let l_v = (view.view * vec4f(l, 0.0)).xyz;
    return mix(1.0, ssdo_visibility(o.p, o.n, l_v, o.c, ao_params.ssdo.w, ao_params.ssdo.y), ao_params.ssdo.x);
}

// Reflected radiance of the local lights at p (mask: the shadow mask texel),
// and with leaf amount `foliage` > 0 the light through the leaf (V5).
fn shade_local(s: Surface, foliage: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f, p: vec3f, mask: vec4f, o: Ssdo) -> vec3f {
    var c = vec3f(0.0);
    for (var k = 0u; k < lights.count.x; k = k + 1u) {
        let l = lights.lights[k];
        let li = local_light_illuminance(l, p);
        if (!li.lit) {
            continue;
        }
        let dir = li.dir;
        var e = li.e;
        let channel = u32(l.params.y);
        if (channel > 0u) {
            e *= mask[channel];
        }
        if (SSDO) {
            e *= ssdo_light(o, dir);
        }
        var f = brdf_cos(s, t, b, n, v, dir);
        if (foliage > 0.0) {
            f += leaf_translucency(s.diffuse_albedo, foliage, n, v, dir);
        }
        c += f * e;
    }
    return c;
}

// Outgoing radiance toward v (before aerial perspective).
// `sun_visibility` in [0,1] scales the sun only; sky light is not shadowed here.
// `sky_vis`: SH2 sky visibility (open sky when SKY_OCCLUSION is off).
// `spec_ao`: the occlusion of ambient specular (ao_in without reflection occlusion).
// `bleed`: O5 bleed colour (black: plain occlusion). `ambient`: the ambient
// lights' multiplier of both ambient terms. `indirect`: L5's irradiance
// (rgb) and coverage (a; 0 keeps the sky SH's flat ground). `foliage`: the
// leaf amount (0 without leaf shading): the sun through the leaf (V5).
fn shade(s: Surface, foliage: f32, glossiness: f32, anisotropy: f32, ao_in: f32, spec_ao: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f, sun_visibility: f32, sky_vis: vec4f, bleed: vec3f, ambient: vec3f, indirect: vec4f) -> vec3f {
    let l = lighting.sun_direction.xyz;
    var sun = brdf_cos(s, t, b, n, v, l);
    if (foliage > 0.0) {
        sun += leaf_translucency(s.diffuse_albedo, foliage, n, v, l);
    }
    var c = sun * lighting.sun_illuminance.rgb * sun_visibility;
    let n_o_v = max(dot(n, v), 1e-4);
    var n_sky = n;
    var sky_visibility = 1.0;
    if (SKY_OCCLUSION) {
        if (lighting.fog.w > 0.5) {
            n_sky = bent_normal_from_sh_visibility(n, sky_vis);
        }
        sky_visibility = sh2_visibility_cosine(sky_vis, n_sky);
    }
    let ao = ao_in * sky_visibility;
    let e_n = max(sh9_eval(lighting.sky_irradiance, n_sky), vec3f(0.0));
    let roughness = perceptual_roughness_from_glossiness(glossiness);
    if (ENV_SPECULAR) {
        // Radiance (kcd/m^2 = klux/sr): no 1/pi, unlike the irradiance terms.
        let r = reflect(-v, m4_reflection_normal(n, b, v, anisotropy));
        let lod = roughness * f32(textureNumLevels(env_specular) - 1u);
        let prefiltered = textureSampleLevel(env_specular, env_sampler, r, lod).rgb;
        let ab = textureSampleLevel(dfg_lut, env_sampler, vec2f(n_o_v, roughness), 0.0).xy;
        // L3: the cube was lit by the open sky; scale it by the luminance (not
        // the colour) of this pixel's sky ambient over the open sky's along n.
        var ratio = 1.0;
        if (SKY_OCCLUSION) {
            let e_open = max(sh9_eval(lighting.sky_irradiance, n), vec3f(0.0));
            ratio = saturate(luminance(e_n) * sky_visibility / max(luminance(e_open), 1e-9));
        }
        c += prefiltered * (s.f0 * ab.x + ab.y) * (ambient * (spec_ao * ratio));
    } else {
        let e_r = max(sh9_eval(lighting.sky_irradiance, reflect(-v, n)), vec3f(0.0));
        let ao_spec = spec_ao * sky_visibility;
        c += env_brdf_approx(s.f0, roughness, n_o_v) * e_r * (ambient * (ao_spec / PI));
    }
    var ao_diffuse = vec3f(ao_in);
    if (AO_BLEED) {
        ao_diffuse = ao_bleed_occlusion(ao_in, bleed);
    }
    // Sky light through the sky's visibility; L5's bounce instead of the
    // flat ground where the probes cover p (it comes from the occluders, so
    // sky occlusion does not darken it again).
    var e_ambient = e_n * sky_visibility;
    if (INDIRECT) {
        let e_ground = max(sh9_eval(indirect_params.ground, n_sky), vec3f(0.0));
        e_ambient = max(e_n - e_ground * indirect.a, vec3f(0.0)) * sky_visibility + indirect.rgb;
    }
    c += s.diffuse_albedo * e_ambient * (ambient * ao_diffuse / PI);
    return c;
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let d = textureLoad(depth, px, 0);
    if (d <= 0.0) {
        discard;
    }
    let p = world_at_fragment(view, frag.xy, d);
    let albedo_ao = textureLoad(gbuffer_albedo, px, 0);
    let tbn = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, px, 0)));
    let m = textureLoad(gbuffer_material, px, 0);
    // V5: a leaf's glossiness and F0, by the pixel's leaf amount.
    var foliage = 0.0;
    var gloss_f0 = m.xy;
    if (lighting.sun_direction.w > 0.5) {
        foliage = gbuffer_foliage(m.z);
        gloss_f0 = leaf_material(m.x, m.y, foliage);
    }
    let glossiness = gloss_f0.x;
    // R4: the sun and local lights see the remapped visibility (when on).
    let s = analytic_surface(surface_from_material(albedo_ao.rgb, glossiness, gloss_f0.y, gbuffer_metallic(m.z), m.w), lighting.sun_illuminance.w);
    let dist = length(view.camera_position.xyz - p);
    let v = to_eye(view, p);
    var mask = vec4f(1.0);
    if (SHADOWS) {
        mask = textureLoad(shadow_mask, min(px, vec2i(textureDimensions(shadow_mask)) - 1), 0);
    }
    // Screen-space AO darkens the ambient terms only, like the material's baked AO (O1).
    var ssao = 1.0;
    if (SSAO) {
        ssao = textureLoad(ao, min(px, vec2i(textureDimensions(ao)) - 1), 0).x;
    }
    var sky_vis = vec4f(0.0);
    if (SKY_OCCLUSION) {
        sky_vis = sky_occlusion_lookup(skyocc_table, skyocc_vis, skyocc_heights_load, skyocc_sampler, p, tbn[2]);
    }
    let ao_in = albedo_ao.a * ssao;
    var spec_ao = ao_in;
    var sun_visibility = mask.r;
    var o = Ssdo(vec3f(0.0), vec3f(0.0), vec2f(0.0));
    if (SSDO) {
        let coeffs = textureLoad(ao_dir, min(px, vec2i(textureDimensions(ao_dir)) - 1), 0).xy;
        o = Ssdo((view.view * vec4f(p, 1.0)).xyz, (view.view * vec4f(tbn[2], 0.0)).xyz, coeffs);
        sun_visibility *= ssdo_light(o, lighting.sun_direction.xyz);
    }
    if (REFLECTION_OCCLUSION) {
        // Both bands (Ryse): the constant through Lagarde's formula, times the
        // directional term along the reflection vector.
        let roughness = perceptual_roughness_from_glossiness(glossiness);
        spec_ao = albedo_ao.a * specular_occlusion_lagarde(max(dot(tbn[2], v), 1e-4), ssao, roughness);
        if (SSDO) {
            let r = reflect(-v, m4_reflection_normal(tbn[2], tbn[1], v, m.w));
            let r_v = (view.view * vec4f(r, 0.0)).xyz;
            let soft = ao_params.ssdo.y + ao_params.ssdo.z * roughness;
            spec_ao *= ssdo_visibility(o.p, o.n, r_v, o.c, ao_params.ssdo.w, soft);
        }
    }
    var bleed = vec3f(0.0);
    if (AO_BLEED) {
        let uv = frag.xy / (4.0 * vec2f(textureDimensions(ao_bleed)));
        bleed = ao_bleed_colour(textureSampleLevel(ao_bleed, env_sampler, uv, 0.0));
    }
    var indirect = vec4f(0.0);
    if (INDIRECT) {
        indirect = indirect_irradiance(indirect_params, indirect_r, indirect_g, indirect_b, indirect_sampler, p, tbn[2]);
        if (INDIRECT_VIEW) {
            if (indirect_params.counts.y == 0u) {
                return vec4f(indirect.rgb, 1.0);
            }
            return vec4f(indirect_debug_view(indirect_params, p, indirect.rgb), 1.0);
        }
    }
    var c = shade(s, foliage, glossiness, m.w, ao_in, spec_ao, tbn[0], tbn[1], tbn[2], v, sun_visibility, sky_vis, bleed, ambient_scale(p), indirect);
    c += shade_local(s, foliage, tbn[0], tbn[1], tbn[2], v, p, mask, o);
    if (FOG) {
        let ap = aerial_perspective(dist, v, lighting.fog, lighting.sky_irradiance, preetham_sky_radiance(sky, -v));
        c = c * ap.a + ap.rgb * (1.0 - ap.a);
    }
    return vec4f(c, 1.0);
}
