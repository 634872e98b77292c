// ao.hbao: horizon-based ambient occlusion from the depth buffer (TECHNIQUES O1), at
// AO resolution (half or full), plus the continuity mask of the selective temporal
// filter (O2, pass 1 of the talk).
// Target: Rg16Float (x: AO in [0,1], 1 = unoccluded; y: 1 = continuous, 0 = discontinuous).
// Bindings: params (AoParams), depth (full-res device depth), jitter_load (4x4 rotation
// fraction and step offset).
// Sources: Bavoil, Sainz, Dimitrov, "Image-Space Horizon-Based Ambient Occlusion" (2008);
// Bavoil, Andersson, "Stable SSAO in Battlefield 3 with Selective Temporal Filtering" (GDC 2012).
// SSDO (O4): Rgba16Float (AO, continuity, c1, c2), the first harmonic of each
// direction's occlusion over the slice angle a: c1 = 2/D sum occ_d cos a_d,
// c2 = 2/D sum occ_d sin a_d (times strength); its constant is 1 - AO.
// CPU twin: passes/ao/reference.rs `hbao`, `hbao_ssdo`.
#import view
#import ao
#import math
#import fullscreen

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
override SSDO: bool = false;

@group(0) @binding(0) var<storage, read> params: AoParams;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var jitter_load: texture_2d<f32>;

// View-space position of AO texel q: the full-res depth sample at q * scale (clamped to the screen).
fn texel_position(q: vec2i) -> vec3f {
    let qc = clamp(q, vec2i(0), vec2i(params.ao_size.xy) - 1);
    let full = qc * i32(params.hbao_steps.z);
    let z = ao_linear_depth(params, textureLoad(depth, full, 0));
    // The pixel centre sampled the scene at the jittered position (sample offset j).
    let uv = (vec2f(full) + 0.5 + params.jitter.xy) * params.full_size.zw;
    return ao_view_position(params, uv, z);
}

// The shorter of two one-sided differences (a zero difference at the screen border loses).
fn nearer(a: vec3f, b: vec3f) -> vec3f {
    let la = dot(a, a);
    let lb = dot(b, b);
    if (la == 0.0) {
        return b;
    }
    if (lb == 0.0 || la < lb) {
        return a;
    }
    return b;
}

// Occlusion along one screen direction: march S steps, raise the horizon, add
// W(r) (sin h_new - sin h_old) with W(r) = 1 - r^2 / R^2. Samples along a screen
// direction lie in the slice plane spanned by v (towards the camera) and the
// direction; elevations are measured from the plane normal to v in that slice.
fn integrate_direction(p: vec3f, n: vec3f, q: vec2i, dir: vec2f, step_px: f32, offset: f32) -> f32 {
    let v = normalize(-p);
    let t3 = vec3f(dir.x, -dir.y, 0.0); // screen y down = view y down
    // Tangent: the line where the tangent plane cuts the slice, oriented so that
    // it moves along `dir` on screen.
    var t = cross(n, cross(t3, v));
    let t_len = length(t);
    var sin_t = 0.0;
    if (t_len > 1e-12) {
        t /= t_len;
        let screen = t.xy * -p.z + p.xy * t.z;
        t = select(t, -t, dot(screen, t3.xy) < 0.0);
        sin_t = dot(t, v);
    }
    var sin_h = sin(min(asin(clamp(sin_t, -1.0, 1.0)) + params.hbao.w, HALF_PI));
    var ray = offset * step_px + 1.0;
    var occlusion = 0.0;
    let steps = u32(params.hbao_steps.y);
    for (var s = 0u; s < steps; s++) {
        let sq = vec2i(floor(vec2f(q) + 0.5 + dir * ray));
        // Off screen the depth buffer knows nothing: stop rather than clamp
        // (clamped samples leave the slice and self-occlude planes).
        if (any(sq < vec2i(0)) || any(sq >= vec2i(params.ao_size.xy))) {
            break;
        }
        let d = texel_position(sq) - p;
        let d2 = dot(d, d);
        if (d2 > 0.0 && d2 < params.hbao.x * params.hbao.x) {
            let sin_s = dot(d, v) * inverseSqrt(d2);
            if (sin_s > sin_h) {
                occlusion += (1.0 - d2 * params.hbao.y) * (sin_s - sin_h);
                sin_h = sin_s;
            }
        }
        ray += step_px;
    }
    return occlusion;
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let q = vec2i(frag.xy);
    let p = texel_position(q);
    if (-p.z >= AO_SKY_DEPTH) {
        return vec4f(1.0, 0.0, 0.0, 0.0);
    }
    // Normal from the nearer neighbour of each pair; the same differences
    // classify the pixel (continuous when both are shorter than L).
    let dx = nearer(texel_position(q + vec2i(1, 0)) - p, p - texel_position(q - vec2i(1, 0)));
    let dy = nearer(texel_position(q + vec2i(0, 1)) - p, p - texel_position(q - vec2i(0, 1)));
    let continuous = length(dx) < params.stf.z && length(dy) < params.stf.z;
    var n = cross(dx, dy);
    let len = length(n);
    n = select(vec3f(0.0, 0.0, 1.0), n / max(len, 1e-20), len > 1e-20);
    if (dot(n, ao_ray(params, p)) > 0.0) {
        n = -n;
    }
    let mask = select(0.0, 1.0, continuous);
    let radius_px = min(params.hbao.x * params.proj.w / ao_clip_w(params, -p.z), params.hbao_steps.w);
    if (radius_px < 1.0) {
        return vec4f(1.0, mask, 0.0, 0.0);
    }
    let steps = params.hbao_steps.y;
    let step_px = radius_px / (steps + 1.0);
    let jitter = textureLoad(jitter_load, q & vec2i(3), 0);
    let directions = u32(params.hbao_steps.x);
    let sector = TAU / params.hbao_steps.x;
    var occlusion = 0.0;
    var harmonic = vec2f(0.0);
    for (var d = 0u; d < directions; d++) {
        let a = (f32(d) + jitter.x) * sector;
        let dir = vec2f(cos(a), sin(a));
        let occ = integrate_direction(p, n, q, dir, step_px, jitter.y);
        occlusion += occ;
        if (SSDO) {
            harmonic += occ * dir;
        }
    }
    let ao = clamp(1.0 - occlusion / params.hbao_steps.x * params.hbao.z, 0.0, 1.0);
    if (SSDO) {
        return vec4f(ao, mask, harmonic * (2.0 / params.hbao_steps.x * params.hbao.z));
    }
    return vec4f(ao, mask, 0.0, 0.0);
}
