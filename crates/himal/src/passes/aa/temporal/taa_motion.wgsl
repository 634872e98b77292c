// aa.taa_motion: a stabilised motion buffer (TECHNIQUES A3 on other buffers).
// The jitter-free motion m0 (G-buffer motion minus the jitter change) gets the
// aa.taa update with itself as the signal:
//   H_N = lerp(clamp(H_N-1(q), box3x3(m0) +- t / size), m0_N, alpha),  q = p + m0
//   alpha = mix(alpha_low, alpha_high, saturate(k * |max - min of the box| in px))
//   alpha = 1 without history, on incoherent motion (|m0_N - H_N-1(q)| >= tolerance px)
//   or with q off screen.
// Target: next history = the stabilised motion (Rg16Float, previous uv - current uv),
// read by aa.taa_ao and aa.resolve in place of the G-buffer motion.
// CPU twin: temporal/reference.rs `taa_motion`.
#import view
#import aa
#import fullscreen

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AaParams;
@group(0) @binding(1) var motion: texture_2d<f32>;
@group(0) @binding(2) var history: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec2f {
    let p = vec2i(frag.xy);
    let size = vec2f(textureDimensions(motion));
    let dims = vec2i(size) - 1;
    let m = aa_jitter_free_motion(params, textureLoad(motion, p, 0).xy, size);
    var lo = m;
    var hi = m;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let raw = textureLoad(motion, clamp(p + vec2i(i, j), vec2i(0), dims), 0).xy;
            let s = aa_jitter_free_motion(params, raw, size);
            lo = min(lo, s);
            hi = max(hi, s);
        }
    }
    let uv = frag.xy / size + m;
    let q = clamp(vec2i(floor(uv * size)), vec2i(0), dims);
    let m_prev = textureLoad(history, q, 0).xy;
    let inside = all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0));
    let motion_ok = length((m - m_prev) * size) < params.tuning.x;
    let spread = length((hi - lo) * size);
    var alpha = mix(params.state.z, params.state.w, saturate(spread * params.tuning.w));
    if (params.state.x < 1.0 || !motion_ok || !inside) {
        alpha = 1.0;
    }
    let t = vec2f(params.tuning.y) / size;
    let h = clamp(textureSampleLevel(history, linear_sampler, uv, 0.0).xy, lo - t, hi + t);
    return mix(h, m, alpha);
}
