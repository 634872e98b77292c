//! Moving objects: a horizontal circular path at constant speed (`orbit`),
//! and glTF animation (`gltf::Animated`) on top of it.
//!
//! The object's placed `position` is the path's centre. At time `t`
//! (seconds) the object sits at
//! `centre + Ry(theta(t)) * (radius, 0, 0)` with
//! `theta(t) = phase + 2 pi t / period` (radians; `Ry` is the right-handed
//! rotation about +Y, so a positive period runs counter-clockwise seen from
//! above and a negative one clockwise). The speed is `2 pi radius / |period|`
//! metres per second. With `turn = true` the object also yaws by `theta(t)`
//! (it keeps its pose relative to the path, like a cart); otherwise it only
//! translates, so every point of it moves by the same vector.

use glam::{Mat4, Quat, Vec3};

use super::gltf::Animated;

/// A closed circular path over the ground (scene key `orbit`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    /// World centre of the circle (the object's placed position).
    pub centre: Vec3,
    /// Metres, > 0.
    pub radius: f32,
    /// Seconds per revolution, non-zero; negative runs clockwise seen from above.
    pub period: f32,
    /// Angle at t = 0 in radians (scene file: degrees).
    pub phase: f32,
    /// Yaw with the path (true) or translate only (false).
    pub turn: bool,
}

impl Orbit {
    /// Path angle theta(t) in radians.
    pub fn angle_at(&self, t: f32) -> f32 {
        // Reduce t modulo the period first: keeps f32 precise over long sequences.
        let cycles = (t / self.period).rem_euclid(1.0);
        self.phase + std::f32::consts::TAU * cycles
    }

    /// Offset from the centre at time `t`.
    pub fn offset_at(&self, t: f32) -> Vec3 {
        let a = self.angle_at(t);
        Vec3::new(a.cos(), 0.0, -a.sin()) * self.radius
    }

    /// Object to world at time `t`; `base` is the object's transform placed
    /// at the centre (translation = centre).
    pub fn transform_at(&self, base: &Mat4, t: f32) -> Mat4 {
        let moved = Mat4::from_translation(self.offset_at(t));
        if self.turn {
            let yaw = Quat::from_rotation_y(self.angle_at(t));
            let about_centre = Mat4::from_translation(self.centre)
                * Mat4::from_quat(yaw)
                * Mat4::from_translation(-self.centre);
            moved * about_centre * *base
        } else {
            moved * *base
        }
    }
}

/// How an object changes over time: a path, a glTF animation, or both
/// (a skinned character walking a circle).
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// The path; `None` keeps `base`.
    pub orbit: Option<Orbit>,
    /// Transform at the orbit's centre (before the path offset).
    pub base: Mat4,
    /// The object's glTF node animation or skin, applied before `base`.
    pub animated: Option<Animated>,
}

impl Motion {
    /// A path alone.
    pub fn orbit(orbit: Orbit, base: Mat4) -> Self {
        Motion {
            orbit: Some(orbit),
            base,
            animated: None,
        }
    }

    /// Object to world at `t`: path(base) · animated node.
    pub fn transform_at(&self, t: f32) -> Mat4 {
        let placed = match &self.orbit {
            Some(o) => o.transform_at(&self.base, t),
            None => self.base,
        };
        match &self.animated {
            Some(a) => placed * a.local_at(t),
            None => placed,
        }
    }
}
