// The vertex stage of the forward passes over glTF surfaces (passes/forward:
// forward.wgsl, layers.wgsl, transmission.wgsl) and the material as the
// blended and transmissive ones shade it. Kept apart from
// shaders/forward.wgsl, whose shading functions compute kernels import
// without any material bindings.
#import view
#import scene
#import gbuffer_io
#import object_vertex
#import gltf_material
#import brdf
#import tangent_frame
#import envmap

struct ForwardVertexOut {
    // invariant: depth test Equal against the G-buffer must see its value
    @builtin(position) @invariant clip: vec4f,
    @location(0) normal: vec3f,
    @location(1) tangent: vec4f,
    @location(2) color: vec4f,
    @location(3) surface: vec4f,
    @location(4) world: vec3f,
    // TEXCOORD_0 in xy, TEXCOORD_1 in zw (material_uv picks per slot)
    @location(6) uv: vec4f,
    // The object's linear scale, |det M|^(1/3): KHR_materials_volume's
    // thickness is in the mesh's units.
    @location(7) @interpolate(flat) scale: f32,
}

// The vertex stage of every forward pass: the same object_vertex call as
// passes/gbuffer/textured.wgsl, so the same clip position (@invariant).
fn forward_vertex(o: Object, in: GBufferVertexIn, view: View) -> ForwardVertexOut {
    let v = object_vertex(o, in, view.view_proj, view.prev_view_proj, false, view.time.xy);
    var out: ForwardVertexOut;
    out.uv = vec4f(in.uv, in.uv1);
    out.clip = v.clip;
    out.world = v.world.xyz;
    out.normal = v.normal;
    out.tangent = gltf_world_tangent(o, v.tangent, in.tangent.w);
    out.color = in.color;
    out.surface = in.surface;
    let det = determinant(mat3x3f(o.model[0].xyz, o.model[1].xyz, o.model[2].xyz));
    out.scale = pow(abs(det), 1.0 / 3.0);
    return out;
}

// A glTF surface sampled at a fragment, in the BRDF's terms (as
// passes/gbuffer/textured.wgsl derives it for the G-buffer).
struct ForwardSurface {
    s: Surface,
    // Schlick's F90 (below 1 for a KHR_materials_specular dielectric)
    f90: f32,
    // right-handed shading frame (t, b, n), anisotropy direction applied
    tbn: mat3x3f,
    // perceptual roughness, metallic, M1 anisotropy
    roughness: f32,
    metallic: f32,
    anisotropy: f32,
    // base colour x COLOR_0, its coverage, material occlusion, emission
    albedo: vec3f,
    alpha: f32,
    ao: f32,
    emissive: vec3f,
}

// Samples the material (call in uniform control flow: it takes implicit
// derivatives) and builds the surface of this fragment.
fn forward_surface(in: ForwardVertexOut, front: bool) -> ForwardSurface {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    let normal_sample = textureSample(normal_texture, normal_sampler, material_uv(SLOT_NORMAL, in.uv));
    let ts = normal_sample.xyz * 2.0 - 1.0;
    let at = textureSample(anisotropy_texture, anisotropy_sampler, material_uv(SLOT_ANISOTROPY, in.uv)).xyz;
    let mr = textureSample(metal_rough_texture, metal_rough_sampler, material_uv(SLOT_METAL_ROUGH, in.uv));
    let occlusion = textureSample(occlusion_texture, occlusion_sampler, material_uv(SLOT_OCCLUSION, in.uv)).r;
    let emissive = textureSample(emissive_texture, emissive_sampler, material_uv(SLOT_EMISSIVE, in.uv)).rgb;
    let spec_a = textureSample(specular_texture, specular_sampler, material_uv(SLOT_SPECULAR, in.uv)).a;
    let spec_rgb = textureSample(specular_color_texture, specular_color_sampler, material_uv(SLOT_SPECULAR_COLOR, in.uv)).rgb;
    var out: ForwardSurface;
    out.albedo = in.color.rgb * base.rgb;
    out.alpha = material.base_color.a * base.a;
    out.emissive = material.emissive.rgb * emissive;
    let facing = gltf_facing(in.normal, in.tangent, front);
    let tangent = facing.tangent;
    let n_mapped = apply_normal_map(facing.n, tangent, gltf_scaled_normal(ts, material.params.x));
    let c = cos(material.params.w);
    let s = sin(material.params.w);
    let d0 = at.xy * 2.0 - 1.0;
    let d = vec2f(c * d0.x - s * d0.y, s * d0.x + c * d0.y);
    let f = shading_frame(n_mapped, tangent);
    let w = select(1.0, -1.0, tangent.w < 0.0);
    out.tbn = shading_frame(n_mapped, vec4f(f[0] * d.x + f[1] * (w * d.y), 1.0));
    // E3: the normal map's variance under this footprint widens the lobe.
    out.roughness = gltf_specular_aa_roughness(saturate((1.0 - in.surface.x) * mr.g), normal_sample.a, material.alpha.w, material.params.x);
    out.metallic = saturate(in.surface.z * mr.b);
    out.ao = 1.0 + material.params.y * (occlusion - 1.0);
    out.anisotropy = anisotropy_from_khr(material.params.z * at.z, out.roughness * out.roughness);
    out.s = surface_from_material(out.albedo, 1.0 - out.roughness, 0.0, out.metallic, out.anisotropy);
    // KHR_materials_specular: the dielectric's coloured F0 and its F90.
    let fresnel = gltf_dielectric_fresnel(in.surface.y, spec_a, spec_rgb);
    out.s.f0 = mix(fresnel.rgb, out.albedo, out.metallic);
    out.f90 = mix(fresnel.w, 1.0, out.metallic);
    return out;
}

// The filtered cube along the (M4) reflection vector and the DFG table's
// (A, B) for surface `f` seen along `v`.
struct ForwardEnv {
    prefiltered: vec3f,
    dfg: vec2f,
}

fn forward_env(f: ForwardSurface, v: vec3f, cube: texture_cube<f32>, s: sampler,
        dfg_lut: texture_2d<f32>) -> ForwardEnv {
    let n_o_v = max(dot(f.tbn[2], v), 1e-4);
    let r = reflect(-v, m4_reflection_normal(f.tbn[2], f.tbn[1], v, f.anisotropy));
    let lod = f.roughness * f32(textureNumLevels(cube) - 1u);
    return ForwardEnv(textureSampleLevel(cube, s, r, lod).rgb,
        textureSampleLevel(dfg_lut, s, vec2f(n_o_v, f.roughness), 0.0).xy);
}
