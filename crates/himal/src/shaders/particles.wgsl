// Particles (TECHNIQUES E4): the buffers' structs shared by
// particles.simulate, particles.light and forward.particles, the spawn
// hash, one simulation step of one slot, and the light accumulation
// (Ryse: per vertex, the lights' illuminance and their intensity-weighted
// mean direction). CPU twin: passes/particles/reference.rs (`step_slot`,
// `spawn_random`, `LightAcc`).
#import color
#import math

// One slot of the particle buffer (twin: `ParticleGpu`).
struct Particle {
    // xyz: position (m), w: age (s)
    pos_age: vec4f,
    // xyz: velocity (m/s), w: 1 alive, 0 dead
    vel_alive: vec4f,
}

// One emitter (twin: `EmitterGpu`).
struct ParticleEmitter {
    // xyz: position at time 0 (m; ParticleStep.origin: where it is), w: births per second
    position_rate: vec4f,
    // xyz: initial velocity (m/s), w: spread (m/s per axis)
    velocity_spread: vec4f,
    // x: lifetime (s), y: downward acceleration (m/s^2), z: wind response (1/s)
    motion: vec4f,
    // x: size at birth, y: size at death (m)
    size: vec4f,
    color_start: vec4f,
    color_end: vec4f,
    // x: first slot in the particle buffer, y: capacity (ring length)
    slots: vec4u,
}

// One emitter's births in one step (twin: `StepGpu`).
struct ParticleStep {
    // x: ring slot of the first birth, y: births (<= capacity),
    // z: number of the first birth (mod 2^32), w: the step's tick (frame index)
    spawn: vec4u,
    // x: age of the first birth at the step's end (s), y: step length (s),
    // zw: unused
    time: vec4f,
    // xyz: the emitter's position at the step's end (m)
    origin: vec4f,
    // xyz: its mean velocity over the step (m/s; riding a moving object)
    drift: vec4f,
}

// PCG hash (Jarzynski and Olano 2020).
fn particle_pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// Three numbers in [0, 1) from (emitter, particle number, tick): no random
// state, the same on every run and on the CPU.
fn particle_random(emitter: u32, n: u32, tick: u32) -> vec3f {
    let h = particle_pcg(emitter ^ particle_pcg(n ^ particle_pcg(tick)));
    let a = particle_pcg(h);
    let b = particle_pcg(a);
    let c = particle_pcg(b);
    return vec3f(f32(a >> 8u), f32(b >> 8u), f32(c >> 8u)) / 16777216.0;
}

// Slot `r` (ring index) of emitter `ei` after step `s`: born this step
// (the ring's slots first_slot .. first_slot + births), else moved
// (semi-implicit Euler: a = (0, -g, 0) + k (wind - v)) and aged; dead at
// its lifetime. Returns the slot and whether it was born.
struct ParticleStepped {
    p: Particle,
    born: bool,
}

fn particle_step(p_in: Particle, e: ParticleEmitter, ei: u32, r: u32, s: ParticleStep, wind: vec3f) -> ParticleStepped {
    var out: ParticleStepped;
    out.p = p_in;
    out.born = false;
    let cap = e.slots.y;
    let k = (r + cap - s.spawn.x) % cap;
    let lifetime = e.motion.x;
    if (k < s.spawn.y) {
        let n = s.spawn.z + k;
        let age = s.time.x - f32(k) / e.position_rate.w;
        let rnd = particle_random(ei, n, s.spawn.w);
        let v = e.velocity_spread.xyz + e.velocity_spread.w * (2.0 * rnd - 1.0);
        // Born where the emitter was `age` ago (on the step's chord).
        out.p.pos_age = vec4f(s.origin.xyz + (v - s.drift.xyz) * age, age);
        out.p.vel_alive = vec4f(v, select(0.0, 1.0, age < lifetime));
        out.born = true;
        return out;
    }
    if (p_in.vel_alive.w < 0.5) {
        return out;
    }
    let dt = s.time.y;
    let a = vec3f(0.0, -e.motion.y, 0.0) + e.motion.z * (wind - p_in.vel_alive.xyz);
    let v = p_in.vel_alive.xyz + a * dt;
    let age = p_in.pos_age.w + dt;
    out.p.pos_age = vec4f(p_in.pos_age.xyz + v * dt, age);
    out.p.vel_alive = vec4f(v, select(0.0, 1.0, age < lifetime));
    return out;
}

