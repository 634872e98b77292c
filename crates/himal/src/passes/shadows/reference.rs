//! CPU side of the sun shadow map: the light-space fit, used by the GPU path.
//! The map and its filter are checked end to end against CPU ray casting
//! (`tests/shadows.rs`): a box on a plane under three sun positions.

use glam::Vec3;

use super::ShadowFit;
use crate::scene::Aabb;

/// Orthographic sun view around the bounding sphere of `bounds`: the whole
/// scene casts and receives; texel size = diameter / resolution.
pub fn sun_shadow_fit(bounds: &Aabb, sun_direction: Vec3, resolution: u32) -> ShadowFit {
    let (center, radius) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), (bounds.extent().length() * 0.5).max(1e-3))
    };
    let d = sun_direction.normalize_or(Vec3::Y);
    let up = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let view = glam::camera::rh::view::look_at_mat4(center + d * radius, center, up);
    // wgpu clip space: y up, depth in [0, 1] (glam's "directx" convention).
    let proj = glam::camera::rh::proj::directx::orthographic(
        -radius,
        radius,
        -radius,
        radius,
        0.0,
        2.0 * radius,
    );
    ShadowFit {
        light_view_proj: proj * view,
        texel_world: 2.0 * radius / resolution.max(1) as f32,
        depth_range: 2.0 * radius,
    }
}
