//! CPU twins of `simulate.wgsl` (one tree slot's frame) and of the vertex
//! stage's bend (`shaders/object_vertex.wgsl`, `tree_world`), in the same
//! order of operations.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};

use super::SimFrame;
use crate::gpu_scene::trees::RigBoneGpu;
use crate::scene::tree::rig::BONES;
use crate::scene::wind::WindGpu;

/// `bend_target`: gain |u| u, no longer than the bone's largest angle.
pub fn bend_target(bone: &RigBoneGpu, u: Vec2) -> Vec2 {
    let t = bone.sample[3] * u.length() * u;
    let l = t.length();
    if l > bone.dynamics[2] {
        t * (bone.dynamics[2] / l)
    } else {
        t
    }
}

/// `bend_rotation`: |theta| about (theta.y, 0, -theta.x).
pub fn bend_rotation(theta: Vec2) -> Mat3 {
    let a = theta.length();
    if a < 1e-9 {
        return Mat3::IDENTITY;
    }
    Mat3::from_axis_angle(Vec3::new(theta.y, 0.0, -theta.x) / a, a)
}

/// `rotate_about`: T(c) R T(-c) m.
pub fn rotate_about(r: Mat3, c: Vec3, m: Mat4) -> Mat4 {
    Mat4::from_translation(c) * Mat4::from_mat3(r) * Mat4::from_translation(-c) * m
}

/// A tree's bones in one frame: world transforms and the wind speed at
/// each (V5's waves; 0 with them off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// World transform per bone.
    pub bones: [Mat4; BONES],
    /// Wind speed at each bone (m/s).
    pub speed: [f32; BONES],
}

impl Default for Pose {
    fn default() -> Self {
        Pose {
            bones: [Mat4::IDENTITY; BONES],
            speed: [0.0; BONES],
        }
    }
}

/// One slot's frame: `state` (per bone: theta xy, rate zw) advanced by
/// `frame` in `wind` for a tree placed by `model` with bones `rig`;
/// returns the bones' pose (`waves`: V5 on, the speeds written).
pub fn step_slot(
    rig: &[RigBoneGpu],
    model: Mat4,
    state: &mut [Vec4; BONES],
    frame: &SimFrame,
    wind: &WindGpu,
    waves: bool,
) -> Pose {
    let mut theta = [Vec2::ZERO; BONES];
    let mut rate = [Vec2::ZERO; BONES];
    let mut at = [Vec3::ZERO; BONES];
    for b in 0..BONES {
        at[b] = model.transform_point3(Vec3::from_slice(&rig[b].sample[..3]));
        theta[b] = state[b].truncate().truncate();
        rate[b] = Vec2::new(state[b].z, state[b].w);
        if frame.reset {
            theta[b] = bend_target(&rig[b], wind.at(at[b], frame.t0, 0.0));
            rate[b] = Vec2::ZERO;
        }
    }
    for i in 0..frame.steps {
        let t = frame.t0 + (i + 1) as f32 * frame.h;
        let f = (i + 1) as f32 / frame.steps as f32;
        for b in 0..BONES {
            let bone = &rig[b];
            let target = bend_target(bone, wind.at(at[b], t, f));
            let w = bone.dynamics[0];
            let a = w * w * (target - theta[b]) - 2.0 * bone.dynamics[1] * w * rate[b];
            rate[b] += frame.h * a;
            theta[b] += frame.h * rate[b];
            let l = theta[b].length();
            if l > bone.dynamics[2] {
                theta[b] *= bone.dynamics[2] / l;
            }
        }
    }
    let t1 = frame.t0 + frame.steps as f32 * frame.h;
    let speed = std::array::from_fn(|b| match waves {
        true => wind.at(at[b], t1, 1.0).length(),
        false => 0.0,
    });
    let root = model.transform_point3(Vec3::from_slice(&rig[0].pivot[..3]));
    let w0 = rotate_about(bend_rotation(theta[0]), root, model);
    let bones = std::array::from_fn(|b| {
        state[b] = Vec4::new(theta[b].x, theta[b].y, rate[b].x, rate[b].y);
        if b == 0 {
            return w0;
        }
        let pivot = w0.transform_point3(Vec3::from_slice(&rig[b].pivot[..3]));
        rotate_about(bend_rotation(theta[b]), pivot, w0)
    });
    Pose { bones, speed }
}

/// Metres of V5 wave per m/s at full weight (`BRANCH_MACRO`, `BRANCH_MICRO`).
pub const BRANCH_MACRO: f32 = 0.012;
/// See [`BRANCH_MACRO`].
pub const BRANCH_MICRO: f32 = 0.004;

fn smooth_triangle(x: f32) -> f32 {
    let t = ((x + 0.5).rem_euclid(1.0) * 2.0 - 1.0).abs();
    t * t * (3.0 - 2.0 * t)
}

