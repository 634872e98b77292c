// vegetation.ripple (V2 grass): one step of the damped wave equation per
// frame on the window of cells around the camera (shaders/ripple.wgsl),
// one thread per cell:
//   a = c^2 lap(h) - omega^2 h - gamma v + F,   v' = v + dt a,   h' = h + dt v'
// F = -K sum_sources strength (1 - (d / radius)^2)^2 (d horizontal): a
// source presses the grass down and the wave runs outward. Reads half z of
// the header, writes half 1 - z and the gradient of the read heights
// (central differences) for the draws; a reset writes the sources' static
// depression F / omega^2 and its gradient. CPU twin: ripple.rs `step`.
#import wind
#import ripple

struct RippleStep {
    // x: time at the end of the step (s); y: 1 = start from flat
    time: vec4f,
    wind: Wind,
}

@group(0) @binding(0) var<uniform> step: RippleStep;
@group(0) @binding(1) var<storage, read_write> ripple: Ripple;

// Restoring frequency (rad/s), damping (1/s), push per m/s of source (m/s^2).
const RIPPLE_OMEGA: f32 = 5.0;
const RIPPLE_DAMPING: f32 = 1.5;
const RIPPLE_PUSH: f32 = 1.5;

fn ripple_force(p: vec2f) -> f32 {
    var f = 0.0;
    let n = min(u32(step.wind.global.w), 8u);
    for (var i = 0u; i < n; i++) {
        let s = step.wind.sources[i];
        let d = p - s.finish.xz;
        let q = min(dot(d, d) / (s.start.w * s.start.w), 1.0);
        f -= RIPPLE_PUSH * s.finish.w * (1.0 - q) * (1.0 - q);
    }
    return f;
}

fn ripple_read(c: vec2i, half: u32) -> vec2f {
    if (step.time.y != 0.0) {
        return vec2f(0.0);
    }
    return ripple_entry(c, half);
}

@compute @workgroup_size(8, 8)
fn cs_step(@builtin(global_invocation_id) id: vec3u) {
    let h = ripple.header;
    let n = h.window.w;
    if (id.x >= u32(n) || id.y >= u32(n)) {
        return;
    }
    let c = h.window.xy + vec2i(id.xy);
    let src = u32(h.window.z);
    let dst = 1u - src;
    let dx = h.params.x;
    let dt = h.params.y;
    let speed = h.params.z;
    let own = ripple_read(c, src);
    let xp = ripple_read(c + vec2i(1, 0), src).x;
    let xm = ripple_read(c - vec2i(1, 0), src).x;
    let zp = ripple_read(c + vec2i(0, 1), src).x;
    let zm = ripple_read(c - vec2i(0, 1), src).x;
    let lap = (xp + xm + zp + zm - 4.0 * own.x) / (dx * dx);
    let centre = (vec2f(c) + 0.5) * dx;
    let a = speed * speed * lap - RIPPLE_OMEGA * RIPPLE_OMEGA * own.x - RIPPLE_DAMPING * own.y + ripple_force(centre);
    let v = own.y + dt * a;
    let height = own.x + dt * v;
    let slot = ripple_slot(c, n);
    let nn = u32(n * n);
    let tag = vec2f(c);
    if (step.time.y != 0.0) {
        // A reset starts from the sources' static depression, F / omega^2.
        let w2 = RIPPLE_OMEGA * RIPPLE_OMEGA;
        let e = vec2f(dx, 0.0);
        let g = vec2f(ripple_force(centre + e.xy) - ripple_force(centre - e.xy),
                      ripple_force(centre + e.yx) - ripple_force(centre - e.yx)) / (2.0 * dx * w2);
        ripple.cells[dst * nn + slot] = vec4f(ripple_force(centre) / w2, 0.0, tag);
        ripple.cells[(2u + dst) * nn + slot] = vec4f(g, tag);
        return;
    }
    ripple.cells[dst * nn + slot] = vec4f(height, v, tag);
    ripple.cells[(2u + dst) * nn + slot] = vec4f((xp - xm) / (2.0 * dx), (zp - zm) / (2.0 * dx), tag);
}
