//! CPU twin of `vegetation.ao` (`decal.wgsl`): the factor on the sky light
//! at a world point is the product, over the trees whose box holds it, of
//! their volume's [`AoVolume::factor`] at the point in the tree's space.

use glam::{Mat4, Vec3};

use crate::scene::tree::ao::AoVolume;

/// The factor at world point `p` under `trees` (each tree's model matrix
/// and its volume): 1 outside every box.
pub fn factor(trees: &[(Mat4, &AoVolume)], p: Vec3) -> f32 {
    (trees.iter())
        .map(|(model, v)| v.factor(model.inverse().transform_point3(p)))
        .product()
}

/// The factor as the frame stores it: quantised to the 8-bit target it is
/// multiplied into (the decal's one multiply per box, then rounding).
pub fn stored(factor: f32) -> f32 {
    (factor.clamp(0.0, 1.0) * 255.0).round() / 255.0
}
