// cull.hiz.mipK (V6 Hi-Z, issue #17 item 5): mip k of the min-depth pyramid
// from mip k - 1. Reverse-Z: z = 0 is the far plane, so a texel keeps the
// minimum (farthest) of its parents: 2 x 2, and where the parent's size is
// odd the last texel of a row or column also takes the parent's last (three
// wide), so every parent texel is covered. Twin: reference.rs `hiz_reduce`.

@group(0) @binding(0) var parent_load: texture_2d<f32>;
@group(0) @binding(1) var child: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_reduce(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(child);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let parent = textureDimensions(parent_load);
    let p0 = id.xy * 2u;
    // The last texel reaches the parent's end (three wide for an odd size).
    let p1 = select(min(p0 + 1u, parent - 1u), parent - 1u, id.xy == size - 1u);
    var z = 3.0e38;
    for (var y = p0.y; y <= p1.y; y++) {
        for (var x = p0.x; x <= p1.x; x++) {
            z = min(z, textureLoad(parent_load, vec2u(x, y), 0).x);
        }
    }
    textureStore(child, id.xy, vec4f(z, 0.0, 0.0, 1.0));
}
