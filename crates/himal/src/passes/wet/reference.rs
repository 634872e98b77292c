//! CPU twin of `wet.wgsl` (`gbuffer.wet`): the water film and E3's
//! screen-space normal-variance filter, per texel of a G-buffer held as
//! arrays.

use glam::{Vec3, Vec4};

use crate::math::brdf::{perceptual_roughness_from_glossiness, toksvig_roughness};

/// Albedo darkening of a fully wet dielectric (1 - 0.4).
pub const DARKEN: f32 = 0.4;
/// Perceptual roughness of the water film.
pub const FILM_ROUGHNESS: f32 = 0.08;

/// The wetness w of a surface with normal `n` under `amount` (0..1): up-facing
/// surfaces only, smoothstep(0.6, 0.95, n.y).
pub fn wetness(amount: f32, n: Vec3) -> f32 {
    let t = ((n.y - 0.6) / 0.35).clamp(0.0, 1.0);
    amount * t * t * (3.0 - 2.0 * t)
}

/// A G-buffer on the CPU: per texel the linear albedo (rgb, AO), the
/// shading normal, the material (glossiness, reflectance, metal,
/// anisotropy) and whether it holds geometry (depth > 0).
pub struct GBufferCpu {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Linear albedo and material AO.
    pub albedo: Vec<Vec4>,
    /// Unit shading normal (world space).
    pub normal: Vec<Vec3>,
    /// Glossiness, reflectance, metal, anisotropy.
    pub material: Vec<Vec4>,
    /// Depth > 0 (not sky).
    pub geometry: Vec<bool>,
}

/// Texel `(x, y)` after `gbuffer.wet`: (albedo, material).
pub fn wet_texel(
    g: &GBufferCpu,
    x: usize,
    y: usize,
    amount: f32,
    specular_aa: bool,
) -> (Vec4, Vec4) {
    let i = y * g.width + x;
    let (albedo, m) = (g.albedo[i], g.material[i]);
    if !g.geometry[i] {
        return (albedo, m);
    }
    let n = g.normal[i];
    let w = wetness(amount, n);
    let albedo = (albedo.truncate() * (1.0 - DARKEN * w * (1.0 - m.z))).extend(albedo.w);
    let r0 = perceptual_roughness_from_glossiness(m.x);
    let mut r = r0 + (FILM_ROUGHNESS - r0) * w;
    if specular_aa && w > 0.0 {
        let mut mean = Vec3::ZERO;
        for dy in -1i32..=1 {
            for dx in -1i32..=1 {
                let qx = (x as i32 + dx).clamp(0, g.width as i32 - 1) as usize;
                let qy = (y as i32 + dy).clamp(0, g.height as i32 - 1) as usize;
                let q = qy * g.width + qx;
                let weight = ((2 - dx.abs()) * (2 - dy.abs())) as f32 / 16.0;
                mean += weight * if g.geometry[q] { g.normal[q] } else { n };
            }
        }
        let len = mean.length().max(1e-4);
        r = toksvig_roughness(r, w * (1.0 - len) / len);
    }
    (albedo, Vec4::new(1.0 - r, m.y, m.z, m.w))
}
