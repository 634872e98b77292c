// A glTF material as the textured G-buffer (passes/gbuffer/textured.wgsl)
// and the forward passes (passes/forward/forward.wgsl) bind it: the factors
// and the fifteen texture/sampler pairs of group 1 (gpu_scene/textures.rs
// `MaterialTextures::bind_groups`), and what both derive from them.
#import scene
#import color
#import brdf

// The factors (group 1 binding 0); twin of gpu_scene/textures.rs `MaterialGpu`.
struct MaterialGpu {
    base_color: vec4f,
    emissive: vec4f,
    // x normal scale, y occlusion strength, z anisotropy strength, w anisotropy rotation (rad)
    params: vec4f,
    // x mode (0 opaque, 1 mask, 2 blend), y cut-off, z 1 when unlit, w 1
    // when the normal texture's alpha holds normal variance (E3)
    alpha: vec4f,
    // KHR_materials_clearcoat: x factor, y roughness, z normal scale, w 1
    // when the coat normal texture's alpha holds normal variance (E3)
    clearcoat: vec4f,
    // KHR_materials_sheen: rgb colour (linear), a roughness
    sheen: vec4f,
    // KHR_materials_specular: rgb colour factor (linear), a specular factor
    specular: vec4f,
    // KHR_materials_transmission / _volume: x transmission, y thickness,
    // z 1 / attenuation distance (0: none), w ior
    transmission: vec4f,
    // KHR_materials_volume: rgb attenuation colour (linear)
    attenuation: vec4f,
    // KHR_texture_transform per slot (SLOT_*): rows 2k, 2k+1 of the 2x3
    // matrix in xyz; row 2k's w is the slot's UV set (0 or 1)
    uv: array<vec4f, 30>,
}

const SLOT_BASE_COLOR: u32 = 0u;
const SLOT_METAL_ROUGH: u32 = 1u;
const SLOT_NORMAL: u32 = 2u;
const SLOT_OCCLUSION: u32 = 3u;
const SLOT_EMISSIVE: u32 = 4u;
const SLOT_ANISOTROPY: u32 = 5u;
const SLOT_CLEARCOAT: u32 = 6u;
const SLOT_CLEARCOAT_ROUGHNESS: u32 = 7u;
const SLOT_CLEARCOAT_NORMAL: u32 = 8u;
const SLOT_SHEEN_COLOR: u32 = 9u;
const SLOT_SHEEN_ROUGHNESS: u32 = 10u;
const SLOT_SPECULAR: u32 = 11u;
const SLOT_SPECULAR_COLOR: u32 = 12u;
const SLOT_TRANSMISSION: u32 = 13u;
const SLOT_THICKNESS: u32 = 14u;

@group(1) @binding(0) var<uniform> material: MaterialGpu;
@group(1) @binding(1) var base_color_texture: texture_2d<f32>;
@group(1) @binding(2) var base_color_sampler: sampler;
@group(1) @binding(3) var metal_rough_texture: texture_2d<f32>;
@group(1) @binding(4) var metal_rough_sampler: sampler;
@group(1) @binding(5) var normal_texture: texture_2d<f32>;
@group(1) @binding(6) var normal_sampler: sampler;
@group(1) @binding(7) var occlusion_texture: texture_2d<f32>;
@group(1) @binding(8) var occlusion_sampler: sampler;
@group(1) @binding(9) var emissive_texture: texture_2d<f32>;
@group(1) @binding(10) var emissive_sampler: sampler;
@group(1) @binding(11) var anisotropy_texture: texture_2d<f32>;
@group(1) @binding(12) var anisotropy_sampler: sampler;
// Layers (forward.layers): clearcoat R, clearcoat roughness G, coat normal,
// sheen colour RGB (sRGB), sheen roughness A.
@group(1) @binding(13) var clearcoat_texture: texture_2d<f32>;
@group(1) @binding(14) var clearcoat_sampler: sampler;
@group(1) @binding(15) var clearcoat_roughness_texture: texture_2d<f32>;
@group(1) @binding(16) var clearcoat_roughness_sampler: sampler;
@group(1) @binding(17) var clearcoat_normal_texture: texture_2d<f32>;
@group(1) @binding(18) var clearcoat_normal_sampler: sampler;
@group(1) @binding(19) var sheen_color_texture: texture_2d<f32>;
@group(1) @binding(20) var sheen_color_sampler: sampler;
@group(1) @binding(21) var sheen_roughness_texture: texture_2d<f32>;
@group(1) @binding(22) var sheen_roughness_sampler: sampler;
// KHR_materials_specular: specular A, specular colour RGB (sRGB).
@group(1) @binding(23) var specular_texture: texture_2d<f32>;
@group(1) @binding(24) var specular_sampler: sampler;
@group(1) @binding(25) var specular_color_texture: texture_2d<f32>;
@group(1) @binding(26) var specular_color_sampler: sampler;
// KHR_materials_transmission R, KHR_materials_volume thickness G.
@group(1) @binding(27) var transmission_texture: texture_2d<f32>;
@group(1) @binding(28) var transmission_sampler: sampler;
@group(1) @binding(29) var thickness_texture: texture_2d<f32>;
@group(1) @binding(30) var thickness_sampler: sampler;

