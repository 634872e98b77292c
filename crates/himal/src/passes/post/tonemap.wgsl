// post.tonemap: bloom composite and a tone mapper (TECHNIQUES H2, H3;
// Reinhard et al. 2002 eq. 2-4; the other curves in docs/techniques/H3.md):
//   c' = c + strength * bloom                      (BLOOM: HDR composite before tone mapping)
//   L = s * L_w(c'),  s = key / L_exposure * 2^EV  (L_exposure: adapted or this frame's log-average)
//   TONEMAP 0, Reinhard: L_d = L / (1 + L)         (WHITE_POINT off)
//     L_d = L * (1 + L / L_white^2) / (1 + L)      (WHITE_POINT on, eq. 4)
//     colour scaled by L_d / L_w (hue kept).
//   TONEMAP 1, 2, 3: Khronos PBR Neutral, ACES (Hill's fit), AgX on s * c'.
// Bindings: post (uniform), hdr, exposure (storage), bloom + bloom_sampler.
// Target: Rgba8UnormSrgb (hardware sRGB encoding). CPU twin: post/reference.rs.
#import view
#import color
#import post
#import fullscreen

override BLOOM: bool = false;
override WHITE_POINT: bool = false;
// 0 Reinhard, 1 Khronos PBR Neutral, 2 ACES (Hill), 3 AgX (Tonemapper).
override TONEMAP: u32 = 0u;

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

// Khronos PBR Neutral as specified: F90 = 0.04, K_s = 0.8 - F90, K_d = 0.15.
fn pbr_neutral(c_in: vec3f) -> vec3f {
    let f90 = 0.04;
    let k_s = 0.8 - f90;
    let k_d = 0.15;
    let x = min(c_in.r, min(c_in.g, c_in.b));
    let f = select(f90, x - x * x / (4.0 * f90), x <= 2.0 * f90);
    let c = c_in - f;
    let p = max(c.r, max(c.g, c.b));
    if (p <= k_s) {
        return c;
    }
    let p_n = 1.0 - (1.0 - k_s) * (1.0 - k_s) / (p + 1.0 - 2.0 * k_s);
    let g = 1.0 / (k_d * (p - p_n) + 1.0);
    return c * (p_n / p) * g + vec3f(p_n) * (1.0 - g);
}

// Hill's ACES fit; WGSL matrices are columns (the published rows transposed).
const ACES_IN = mat3x3f(
    vec3f(0.59719, 0.07600, 0.02840),
    vec3f(0.35458, 0.90834, 0.13383),
    vec3f(0.04823, 0.01566, 0.83777),
);
const ACES_OUT = mat3x3f(
    vec3f(1.60475, -0.10208, -0.00327),
    vec3f(-0.53108, 1.10813, -0.07276),
    vec3f(-0.07367, -0.00605, 1.07602),
);

fn aces_hill(c: vec3f) -> vec3f {
    let v = ACES_IN * (c / 0.6);
    let rrt = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.432951) + 0.238081);
    return clamp(ACES_OUT * rrt, vec3f(0.0), vec3f(1.0));
}

// AgX inset / outset (columns) and its curve's constants, derived in
// reference.rs AgxCurve::new (log2 0.18 - 10 .. + 6.5 EV, slope 2.4, power 1.5).
const AGX_INSET = mat3x3f(
    vec3f(0.5449081, 0.14044006, 0.08882741),
    vec3f(0.37377946, 0.7541096, 0.17887712),
    vec3f(0.08138498, 0.10543358, 0.73225),
);
const AGX_OUTSET = mat3x3f(
    vec3f(1.964551, -0.29932243, -0.16436834),
    vec3f(-0.85585845, 1.3264511, -0.23822464),
    vec3f(-0.10886711, -0.02708402, 1.4026653),
);
const AGX_MIN_EV: f32 = -12.473931;
const AGX_RANGE_EV: f32 = 16.5;
const AGX_X_PIVOT: f32 = 0.60606060;
const AGX_Y_PIVOT: f32 = 0.48943709;
const AGX_K_BOTTOM: f32 = 4.2427143;
const AGX_K_TOP: f32 = 3.3557127;

fn agx(c: vec3f) -> vec3f {
    let v = AGX_INSET * max(c, vec3f(2e-10));
    let x = max((log2(v) - AGX_MIN_EV) / AGX_RANGE_EV, vec3f(0.0));
    let d = x - AGX_X_PIVOT;
    let k = select(vec3f(AGX_K_BOTTOM), vec3f(AGX_K_TOP), d >= vec3f(0.0));
    let y = AGX_Y_PIVOT + 2.4 * d / pow(1.0 + pow(k * abs(d), vec3f(1.5)), vec3f(1.0 / 1.5));
    return AGX_OUTSET * pow(y, vec3f(2.4));
}

fn tonemap(c_in: vec3f, scale: f32) -> vec3f {
    let c = max(c_in, vec3f(0.0));
    switch TONEMAP {
        case 1u: { return pbr_neutral(c * scale); }
        case 2u: { return aces_hill(c * scale); }
        case 3u: { return agx(c * scale); }
        default: { return reinhard(c, scale); }
    }
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    var c = textureLoad(hdr, vec2i(frag.xy), 0).rgb;
    if (BLOOM) {
        let uv = frag.xy / vec2f(textureDimensions(hdr));
        c += post.bloom.y * textureSampleLevel(bloom, bloom_sampler, uv, 0.0).rgb;
    }
    let scale = exposure_scale(post, exposure.y);
    return vec4f(tonemap(c, scale), 1.0);
}
