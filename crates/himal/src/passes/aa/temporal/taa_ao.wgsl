// aa.taa_ao: TAA on the AO result (TECHNIQUES A3 on other buffers; Far Cry 4
// applies its TAA to more than the final colour). The aa.taa update with the
// AO in place of the colour:
//   H_N = lerp(clamp(H_N-1(q), box3x3(AO) +- t), AO_N, alpha),  q = p + m0
//   alpha = mix(alpha_low, alpha_high, saturate(k * (max - min of the box)))
//   alpha = 1 without history, on incoherent motion (|m0_N - m0_N-1(q)| >= tolerance px)
//   or with q off screen.
// m0 is the jitter-free motion: the G-buffer's minus the jitter change, or the
// stabilised motion of aa.taa_motion (JITTER_FREE_MOTION). The history keeps
// (AO, m0) so the coherence test needs no other buffer.
// Target 0: (AO, Z, N) as the AO chain wrote it with the new AO; target 1: next history.
// CPU twin: temporal/reference.rs `taa_ao`.
#import view
#import aa
#import fullscreen

override JITTER_FREE_MOTION: bool = false;

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AaParams;
@group(0) @binding(1) var ao: texture_2d<f32>;
@group(0) @binding(2) var history: texture_2d<f32>;
@group(0) @binding(3) var motion: texture_2d<f32>;
@group(0) @binding(4) var linear_sampler: sampler;

struct TaaAoOut {
    @location(0) ao: vec4f,
    @location(1) history: vec4f,
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> TaaAoOut {
    let p = vec2i(frag.xy);
    let size = vec2f(textureDimensions(ao));
    let dims = vec2i(size) - 1;
    let x = textureLoad(ao, p, 0);
    var lo = x.x;
    var hi = x.x;
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let s = textureLoad(ao, clamp(p + vec2i(i, j), vec2i(0), dims), 0).x;
            lo = min(lo, s);
            hi = max(hi, s);
        }
    }
    let raw = textureLoad(motion, p, 0).xy;
    var m = raw;
    if (!JITTER_FREE_MOTION) {
        m = aa_jitter_free_motion(params, raw, size);
    }
    let uv = frag.xy / size + m;
    let q = clamp(vec2i(floor(uv * size)), vec2i(0), dims);
    let m_prev = textureLoad(history, q, 0).yz;
    let inside = all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0));
    let motion_ok = length((m - m_prev) * size) < params.tuning.x;
    var alpha = mix(params.state.z, params.state.w, saturate((hi - lo) * params.tuning.w));
    if (params.state.x < 1.0 || !motion_ok || !inside) {
        alpha = 1.0;
    }
    let t = params.tuning.y;
    let h = clamp(textureSampleLevel(history, linear_sampler, uv, 0.0).x, lo - t, hi + t);
    let result = mix(h, x.x, alpha);
    var out: TaaAoOut;
    out.ao = vec4f(result, x.yz, 1.0);
    out.history = vec4f(result, m, 1.0);
    return out;
}
