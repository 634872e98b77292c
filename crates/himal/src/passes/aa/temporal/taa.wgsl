// aa.taa: temporal anti-aliasing (TECHNIQUES A3; Far Cry 4 HRAA, Ryse SMAA 1TX).
// Exponential history: H_N = lerp(clamp(H_N-1(q), box3x3), X_N, alpha), q = p + jitter-free
// motion (bilinear). Same acceptance as the resolve: history from complete
// resolves (3 frames) and coherent motion (N vs N-1), else alpha = 1; the colour test clamps the
// history into the 3x3 box of the input, widened by the colour tolerance. Sample count follows signal frequency
// (Ryse): alpha = mix(alpha_low, alpha_high, saturate(luma contrast of the box * k)),
// fewer frames where the image is smooth, more on edges and detail.
// REACTIVE (E4): particles' coverage this frame (`reactive`, forward.particles)
// and in the history (its alpha) raise alpha to at least that coverage: no
// motion vectors follow smoke, so its history is dropped where it drew.
// Target 0: next history (linear, Rgba16Float); target 1: the frame's colour.
// CPU twin: temporal/reference.rs.
#import view
#import color
#import aa
#import fullscreen

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AaParams;
@group(0) @binding(1) var input: texture_2d<f32>;
@group(0) @binding(2) var history: texture_2d<f32>;
@group(0) @binding(3) var motion: texture_2d<f32>;
@group(0) @binding(4) var previous_motion: texture_2d<f32>;
@group(0) @binding(5) var linear_sampler: sampler;
@group(0) @binding(6) var reactive: texture_2d<f32>;

override REACTIVE: bool = false;

struct TaaOut {
    @location(0) history: vec4f,
    @location(1) color: vec4f,
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> TaaOut {
    let p = vec2i(frag.xy);
    let size = vec2f(textureDimensions(input));
    let dims = vec2i(size) - 1;
    let x = textureLoad(input, p, 0).rgb;
    var lo = x;
    var hi = x;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let s = textureLoad(input, clamp(p + vec2i(i, j), vec2i(0), dims), 0).rgb;
            lo = min(lo, s);
            hi = max(hi, s);
        }
    }
    // The resolve already wrote this frame's jitter-free motion.
    let m = textureLoad(motion, p, 0).xy;
    let uv = frag.xy / size + m;
    let q = clamp(vec2i(floor(uv * size)), vec2i(0), dims);
    let m_prev = textureLoad(previous_motion, q, 0).xy;
    let inside = all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0));
    let motion_ok = length((m - m_prev) * size) < params.tuning.x;
    let contrast = luminance(linear_to_srgb(hi)) - luminance(linear_to_srgb(lo));
    var alpha = mix(params.state.z, params.state.w, saturate(contrast * params.tuning.w));
    // The resolve's first complete output is the third frame (it needs N-2):
    // an earlier history would carry its one-frame fallback for many frames.
    if (params.state.x < 3.0 || !motion_ok || !inside) {
        alpha = 1.0;
    }
    let tolerance = vec3f(params.tuning.y);
    let hs = textureSampleLevel(history, linear_sampler, uv, 0.0);
    var coverage = 1.0;
    if (REACTIVE) {
        coverage = textureSampleLevel(reactive, linear_sampler, frag.xy / size, 0.0).r;
        alpha = max(alpha, saturate(AA_REACTIVE_GAIN * max(coverage, hs.a)));
    }
    let h = clamp(hs.rgb, lo - tolerance, hi + tolerance);
    let result = mix(h, x, alpha);
    var out: TaaOut;
    out.history = vec4f(result, coverage);
    out.color = vec4f(result, 1.0);
    return out;
}
