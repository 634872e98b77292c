//! S4 hero shadow map: a small sun map fitted tightly around one object
//! (the demo's moving ball), max-blended into the mask over the cascades.

use glam::Vec3;

use super::cascades::{ShadowFit, light_rotation, ortho_fit, top_of};
use crate::scene::{Aabb, Object};

/// Fit around `object` (mesh bounds `mesh`) at time `t`: its light-view
/// rectangle with two texels of margin, from above the scene down to the
/// scene's lowest point (its shadow falls on receivers straight behind it).
pub fn hero_fit(
    object: &Object,
    mesh: &Aabb,
    t: f32,
    sun_direction: Vec3,
    scene: &Aabb,
    resolution: u32,
) -> ShadowFit {
    let rotation = light_rotation(sun_direction);
    let b = mesh.transform(&object.transform_at(t)).transform(&rotation);
    let c = b.center();
    let n = resolution.max(8) as f32;
    let half = (b.extent().x.max(b.extent().y) * 0.5).max(0.05) * n / (n - 4.0);
    let z_near = top_of(rotation, scene).max(b.max.z + 1.0);
    let z_far = scene.transform(&rotation).min.z.min(b.min.z) - 1.0;
    ortho_fit(rotation, c, half, z_near, z_far, resolution)
}
