// post.bloom.*: Kawase bloom (TECHNIQUES H2; Kawase, GDC 2003, as used in
// Far Cry: Wenzel, GDC 2005): repeated small blurs with growing offsets at
// quarter resolution, composited in HDR by post.tonemap.
//   fs_bright (post.bloom.bright): one quarter-resolution pixel from its 4x4
//     full-resolution block with 4 bilinear taps at the centres of its 2x2 quads;
//     each tap keeps the part above the threshold T in scaled luminance:
//     b = c * max(L_s - T, 0) / L_s,  L_s = s * L(c),  s = key / L_exposure * 2^EV.
//   fs_blur (post.bloom.blurK): one Kawase pass at offset k = OFFSET:
//     mean of 4 bilinear taps at (+-(k + 1/2), +-(k + 1/2)) texels (each averages 2x2).
// Bindings: post (uniform), exposure (storage), src (texture), src_sampler (linear, clamp).
// CPU twin: post/reference.rs `kawase_pass`, `bright_pass`.
#import view
#import color
#import post
#import fullscreen

override OFFSET: f32 = 0.0;

@group(0) @binding(0) var<uniform> post: Post;
@group(0) @binding(1) var<storage, read> exposure: vec4f;
@group(0) @binding(2) var src: texture_2d<f32>;
@group(0) @binding(3) var src_sampler: sampler;

fn tap(p: vec2f, inv_size: vec2f) -> vec3f {
    return textureSampleLevel(src, src_sampler, p * inv_size, 0.0).rgb;
}

fn bright(c: vec3f, scale: f32) -> vec3f {
    let l_s = luminance(c) * scale;
    if (!(l_s > 0.0)) { // also drops NaN
        return vec3f(0.0);
    }
    return c * (max(l_s - post.bloom.x, 0.0) / l_s);
}

@fragment
fn fs_bright(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let inv = 1.0 / vec2f(textureDimensions(src));
    let scale = exposure_scale(post, exposure.y);
    // Centre of the 4x4 block in full-resolution pixels.
    let centre = (floor(frag.xy) * 4.0) + 2.0;
    var sum = vec3f(0.0);
    sum += bright(tap(centre + vec2f(-1.0, -1.0), inv), scale);
    sum += bright(tap(centre + vec2f(1.0, -1.0), inv), scale);
    sum += bright(tap(centre + vec2f(-1.0, 1.0), inv), scale);
    sum += bright(tap(centre + vec2f(1.0, 1.0), inv), scale);
    // fp16 target: keep finite.
    return vec4f(min(sum * 0.25, vec3f(65504.0)), 1.0);
}

@fragment
fn fs_blur(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let inv = 1.0 / vec2f(textureDimensions(src));
    let d = OFFSET + 0.5;
    var sum = tap(frag.xy + vec2f(-d, -d), inv);
    sum += tap(frag.xy + vec2f(d, -d), inv);
    sum += tap(frag.xy + vec2f(-d, d), inv);
    sum += tap(frag.xy + vec2f(d, d), inv);
    return vec4f(sum * 0.25, 1.0);
}