// KHR_materials_specular: the dielectric's (F0 rgb, F90) from the material's
// F0 by its ior (`f0_ior`, Vertex::surface.y) and the two textures' samples:
// (min(f0_ior colour, 1) specular, specular). CPU twin:
// scene::gltf::PbrMaterial::dielectric_fresnel.
fn gltf_dielectric_fresnel(f0_ior: f32, specular_a: f32, color_rgb: vec3f) -> vec4f {
    let s = material.specular.a * specular_a;
    return vec4f(min(vec3f(f0_ior) * material.specular.rgb * color_rgb, vec3f(1.0)) * s, s);
}

// The grey F0 the G-buffer holds for a dielectric F0 (Rec. 709 luminance,
// as bright as the coloured one under white light).
fn gltf_grey_reflectance(dielectric_f0: vec3f) -> f32 {
    return luminance(dielectric_f0);
}

// Whether a fragment of coverage `alpha` (base colour factor x texture
// alpha) is cut away: MASK below its cut-off; as a shadow caster
// (`caster`) BLEND below 0.5 as well (docs/gltf.md "Alpha in shadows").
// CPU twin: scene::gltf::AlphaMode::cuts.
fn gltf_cut_out(alpha: f32, caster: bool) -> bool {
    let mode = material.alpha.x;
    let mask = mode > 0.5 && mode < 1.5 && alpha < material.alpha.y;
    return mask || (caster && mode > 1.5 && alpha < 0.5);
}

// The UV a slot samples at: its set of `uvs` (TEXCOORD_0 in xy, _1 in zw)
// with its KHR_texture_transform applied (CPU twin:
// scene::gltf::UvTransform::apply).
fn material_uv(slot: u32, uvs: vec4f) -> vec2f {
    let r0 = material.uv[2u * slot];
    let r1 = material.uv[2u * slot + 1u];
    let uv = select(uvs.xy, uvs.zw, r0.w > 0.5);
    return vec2f(dot(r0.xy, uv) + r0.z, dot(r1.xy, uv) + r1.z);
}

// KHR_materials_anisotropy strength s at GGX alpha -> himal anisotropy with
// the same alpha_t / alpha_b ratio (CPU twin: scene::gltf::anisotropy_from_khr).
fn anisotropy_from_khr(strength: f32, alpha: f32) -> f32 {
    let a = max(alpha, 0.002);
    let s = saturate(strength);
    let alpha_t = a + (1.0 - a) * s * s;
    return saturate((1.0 - a / alpha_t) / 0.9);
}

// The world tangent (ObjectVertex.tangent) with the vertex's sign w; a
// mirroring model matrix flips handedness, so its sign folds into w.
fn gltf_world_tangent(o: Object, world_tangent: vec3f, w: f32) -> vec4f {
    let det = determinant(mat3x3f(o.model[0].xyz, o.model[1].xyz, o.model[2].xyz));
    return vec4f(world_tangent, w * sign(det));
}

// The interpolated normal and tangent as the visible side sees them:
// double-sided back faces flip the normal (glTF) and the tangent frame
// mirrors with it.
struct GltfFacing {
    n: vec3f,
    tangent: vec4f,
}

fn gltf_facing(normal: vec3f, tangent: vec4f, front: bool) -> GltfFacing {
    var f = GltfFacing(normalize(normal), tangent);
    if (!front) {
        f.n = -f.n;
        f.tangent.w = -f.tangent.w;
    }
    return f;
}

// A normal texture's tangent-space sample (in [-1, 1]) with its `scale`
// on x and y, renormalised (z kept positive).
fn gltf_scaled_normal(ts: vec3f, scale: f32) -> vec3f {
    return normalize(vec3f(ts.xy * scale, max(ts.z, 1e-4)));
}

// E3 specular anti-aliasing (`--specular-aa`): permutations of the G-buffer
// (GBufferKey::specular_aa) and forward (ForwardKey::specular_aa) passes;
// off reads no variance, so the widening folds away.
override SPECULAR_AA: bool = true;

// Perceptual roughness `r` widened by the normal variance a baked normal
// texture's trilinear sample carries in alpha (`baked`: MaterialGpu's flag
// for the slot; `scale`: the slot's normal scale, which scales the slopes
// and so, for small slopes, the variance by scale^2). Toksvig: r' = (r^4 +
// 2 sigma^2)^(1/4) (brdf.wgsl toksvig_roughness, docs/techniques/E3.md).
fn gltf_specular_aa_roughness(r: f32, normal_alpha: f32, baked: f32, scale: f32) -> f32 {
    if (!SPECULAR_AA || baked < 0.5) {
        return r;
    }
    return toksvig_roughness(r, normal_variance_decode(normal_alpha) * scale * scale);
}
