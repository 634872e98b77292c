// aa.smaa.blend: SMAA neighbourhood blending (Jimenez et al. 2012,
// SMAANeighborhoodBlendingPS): each pixel mixes with its neighbours across
// the edges it shares, by the weights of itself (top, left) and of its right
// and bottom neighbours; the stronger direction (horizontal or vertical)
// wins. Colour is sampled bilinearly in linear space (sRGB texture).
// CPU twin: smaa/reference.rs.
#import view
#import fullscreen

@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var weights_tex: texture_2d<f32>;
@group(0) @binding(2) var linear_sampler: sampler;

fn smaa_weights_at(p: vec2i) -> vec4f {
    let q = clamp(p, vec2i(0), vec2i(textureDimensions(weights_tex)) - 1);
    return textureLoad(weights_tex, q, 0);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let p = vec2i(frag.xy);
    let size = vec2f(textureDimensions(color));
    let rt = vec4f(1.0 / size, size);
    let tc = frag.xy * rt.xy;
    let own = smaa_weights_at(p);
    // a: right neighbour's left weight, bottom's top weight, own left, own top.
    let a = vec4f(smaa_weights_at(p + vec2i(1, 0)).a, smaa_weights_at(p + vec2i(0, 1)).g, own.z, own.x);
    if (dot(a, vec4f(1.0)) < 1e-5) {
        return textureLoad(color, p, 0);
    }
    let horizontal = max(a.x, a.z) > max(a.y, a.w);
    var offset = vec4f(0.0, a.y, 0.0, a.w);
    var weight = a.yw;
    if (horizontal) {
        offset = vec4f(a.x, 0.0, a.z, 0.0);
        weight = a.xz;
    }
    weight /= dot(weight, vec2f(1.0));
    let c1 = tc + offset.xy * rt.xy;
    let c2 = tc - offset.zw * rt.xy;
    return weight.x * textureSampleLevel(color, linear_sampler, c1, 0.0)
        + weight.y * textureSampleLevel(color, linear_sampler, c2, 0.0);
}
