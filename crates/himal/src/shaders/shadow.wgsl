// Sun shadow lookup shared by lighting passes (TECHNIQUES S1 foundation).
// A 3x3 grid of hardware-compared bilinear taps (a 4x4-texel tent): smooth
// edges, no noise, so the result is deterministic. Checked against CPU ray
// casting in tests/shadows.rs.

// Visibility in [0,1] of world point `p` (already offset along its normal)
// for a light-space matrix mapping world to clip (xy in [-1,1], z in [0,1]).
fn sun_shadow_visibility(map: texture_depth_2d, cmp: sampler_comparison, light_view_proj: mat4x4f,
                         p: vec3f, depth_bias: f32) -> f32 {
    let c = light_view_proj * vec4f(p, 1.0);
    let uv = vec2f(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
    if (any(uv < vec2f(0.0)) || any(uv > vec2f(1.0)) || c.z > 1.0) {
        return 1.0;
    }
    let texel = 1.0 / vec2f(textureDimensions(map));
    var sum = 0.0;
    for (var j = -1; j <= 1; j = j + 1) {
        for (var i = -1; i <= 1; i = i + 1) {
            sum = sum + textureSampleCompareLevel(map, cmp, uv + vec2f(f32(i), f32(j)) * texel, c.z - depth_bias);
        }
    }
    return sum / 9.0;
}
