// renderer.normal_mipmap (E3, Toksvig): one mip level of a normal map from
// the previous one, keeping the normal variance the average loses. Each
// texel loads its four parents (2x, 2x + 1 clamped to the edge: odd sizes
// drop the last row / column as mipmap.wgsl does), normalises each (8-bit
// RGB has no usable length), and writes
//   RGB = encode(normalize(m)),  m = mean(n_i),
//   A   = encode(mean(sigma_i^2) + (1 - |m|) / |m|)
// (brdf.wgsl normal_variance_encode). Level 0's alpha is 0 (set at upload).
// CPU twin: gpu_scene/textures.rs `next_normal_mip_reference`.
#import view
#import fullscreen
#import brdf

@group(0) @binding(0) var source_load: texture_2d<f32>;

// A unit normal from an RGB texel; +z where it has no direction.
fn unit_normal(rgb: vec3f) -> vec3f {
    let n = rgb * 2.0 - 1.0;
    let len = length(n);
    return select(vec3f(0.0, 0.0, 1.0), n / len, len > 1e-6);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let last = vec2i(textureDimensions(source_load, 0)) - 1;
    let p = vec2i(frag.xy) * 2;
    var m = vec3f(0.0);
    var variance = 0.0;
    for (var i = 0; i < 4; i++) {
        let t = textureLoad(source_load, min(p + vec2i(i & 1, i >> 1u), last), 0);
        m += unit_normal(t.rgb);
        variance += normal_variance_decode(t.a);
    }
    m *= 0.25;
    // Opposite normals average to nothing: as rough as the encoding holds.
    let len = max(length(m), 1e-4);
    variance = 0.25 * variance + (1.0 - len) / len;
    let n = select(vec3f(0.0, 0.0, 1.0), m / len, length(m) > 1e-6);
    return vec4f(n * 0.5 + 0.5, normal_variance_encode(variance));
}
