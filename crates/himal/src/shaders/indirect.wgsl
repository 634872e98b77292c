// L5 indirect light (TECHNIQUES L5): the probe constants, the clip map's
// cascade choice and its bilinear SH2 sampling in deferred lighting.
// Twin: crates/himal/src/passes/indirect/reference.rs (constants there too).
// SH2 layout per colour channel: [L00, L1-1 (y), L10 (z), L11 (x)].
#import sh

const INDIRECT_CLIP_RES: i32 = 32;
const INDIRECT_CASCADES: i32 = 5;
// Sampling stays this many texels inside a cascade (the cells the pool
// guarantees: 1.5 cells of each side of the camera), C + 1 fading in over
// the last INDIRECT_BLEND_TEXELS.
const INDIRECT_GUARANTEED_TEXELS: f32 = 12.0;
const INDIRECT_BLEND_TEXELS: f32 = 3.0;
// Probe spacing of mip 0 (m); mip m: 8 m x 2^m.
const INDIRECT_SPACING: f32 = 8.0;

struct IndirectParams {
    // The lighting SH2 (sky above the horizon + the sun), rgb per coefficient.
    lighting: array<vec4f, 4>,
    // xy: grid origin (sector (0, 0)'s min corner); zw: camera (x, z).
    origin_camera: vec4f,
    // Per cascade: global probe index (x, z) of texel (0, 0).
    base: array<vec4i, 5>,
    // x: sectors per axis of the combined page table (160).
    grid: vec4i,
    // The flat ground bounce of the sky SH, which the probes replace.
    ground: Sh9,
    // x: probes in the pool (slots x 64); y: what --view shows (0 irradiance,
    // 1 probe cells, 2 clip-map cascades).
    counts: vec4u,
    // The flat ground bounce as SH2 radiance per channel (r, g, b): what a
    // texel with no baked cell holds.
    fallback: array<vec4f, 3>,
}

fn indirect_texel_size(c: i32) -> f32 {
    return INDIRECT_SPACING * f32(1u << u32(c));
}

// x: the cascade p (x, z) falls in (-1 beyond all), y: weight of C + 1.
fn indirect_cascade(camera: vec2f, p: vec2f) -> vec2f {
    let d = max(abs(p.x - camera.x), abs(p.y - camera.y));
    for (var c = 0; c < INDIRECT_CASCADES; c++) {
        let size = indirect_texel_size(c);
        let edge = (INDIRECT_GUARANTEED_TEXELS - 1.0) * size;
        if (d < edge) {
            let band = INDIRECT_BLEND_TEXELS * size;
            var w = clamp((d - (edge - band)) / band, 0.0, 1.0);
            if (c + 1 >= INDIRECT_CASCADES) {
                w = 0.0;
            }
            return vec2f(f32(c), w);
        }
    }
    return vec2f(-1.0, 0.0);
}

// Irradiance for normal n from one channel's SH2 radiance: A0 Y0 L0 + A1 Y1 (L1 . n).
fn indirect_sh2_irradiance(l: vec4f, n: vec3f) -> f32 {
    let a0y0 = 3.14159265 * 0.282095;
    let a1y1 = 2.0943951 * 0.488603;
    return a0y0 * l.x + a1y1 * (l.y * n.y + l.z * n.z + l.w * n.x);
}

// SH2 (r, g, b rows) of cascade c at p (x, z), bilinear between probes.
fn indirect_sample_cascade(
    params: IndirectParams,
    clip_r: texture_2d_array<f32>,
    clip_g: texture_2d_array<f32>,
    clip_b: texture_2d_array<f32>,
    clip_sampler: sampler,
    c: i32,
    p: vec2f,
) -> mat3x4f {
    let f = (p - params.origin_camera.xy) / indirect_texel_size(c) - vec2f(params.base[c].xy);
    let uv = f / f32(INDIRECT_CLIP_RES);
    return mat3x4f(
        textureSampleLevel(clip_r, clip_sampler, uv, c, 0.0),
        textureSampleLevel(clip_g, clip_sampler, uv, c, 0.0),
        textureSampleLevel(clip_b, clip_sampler, uv, c, 0.0),
    );
}

// `--view probe-cells` / `clipmap` over the irradiance e at p (lighting
// view display; auto exposure brings either to the screen).
fn indirect_debug_view(params: IndirectParams, p: vec3f, e: vec3f) -> vec3f {
    let cw = indirect_cascade(params.origin_camera.zw, p.xz);
    if (cw.x < 0.0) {
        return vec3f(0.0);
    }
    let c = i32(cw.x);
    let level = max(dot(e, vec3f(0.2126, 0.7152, 0.0722)), 1e-3);
    if (params.counts.y == 2u) {
        var hues = array<vec3f, 5>(vec3f(1.0, 0.25, 0.2), vec3f(1.0, 0.8, 0.2), vec3f(0.3, 1.0, 0.3), vec3f(0.2, 0.7, 1.0), vec3f(0.8, 0.35, 1.0));
        let next = hues[min(c + 1, INDIRECT_CASCADES - 1)];
        return mix(hues[c], next, cw.y) * level;
    }
    // Probe cells: probes of cascade C (its mip's spacing) as dots, the
    // borders of their 8 x 8 cells as lines, over the irradiance.
    let s = indirect_texel_size(c);
    let f = (p.xz - params.origin_camera.xy) / s;
    let to_probe = length((fract(f) - 0.5) * s);
    let g = fract(f / 8.0);
    let to_border = min(min(g.x, 1.0 - g.x), min(g.y, 1.0 - g.y)) * 8.0 * s;
    let width = 0.06 * s;
    if (to_probe < 1.5 * width) {
        return vec3f(4.0 * level);
    }
    if (to_border < 0.5 * width) {
        return vec3f(2.0, 0.4, 0.2) * level;
    }
    return e;
}

// Indirect irradiance at world p for normal n (rgb, klux); a = 1 where the
// clip map covers p, 0 beyond (the caller keeps the flat ground there).
fn indirect_irradiance(
    params: IndirectParams,
    clip_r: texture_2d_array<f32>,
    clip_g: texture_2d_array<f32>,
    clip_b: texture_2d_array<f32>,
    clip_sampler: sampler,
    p: vec3f,
    n: vec3f,
) -> vec4f {
    let xz = p.xz;
    let cw = indirect_cascade(params.origin_camera.zw, xz);
    if (cw.x < 0.0) {
        return vec4f(0.0);
    }
    let c = i32(cw.x);
    var sh = indirect_sample_cascade(params, clip_r, clip_g, clip_b, clip_sampler, c, xz);
    if (cw.y > 0.0) {
        let next = indirect_sample_cascade(params, clip_r, clip_g, clip_b, clip_sampler, c + 1, xz);
        sh = mat3x4f(mix(sh[0], next[0], cw.y), mix(sh[1], next[1], cw.y), mix(sh[2], next[2], cw.y));
    }
    let e = vec3f(indirect_sh2_irradiance(sh[0], n), indirect_sh2_irradiance(sh[1], n), indirect_sh2_irradiance(sh[2], n));
    return vec4f(max(e, vec3f(0.0)), 1.0);
}
