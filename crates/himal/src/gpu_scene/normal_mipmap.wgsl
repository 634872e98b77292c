// renderer.normal_mipmap (E3, Toksvig): one mip level of a normal map from
// the previous one, keeping the normal variance the average loses. Each
// texel loads its four parents (2x, 2x + 1 clamped to the edge: odd sizes
// drop the last row / column as mipmap.wgsl does), normalises each (8-bit
// RGB has no usable length), and writes
//   RGB = encode(normalize(m)),  m = mean(n_i),
//   A   = encode(mean(sigma_i^2) + (1 - |m|) / |m|)
// (brdf.wgsl normal_variance_encode). Level 0's alpha is 0 (set at upload).
// FROM_LEVEL0 (level 1): the spread is that of the surface the sampler
// shows, level 0's bilinear field over the footprint, not that of the four
// texels (for white noise the texels' is 9/4 of the field's).
// CPU twin: gpu_scene/textures.rs `next_normal_mip_reference`.
#import view
#import fullscreen
#import brdf

override FROM_LEVEL0: bool = false;

@group(0) @binding(0) var source: texture_2d<f32>;
// Bilinear, clamped to the edge (FROM_LEVEL0's taps of level 0).
@group(0) @binding(1) var source_sampler: sampler;

// A unit normal from an RGB texel; +z where it has no direction.
fn unit_normal(rgb: vec3f) -> vec3f {
    let n = rgb * 2.0 - 1.0;
    let len = length(n);
    return select(vec3f(0.0, 0.0, 1.0), n / len, len > 1e-6);
}

// (1 - |m|) / |m| of a mean of unit normals; opposite normals average to
// nothing: as rough as the encoding holds.
fn spread(m: vec3f) -> f32 {
    let len = max(length(m), 1e-4);
    return (1.0 - len) / len;
}

// (1 - |m|) / |m| of level 0's bilinear field over texel p's footprint
// [p - 1/2, p + 3/2] (texel-centre coordinates), m the mean of its unit
// normals by two-point Gauss-Legendre on each of the field's three linear
// pieces per axis ([p - 1/2, p], [p, p + 1], [p + 1, p + 3/2]: exact for
// the field's quadratic moments before normalising), 6 x 6 bilinear taps.
fn field_spread(p: vec2i) -> f32 {
    let size = vec2f(textureDimensions(source, 0));
    var m = vec3f(0.0);
    for (var j = 0; j < 36; j++) {
        let a = gauss_node(j % 6);
        let b = gauss_node(j / 6);
        let uv = (vec2f(p) + 0.5 + vec2f(a.x, b.x)) / size;
        let rgb = textureSampleLevel(source, source_sampler, uv, 0.0).rgb;
        m += a.y * b.y * unit_normal(rgb);
    }
    return spread(m);
}

// Node k of 0..6 along one axis (offset from texel p's centre) and its
// weight (the weights sum to 1): piece k / 2 has centre -1/4, 1/2, 5/4 and
// half-length 1/4, 1/2, 1/4 of the footprint's length 2.
fn gauss_node(k: i32) -> vec2f {
    let piece = f32(k / 2);
    let half = select(0.25, 0.5, k / 2 == 1);
    let side = select(-1.0, 1.0, (k & 1) == 1);
    return vec2f(-0.25 + 0.75 * piece + side * half * 0.57735027, half * 0.5);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let last = vec2i(textureDimensions(source, 0)) - 1;
    let p = vec2i(frag.xy) * 2;
    var m = vec3f(0.0);
    var variance = 0.0;
    for (var i = 0; i < 4; i++) {
        let t = textureLoad(source, min(p + vec2i(i & 1, i >> 1u), last), 0);
        m += unit_normal(t.rgb);
        variance += normal_variance_decode(t.a);
    }
    m *= 0.25;
    if (FROM_LEVEL0) {
        variance = field_spread(p);
    } else {
        variance = 0.25 * variance + spread(m);
    }
    let n = select(vec3f(0.0, 0.0, 1.0), m / max(length(m), 1e-4), length(m) > 1e-6);
    return vec4f(n * 0.5 + 0.5, normal_variance_encode(variance));
}
