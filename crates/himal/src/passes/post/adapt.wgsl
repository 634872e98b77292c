// post.adapt: light adaptation (TECHNIQUES H3; Wenzel, GDC 2005: "replace Lum_avg
// by an adapted luminance value which slowly converges towards Lum_avg").
// One thread; the state stays on the GPU (no read-back):
//   L_a' = L_avg + (L_a - L_avg) * exp(-dt / tau),
//   tau = tau_brighten if L_avg > L_a, else tau_darken.
// On reset (first frame, camera cut) L_a' = L_avg: the first frame starts adapted.
// Bindings: post (uniform), measured (storage: post.luminance result),
// adapted (storage, persistent): (log L_a, L_a, L_avg of this frame, frames since reset).
#import post

@group(0) @binding(0) var<uniform> post: Post;
@group(0) @binding(1) var<storage, read> measured: vec4f;
@group(0) @binding(2) var<storage, read_write> adapted: vec4f;

@compute @workgroup_size(1)
fn cs_main() {
    let l_avg = measured.y;
    let prev = adapted;
    var l_a = l_avg;
    var frames = 0.0;
    // A non-finite state (never expected) restarts adapted instead of spreading.
    let valid = prev.y > 0.0 && prev.y < 3.0e38;
    if (post.adapt.w < 0.5 && valid) {
        let tau = select(post.adapt.z, post.adapt.y, l_avg > prev.y);
        let k = exp(-post.adapt.x / max(tau, 1e-6));
        l_a = l_avg + (prev.y - l_avg) * k;
        frames = prev.w + 1.0;
    }
    adapted = vec4f(log(l_a), l_a, l_avg, frames);
}