/// `branch_waves`: V5's smooth triangle waves, macro X, Y, Z and micro X, Z.
pub fn waves(phase: f32, local: Vec3, t: f32, speed: f32, weight: f32) -> Vec3 {
    let m = Vec3::new(
        smooth_triangle(0.31 * t + phase),
        smooth_triangle(0.23 * t + 1.3 * phase),
        smooth_triangle(0.27 * t + 0.7 * phase),
    ) * 2.0
        - Vec3::ONE;
    let vp = local.dot(Vec3::new(0.71, 0.53, 0.37));
    let u = [
        smooth_triangle(1.9 * t + vp + phase) * 2.0 - 1.0,
        smooth_triangle(2.3 * t + 1.7 * vp + phase) * 2.0 - 1.0,
    ];
    (weight * speed) * (BRANCH_MACRO * m + BRANCH_MICRO * Vec3::new(u[0], 0.0, u[1]))
}

/// `tree_world`: a tree vertex at `position` (tree space) with `uv1 =
/// (bone, weight)` placed by `model`, bent by `pose` at time `t`
/// (`inv_height`: 1 / the tree's height; `impostor`: a grid point).
pub fn deform(
    model: Mat4,
    pose: &Pose,
    inv_height: f32,
    position: Vec3,
    uv1: [f32; 2],
    t: f32,
    impostor: bool,
) -> Vec3 {
    let rest = model.transform_point3(position);
    let h = (position.y * inv_height).clamp(0.0, 1.0);
    let bent = pose.bones[0].transform_point3(position);
    let mut world = rest + (bent - rest) * (h * h);
    let phase = 0.13 * model.w_axis.x + 0.17 * model.w_axis.z;
    let b = (uv1[0].max(0.0) + 0.5) as usize;
    if impostor {
        world += waves(phase, position, t, pose.speed[0], h * h);
    } else if uv1[0] >= 0.0 && (1..BONES).contains(&b) {
        world += (pose.bones[b].transform_point3(position) - bent) * uv1[1];
        world += waves(phase + 1.7 * b as f32, position, t, pose.speed[b], uv1[1]);
    }
    world
}

/// `leaf_flutter` (shaders/scene.wgsl): V5's value noise over a card.
pub fn leaf_flutter(uv: Vec2, t: f32) -> Vec2 {
    use crate::scene::vegetation::foliage_hash;
    let p = uv * 5.0 + Vec2::new(1.7, 1.3) * t;
    let i = p.floor();
    let f = p - i;
    let s = f * f * (Vec2::splat(3.0) - 2.0 * f);
    let unit = |h: u32, shift: u32| ((h >> shift) & 255) as f32 / 255.0;
    let c: [Vec2; 4] = std::array::from_fn(|k| {
        let q = (i.x as i32 + (k & 1) as i32, i.y as i32 + (k >> 1) as i32);
        let h = foliage_hash(
            (q.0 as u32)
                .wrapping_mul(1973)
                .wrapping_add((q.1 as u32).wrapping_mul(9277))
                .wrapping_add(26699),
        );
        Vec2::new(unit(h, 0), unit(h, 8)) * 2.0 - Vec2::ONE
    });
    c[0].lerp(c[1], s.x).lerp(c[2].lerp(c[3], s.x), s.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bend_moves_the_top_toward_theta() {
        let r = bend_rotation(Vec2::new(0.1, 0.0));
        let top = r * Vec3::Y;
        assert!(top.x > 0.09 && top.z.abs() < 1e-6);
        let r = bend_rotation(Vec2::new(0.0, -0.2));
        assert!((r * Vec3::Y).z < -0.19);
    }

    #[test]
    fn a_steady_wind_settles_at_the_target() {
        let bone = RigBoneGpu {
            pivot: [0.0, 0.0, 0.0, 10.0],
            sample: [0.0, 5.0, 0.0, 1.0e-3],
            dynamics: [std::f32::consts::TAU * 0.5, 0.3, 0.2, 0.1],
        };
        let rig = [bone; BONES];
        let wind = crate::scene::wind::WindField::new(Vec3::new(5.0, 0.0, 0.0));
        let mut state = [Vec4::ZERO; BONES];
        // 20 s from rest at 60 Hz, no gusts at 0 speed... gusts apply: the
        // mean stays near gain u^2 = 0.025 rad.
        let mut mean = 0.0;
        let mut last = None;
        for k in 0..1200 {
            let t = k as f32 / 60.0;
            let f = SimFrame::advance(last, t);
            last = Some(t);
            step_slot(
                &rig,
                Mat4::IDENTITY,
                &mut state,
                &f,
                &f.gpu(1, &wind, true).wind,
                true,
            );
            if k >= 600 {
                mean += state[0].x / 600.0;
            }
        }
        assert!((mean - 0.025).abs() < 0.01, "{mean}");
        assert!(state[0].y.abs() < 1e-6);
    }
}
