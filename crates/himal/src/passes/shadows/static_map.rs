//! S2 static shadow map: one large sun map of the whole scene holding the
//! static objects, rendered once and then only read; it replaces the far
//! cascade. Updates are time-sliced (at most `cap` draws a frame) into a back
//! map that is swapped in when complete, so a moving sun re-renders it
//! progressively while the previous map is still shown.

use std::ops::Range;

use glam::Vec3;

use super::cascades::{ShadowFit, light_rotation, ortho_fit, top_of};
use crate::scene::Aabb;

/// Depth format of the static map: 16 bits as in Ryse (8192² = 128 MB).
pub const STATIC_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth16Unorm;

/// The sun moves this much (radians, ~0.1°) before the map is re-rendered.
pub const SUN_EPSILON: f32 = 0.0017;

/// Whether a map last filled for `last` (sun, resolution) must be filled
/// again: none yet, another resolution, or the sun turned by more than
/// [`SUN_EPSILON`] (`sun` normalised).
pub fn needs_fill(last: Option<(Vec3, u32)>, sun: Vec3, resolution: u32) -> bool {
    last.is_none_or(|(s, n)| n != resolution || s.dot(sun).clamp(-1.0, 1.0).acos() > SUN_EPSILON)
}

/// Orthographic fit around the bounding sphere of `scene`; view-independent.
pub fn static_fit(scene: &Aabb, sun_direction: Vec3, resolution: u32) -> ShadowFit {
    let (center, radius) = if scene.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (scene.center(), (scene.extent().length() * 0.5).max(1e-3))
    };
    let rotation = light_rotation(sun_direction);
    let c = rotation.transform_point3(center);
    let z_near = top_of(rotation, scene).max(c.z + radius);
    ortho_fit(rotation, c, radius, z_near, c.z - radius, resolution)
}

/// This frame's slice of the static draw list.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticUpdate {
    /// Indices into the static draw list.
    pub range: Range<usize>,
    /// Clear the target first (first slice of a fill).
    pub clear: bool,
    /// Which of the two maps is written.
    pub target: usize,
    /// The sun view the slice is rendered with (the fill's fit).
    pub fit: ShadowFit,
}

/// Time slicing of the static map (pure CPU; the pass records what it plans).
#[derive(Clone, Debug, Default)]
pub struct StaticMapState {
    /// The complete map shown (index into the two maps) and its fit.
    pub shown: Option<(usize, ShadowFit)>,
    /// The fill in progress: fit, sun it was made for, next draw index.
    filling: Option<(ShadowFit, Vec3, usize)>,
    /// Sun and resolution of the last fill started.
    last: Option<(Vec3, u32)>,
}

impl StaticMapState {
    /// Forget everything (new scene, resolution change).
    pub fn reset(&mut self) {
        *self = Self::default();
    }

    /// Plans this frame: when no fill is running, starts one if the sun moved
    /// by more than [`SUN_EPSILON`] (or the resolution changed); then takes up to `cap`
    /// draws of the `total` static ones. A fill that ends this frame is shown
    /// from this frame on.
    pub fn plan(
        &mut self,
        scene: &Aabb,
        sun_direction: Vec3,
        resolution: u32,
        total: usize,
        cap: usize,
    ) -> Option<StaticUpdate> {
        let sun = sun_direction.normalize_or(Vec3::Y);
        let moved = needs_fill(self.last, sun, resolution);
        // A fill in progress finishes first, else a sun moving faster than
        // the fill would never show a map; the next fill catches up.
        if moved && self.filling.is_none() {
            self.filling = Some((static_fit(scene, sun, resolution), sun, 0));
            self.last = Some((sun, resolution));
        }
        let (fit, sun_then, cursor) = self.filling?;
        let target = match self.shown {
            Some((front, _)) => 1 - front,
            None => 0,
        };
        let end = (cursor + cap.max(1)).min(total);
        if end >= total {
            self.shown = Some((target, fit));
            self.filling = None;
        } else {
            self.filling = Some((fit, sun_then, end));
        }
        Some(StaticUpdate {
            range: cursor..end,
            clear: cursor == 0,
            target,
            fit,
        })
    }
}
