//! CPU twin of `shaders/ao_large_scale.wgsl` and `large_scale.wgsl` (O6).

use glam::{Vec2, Vec3};

/// The talk's sampling radius (m): `AO_LS_RADIUS`.
pub const RADIUS: f32 = 7.5;
/// A point whose own column rises this far (m) above it is under a roof
/// (`AO_LS_COVER`).
pub const COVER: f32 = 2.0;
/// The lookup centre moves this far (m) along the normal's horizontal part
/// (`SKYOCC_NORMAL_OFFSET`, shared with L2).
pub const NORMAL_OFFSET: f32 = 0.75;

/// `ao_ls_sample`: sample k of 4 at jitter (rot, off): unit xz direction at
/// angle 2 pi (rot + k / 4) and radius R (k + off + 0.25) / 4.25.
pub fn sample(k: u32, rot: f32, off: f32) -> (Vec2, f32) {
    let a = 2.0 * std::f32::consts::PI * (rot + k as f32 * 0.25);
    (
        Vec2::new(a.cos(), a.sin()),
        RADIUS * (k as f32 + off + 0.25) / 4.25,
    )
}

/// `ao_ls_visibility`: cos^2 of the horizon elevation, r^2 / (r^2 + rise^2);
/// under a roof `roof` m above the point (> 0), 0 for a rising sample and
/// the roof edge's r^2 / (r^2 + roof^2) for an open one.
pub fn visibility(rise: f32, r: f32, roof: f32) -> f32 {
    let up = rise.max(0.0);
    if roof > 0.0 {
        if up > 0.0 {
            return 0.0;
        }
        return (r * r) / (r * r + roof * roof);
    }
    (r * r) / (r * r + up * up)
}

/// `ao_ls_roof`: the rise of the point's own column when above [`COVER`], else 0.
pub fn roof(rise: f32) -> f32 {
    if rise > COVER { rise } else { 0.0 }
}

/// `ao_ls_weight`: 1 along the ground, 0 for directions into a wall.
pub fn weight(n: Vec3, d: Vec2) -> f32 {
    (1.0 + n.x * d.x + n.z * d.y).clamp(0.0, 1.0)
}

/// The large-scale AO of a point `p` with normal `n` at jitter (rot, off):
/// `height(xz)` is the height field there (`None`: no sector resident, no
/// occlusion).
pub fn large_scale_ao(
    p: Vec3,
    n: Vec3,
    rot: f32,
    off: f32,
    height: impl Fn(Vec2) -> Option<f32>,
) -> f32 {
    let centre = Vec2::new(p.x, p.z) + Vec2::new(n.x, n.z) * NORMAL_OFFSET;
    let roof = roof(height(Vec2::new(p.x, p.z)).unwrap_or(p.y) - p.y);
    let (mut sum, mut weights) = (0.0, 0.0);
    for k in 0..4 {
        let (d, r) = sample(k, rot, off);
        let w = weight(n, d);
        let h = height(centre + d * r).unwrap_or(p.y);
        sum += w * visibility(h - p.y, r, roof);
        weights += w;
    }
    if weights > 0.0 { sum / weights } else { 1.0 }
}
