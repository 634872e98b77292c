// V6 Hi-Z occlusion test (issue #17 item 5; docs/techniques/V6.md "Hi-Z
// occlusion"), shared by cull.wgsl and the GPU-vs-CPU test kernel. Twin:
// passes/cull/reference.rs `hiz_occluded`, the same steps in the same order.
//
// `hiz`: the previous frame's min-depth pyramid (R32Float, reverse-Z: each
// texel of mip k+1 keeps the farthest, i.e. smallest, depth of its texels in
// mip k; the last texel of an odd row or column covers three). `view_proj`:
// the matrix that depth was rendered with. The box (centre c, half extent e)
// is occluded when even its nearest corner, max z/w, lies behind the
// farthest depth over the texels its screen rectangle touches.

// Texel of v in a mip k levels down.
fn hiz_texel(v: vec2u, k: u32) -> vec2u {
    return vec2u(v.x >> k, v.y >> k);
}

fn hiz_occluded(hiz: texture_2d<f32>, view_proj: mat4x4f, c: vec3f, e: vec3f) -> bool {
    let size = textureDimensions(hiz, 0u);
    let screen = vec2f(size);
    var lo = vec2f(3.0e38);
    var hi = vec2f(-3.0e38);
    var z_near = -3.0e38;
    for (var i = 0u; i < 8u; i++) {
        let s = vec3f(
            select(-1.0, 1.0, (i & 1u) != 0u),
            select(-1.0, 1.0, (i & 2u) != 0u),
            select(-1.0, 1.0, (i & 4u) != 0u),
        );
        let p = view_proj * vec4f(c + s * e, 1.0);
        // Behind the eye or nearer than the near plane (z > w in reverse-Z):
        // the rectangle is unbounded, keep.
        if (p.w <= 0.0 || p.z > p.w) {
            return false;
        }
        let ndc = p.xyz / p.w;
        // Pixels, y down (pixel i covers [i, i + 1)).
        let px = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * screen;
        lo = min(lo, px);
        hi = max(hi, px);
        z_near = max(z_near, ndc.z);
    }
    // Partly outside last frame's screen: no depth there, keep.
    if (any(lo < vec2f(0.0)) || any(hi > screen)) {
        return false;
    }
    let a = vec2u(lo);
    let b = min(vec2u(hi), size - 1u);
    // The finest mip where the rectangle spans at most 2 x 2 texels.
    let levels = textureNumLevels(hiz);
    var level = 0u;
    while (level + 1u < levels && any(hiz_texel(b, level) - hiz_texel(a, level) > vec2u(1u))) {
        level += 1u;
    }
    // Pixel p is in texel min(p >> k, size_k - 1) of mip k (the last texel
    // of a mip covers the rest of its parent's row).
    // Mip sizes by arithmetic (max(size >> k, 1)): lavapipe 22.3 answers
    // textureDimensions with a non-constant level with another mip's size.
    let last = max(hiz_texel(size, level), vec2u(1u)) - 1u;
    let ak = vec2i(min(hiz_texel(a, level), last));
    let bk = vec2i(min(hiz_texel(b, level), last));
    let l = i32(level);
    let farthest = min(
        min(textureLoad(hiz, ak, l).x, textureLoad(hiz, vec2i(bk.x, ak.y), l).x),
        min(textureLoad(hiz, vec2i(ak.x, bk.y), l).x, textureLoad(hiz, bk, l).x),
    );
    return z_near < farthest;
}
