// The glTF casters with alpha (MASK, and BLEND as a mask at 0.5) in every
// sun map and the local lights' atlas: the base colour's alpha is tested as
// the G-buffer tests it (`gltf_cut_out`), so a leaf card casts its holes.
// Group 0 as depth.wgsl (shaders/shadow_caster.wgsl), group 1 the material
// (gltf_material.wgsl). docs/gltf.md "Alpha in shadows".

#import scene
#import object_vertex
#import shadow_caster
#import gltf_material

struct MaskedOut {
    @builtin(position) clip: vec4f,
    // TEXCOORD_0 in xy, TEXCOORD_1 in zw (material_uv picks)
    @location(0) uv: vec4f,
}

@vertex
fn vs_masked(
    @location(0) position: vec3f,
    @location(3) uv: vec2f,
    @location(6) uv1: vec2f,
    @builtin(instance_index) instance: u32,
) -> MaskedOut {
    let o = objects[instance_object(instances[instance])];
    var out: MaskedOut;
    out.clip = shadow.light_view_proj * object_rest(o, position);
    out.uv = vec4f(uv, uv1);
    return out;
}

@fragment
fn fs_masked(in: MaskedOut) {
    let base = textureSample(base_color_texture, base_color_sampler, material_uv(SLOT_BASE_COLOR, in.uv));
    if (gltf_cut_out(material.base_color.a * base.a, true)) {
        discard;
    }
}
