// skyocc.blur: separable binomial blur (1 4 6 4 1 / 16, sigma = 1 texel =
// 25 cm) of the rendered height fields, AXIS 0 = x, 1 = y; taps clamp to
// the image (TECHNIQUES L2, talk: "blurred before generating SH visibility").
// One z slice of the dispatch per sector of this frame.
// Twin: passes/skyocc/reference.rs `blur`.

override AXIS: u32 = 0u;

@group(0) @binding(0) var src_load: texture_2d_array<f32>;
@group(0) @binding(1) var dst: texture_storage_2d_array<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let size = vec2i(textureDimensions(src_load));
    let p = vec2i(id.xy);
    if (p.x >= size.x || p.y >= size.y) {
        return;
    }
    let layer = i32(id.z);
    let step = select(vec2i(0, 1), vec2i(1, 0), AXIS == 0u);
    let w = array<f32, 5>(1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0);
    var s = 0.0;
    for (var k = 0; k < 5; k = k + 1) {
        let q = clamp(p + step * (k - 2), vec2i(0), size - 1);
        s += w[k] * textureLoad(src_load, q, layer, 0).x;
    }
    textureStore(dst, p, layer, vec4f(s, 0.0, 0.0, 1.0));
}
