// Shared by the temporal anti-aliasing passes (passes/aa/temporal, TECHNIQUES A2-A4).
// Twin: passes/aa/temporal/mod.rs `AaParams`.

struct AaParams {
    // xy: this frame's sample offset (px, y down, from the pixel centre); zw: previous frame's
    jitter: vec4f,
    // x: consecutive frames of history (0 after a cut); y: phase (0 = frame A, 1 = B);
    // z: TAA weight of the new frame at low frequency; w: at high frequency
    state: vec4f,
    // x: motion coherence tolerance (px); y: colour box tolerance (display units);
    // z: unsharp strength; w: local-contrast scale for the TAA frequency estimate
    tuning: vec4f,
}

// Motion (previous uv - current uv) without the jitter change: the matrices
// carry each frame's jitter, so the raw motion of a static point is the
// jitter difference (prev_uv = uv0 - j_prev/size, curr_uv = uv0 - j/size).
// E4 reactive mask: particle coverage at which aa.resolve and aa.taa drop
// the previous frames entirely is 1 / gain (smoke's soft edges, a few %
// alpha, still left a visible trail at gain 1). Twin: temporal/reference.rs.
const AA_REACTIVE_GAIN: f32 = 4.0;

fn aa_jitter_free_motion(p: AaParams, motion: vec2f, size: vec2f) -> vec2f {
    return motion + (p.jitter.zw - p.jitter.xy) / size;
}

fn aa_in_box(c: vec3f, lo: vec3f, hi: vec3f, tolerance: f32) -> bool {
    return all(c >= lo - vec3f(tolerance)) && all(c <= hi + vec3f(tolerance));
}
