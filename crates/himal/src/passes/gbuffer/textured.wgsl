// gbuffer.textured: glTF metallic-roughness materials into the same G-buffer
// as gbuffer.wgsl (docs/gltf.md). Vertices carry the factors (colour = base
// colour factor * COLOR_0, surface = glossiness, F0 0.04, metallic,
// anisotropy strength); group 1 holds the material's textures and uniform.
// Alpha: MASK discards below the cut-off; BLEND materials are not drawn here
// but by passes/forward (forward.blend), which also adds the emission
// (forward.emissive, depth Equal: the clip position is @invariant in both).
#import gbuffer_io
#import view
#import tangent_frame
#import scene
#import gltf_material
#import object_vertex
#import deform
// V3: declared for the layout gbuffer.wgsl shares (bindings 8-10).
#import impostor_atlas
#import ripple
// Metallic in the material's blue channel, 7 bits (V5 keeps the upper half for foliage).
#import gbuffer_material

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> objects: array<Object>;
// Instance -> object: the identity for draws recorded on the CPU, a culled list (V6).
@group(0) @binding(2) var<storage, read> instances: array<u32>;
// gbuffer.wgsl's V2 ripple grid: declared so the two pipelines share the
// `gbuffer` node's group 0 (glTF meshes do not bend with it).
@group(0) @binding(12) var<storage, read> ripple: Ripple;

struct VertexOut {
    @builtin(position) @invariant clip: vec4f,
    @location(0) normal: vec3f,
    @location(1) tangent: vec4f,
    @location(2) color: vec4f,
    @location(3) surface: vec4f,
    @location(4) curr_clip: vec4f,
    @location(5) prev_clip: vec4f,
    // TEXCOORD_0 in xy, TEXCOORD_1 in zw (material_uv picks per slot)
    @location(6) uv: vec4f,
}

@vertex
fn vs_main(in: GBufferVertexIn, @builtin(vertex_index) vertex: u32) -> VertexOut {
    let o = objects[instance_object(instances[in.instance])];
    let v = object_vertex(o, in, view.view_proj, view.prev_view_proj, false, view.time.xy);
    var out: VertexOut;
    out.uv = vec4f(in.uv, in.uv1);
    out.curr_clip = v.clip;
    // Skinned and morphed vertices: the previous frame's shape, not only its transform.
    let prev = deform_prev_position(vertex, in.position);
    out.prev_clip = view.prev_view_proj * (o.prev_model * vec4f(prev, 1.0));
    out.clip = v.clip;
    out.normal = v.normal;
    out.tangent = gltf_world_tangent(o, v.tangent, in.tangent.w);
    out.color = in.color;
    out.surface = in.surface;
    return out;
}

// A2: -0.5 under temporal anti-aliasing (two jittered samples per pixel
// over frames A and B sharpen what a full-rate mip would blur); an E1
// permutation (GBufferKey::mip_bias).
override MIP_BIAS: f32 = 0.0;
// `--view lod`: the level these draws are at (< 0: not that view).
override LOD_VIEW: f32 = -1.0;

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> GBufferOut {
    let base = textureSampleBias(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv), MIP_BIAS);
    let alpha = material.base_color.a * base.a;
    // Every sample precedes the discards (uniform control flow for derivatives).
    let normal_sample = textureSampleBias(normal_texture, normal_sampler, material_uv(SLOT_NORMAL, in.uv), MIP_BIAS);
    let ts = normal_sample.xyz * 2.0 - 1.0;
    let at = textureSampleBias(anisotropy_texture, anisotropy_sampler, material_uv(SLOT_ANISOTROPY, in.uv), MIP_BIAS).xyz;
    let mr = textureSampleBias(metal_rough_texture, metal_rough_sampler, material_uv(SLOT_METAL_ROUGH, in.uv), MIP_BIAS);
    let occlusion = textureSampleBias(occlusion_texture, occlusion_sampler, material_uv(SLOT_OCCLUSION, in.uv), MIP_BIAS).r;
    let emissive = textureSampleBias(emissive_texture, emissive_sampler, material_uv(SLOT_EMISSIVE, in.uv), MIP_BIAS).rgb;
    let spec_a = textureSampleBias(specular_texture, specular_sampler, material_uv(SLOT_SPECULAR, in.uv), MIP_BIAS).a;
    let spec_rgb = textureSampleBias(specular_color_texture, specular_color_sampler, material_uv(SLOT_SPECULAR_COLOR, in.uv), MIP_BIAS).rgb;
    if (gltf_cut_out(alpha, false)) {
        discard;
    }
    let facing = gltf_facing(in.normal, in.tangent, front);
    let tangent = facing.tangent;
    let n_mapped = apply_normal_map(facing.n, tangent, gltf_scaled_normal(ts, material.params.x));
    // Anisotropy direction in the tangent plane: texture rg (default +t),
    // rotated by anisotropyRotation, bitangent = cross(n, t) * w (glTF).
    let c = cos(material.params.w);
    let s = sin(material.params.w);
    let d0 = at.xy * 2.0 - 1.0;
    let d = vec2f(c * d0.x - s * d0.y, s * d0.x + c * d0.y);
    let f = shading_frame(n_mapped, tangent);
    let w = select(1.0, -1.0, tangent.w < 0.0);
    let aniso_dir = f[0] * d.x + f[1] * (w * d.y);
    let tbn = shading_frame(n_mapped, vec4f(aniso_dir, 1.0));

    // E3: the normal map's variance under this footprint widens the lobe.
    let roughness = gltf_specular_aa_roughness(saturate((1.0 - in.surface.x) * mr.g), normal_sample.a, material.alpha.w, material.params.x);
    let metallic = saturate(in.surface.z * mr.b);
    let ao = 1.0 + material.params.y * (occlusion - 1.0);
    let strength = material.params.z * at.z;
    var out: GBufferOut;
    out.albedo = vec4f(in.color.rgb * base.rgb, ao);
    out.frame = pack_quat(frame_to_quat(tbn[0], tbn[1], tbn[2]));
    // KHR_materials_specular: the grey part of the dielectric's F0 (forward.layers
    // adds the colour and F90 where they differ: PbrMaterial::specular_differs).
    let reflectance = gltf_grey_reflectance(gltf_dielectric_fresnel(in.surface.y, spec_a, spec_rgb).rgb);
    out.material = vec4f(1.0 - roughness, reflectance, gbuffer_metallic_foliage(metallic, 0.0), anisotropy_from_khr(strength, roughness * roughness));
    out.motion = gbuffer_motion(in.curr_clip, in.prev_clip);
    // Emissive is sampled so its binding stays in the reflected layout (the
    // material bind group is shared with passes/forward, which draws it).
    out.albedo.a = out.albedo.a + 0.0 * emissive.r * material.emissive.r;
    if (LOD_VIEW >= 0.0) {
        out.albedo = vec4f(lod_view_albedo(u32(LOD_VIEW), out.albedo.rgb), out.albedo.a);
    }
    return out;
}
