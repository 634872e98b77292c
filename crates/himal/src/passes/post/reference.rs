//! CPU twins of `luminance.wgsl` and `tonemap.wgsl`.

use glam::Vec3;

/// Offset inside the logarithm (Reinhard 2002's delta), as in the shader.
pub const DELTA: f64 = 1e-4;

pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// exp(mean(log(delta + L))) over all pixels, accumulated in f64.
pub fn log_average_luminance(pixels: &[Vec3]) -> f64 {
    if pixels.is_empty() {
        return DELTA;
    }
    let sum: f64 = pixels
        .iter()
        .map(|&c| (DELTA + luminance(c).clamp(0.0, 65504.0) as f64).ln())
        .sum();
    (sum / pixels.len() as f64).exp()
}

/// Reinhard's global operator with hue preserved: the colour is scaled by
/// L_d / L_w where L = key / L_avg * L_w and L_d = L / (1 + L).
pub fn reinhard(c: Vec3, key: f32, log_average: f32) -> Vec3 {
    let scale = key / log_average.max(1e-6);
    let l_w = luminance(c) * scale;
    if l_w <= 0.0 {
        return Vec3::ZERO;
    }
    let l_d = l_w / (1.0 + l_w);
    c * scale * (l_d / l_w)
}
