// aa.resolve: temporal FLIPQUAD resolve (TECHNIQUES A2; Drobot 2014 via Far Cry 4).
// Frames alternate sample offsets A (left pixel edge) and B (top pixel edge)
// through projection jitter. A pixel's FLIPQUAD-like footprint is its own
// sample and its right (A) or lower (B) neighbour's, of both frames:
//   out = (C(p) + C(p + d_now) + P(q) + P(q + d_prev)) / 4,   d_A = (1, 0), d_B = (0, 1)
// with P the previous frame reprojected (q = p + jitter-free motion, nearest).
// The previous samples are used only when
//   - motion is coherent: |m_N(p) - m_N-1(q)| < tolerance (px),
//   - colour is coherent: the N-2 sample (same jitter) lies in the 3x3 box
//     of frame N around p (the centre pixel's window, not the mean),
//   - jitter matches: history of at least 2 consecutive frames (phases alternate);
// otherwise out = (C(p) + C(p + d_now)) / 2.
// REACTIVE (E4): where particles drew this frame (`reactive`) or the last
// (the TAA history's alpha at q), the previous sample is dropped in
// proportion: smoke has no motion vectors, its N-1 sample is a ghost.
// MODE 0: pass-through (TAA alone), 1: two-tap SMAA T2x (own samples), 2: FLIPQUAD.
// Target 0: resolved colour (linear, Rgba16Float); target 1: jitter-free motion history.
// CPU twin: temporal/reference.rs.
#import view
#import aa
#import fullscreen

override MODE: u32 = 2u;
// The motion input is aa.taa_motion's stabilised jitter-free motion.
override JITTER_FREE_MOTION: bool = false;
override REACTIVE: bool = false;

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AaParams;
@group(0) @binding(1) var current: texture_2d<f32>;
@group(0) @binding(2) var previous: texture_2d<f32>;
@group(0) @binding(3) var previous2: texture_2d<f32>;
@group(0) @binding(4) var motion: texture_2d<f32>;
@group(0) @binding(5) var previous_motion: texture_2d<f32>;
@group(0) @binding(6) var reactive: texture_2d<f32>;
@group(0) @binding(7) var taa_history: texture_2d<f32>;
@group(0) @binding(8) var linear_sampler: sampler;

struct ResolveOut {
    @location(0) color: vec4f,
    @location(1) motion: vec2f,
}

fn aa_load(t: texture_2d<f32>, p: vec2i) -> vec3f {
    return textureLoad(t, clamp(p, vec2i(0), vec2i(textureDimensions(t)) - 1), 0).rgb;
}

fn aa_load_motion(t: texture_2d<f32>, p: vec2i) -> vec2f {
    return textureLoad(t, clamp(p, vec2i(0), vec2i(textureDimensions(t)) - 1), 0).xy;
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> ResolveOut {
    let p = vec2i(frag.xy);
    let size = vec2f(textureDimensions(current));
    var m = textureLoad(motion, p, 0).xy;
    if (!JITTER_FREE_MOTION) {
        m = aa_jitter_free_motion(params, m, size);
    }
    var out: ResolveOut;
    out.motion = m;
    let c = aa_load(current, p);
    if (MODE == 0u) {
        out.color = vec4f(c, 1.0);
        return out;
    }
    // Neighbour sharing this frame's sample row/column (FLIPQUAD) or none (T2x).
    let d_now = select(vec2i(0, 1), vec2i(1, 0), params.state.y < 0.5);
    let d_prev = vec2i(1, 1) - d_now;
    var now = c;
    if (MODE == 2u) {
        now = 0.5 * (c + aa_load(current, p + d_now));
    }
    out.color = vec4f(now, 1.0);
    if (params.state.x < 2.0) {
        return out;
    }
    let q = vec2i(floor(frag.xy + m * size));
    let m_prev = aa_load_motion(previous_motion, q);
    let motion_ok = length((m - m_prev) * size) < params.tuning.x;
    let q2 = vec2i(floor(vec2f(q) + 0.5 + m_prev * size));
    var lo = c;
    var hi = c;
    for (var y = -1; y <= 1; y++) {
        for (var x = -1; x <= 1; x++) {
            let s = aa_load(current, p + vec2i(x, y));
            lo = min(lo, s);
            hi = max(hi, s);
        }
    }
    let colour_ok = aa_in_box(aa_load(previous2, q2), lo, hi, params.tuning.y);
    if (!(motion_ok && colour_ok)) {
        return out;
    }
    var before = aa_load(previous, q);
    if (MODE == 2u) {
        before = 0.5 * (before + aa_load(previous, q + d_prev));
    }
    var result = 0.5 * (now + before);
    if (REACTIVE) {
        let covered = max(textureSampleLevel(reactive, linear_sampler, frag.xy / size, 0.0).r,
                          textureLoad(taa_history, clamp(q, vec2i(0), vec2i(size) - 1), 0).a);
        result = mix(result, now, saturate(AA_REACTIVE_GAIN * covered));
    }
    out.color = vec4f(result, 1.0);
    return out;
}
