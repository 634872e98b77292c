// forward.scene_color: the opaque scene's HDR radiance copied for the
// transmissive surfaces to sample (mip 0, cs_copy), then its box-filtered
// mip chain (cs_downsample, one dispatch per level: each texel averages its
// 2x2 parents, clamped at odd edges). Sampled by forward.transmission at
// a mip by the BTDF's roughness (docs/gltf.md "Transmission and volume").
@group(0) @binding(0) var parent: texture_2d<f32>;
@group(0) @binding(1) var child: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_copy(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(child);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    textureStore(child, id.xy, vec4f(textureLoad(parent, vec2i(id.xy), 0).rgb, 1.0));
}

@compute @workgroup_size(8, 8, 1)
fn cs_downsample(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(child);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let last = vec2i(textureDimensions(parent)) - 1;
    let p = vec2i(id.xy * 2u);
    let sum = textureLoad(parent, p, 0) + textureLoad(parent, min(p + vec2i(1, 0), last), 0)
        + textureLoad(parent, min(p + vec2i(0, 1), last), 0) + textureLoad(parent, min(p + vec2i(1, 1), last), 0);
    textureStore(child, id.xy, sum * 0.25);
}
