// post.tonemap: bloom composite and Reinhard's global operator (TECHNIQUES H2, H3;
// Reinhard et al. 2002 eq. 2-4):
//   c' = c + strength * bloom                      (BLOOM: HDR composite before tone mapping)
//   L = s * L_w(c'),  s = key / L_exposure * 2^EV  (L_exposure: adapted or this frame's log-average)
//   L_d = L / (1 + L)                              (WHITE_POINT off)
//   L_d = L * (1 + L / L_white^2) / (1 + L)        (WHITE_POINT on, eq. 4)
//   colour scaled by L_d / L_w (hue kept).
// Bindings: post (uniform), hdr, exposure (storage), bloom + bloom_sampler.
// Target: Rgba8UnormSrgb (hardware sRGB encoding). CPU twin: post/reference.rs.
#import view
#import color
#import post
#import fullscreen

override BLOOM: bool = false;
override WHITE_POINT: bool = false;

@group(0) @binding(0) var<uniform> post: Post;
@group(0) @binding(1) var hdr: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> exposure: vec4f;
@group(0) @binding(3) var bloom: texture_2d<f32>;
@group(0) @binding(4) var bloom_sampler: sampler;

fn reinhard(c: vec3f, scale: f32) -> vec3f {
    let l_w = luminance(c) * scale;
    if (l_w <= 0.0) {
        return vec3f(0.0);
    }
    var l_d = l_w / (1.0 + l_w);
    if (WHITE_POINT) {
        let l_white = max(post.tone.y, 1e-3);
        l_d = l_d * (1.0 + l_w / (l_white * l_white));
    }
    return c * scale * (l_d / l_w);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    var c = textureLoad(hdr, vec2i(frag.xy), 0).rgb;
    if (BLOOM) {
        let uv = frag.xy / vec2f(textureDimensions(hdr));
        c += post.bloom.y * textureSampleLevel(bloom, bloom_sampler, uv, 0.0).rgb;
    }
    let scale = exposure_scale(post, exposure.y);
    return vec4f(reinhard(c, scale), 1.0);
}
