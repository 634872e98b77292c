// envmap.mips (TECHNIQUES L4): the box-filtered mip chain of the source cube,
// one dispatch per level, faces in z: each texel averages its 2x2 parents.
@group(0) @binding(0) var parent: texture_2d_array<f32>;
@group(0) @binding(1) var child: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_downsample(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(child);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2i(id.xy * 2u);
    let f = i32(id.z);
    let sum = textureLoad(parent, p, f, 0) + textureLoad(parent, p + vec2i(1, 0), f, 0)
        + textureLoad(parent, p + vec2i(0, 1), f, 0) + textureLoad(parent, p + vec2i(1, 1), f, 0);
    textureStore(child, id.xy, id.z, sum * 0.25);
}
