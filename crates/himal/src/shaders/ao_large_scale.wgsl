// O6 large-scale AO (Ryse, SIGGRAPH 2014): occlusion at a scale the screen
// cannot see, from the top-down height field (the L2 sector pool's fade
// heights, passes/skyocc), 4 samples per pixel within 7.5 m, interleaved over
// the 4x4 jitter so the AO blur gathers 16 directions. CPU twin:
// passes/ao/large_scale/reference.rs; docs/techniques/O6.md.

#import math

// The talk's sampling radius (m).
const AO_LS_RADIUS: f32 = 7.5;
// A point whose own column rises this far (m) above it is under a roof.
const AO_LS_COVER: f32 = 2.0;

// Sample k of 4 at jitter (rot, off) in [0, 1)^2: unit horizontal direction
// at angle 2 pi (rot + k / 4) in xz, radius R (k + off + 0.25) / 4.25.
fn ao_ls_sample(k: u32, rot: f32, off: f32) -> vec3f {
    let a = 2.0 * PI * (rot + f32(k) * 0.25);
    return vec3f(cos(a), sin(a), AO_LS_RADIUS * (f32(k) + off + 0.25) / 4.25);
}

// Visibility of the sky over one sample: a horizon of elevation e (rise
// above the point over the distance) leaves cos^2 e of a cosine-weighted
// hemisphere open, r^2 / (r^2 + rise^2). Under a roof `roof` m above the
// point (its own column rises more than AO_LS_COVER; else 0) a sample that
// rises too continues the roof, no sky that way; one that does not lies
// beyond the roof's edge, which rises at least `roof` at less than r.
fn ao_ls_visibility(rise: f32, r: f32, roof: f32) -> f32 {
    let up = max(rise, 0.0);
    if (roof > 0.0) {
        if (up > 0.0) {
            return 0.0;
        }
        return (r * r) / (r * r + roof * roof);
    }
    return (r * r) / (r * r + up * up);
}

// The roof over a point whose own column rises `rise` above it: the rise
// when above AO_LS_COVER, else 0 (open sky).
fn ao_ls_roof(rise: f32) -> f32 {
    return select(0.0, rise, rise > AO_LS_COVER);
}

// Weight of a sample in direction d (xz) for normal n: 1 along the ground,
// fading to 0 behind a wall (directions into the surface see nothing).
fn ao_ls_weight(n: vec3f, d: vec2f) -> f32 {
    return saturate(1.0 + dot(n.xz, d));
}