// Size (m) and colour at `age` (linear over the life).
fn particle_size(e: ParticleEmitter, age: f32) -> f32 {
    return mix(e.size.x, e.size.y, saturate(age / e.motion.x));
}

fn particle_color(e: ParticleEmitter, age: f32) -> vec4f {
    return mix(e.color_start, e.color_end, saturate(age / e.motion.x));
}

// A particle's incoming light (twin: `ParticleLightGpu`), written by
// particles.light.
struct ParticleLight {
    // rgb: illuminance summed over the sun and the local lights (klux),
    // w: sum of their luminances (the weights)
    e: vec4f,
    // xyz: the luminance-weighted sum of the unit directions to the lights
    // (divide by e.w for their mean), w: the sun's visibility
    d: vec4f,
}

// Adds illuminance `e` arriving from unit direction `l`.
fn particle_light_add(acc: ParticleLight, e: vec3f, l: vec3f) -> ParticleLight {
    let w = luminance(e);
    var out = acc;
    out.e += vec4f(e, w);
    out.d += vec4f(l * w, 0.0);
    return out;
}

// Diffuse radiance (kcd/m^2) of a white Lambertian particle with normal n:
// E (n . d_mean) / pi. d_mean is not renormalised: its length (below 1
// when the lights spread) keeps the sum exact for lights in front of n.
fn particle_light_diffuse(acc: ParticleLight, n: vec3f) -> vec3f {
    let d = acc.d.xyz / max(acc.e.w, 1e-12);
    return acc.e.rgb * (saturate(dot(n, d)) / PI);
}

// particles.light's records per slot: the quad's centre, then its corners.
const PARTICLE_RECORDS: u32 = 5u;

// Corner k (0..3, counter-clockwise from the bottom left) of a particle's
// quad, in [-1, 1]^2.
fn particle_corner(k: u32) -> vec2f {
    let corners = array<vec2f, 4>(vec2f(-1.0, -1.0), vec2f(1.0, -1.0), vec2f(1.0, 1.0), vec2f(-1.0, 1.0));
    return corners[k];
}

// Point c in [-1, 1]^2 of the camera-facing quad of a particle at x, `size`
// metres wide. `view_m`: world -> view (its rows are the camera's axes).
fn particle_quad_point(view_m: mat4x4f, x: vec3f, size: f32, c: vec2f) -> vec3f {
    let right = vec3f(view_m[0].x, view_m[1].x, view_m[2].x);
    let up = vec3f(view_m[0].y, view_m[1].y, view_m[2].y);
    return x + (right * c.x + up * c.y) * (0.5 * size);
}

// The sprite's angle on its quad, from the slot: (cos, sin), so
// neighbouring puffs do not repeat one picture.
fn particle_sprite_angle(slot: u32) -> vec2f {
    let a = f32(particle_pcg(slot ^ 0x9e3779b9u) >> 8u) / 16777216.0 * 2.0 * PI;
    return vec2f(cos(a), sin(a));
}

// Quad point c seen in the sprite, turned by the sprite's angle
// rot = (cos, sin): R(a) c.
fn particle_sprite_rotate(c: vec2f, rot: vec2f) -> vec2f {
    return vec2f(rot.x * c.x - rot.y * c.y, rot.y * c.x + rot.x * c.y);
}

// The world normal of a sprite-space normal t (x right, y up, z toward
// the camera) on a quad whose point c shows sprite point R(a) c: t's xy
// turned back by -a into the quad's axes. `view_m`: world -> view (its
// rows are the camera's axes).
fn particle_sprite_normal_mapped(view_m: mat4x4f, t: vec3f, rot: vec2f) -> vec3f {
    let right = vec3f(view_m[0].x, view_m[1].x, view_m[2].x);
    let up = vec3f(view_m[0].y, view_m[1].y, view_m[2].y);
    let back = vec3f(view_m[0].z, view_m[1].z, view_m[2].z);
    let q = vec2f(rot.x * t.x + rot.y * t.y, rot.x * t.y - rot.y * t.x);
    return normalize(right * q.x + up * q.y + back * t.z);
}

// The disc sprite's per-pixel normal (world): a hemisphere bulging toward
// the camera over the quad's disc, corner c in [-1, 1]^2, r2 = |c|^2 < 1.
fn particle_sprite_normal(view_m: mat4x4f, c: vec2f, r2: f32) -> vec3f {
    return particle_sprite_normal_mapped(view_m, vec3f(c, sqrt(max(1.0 - r2, 0.0))), vec2f(1.0, 0.0));
}
