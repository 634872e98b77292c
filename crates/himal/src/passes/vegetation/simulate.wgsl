// vegetation.simulate (V2): one thread per tree slot. Each of its four
// bones (trunk, three branch sectors; scene/tree/rig.rs) is a damped
// spring on a 2D bend angle theta (x, z: the horizontal direction its top
// moves, radians), driven toward gain |u| u by the wind u at the bone's
// sample point (shaders/wind.wgsl):
//   theta'' = omega^2 (clamp(gain |u| u) - theta) - 2 zeta omega theta'
// semi-implicit Euler over this frame's fixed steps; then the bones'
// world transforms, once per tree: W0 = rotation by |theta0| about
// (theta0.z, 0, -theta0.x) around the root's world position, times the
// model; Wb = the same for bone b around its pivot moved by W0, times W0.
// Written into the tree's bone records in `objects` (model now, prev_model
// the previous frame's: motion vectors) with the wind speed at each bone
// (params.y now, z before: V5's branch waves). CPU twin: reference.rs
// `step_slot`.
// docs/techniques/V2.md.
#import scene
#import wind

struct RigBone {
    // pivot (tree space); w: length
    pivot: vec4f,
    // wind sample point (tree space); w: gain (rad per (m/s)^2)
    sample: vec4f,
    // omega (rad/s), damping ratio, largest angle (rad), 1 / height
    dynamics: vec4f,
}

struct Slot {
    object: u32,
    rig: u32,
    first_record: u32,
    pad: u32,
}

struct Sim {
    // slots, steps this frame, reset (1: start from the equilibrium),
    // V5 branch waves (1: on)
    counts: vec4u,
    // time at the start of the steps (s), step (s), 0, 0
    time: vec4f,
    wind: Wind,
}

@group(0) @binding(0) var<uniform> sim: Sim;
@group(0) @binding(1) var<storage, read> slots: array<Slot>;
@group(0) @binding(2) var<storage, read> rigs: array<RigBone>;
@group(0) @binding(3) var<storage, read_write> state: array<vec4f>;
@group(0) @binding(4) var<storage, read_write> objects: array<Object>;

// The spring's target: gain |u| u, no longer than the bone's largest angle.
fn bend_target(bone: RigBone, u: vec2f) -> vec2f {
    let t = bone.sample.w * length(u) * u;
    let l = length(t);
    if (l > bone.dynamics.z) {
        return t * (bone.dynamics.z / l);
    }
    return t;
}

// Rotation by |theta| about the horizontal axis (theta.y, 0, -theta.x):
// the bone's top moves toward (theta.x, 0, theta.y). Rodrigues.
fn bend_rotation(theta: vec2f) -> mat3x3f {
    let a = length(theta);
    if (a < 1e-9) {
        return mat3x3f(vec3f(1.0, 0.0, 0.0), vec3f(0.0, 1.0, 0.0), vec3f(0.0, 0.0, 1.0));
    }
    let k = vec3f(theta.y, 0.0, -theta.x) / a;
    let c = cos(a);
    let s = sin(a);
    let t = 1.0 - c;
    // Columns.
    return mat3x3f(
        vec3f(t * k.x * k.x + c, t * k.x * k.y + s * k.z, t * k.x * k.z - s * k.y),
        vec3f(t * k.x * k.y - s * k.z, t * k.y * k.y + c, t * k.y * k.z + s * k.x),
        vec3f(t * k.x * k.z + s * k.y, t * k.y * k.z - s * k.x, t * k.z * k.z + c));
}

// The rotation r about world point c applied after m: T(c) R T(-c) m.
fn rotate_about(r: mat3x3f, c: vec3f, m: mat4x4f) -> mat4x4f {
    let l = mat3x3f(m[0].xyz, m[1].xyz, m[2].xyz);
    let rl = r * l;
    let t = r * (m[3].xyz - c) + c;
    return mat4x4f(vec4f(rl[0], 0.0), vec4f(rl[1], 0.0), vec4f(rl[2], 0.0), vec4f(t, 1.0));
}

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let si = id.x;
    if (si >= sim.counts.x) {
        return;
    }
    let slot = slots[si];
    let model = objects[slot.object].model;
    let steps = sim.counts.y;
    let h = sim.time.y;
    var theta: array<vec2f, 4>;
    var rate: array<vec2f, 4>;
    var at: array<vec3f, 4>;
    for (var b = 0u; b < 4u; b++) {
        let bone = rigs[slot.rig * 4u + b];
        at[b] = (model * vec4f(bone.sample.xyz, 1.0)).xyz;
        let s = state[si * 4u + b];
        theta[b] = s.xy;
        rate[b] = s.zw;
        if (sim.counts.z != 0u) {
            theta[b] = bend_target(bone, wind_at(sim.wind, at[b], sim.time.x, 0.0));
            rate[b] = vec2f(0.0);
        }
    }
    for (var i = 0u; i < steps; i++) {
        let t = sim.time.x + f32(i + 1u) * h;
        let f = f32(i + 1u) / f32(steps);
        for (var b = 0u; b < 4u; b++) {
            let bone = rigs[slot.rig * 4u + b];
            let goal = bend_target(bone, wind_at(sim.wind, at[b], t, f));
            let w = bone.dynamics.x;
            let a = w * w * (goal - theta[b]) - 2.0 * bone.dynamics.y * w * rate[b];
            rate[b] += h * a;
            theta[b] += h * rate[b];
            let l = length(theta[b]);
            if (l > bone.dynamics.z) {
                theta[b] *= bone.dynamics.z / l;
            }
        }
    }
    // V5: the wind speed at each bone drives its branch waves (0: off).
    var speed: array<f32, 4>;
    for (var b = 0u; b < 4u; b++) {
        speed[b] = 0.0;
        if (sim.counts.w != 0u) {
            speed[b] = length(wind_at(sim.wind, at[b], sim.time.x + f32(steps) * h, 1.0));
        }
    }
    let trunk = rigs[slot.rig * 4u];
    let root = (model * vec4f(trunk.pivot.xyz, 1.0)).xyz;
    let w0 = rotate_about(bend_rotation(theta[0]), root, model);
    for (var b = 0u; b < 4u; b++) {
        state[si * 4u + b] = vec4f(theta[b], rate[b]);
        var wb = w0;
        if (b > 0u) {
            let pivot = (w0 * vec4f(rigs[slot.rig * 4u + b].pivot.xyz, 1.0)).xyz;
            wb = rotate_about(bend_rotation(theta[b]), pivot, w0);
        }
        let r = slot.first_record + b;
        var prev = objects[r].model;
        var prev_speed = objects[r].params.y;
        if (sim.counts.z != 0u) {
            prev = wb;
            prev_speed = speed[b];
        }
        objects[r].prev_model = prev;
        objects[r].model = wb;
        objects[r].params = vec4f(objects[r].params.x, speed[b], prev_speed, 0.0);
    }
}
