// forward: glTF surfaces drawn after lighting and sky into the HDR target
// (issue #8, docs/gltf.md).
// - fs_blend (`forward.blend`): alpha BLEND materials, back to front per
//   object, premultiplied alpha over the HDR (One, OneMinusSrcAlpha), depth
//   test against the G-buffer depth without writing it. Lit by the sun
//   (unshadowed), the sky SH and the filtered environment cube
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

@vertex
fn vs_main(in: GBufferVertexIn) -> ForwardVertexOut {
    return forward_vertex(objects[instance_object(instances[in.instance])], in, view);
}

@fragment
fn fs_blend(in: ForwardVertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4f {
    let f = forward_surface(in, front);
    if (material.alpha.z > 0.5) {
        let c = unlit_radiance(f.albedo, lighting.sun_direction.xyz,
            lighting.sun_illuminance.rgb, lighting.sky_irradiance);
        let a = saturate(f.alpha);
        return vec4f(c * a, a);
    }
    let v = to_eye(view, in.world);
    let env = forward_env(f, v, env_specular, env_sampler, dfg_lut);
    return forward_shade_premultiplied(analytic_surface(f.s, lighting.sun_illuminance.w), f.f90, f.tbn[0], f.tbn[1], f.tbn[2], v,
        lighting.sun_direction.xyz, lighting.sun_illuminance.rgb, lighting.sky_irradiance,
        env.prefiltered, env.dfg, f.ao * ambient_scale(in.world), f.emissive, f.alpha);
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
