//! CPU twins of `particles.simulate` (shaders/particles.wgsl,
//! `simulate.wgsl`: the same births, hashing, integration and deaths in
//! f32) and of `particles.light` (the light accumulation), for the
//! GPU-versus-CPU tests.

use glam::{Vec3, Vec4};

use super::{EmitterGpu, ParticleGpu, ParticleLightGpu, SimFrame, StepGpu};
use crate::passes::lighting::reference::{local_light_falloff, spot_cone};
use crate::passes::post::reference::luminance;
use crate::passes::shadows::local::LocalLightGpu;

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
        let pos = Vec3::from_slice(&s.origin[..3]) + (v - Vec3::from_slice(&s.drift[..3])) * age;
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
                let f = (s + 1) as f32 / frame.steps_count() as f32;
                let push = frame
                    .field
                    .sources_push(Vec3::from_slice(&p.pos_age[..3]), f);
                let wind = frame.wind + Vec3::new(push.x, 0.0, push.y);
                let (q, b) = step_slot(p, e, ei as u32, r as u32, st, wind);
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

/// `local_light_illuminance` (shaders/shadow.wgsl): illuminance (klux) at
/// `p` from `l` and the unit direction to it; `None` outside its range.
pub fn local_illuminance(l: &LocalLightGpu, p: Vec3) -> Option<(Vec3, Vec3)> {
    let to_l = Vec3::from_slice(&l.position_range[..3]) - p;
    let d = to_l.length();
    let range = l.position_range[3];
    if d >= range || d <= 0.0 {
        return None;
    }
    let dir = to_l / d;
    let mut e = Vec3::from_slice(&l.color_kind[..3]) * local_light_falloff(d, range);
    if l.color_kind[3] > 0.5 {
        let axis = Vec3::from_slice(&l.direction_cos_outer[..3]);
        e *= spot_cone((-dir).dot(axis), l.direction_cos_outer[3], l.params[0]);
    }
    Some((e, dir))
}

/// `particle_light_add`: illuminance `e` from unit direction `l`.
pub fn light_add(acc: ParticleLightGpu, e: Vec3, l: Vec3) -> ParticleLightGpu {
    let w = luminance(e);
    let (e0, d0) = (Vec4::from(acc.e), Vec4::from(acc.d));
    ParticleLightGpu {
        e: (e0 + e.extend(w)).to_array(),
        d: (d0 + (l * w).extend(0.0)).to_array(),
    }
}

/// `particle_light_diffuse`: a white Lambertian particle's radiance
/// (kcd/m²) with normal `n`, E (n . d_mean) / pi.
pub fn light_diffuse(acc: &ParticleLightGpu, n: Vec3) -> Vec3 {
    let d = Vec3::from_slice(&acc.d[..3]) / acc.e[3].max(1e-12);
    Vec3::from_slice(&acc.e[..3]) * (n.dot(d).clamp(0.0, 1.0) / std::f32::consts::PI)
}

/// The per-pixel reference `light_diffuse` approximates: sum over the
/// lights of E_k saturate(n . l_k) / pi.
pub fn exact_diffuse(lights: &[(Vec3, Vec3)], n: Vec3) -> Vec3 {
    lights
        .iter()
        .map(|(e, l)| *e * (n.dot(*l).clamp(0.0, 1.0) / std::f32::consts::PI))
        .sum()
}

/// The light `particles.light` accumulates at `x` (a live particle's
/// centre or a corner of its quad, [`quad_point`]): the sun (`sun_e` klux
/// toward `sun_dir`, visibility `vis`, the shadow filter's result) and
/// `lights`, light k seen with visibility `local_vis(k, x)` (its atlas
/// lookup, `shadows::reference::local_point_visibility`; 1 unshadowed).
pub fn light_point(
    x: Vec3,
    sun_dir: Vec3,
    sun_e: Vec3,
    vis: f32,
    lights: &[LocalLightGpu],
    local_vis: impl Fn(usize, Vec3) -> f32,
) -> ParticleLightGpu {
    let mut acc = light_add(ParticleLightGpu::default(), sun_e * vis, sun_dir);
    acc.d[3] = vis;
    for (k, l) in lights.iter().enumerate() {
        if let Some((e, dir)) = local_illuminance(l, x) {
            acc = light_add(acc, e * local_vis(k, x), dir);
        }
    }
    acc
}

