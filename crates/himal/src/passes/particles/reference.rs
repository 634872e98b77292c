//! CPU twin of `particles.simulate` (shaders/particles.wgsl,
//! `simulate.wgsl`): the same births, hashing, integration and deaths in
//! f32, for the GPU-versus-CPU tests.

use glam::{Vec3, Vec4};

use super::{EmitterGpu, ParticleGpu, SimFrame, StepGpu};

/// `particle_pcg` (PCG hash, Jarzynski and Olano 2020).
pub fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

/// `particle_random`: three numbers in [0, 1) from (emitter, particle
/// number, tick).
pub fn spawn_random(emitter: u32, n: u32, tick: u32) -> Vec3 {
    let h = pcg(emitter ^ pcg(n ^ pcg(tick)));
    let a = pcg(h);
    let b = pcg(a);
    let c = pcg(b);
    Vec3::new((a >> 8) as f32, (b >> 8) as f32, (c >> 8) as f32) / 16777216.0
}

/// `particle_step`: slot `r` of emitter `ei` after step `s`; true when
/// it was born in it.
pub fn step_slot(
    p: ParticleGpu,
    e: &EmitterGpu,
    ei: u32,
    r: u32,
    s: &StepGpu,
    wind: Vec3,
) -> (ParticleGpu, bool) {
    let cap = e.slots[1];
    let k = (r + cap - s.spawn[0]) % cap;
    let lifetime = e.motion[0];
    let rate = e.position_rate[3];
    if k < s.spawn[1] {
        let n = s.spawn[2].wrapping_add(k);
        let age = s.time[0] - k as f32 / rate;
        let rnd = spawn_random(ei, n, s.spawn[3]);
        let vs = Vec4::from(e.velocity_spread);
        let v = vs.truncate() + vs.w * (2.0 * rnd - Vec3::ONE);
        let pos = Vec3::from_slice(&e.position_rate[..3]) + v * age;
        let alive = if age < lifetime { 1.0 } else { 0.0 };
        return (
            ParticleGpu {
                pos_age: pos.extend(age).to_array(),
                vel_alive: v.extend(alive).to_array(),
            },
            true,
        );
    }
    if p.vel_alive[3] < 0.5 {
        return (p, false);
    }
    let dt = s.time[1];
    let v0 = Vec3::from_slice(&p.vel_alive[..3]);
    let a = Vec3::new(0.0, -e.motion[1], 0.0) + e.motion[2] * (wind - v0);
    let v = v0 + a * dt;
    let age = p.pos_age[3] + dt;
    let pos = Vec3::from_slice(&p.pos_age[..3]) + v * dt;
    let alive = if age < lifetime { 1.0 } else { 0.0 };
    (
        ParticleGpu {
            pos_age: pos.extend(age).to_array(),
            vel_alive: v.extend(alive).to_array(),
        },
        false,
    )
}

/// `cs_main` over every slot: `particles` after `frame`'s steps, and per
/// emitter (alive, births) as the counters hold them.
pub fn simulate(particles: &mut [ParticleGpu], frame: &SimFrame) -> Vec<[u32; 2]> {
    let ne = frame.emitters.len();
    let mut counters = vec![[0u32; 2]; ne];
    for (ei, e) in frame.emitters.iter().enumerate() {
        let (first, cap) = (e.slots[0] as usize, e.slots[1] as usize);
        for r in 0..cap {
            let mut p = if frame.reset {
                ParticleGpu::default()
            } else {
                particles[first + r]
            };
            let mut born = 0;
            for s in 0..frame.steps_count() {
                let st = &frame.steps[s * ne + ei];
                let (q, b) = step_slot(p, e, ei as u32, r as u32, st, frame.wind);
                p = q;
                born += b as u32;
            }
            particles[first + r] = p;
            counters[ei][0] += (p.vel_alive[3] > 0.5) as u32;
            counters[ei][1] += born;
        }
    }
    counters
}
