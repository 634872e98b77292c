//! Pinhole camera: right-handed, Y up, reverse-Z with an infinite far plane;
//! or an orthographic one (glTF's), reverse-Z between near and far.

use glam::{Mat4, Vec3, Vec4};

/// Parallel projection: the view's half height and its far plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orthographic {
    /// Half the view's height in metres (glTF `ymag`); the width follows
    /// the image's aspect.
    pub half_height: f32,
    /// Far plane distance in metres (depth 0 there).
    pub far: f32,
}

/// A perspective (or orthographic) camera in world space.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position in world space (metres, Y up).
    pub position: Vec3,
    /// Unit view direction.
    pub forward: Vec3,
    /// World up hint (need not be orthogonal to `forward`, must not be parallel).
    pub up: Vec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f32,
    /// Near plane distance in metres (depth 1 there).
    pub near: f32,
    /// `Some`: an orthographic camera (`fov_y_deg` then only sizes what
    /// needs an angle, e.g. the terrain's detail).
    pub orthographic: Option<Orthographic>,
}

/// Near plane used when a scene file does not give one.
pub const DEFAULT_NEAR: f32 = 0.1;

/// An up vector that is not parallel to `forward` (Y unless looking straight up or down).
pub fn up_for(forward: Vec3) -> Vec3 {
    if forward.normalize_or_zero().y.abs() > 0.999 {
        Vec3::NEG_Z
    } else {
        Vec3::Y
    }
}

impl Camera {
    /// Camera at `position` looking at `target` with Y up.
    pub fn look_at(position: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
        let forward = (target - position).normalize_or(Vec3::NEG_Z);
        Camera {
            position,
            forward,
            up: up_for(forward),
            fov_y_deg,
            near: DEFAULT_NEAR,
            orthographic: None,
        }
    }

    /// Camera at `distance` from `target`, `yaw_deg` about +Y from +Z
    /// (positive toward +X) and `pitch_deg` above the horizon, looking at it.
    pub fn orbit(
        target: Vec3,
        yaw_deg: f32,
        pitch_deg: f32,
        distance: f32,
        fov_y_deg: f32,
    ) -> Camera {
        let (yaw, pitch) = (yaw_deg.to_radians(), pitch_deg.to_radians());
        let direction = Vec3::new(
            pitch.cos() * yaw.sin(),
            pitch.sin(),
            pitch.cos() * yaw.cos(),
        );
        Camera::look_at(target + direction * distance, target, fov_y_deg)
    }

    /// World to view: right-handed view space, camera looks down -Z, Y up.
    pub fn view(&self) -> Mat4 {
        let forward = self.forward.normalize_or(Vec3::NEG_Z);
        let up = if forward.cross(self.up).length_squared() < 1e-8 {
            up_for(forward)
        } else {
            self.up.normalize()
        };
        glam::camera::rh::view::look_to_mat4(self.position, forward, up)
    }

    /// View to clip, reverse-Z with an infinite far plane: depth = near / distance,
    /// so 1 at the near plane and 0 at infinity; clip z in [0, 1], NDC Y up (wgpu).
    /// Orthographic: depth = (far - distance) / (far - near), 1 at the near
    /// plane and 0 at the far one, x and y scaled by the half extents.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        match self.orthographic {
            Some(o) => {
                let (n, f) = (self.near, o.far.max(self.near * 1.001 + 1e-3));
                let hh = o.half_height.max(1e-6);
                Mat4::from_cols(
                    Vec4::new(1.0 / (hh * aspect), 0.0, 0.0, 0.0),
                    Vec4::new(0.0, 1.0 / hh, 0.0, 0.0),
                    Vec4::new(0.0, 0.0, 1.0 / (f - n), 0.0),
                    Vec4::new(0.0, 0.0, f / (f - n), 1.0),
                )
            }
            None => glam::camera::rh::proj::directx::perspective_infinite_reverse(
                self.fov_y_deg.to_radians(),
                aspect,
                self.near,
            ),
        }
    }

    /// World to clip: [`Self::projection`] times [`Self::view`] for an image of `aspect` = width / height.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    #[test]
    fn projection_is_reverse_z_with_infinite_far_plane() {
        let cam = Camera::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, -10.0), 60.0);
        let vp = cam.view_projection(16.0 / 9.0);
        let depth = |d: f32| {
            let c: Vec4 = vp * (cam.position + cam.forward * d).extend(1.0);
            c.z / c.w
        };
        assert!(
            (depth(cam.near) - 1.0).abs() < 1e-6,
            "near depth {}",
            depth(cam.near)
        );
        let mut last = depth(cam.near);
        for k in 1..60 {
            let d = cam.near * 1.5f32.powi(k);
            let z = depth(d);
            assert!(z < last && z > 0.0, "depth {z} at {d} m after {last}");
            assert!(
                (z - cam.near / d).abs() < 1e-6,
                "depth {z} != near / distance at {d} m"
            );
            last = z;
        }
        assert!(depth(1e9) < 1e-9);
        // Straight ahead is the screen centre; up is +y in NDC (wgpu), right is +x.
        let ndc = |p: Vec3| vp.project_point3(p);
        let ahead = ndc(cam.position + cam.forward * 10.0);
        assert!(ahead.x.abs() < 1e-6 && ahead.y.abs() < 1e-6);
        assert!(ndc(cam.position + Vec3::new(0.0, 1.0, -10.0)).y > 0.0);
        assert!(ndc(cam.position + Vec3::new(1.0, 0.0, -10.0)).x > 0.0);
        // The top of the frustum is at fov_y / 2.
        let top = ndc(cam.position + Vec3::new(0.0, (30f32).to_radians().tan() * 10.0, -10.0));
        assert!((top.y - 1.0).abs() < 1e-5, "{top}");
    }

    #[test]
    fn looking_straight_down_still_gives_a_valid_view() {
        let cam = Camera::look_at(Vec3::new(0.0, 100.0, 0.0), Vec3::ZERO, 30.0);
        let v = cam.view();
        assert!(v.to_cols_array().iter().all(|x| x.is_finite()));
        let p = v.transform_point3(Vec3::ZERO);
        assert!((p - Vec3::new(0.0, 0.0, -100.0)).length() < 1e-4, "{p}");
    }
}

/// R3 (Ryse): cinematic shadows, the author's near and far of the sun's
/// cascades, split fully logarithmically between them
/// (`[cinematic_shadows]` or a camera's `cinematic_shadows`;
/// docs/techniques/R3.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CinematicShadows {
    /// View distance where the cascades' texel density peaks (m, > 0).
    pub near: f32,
    /// View distance where the sun's shadows end (m, > `near`).
    pub far: f32,
}
