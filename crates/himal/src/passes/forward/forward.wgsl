// forward: glTF surfaces drawn after lighting and sky into the HDR target
// (issue #8, docs/gltf.md).
// - fs_blend (`forward.blend`): alpha BLEND materials, back to front per
//   object, premultiplied alpha over the HDR (One, OneMinusSrcAlpha), depth
//   test against the G-buffer depth without writing it. Lit like the
//   deferred world (issue #22): the sun through its own shadow maps at the
//   fragment (SHADOWS; the shadow mask holds the surface behind), the local
//   lights with their atlas shadows, the sky SH, the filtered environment
//   cube, then the frame's aerial perspective (FOG, shaders/fog.wgsl)
//   (shaders/forward.wgsl, CPU twin passes/forward/reference.rs).
// - fs_emissive (`forward.emissive`): emissive factor x texture of opaque and
//   mask materials added (One, One) where the G-buffer kept this surface
//   (depth Equal; the clip position is @invariant here and in textured.wgsl).
// - fs_unlit (`forward.unlit`): KHR_materials_unlit surfaces replace the
//   deferred result where the G-buffer kept them (`unlit_radiance`); BLEND
//   unlit ones take it in fs_blend.
// Material sampling follows passes/gbuffer/textured.wgsl.
#import gbuffer_io
#import view
#import tangent_frame
#import scene
#import gltf_material
#import brdf
#import sh
#import envmap
#import forward
#import forward_vertex
#import ambient_lights
#import shadow
#import sky
#import fog

// ForwardKey permutations of fs_blend: the sun's and local lights' shadow
// maps are read (shadows on and drawn this frame); aerial perspective.
override SHADOWS: bool = false;
override FOG: bool = false;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(6) var<storage, read> instances: array<u32>;
// Storage, not uniform: lavapipe 22.3 recompiles, per draw and without
// freeing it, a shader whose branches read a uniform block (the BLEND soak
// growth of #22; docs/reliability.md).
@group(0) @binding(2) var<storage, read> lighting: Lighting;
@group(0) @binding(3) var env_specular: texture_cube<f32>;
@group(0) @binding(4) var env_sampler: sampler;
@group(0) @binding(5) var dfg_lut: texture_2d<f32>;
@group(0) @binding(7) var<storage, read> sky: SkyParams;
// The sun's maps (shadows.mask's lookup) and the local lights with their atlas.
@group(0) @binding(8) var<storage, read> shadow_params: ShadowMaskParams;
@group(0) @binding(9) var cascades: texture_depth_2d_array;
@group(0) @binding(10) var static_map: texture_depth_2d_array;
@group(0) @binding(11) var shadow_sampler: sampler_comparison;
@group(0) @binding(12) var<storage, read> lights: LocalLights;
@group(0) @binding(13) var atlas: texture_depth_2d_array;
@group(0) @binding(14) var<storage, read> light_tiles: array<ShadowTile>;

@vertex
fn vs_main(in: GBufferVertexIn) -> ForwardVertexOut {
    return forward_vertex(objects[instance_object(instances[in.instance])], in, view);
}

// The local lights' reflected radiance at p (normal n_shadow for the
// atlas lookup's offset), each through its atlas tile where it casts.
fn blend_local(s: Surface, f90: f32, t: vec3f, b: vec3f, n: vec3f, v: vec3f, p: vec3f, n_shadow: vec3f) -> vec3f {
    var c = vec3f(0.0);
    for (var k = 0u; k < lights.count.x; k++) {
        let l = lights.lights[k];
        let li = local_light_illuminance(l, p);
        if (!li.lit) {
            continue;
        }
        var vis = 1.0;
        if (SHADOWS && u32(l.params.y) > 0u) {
            let tile = shadow_local_tile(l, p);
            if (tile >= 0) {
                vis = shadow_local_visibility(l, light_tiles[tile], p, n_shadow, atlas, shadow_sampler,
                    shadow_params.filter_params.x);
            }
        }
        c += brdf_cos_f90(s, f90, t, b, n, v, li.dir) * (li.e * vis);
    }
    return c;
}

@fragment
fn fs_blend(in: ForwardVertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4f {
    let f = forward_surface(in, front);
    if (material.alpha.z > 0.5) {
        // Unlit: as forward.unlit gives opaque ones (no shadow, no fog).
        let u = unlit_radiance(f.albedo, lighting.sun_direction.xyz,
            lighting.sun_illuminance.rgb, lighting.sky_irradiance);
        let a = saturate(f.alpha);
        return vec4f(u * a, a);
    }
    let v = to_eye(view, in.world);
    // The interpolated normal facing the eye offsets the shadow lookups
    // (the G-buffer's normal in shadows.mask).
    let n_geo = select(-1.0, 1.0, front) * normalize(in.normal);
    var sun_vis = 1.0;
    if (SHADOWS) {
        let dist = dot(in.world - view.camera_position.xyz, shadow_params.camera_forward.xyz);
        sun_vis = shadow_world_visibility(shadow_params, cascades, static_map, shadow_sampler, in.world, n_geo, dist);
    }
    let s = analytic_surface(f.s, lighting.sun_illuminance.w);
    let local = blend_local(s, f.f90, f.tbn[0], f.tbn[1], f.tbn[2], v, in.world, n_geo);
    let env = forward_env(f, v, env_specular, env_sampler, dfg_lut);
    var c = forward_shade_premultiplied(s, f.f90, f.tbn[0], f.tbn[1], f.tbn[2], v,
        lighting.sun_direction.xyz, lighting.sun_illuminance.rgb * sun_vis, lighting.sky_irradiance,
        env.prefiltered, env.dfg, f.ao * ambient_scale(in.world), f.emissive, local, f.alpha);
    if (FOG) {
        let ap = aerial_perspective(length(view.camera_position.xyz - in.world), v, lighting.fog,
            lighting.sky_irradiance, preetham_sky_radiance(sky, -v));
        c = fog_premultiplied(c, ap);
    }
    return c;
}

@fragment
fn fs_emissive(in: ForwardVertexOut) -> @location(0) vec4f {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    let e = textureSample(emissive_texture, emissive_sampler, material_uv(SLOT_EMISSIVE, in.uv)).rgb;
    // MASK: the G-buffer discarded these texels; a surface behind at the
    // same depth must not glow.
    if (material.alpha.x > 0.5 && material.base_color.a * base.a < material.alpha.y) {
        discard;
    }
    return vec4f(material.emissive.rgb * e, 0.0);
}

// forward.unlit: KHR_materials_unlit opaque and mask surfaces replace what
// the deferred pass shaded there (blend: colour One, Zero; depth Equal).
@fragment
fn fs_unlit(in: ForwardVertexOut) -> @location(0) vec4f {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    if (material.alpha.x > 0.5 && material.base_color.a * base.a < material.alpha.y) {
        discard;
    }
    let c = unlit_radiance(in.color.rgb * base.rgb, lighting.sun_direction.xyz,
        lighting.sun_illuminance.rgb, lighting.sky_irradiance);
    return vec4f(c, 1.0);
}
