// forward.layers: KHR_materials_sheen and KHR_materials_clearcoat over the
// deferred base of opaque and mask glTF surfaces, and the KHR_materials_specular
// correction of that base (docs/gltf.md "Clearcoat and sheen", "Specular"). Drawn where the G-buffer kept this surface (depth Equal, the
// clip position @invariant as in textured.wgsl), blended One,
// OneMinusSrcAlpha: out = layers + base * s_sheen * s_coat
// (shaders/layers.wgsl, CPU twin passes/forward/reference.rs `layers_shade`).
// The sun is shadowed by this pixel's mask, the environment occluded by
// the material's occlusion times SSAO: the surface is the G-buffer's.
#import gbuffer_io
#import view
#import tangent_frame
#import scene
#import gltf_material
#import brdf
#import forward
#import forward_vertex
#import layers
#import ambient_lights

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Storage: see forward.wgsl.
@group(0) @binding(2) var<storage, read> lighting: Lighting;
@group(0) @binding(3) var env_specular: texture_cube<f32>;
@group(0) @binding(4) var env_sampler: sampler;
@group(0) @binding(5) var dfg_lut: texture_2d<f32>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(6) var<storage, read> instances: array<u32>;
// The sun's visibility in .r (1x1 white without shadows).
@group(0) @binding(7) var shadow_mask: texture_2d<f32>;
// Screen-space AO in .x (1x1 white without SSAO).
@group(0) @binding(8) var ao: texture_2d<f32>;
// E(n.v, roughness) of the sheen lobe (passes/forward/reference.rs `sheen_albedo_table`).
@group(0) @binding(9) var sheen_albedo_load: texture_2d<f32>;

@vertex
fn vs_main(in: GBufferVertexIn) -> ForwardVertexOut {
    return forward_vertex(objects[instance_object(instances[in.instance])], in, view);
}

fn load_clamped(t: texture_2d<f32>, px: vec2i) -> vec4f {
    return textureLoad(t, min(px, vec2i(textureDimensions(t)) - 1), 0);
}

@fragment
fn fs_layers(in: ForwardVertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4f {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    let normal_sample = textureSample(normal_texture, normal_sampler, material_uv(SLOT_NORMAL, in.uv));
    let ts = normal_sample.xyz * 2.0 - 1.0;
    let occlusion = textureSample(occlusion_texture, occlusion_sampler, material_uv(SLOT_OCCLUSION, in.uv)).r;
    let cc = textureSample(clearcoat_texture, clearcoat_sampler, material_uv(SLOT_CLEARCOAT, in.uv)).r;
    let ccr = textureSample(clearcoat_roughness_texture, clearcoat_roughness_sampler, material_uv(SLOT_CLEARCOAT_ROUGHNESS, in.uv)).g;
    let coat_sample = textureSample(clearcoat_normal_texture, clearcoat_normal_sampler, material_uv(SLOT_CLEARCOAT_NORMAL, in.uv));
    let ccn = coat_sample.xyz * 2.0 - 1.0;
    let sc = textureSample(sheen_color_texture, sheen_color_sampler, material_uv(SLOT_SHEEN_COLOR, in.uv)).rgb;
    let sr = textureSample(sheen_roughness_texture, sheen_roughness_sampler, material_uv(SLOT_SHEEN_ROUGHNESS, in.uv)).a;
    let mr = textureSample(metal_rough_texture, metal_rough_sampler, material_uv(SLOT_METAL_ROUGH, in.uv));
    let spec_a = textureSample(specular_texture, specular_sampler, material_uv(SLOT_SPECULAR, in.uv)).a;
    let spec_rgb = textureSample(specular_color_texture, specular_color_sampler, material_uv(SLOT_SPECULAR_COLOR, in.uv)).rgb;
    // MASK: the G-buffer discarded these texels (as fs_emissive).
    if (material.alpha.x > 0.5 && material.base_color.a * base.a < material.alpha.y) {
        discard;
    }
    let f = gltf_facing(in.normal, in.tangent, front);
    // The base's normal map for the sheen; the coat's own (flat by default:
    // the geometric normal) for the coat.
    let n_base = apply_normal_map(f.n, f.tangent, gltf_scaled_normal(ts, material.params.x));
    let n_coat = apply_normal_map(f.n, f.tangent, gltf_scaled_normal(ccn, material.clearcoat.z));
    // E3: each normal map's variance widens its lobe (as textured.wgsl).
    let roughness = gltf_specular_aa_roughness(saturate((1.0 - in.surface.x) * mr.g), normal_sample.a, material.alpha.w, material.params.x);
    let metallic = saturate(in.surface.z * mr.b);
    // The G-buffer's unorm8 grey F0 and the deferred pass's F90 = 1 against
    // the dielectric's true Fresnel (textured.wgsl writes the same grey).
    let fresnel = gltf_dielectric_fresnel(in.surface.y, spec_a, spec_rgb);
    let grey = round(saturate(gltf_grey_reflectance(fresnel.rgb)) * 255.0) / 255.0;
    let m = Layers(material.sheen.rgb * sc, saturate(material.sheen.a * sr),
        saturate(material.clearcoat.x * cc),
        gltf_specular_aa_roughness(saturate(material.clearcoat.y * ccr), coat_sample.a, material.clearcoat.w, material.clearcoat.z),
        (1.0 - metallic) * (fresnel.rgb - grey), (1.0 - metallic) * (fresnel.w - 1.0), roughness);

    let px = vec2i(in.clip.xy);
    let v = to_eye(view, in.world);
    let levels = f32(textureNumLevels(env_specular) - 1u);
    let r_sheen = reflect(-v, n_base);
    let r_coat = reflect(-v, n_coat);
    var light: LayerLight;
    light.sun_direction = lighting.sun_direction.xyz;
    light.sun = lighting.sun_illuminance.rgb * load_clamped(shadow_mask, px).r;
    light.sheen_env = textureSampleLevel(env_specular, env_sampler, r_sheen, m.sheen_roughness * levels).rgb;
    light.coat_env = textureSampleLevel(env_specular, env_sampler, r_coat, m.clearcoat_roughness * levels).rgb;
    let n_o_v_coat = max(dot(n_coat, v), 1e-4);
    light.coat_dfg = textureSampleLevel(dfg_lut, env_sampler, vec2f(n_o_v_coat, m.clearcoat_roughness), 0.0).xy;
    light.sheen_albedo = sheen_albedo_lookup(sheen_albedo_load, dot(n_base, v), m.sheen_roughness);
    light.base_env = textureSampleLevel(env_specular, env_sampler, r_sheen, roughness * levels).rgb;
    light.base_dfg = textureSampleLevel(dfg_lut, env_sampler, vec2f(max(dot(n_base, v), 1e-4), roughness), 0.0).xy;
    light.ao = (1.0 + material.params.y * (occlusion - 1.0)) * load_clamped(ao, px).x;
    // Ambient lights scale every environment term, as in lighting.deferred.
    let ambient = ambient_scale(in.world);
    light.sheen_env *= ambient;
    light.coat_env *= ambient;
    light.base_env *= ambient;
    return layers_shade(m, n_base, n_coat, v, light);
}
