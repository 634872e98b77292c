// particles.simulate (E4): one thread per particle slot runs every step
// of this frame (one step per frame; the steps of a pre-warm on a reset)
// for its slot, then counts it. Slots are independent: no sorting, no
// compaction, a fixed-capacity ring per emitter. CPU twin:
// passes/particles/reference.rs `simulate`.
#import particles
#import wind

struct SimParams {
    // x: emitters, y: steps, z: slots in all, w: 1 = start from empty
    counts: vec4u,
    // xyz: wind velocity (m/s)
    wind: vec4f,
    // V2: the scene's local wind sources (global zero), over the frame's steps
    field: Wind,
}

@group(0) @binding(0) var<storage, read> sim: SimParams;
@group(0) @binding(1) var<storage, read> emitters: array<ParticleEmitter>;
@group(0) @binding(2) var<storage, read> steps: array<ParticleStep>;
@group(0) @binding(3) var<storage, read_write> particles: array<Particle>;
// Per emitter: x alive after the frame, y births this frame.
@group(0) @binding(4) var<storage, read_write> counters: array<atomic<u32>>;

@compute @workgroup_size(64)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let i = id.x;
    if (i >= sim.counts.z) {
        return;
    }
    var ei = 0u;
    for (var k = 0u; k < sim.counts.x; k++) {
        if (i >= emitters[k].slots.x) {
            ei = k;
        }
    }
    let e = emitters[ei];
    let r = i - e.slots.x;
    var p = particles[i];
    if (sim.counts.w == 1u) {
        p = Particle(vec4f(0.0), vec4f(0.0));
    }
    var born = 0u;
    for (var s = 0u; s < sim.counts.y; s++) {
        // V2: the local sources push where the particle is.
        let push = wind_sources_push(sim.field, p.pos_age.xyz, f32(s + 1u) / f32(sim.counts.y));
        let wind = sim.wind.xyz + vec3f(push.x, 0.0, push.y);
        let stepped = particle_step(p, e, ei, r, steps[s * sim.counts.x + ei], wind);
        p = stepped.p;
        born += select(0u, 1u, stepped.born);
    }
    particles[i] = p;
    if (p.vel_alive.w > 0.5) {
        atomicAdd(&counters[2u * ei], 1u);
    }
    if (born > 0u) {
        atomicAdd(&counters[2u * ei + 1u], born);
    }
}
