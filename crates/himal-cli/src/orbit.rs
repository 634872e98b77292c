//! `himal view`'s orbit camera (model viewing): yaw and pitch about a
//! target at a distance, turned by dragging, zoomed by the wheel, panned
//! with the middle button, reset to frame the scene by F.

use glam::Vec3;
use himal::scene::{Aabb, Camera};

/// Degrees per pixel dragged.
const DEGREES_PER_PIXEL: f32 = 0.3;
/// Distance factor per wheel step (towards the target).
const ZOOM_PER_STEP: f32 = 0.85;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    /// Degrees about +Y from the front (+Z), positive toward +X.
    pub yaw: f32,
    /// Degrees above the horizon, within ±89.
    pub pitch: f32,
    pub distance: f32,
    /// Radius of what is framed: the near plane stays in front of it.
    pub radius: f32,
}

impl Orbit {
    /// The three-quarter view of `bounds` (as `render --gltf` opens).
    pub fn framing(bounds: &Aabb, fov_y_deg: f32) -> Orbit {
        let (yaw, pitch) = himal::scene::gltf::THREE_QUARTER;
        let c = himal::scene::gltf::orbit_camera(bounds, yaw, pitch, None, fov_y_deg);
        Orbit::around(&c, bounds)
    }

    /// The orbit that `camera` sits on around the centre of `bounds`.
    pub fn around(camera: &Camera, bounds: &Aabb) -> Orbit {
        let (target, radius) = if bounds.is_empty() {
            (camera.position + camera.forward * 5.0, 1.0)
        } else {
            (bounds.center(), (bounds.extent().length() * 0.5).max(1e-3))
        };
        let to = camera.position - target;
        let distance = to.length().max(1e-3);
        let d = to / distance;
        Orbit {
            target,
            yaw: d.x.atan2(d.z).to_degrees(),
            pitch: d.y.clamp(-1.0, 1.0).asin().to_degrees().clamp(-89.0, 89.0),
            distance,
            radius,
        }
    }

    /// Dragging right turns the model right (the camera left), dragging up
    /// looks from above.
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        self.yaw = (self.yaw - dx * DEGREES_PER_PIXEL).rem_euclid(360.0);
        self.pitch = (self.pitch + dy * DEGREES_PER_PIXEL).clamp(-89.0, 89.0);
    }

    /// `steps` wheel steps towards the target (negative: away).
    pub fn zoom(&mut self, steps: f32) {
        self.distance = (self.distance * ZOOM_PER_STEP.powf(steps)).clamp(1e-3, 1e6);
    }

    /// Moves the target with the image: `dx`, `dy` pixels of a view
    /// `height` pixels tall, so the point under the cursor stays under it.
    pub fn pan(&mut self, dx: f32, dy: f32, fov_y_deg: f32, height: u32) {
        let c = self.camera(fov_y_deg);
        let right = c.forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(c.forward);
        let metres_per_pixel =
            2.0 * self.distance * (fov_y_deg.to_radians() * 0.5).tan() / height.max(1) as f32;
        self.target += (-right * dx + up * dy) * metres_per_pixel;
    }

    pub fn camera(&self, fov_y_deg: f32) -> Camera {
        let mut c = Camera::orbit(self.target, self.yaw, self.pitch, self.distance, fov_y_deg);
        c.near = (self.distance - self.radius).max(self.distance * 1e-3) * 0.5;
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Aabb {
        Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }

    #[test]
    fn framing_matches_the_render_camera_and_round_trips() {
        let o = Orbit::framing(&cube(), 40.0);
        let (yaw, pitch) = himal::scene::gltf::THREE_QUARTER;
        assert!(
            (o.yaw - yaw).abs() < 1e-3 && (o.pitch - pitch).abs() < 1e-3,
            "{o:?}"
        );
        let render = himal::scene::gltf::orbit_camera(&cube(), yaw, pitch, None, 40.0);
        let c = o.camera(40.0);
        assert!(c.position.abs_diff_eq(render.position, 1e-4));
        assert!(c.forward.abs_diff_eq(render.forward, 1e-5));
    }

    #[test]
    fn dragging_turns_zooming_approaches_panning_follows_the_cursor() {
        let mut o = Orbit::framing(&cube(), 40.0);
        let (d0, t0) = (o.distance, o.target);
        o.rotate(100.0, 0.0);
        assert!((o.yaw - (35.0 - 30.0)).abs() < 1e-3, "{}", o.yaw);
        o.rotate(0.0, 1000.0);
        assert_eq!(o.pitch, 89.0, "clamped short of the pole");
        assert_eq!(o.distance, d0, "turning keeps the distance");
        assert!(o.camera(40.0).position.distance(t0) - d0 < 1e-3);
        o.zoom(2.0);
        assert!((o.distance - d0 * 0.85 * 0.85).abs() < 1e-4);
        // A 100-pixel pan of a 500-pixel view at 40 degrees moves the target
        // 100 * 2 d tan(20) / 500 metres, sideways to the view.
        let mut p = Orbit::framing(&cube(), 40.0);
        let forward = p.camera(40.0).forward;
        p.pan(100.0, 0.0, 40.0, 500);
        let moved = p.target - t0;
        let expected = 100.0 * 2.0 * p.distance * 20f32.to_radians().tan() / 500.0;
        assert!((moved.length() - expected).abs() < 1e-4, "{moved}");
        assert!(moved.dot(forward).abs() < 1e-5);
    }
}
