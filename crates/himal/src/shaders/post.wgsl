// Post-processing parameters (TECHNIQUES H2, H3), written once per frame by
// the renderer. CPU twin: passes/post/params.rs `PostUniform`.

struct Post {
    // x: frame delta (s), y: tau when brightening (s), z: tau when darkening (s),
    // w: 1 = start adapted (first frame, camera cut), 0 = converge
    adapt: vec4f,
    // x: bright-pass threshold (scaled luminance), y: bloom strength
    bloom: vec4f,
    // x: key a, y: white point L_white (scaled luminance; 0 = none), z: 2^EV bias
    tone: vec4f,
}

// Exposure scale s of Reinhard eq. 2: L = s * L_w with s = a / L_exposure * 2^EV,
// where L_exposure is the adapted (or this frame's) log-average luminance.
fn exposure_scale(post: Post, l_exposure: f32) -> f32 {
    return post.tone.x / max(l_exposure, 1e-6) * post.tone.z;
}