/// `particle_corner`: the quad's corners in [-1, 1]², counter-clockwise
/// from the bottom left (the order of `particles.light`'s records).
pub const CORNERS: [glam::Vec2; 4] = [
    glam::Vec2::new(-1.0, -1.0),
    glam::Vec2::new(1.0, -1.0),
    glam::Vec2::new(1.0, 1.0),
    glam::Vec2::new(-1.0, 1.0),
];

/// `particle_quad_point`: point `c` of the camera-facing quad, `size`
/// metres wide, of a particle at `x` (world-to-view matrix `view`).
pub fn quad_point(view: glam::Mat4, x: Vec3, size: f32, c: glam::Vec2) -> Vec3 {
    let row = |k: usize| Vec3::new(view.x_axis[k], view.y_axis[k], view.z_axis[k]);
    x + (row(0) * c.x + row(1) * c.y) * (0.5 * size)
}

/// `particle_size`: an emitter's size (m) at `age`, linear over its life.
pub fn particle_size(e: &EmitterGpu, age: f32) -> f32 {
    let t = (age / e.motion[0]).clamp(0.0, 1.0);
    e.size[0] + (e.size[1] - e.size[0]) * t
}

/// `particle_sprite_normal`: the disc sprite's normal at corner
/// coordinates `c` (|c|² = `r2` < 1) under world-to-view matrix `view`.
pub fn sprite_normal(view: glam::Mat4, c: glam::Vec2, r2: f32) -> Vec3 {
    let t = c.extend((1.0 - r2).max(0.0).sqrt());
    sprite_normal_mapped(view, t, glam::Vec2::X)
}

/// `particle_sprite_rotate`: quad point `c` seen in a sprite turned by
/// `rot` = (cos a, sin a): R(a) c.
pub fn sprite_rotate(c: glam::Vec2, rot: glam::Vec2) -> glam::Vec2 {
    glam::Vec2::new(rot.x * c.x - rot.y * c.y, rot.y * c.x + rot.x * c.y)
}

/// `particle_sprite_normal_mapped`: the world normal of sprite-space
/// normal `t` (x right, y up, z toward the camera) on a quad turned by
/// `rot` against its sprite (t's xy turned back by −a).
pub fn sprite_normal_mapped(view: glam::Mat4, t: Vec3, rot: glam::Vec2) -> Vec3 {
    let row = |k: usize| Vec3::new(view.x_axis[k], view.y_axis[k], view.z_axis[k]);
    let q = glam::Vec2::new(rot.x * t.x + rot.y * t.y, rot.x * t.y - rot.y * t.x);
    (row(0) * q.x + row(1) * q.y + row(2) * t.z).normalize()
}

/// `particle_sprite_angle`: the sprite's angle on the quad of `slot`, as
/// (cos a, sin a).
pub fn sprite_angle(slot: u32) -> glam::Vec2 {
    let a = (pcg(slot ^ 0x9e37_79b9) >> 8) as f32 / 16_777_216.0 * 2.0 * std::f32::consts::PI;
    glam::Vec2::new(a.cos(), a.sin())
}

/// Twin of `particles.sort`: the slot drawn at each instance. Inside each
/// emitter's ring (`slots` = [first, capacity]) the live particles far to
/// near along `forward` from `eye` (view depth, f32 as on the GPU), then
/// the dead; ties by slot. `sort` off: ring order.
pub fn draw_order(
    particles: &[ParticleGpu],
    emitters: &[super::EmitterGpu],
    eye: Vec3,
    forward: Vec3,
    sort: bool,
) -> Vec<u32> {
    let mut order: Vec<u32> = (0..particles.len() as u32).collect();
    for e in emitters {
        let [first, cap, ..] = e.slots;
        if !sort {
            continue;
        }
        let key = |s: u32| {
            let p = &particles[s as usize];
            if p.vel_alive[3] > 0.5 {
                (Vec3::from_slice(&p.pos_age[..3]) - eye).dot(forward)
            } else {
                -3.0e38
            }
        };
        let ring = &mut order[first as usize..(first + cap) as usize];
        ring.sort_by(|&a, &b| key(b).total_cmp(&key(a)).then(a.cmp(&b)));
    }
    order
}
