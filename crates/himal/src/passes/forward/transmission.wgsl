// forward.transmission: KHR_materials_transmission and _volume surfaces
// over the opaque scene (docs/gltf.md "Transmission and volume"). They are
// not in the G-buffer; drawn after the opaque forward passes with depth
// test and write (reverse-Z Greater), blended premultiplied
// (One, OneMinusSrcAlpha: alpha 1 unless the material is BLEND).
// out = base with (1 - transmission) of its diffuse + transmitted light:
// the opaque scene (forward.scene_color's mip chain) sampled where the ray
// refracted by the ior leaves a volume `thickness` deep, at a mip by the
// BTDF's roughness, through the volume's Beer-Lambert transmittance
// (shaders/forward.wgsl, CPU twin passes/forward/reference.rs).
// SHADOWS: the sun through its own maps at the fragment (as fs_blend; the
// shadow mask holds the surface behind); no local lights, no fog (the
// scene behind is fogged already).
#import gbuffer_io
#import view
#import scene
#import gltf_material
#import brdf
#import sh
#import forward
#import forward_vertex
#import ambient_lights
#import shadow

override SHADOWS: bool = false;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Storage, not uniform: lavapipe 22.3 recompiles per draw a shader whose
// branches read a uniform block (docs/reliability.md).
@group(0) @binding(2) var<storage, read> lighting: Lighting;
@group(0) @binding(3) var env_specular: texture_cube<f32>;
@group(0) @binding(4) var env_sampler: sampler;
@group(0) @binding(5) var dfg_lut: texture_2d<f32>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(6) var<storage, read> instances: array<u32>;
// The opaque scene's HDR radiance and its box mips (forward.scene_color).
@group(0) @binding(7) var scene_color: texture_2d<f32>;
// The sun's maps (shadows.mask's lookup).
@group(0) @binding(8) var<storage, read> shadow_params: ShadowMaskParams;
@group(0) @binding(9) var cascades: texture_depth_2d_array;
@group(0) @binding(10) var static_map: texture_depth_2d_array;
@group(0) @binding(11) var shadow_sampler: sampler_comparison;

@vertex
fn vs_main(in: GBufferVertexIn) -> ForwardVertexOut {
    return forward_vertex(objects[instance_object(instances[in.instance])], in, view);
}

@fragment
fn fs_transmission(in: ForwardVertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4f {
    var f = forward_surface(in, front);
    let tr_tex = textureSample(transmission_texture, transmission_sampler, material_uv(SLOT_TRANSMISSION, in.uv)).r;
    let th_tex = textureSample(thickness_texture, thickness_sampler, material_uv(SLOT_THICKNESS, in.uv)).g;
    if (material.alpha.x > 0.5 && material.alpha.x < 1.5 && f.alpha < material.alpha.y) {
        discard;
    }
    let alpha = select(1.0, saturate(f.alpha), material.alpha.x > 1.5);
    let v = to_eye(view, in.world);
    let env = forward_env(f, v, env_specular, env_sampler, dfg_lut);
    let n = f.tbn[2];
    var sun = lighting.sun_illuminance.rgb;
    if (SHADOWS) {
        let dist = dot(in.world - view.camera_position.xyz, shadow_params.camera_forward.xyz);
        let n_geo = select(-1.0, 1.0, front) * normalize(in.normal);
        sun *= shadow_world_visibility(shadow_params, cascades, static_map, shadow_sampler, in.world, n_geo, dist);
    }
    let ior = material.transmission.w;
    // The dielectric's diffuse share that is transmitted instead.
    let transmission = saturate(material.transmission.x * tr_tex);
    let t_albedo = f.s.diffuse_albedo * transmission;
    f.s.diffuse_albedo *= 1.0 - transmission;
    let base = forward_shade_premultiplied(analytic_surface(f.s, lighting.sun_illuminance.w), f.f90, f.tbn[0], f.tbn[1], n, v,
        lighting.sun_direction.xyz, sun, lighting.sky_irradiance,
        env.prefiltered, env.dfg, f.ao * ambient_scale(in.world), f.emissive, vec3f(0.0), 1.0).rgb;

    // The refracted ray's exit from a volume `thickness` deep (world units);
    // thin-walled (0): the scene straight behind.
    let thickness = material.transmission.y * th_tex * in.scale;
    let refracted = refract(-v, n, 1.0 / ior);
    let exit = in.world + refracted * thickness;
    let clip = view.view_proj * vec4f(exit, 1.0);
    let uv = vec2f(0.5, -0.5) * clip.xy / clip.w + 0.5;
    let width = f32(textureDimensions(scene_color).x);
    let behind = textureSampleLevel(scene_color, env_sampler, uv,
        transmission_lod(f.roughness, ior, width)).rgb;
    let transmittance = volume_attenuation(thickness, material.transmission.z, material.attenuation.rgb);
    let alpha_t = transmission_roughness(sqrt(f.s.alpha.x * f.s.alpha.y), ior);
    let through = transmitted_radiance(f.s.f0, f.f90, env.dfg, t_albedo, transmittance,
        behind, alpha_t, f.tbn[0], f.tbn[1], n, v,
        lighting.sun_direction.xyz, sun);
    return vec4f((base + through) * alpha, alpha);
}
