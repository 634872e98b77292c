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

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(6) var<storage, read> instances: array<u32>;
@group(0) @binding(2) var<uniform> lighting: Lighting;
@group(0) @binding(3) var env_specular: texture_cube<f32>;
@group(0) @binding(4) var env_sampler: sampler;
@group(0) @binding(5) var dfg_lut: texture_2d<f32>;

@vertex
fn vs_main(in: GBufferVertexIn) -> ForwardVertexOut {
    return forward_vertex(objects[instance_object(instances[in.instance])], in, view);
}

@fragment
fn fs_blend(in: ForwardVertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4f {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    let alpha = material.base_color.a * base.a;
    let ts = textureSample(normal_texture, normal_sampler, material_uv(SLOT_NORMAL, in.uv)).xyz * 2.0 - 1.0;
    let at = textureSample(anisotropy_texture, anisotropy_sampler, material_uv(SLOT_ANISOTROPY, in.uv)).xyz;
    let mr = textureSample(metal_rough_texture, metal_rough_sampler, material_uv(SLOT_METAL_ROUGH, in.uv));
    let occlusion = textureSample(occlusion_texture, occlusion_sampler, material_uv(SLOT_OCCLUSION, in.uv)).r;
    let emissive = material.emissive.rgb * textureSample(emissive_texture, emissive_sampler, material_uv(SLOT_EMISSIVE, in.uv)).rgb;
    let spec_a = textureSample(specular_texture, specular_sampler, material_uv(SLOT_SPECULAR, in.uv)).a;
    let spec_rgb = textureSample(specular_color_texture, specular_color_sampler, material_uv(SLOT_SPECULAR_COLOR, in.uv)).rgb;
    if (material.alpha.z > 0.5) {
        let c = unlit_radiance(in.color.rgb * base.rgb, lighting.sun_direction.xyz,
            lighting.sun_illuminance.rgb, lighting.sky_irradiance);
        let a = saturate(alpha);
        return vec4f(c * a, a);
    }
    let facing = gltf_facing(in.normal, in.tangent, front);
    let tangent = facing.tangent;
    let n_mapped = apply_normal_map(facing.n, tangent, gltf_scaled_normal(ts, material.params.x));
    let c = cos(material.params.w);
    let s = sin(material.params.w);
    let d0 = at.xy * 2.0 - 1.0;
    let d = vec2f(c * d0.x - s * d0.y, s * d0.x + c * d0.y);
    let f = shading_frame(n_mapped, tangent);
    let w = select(1.0, -1.0, tangent.w < 0.0);
    let tbn = shading_frame(n_mapped, vec4f(f[0] * d.x + f[1] * (w * d.y), 1.0));

    let roughness = saturate((1.0 - in.surface.x) * mr.g);
    let metallic = saturate(in.surface.z * mr.b);
    let ao = 1.0 + material.params.y * (occlusion - 1.0);
    let anisotropy = anisotropy_from_khr(material.params.z * at.z, roughness * roughness);
    let albedo = in.color.rgb * base.rgb;
    var surf = surface_from_material(albedo, 1.0 - roughness, 0.0, metallic, anisotropy);
    // KHR_materials_specular: the dielectric's coloured F0 and its F90.
    let fresnel = gltf_dielectric_fresnel(in.surface.y, spec_a, spec_rgb);
    surf.f0 = mix(fresnel.rgb, albedo, metallic);
    let f90 = mix(fresnel.w, 1.0, metallic);
    let v = to_eye(view, in.world);
    let n_o_v = max(dot(tbn[2], v), 1e-4);
    let r = reflect(-v, m4_reflection_normal(tbn[2], tbn[1], v, anisotropy));
    let lod = roughness * f32(textureNumLevels(env_specular) - 1u);
    let prefiltered = textureSampleLevel(env_specular, env_sampler, r, lod).rgb;
    let ab = textureSampleLevel(dfg_lut, env_sampler, vec2f(n_o_v, roughness), 0.0).xy;
    return forward_shade_premultiplied(surf, f90, tbn[0], tbn[1], tbn[2], v,
        lighting.sun_direction.xyz, lighting.sun_illuminance.rgb, lighting.sky_irradiance,
        prefiltered, ab, ao, emissive, alpha);
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
