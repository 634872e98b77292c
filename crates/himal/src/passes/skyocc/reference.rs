//! CPU twin of the sky occlusion passes (L2) and the ground truth they are
//! measured against.
//!
//! * [`blur`]: twin of `blur.wgsl` (separable binomial 1-4-6-4-1, clamp to edge).
//! * [`visibility_at`] / [`sector_visibility`]: twin of `visibility.wgsl`
//!   (rotated Poisson disk, horizon march, SH2 cap).
//! * SH2 helpers: twins of `shaders/sky_occlusion.wgsl`.
//! * [`ray_traced_visibility`]: visibility by marching rays over an analytic
//!   height function (the reference of `tests/sky_occlusion.rs`).
//!
//! SH2 layout (same basis as `math/sh.rs`, first four coefficients):
//! `[L00, L1-1 (∝ y), L10 (∝ z), L11 (∝ x)]`, world Y up.

use glam::{Vec2, Vec3, Vec4};

/// Sector edge in metres (Far Cry 4: 64x64 m).
pub const SECTOR_SIZE: f32 = 64.0;
/// Texels per sector edge (25 cm per texel).
pub const SECTOR_TEXELS: usize = 256;
/// Metres per texel.
pub const TEXEL_SIZE: f32 = SECTOR_SIZE / SECTOR_TEXELS as f32;
/// Radius of the sample hemisphere in metres: horizons nearer than this
/// occlude; walls further away are ignored (the talk's "SSAO style").
pub const SAMPLE_RADIUS: f32 = 8.0;
/// Poisson-disk samples per texel.
pub const SAMPLES: usize = 32;
/// Height-field tests along each sample ray (every R / 8 = 1 m at most
/// horizontally, so walls 1 m thick are not stepped over).
pub const MARCH_STEPS: u32 = 8;
/// Binomial blur half width in texels (kernel 1 4 6 4 1 / 16: sigma = 1 texel = 25 cm).
pub const BLUR_RADIUS: usize = 2;
/// The binomial kernel 1 4 6 4 1 / 16 (sums to 1).
pub const BLUR_WEIGHTS: [f32; 2 * BLUR_RADIUS + 1] =
    [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
/// Apron rendered around a sector so that samples and blur near its edge
/// see the neighbours: sample radius (32 texels) + blur radius, rounded up.
pub const MARGIN_TEXELS: usize = 36;
/// Edge of a rendered (and blurred) height field: sector plus apron.
pub const RENDER_TEXELS: usize = SECTOR_TEXELS + 2 * MARGIN_TEXELS;
/// Texels around the sector whose visibility is computed only to feed the
/// 5x5 smoothing of the SH2 visibility (`visibility_smooth.wgsl`).
pub const SMOOTH_BORDER: usize = 2;
/// The texel's own point is lifted this much (m) so that flat ground does
/// not occlude itself through float rounding.
pub const ORIGIN_LIFT: f32 = 0.05;
/// Radius (m) of the disk the fade height averages the blurred field over.
pub const FADE_RADIUS: f32 = 2.0;

/// `SH2SphericalCap` constants (talk, SKY OCCLUSION): the projection of a
/// cap of half angle A around the axis onto Y00 and the axial Y1:
/// L0 = 2π Y00 (1 − cos A) = √π (1 − cos A),
/// L1 = π Y1 (1 − cos² A) = (π Y1 / 2) (1 − cos 2A).
pub const SH_CAP_C0: f32 = 1.772_453_9;
/// (π Y1 / 2): the L1 factor of a cap (see [`SH_CAP_C0`]).
pub const SH_CAP_C2: f32 = 0.767_495;
/// Y00 and the Y1 normalisation (`math/sh.rs`).
const Y0: f32 = 0.282_095;
const Y1: f32 = 0.488_603;

/// A square height image: `h[y * size + x]` is the world height of the
/// texel whose corner (min x, min z) is at `origin + (x, y) * texel`.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightImage {
    /// Texels per edge.
    pub size: usize,
    /// Texel edge in metres.
    pub texel: f32,
    /// World (x, z) of texel (0, 0)'s min corner, in metres.
    pub origin: Vec2,
    /// `size * size` world heights in metres, row-major (rows along z).
    pub h: Vec<f32>,
}

impl HeightImage {
    /// Samples `f(x, z)` at texel centres.
    pub fn from_fn(size: usize, texel: f32, origin: Vec2, f: impl Fn(f32, f32) -> f32) -> Self {
        let mut h = Vec::with_capacity(size * size);
        for y in 0..size {
            for x in 0..size {
                let p = origin + (Vec2::new(x as f32, y as f32) + 0.5) * texel;
                h.push(f(p.x, p.y));
            }
        }
        Self {
            size,
            texel,
            origin,
            h,
        }
    }

    /// The texel under world (x, z), clamped to the image (nearest).
    pub fn at_world(&self, x: f32, z: f32) -> f32 {
        let n = self.size as i32 - 1;
        let tx = (((x - self.origin.x) / self.texel).floor() as i32).clamp(0, n);
        let ty = (((z - self.origin.y) / self.texel).floor() as i32).clamp(0, n);
        self.h[ty as usize * self.size + tx as usize]
    }
}

/// Twin of `blur.wgsl`: the binomial kernel along x, then along y, each tap
/// clamped to the image.
pub fn blur(src: &HeightImage) -> HeightImage {
    let n = src.size;
    let pass = |h: &[f32], dx: usize, dy: usize| -> Vec<f32> {
        let mut out = vec![0.0; n * n];
        for y in 0..n {
            for x in 0..n {
                let mut s = 0.0;
                for (k, w) in BLUR_WEIGHTS.iter().enumerate() {
                    let o = k as i32 - BLUR_RADIUS as i32;
                    let sx = (x as i32 + o * dx as i32).clamp(0, n as i32 - 1) as usize;
                    let sy = (y as i32 + o * dy as i32).clamp(0, n as i32 - 1) as usize;
                    s += w * h[sy * n + sx];
                }
                out[y * n + x] = s;
            }
        }
        out
    };
    let x = pass(&src.h, 1, 0);
    HeightImage {
        h: pass(&x, 0, 1),
        ..src.clone()
    }
}

/// Deterministic Poisson disk of `n` points in the unit disk (Mitchell's
/// best candidate, 32 candidates per point, fixed LCG seed); uploaded to
/// the GPU as is, so both twins use the same points.
pub fn poisson_disk(n: usize) -> Vec<Vec2> {
    let mut seed = 0x2545_f491u32;
    let mut rand = move || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut pts: Vec<Vec2> = Vec::with_capacity(n);
    while pts.len() < n {
        let mut best = (Vec2::ZERO, -1.0f32);
        for _ in 0..32 {
            // Uniform in the disk by area.
            let (r, a) = (rand().sqrt(), rand() * std::f32::consts::TAU);
            let c = Vec2::new(r * a.cos(), r * a.sin());
            let d = pts
                .iter()
                .map(|p| p.distance_squared(c))
                .fold(f32::INFINITY, f32::min);
            if d > best.1 {
                best = (c, d);
            }
        }
        pts.push(best.0);
    }
    pts
}

/// Interleaved gradient noise (Jimenez 2014) in [0, 1): the per-texel disk rotation.
pub fn interleaved_gradient_noise(x: f32, y: f32) -> f32 {
    (52.982_918 * (0.067_110_56 * x + 0.005_837_15 * y).fract()).fract()
}

/// Direction of disk point `q` (|q| <= 1) on the upper hemisphere by the
/// equal-area map cos θ = 1 − |q|²: uniform disk points give uniformly
/// distributed directions, so the visible fraction is the visible solid
/// angle over 2π.
pub fn hemisphere_from_disk(q: Vec2) -> Vec3 {
    let r2 = q.length_squared().min(1.0);
    let lift = (2.0 - r2).max(0.0).sqrt();
    Vec3::new(q.x * lift, 1.0 - r2, q.y * lift)
}

/// Twin of `visibility.wgsl` at texel (x, y) of the rendered images: the
/// fraction of visible samples, the sum of their (unit) directions and the
/// fade height (the blurred field averaged at the disk points scaled to
/// [`FADE_RADIUS`]).
/// A sample direction d is visible when the ray from the texel's point p
/// (raw height + [`ORIGIN_LIFT`]) stays above the blurred height field at
/// p + d R k / [`MARCH_STEPS`], k = 1..steps (nearest texel).
pub fn visibility_at(
    raw: &HeightImage,
    blurred: &HeightImage,
    disk: &[Vec2],
    x: usize,
    y: usize,
) -> (f32, Vec3, f32) {
    let t = raw.texel;
    let p = Vec3::new(
        raw.origin.x + (x as f32 + 0.5) * t,
        raw.h[y * raw.size + x] + ORIGIN_LIFT,
        raw.origin.y + (y as f32 + 0.5) * t,
    );
    let angle = std::f32::consts::TAU * interleaved_gradient_noise(x as f32, y as f32);
    let (s, c) = angle.sin_cos();
    let (mut count, mut sum, mut h_fade) = (0u32, Vec3::ZERO, 0.0f32);
    for d in disk {
        let q = Vec2::new(c * d.x - s * d.y, s * d.x + c * d.y);
        // Unrotated: the same kernel at every texel, a blur (rotating it
        // per texel would streak the fade along walls).
        let f = Vec2::new(p.x, p.z) + *d * FADE_RADIUS;
        h_fade += blurred.at_world(f.x, f.y);
        let dir = hemisphere_from_disk(q);
        let visible = (1..=MARCH_STEPS).all(|k| {
            let a = p + dir * (SAMPLE_RADIUS * k as f32 / MARCH_STEPS as f32);
            blurred.at_world(a.x, a.z) <= a.y
        });
        if visible {
            count += 1;
            sum += dir;
        }
    }
    let n = disk.len().max(1) as f32;
    (count as f32 / n, sum, h_fade / n)
}

/// `SH2SphericalCap(cosA)`, zonal part: (L0, axial L1).
pub fn sh2_spherical_cap(cos_a: f32) -> Vec2 {
    let cos_2a = 2.0 * cos_a * cos_a - 1.0;
    Vec2::new(SH_CAP_C0 * (1.0 - cos_a), SH_CAP_C2 * (1.0 - cos_2a))
}

/// SH2 visibility of a cap holding the visible fraction `f` of the upper
/// hemisphere (solid angle 2π f, so cos A = 1 − f), rotated from +Y to the
/// mean visible direction `sum` (+Y when nothing is visible). An L1 band is
/// a vector: rotating the zonal cap to axis d scales the axial coefficient
/// by (d.y, d.z, d.x) in the basis order.
pub fn sh2_from_visibility(f: f32, sum: Vec3) -> Vec4 {
    let d = sum.try_normalize().unwrap_or(Vec3::Y);
    let cap = sh2_spherical_cap(1.0 - f.clamp(0.0, 1.0));
    Vec4::new(cap.x, cap.y * d.y, cap.y * d.z, cap.y * d.x)
}

/// The SH2 of an unoccluded point: the upper hemisphere (f = 1) around +Y.
pub fn sh2_open_sky() -> Vec4 {
    sh2_from_visibility(1.0, Vec3::Y)
}

/// Unoccluded: the whole sphere (cos A = −1, L0 = 2 C0, L1 = 0): the
/// cosine visibility is 1 along every normal and nothing bends. Used as
/// "fully visible" by the fade and where no sector is resident (a vertical
/// wall is not darkened to the hemisphere's 0.5: the sky SH already lacks
/// the lower half).
pub fn sh2_unoccluded() -> Vec4 {
    Vec4::new(2.0 * SH_CAP_C0, 0.0, 0.0, 0.0)
}

/// `SH2GetPrimaryDirection`: the L1 vector, normalised.
pub fn sh2_primary_direction(sh: Vec4) -> Vec3 {
    Vec3::new(sh.w, sh.y, sh.z)
        .try_normalize()
        .unwrap_or(Vec3::Y)
}

/// `BentNormalFromSHVisibility`: factor = 1 − L0 / C0 = cos A = 1 − f.
pub fn bent_normal_from_sh_visibility(n: Vec3, sh: Vec4) -> Vec3 {
    let factor = (1.0 - sh.x / SH_CAP_C0).clamp(0.0, 1.0);
    (n + sh2_primary_direction(sh) * factor).normalize_or(n)
}

/// Visibility of the diffuse sky along `n`: the SH2 convolved with the
/// clamped cosine (bands × 1, 2/3, i.e. A_l / π) and evaluated at n,
/// clamped to [0, 1]. Exactly 1 for the open sky along +Y.
pub fn sh2_visibility_cosine(sh: Vec4, n: Vec3) -> f32 {
    let v = sh.x * Y0 + (2.0 / 3.0) * Y1 * (sh.y * n.y + sh.z * n.z + sh.w * n.x);
    v.clamp(0.0, 1.0)
}

/// Fade to visible with height above the terrain (talk): full occlusion at
/// the terrain height, none at the blurred (fade) height; the SH blends
/// linearly toward [`sh2_unoccluded`].
pub fn fade_to_visible(sh: Vec4, y: f32, h_terrain: f32, h_blurred: f32) -> Vec4 {
    let t = ((y - h_terrain) / (h_blurred - h_terrain).max(0.1)).clamp(0.0, 1.0);
    sh.lerp(sh2_unoccluded(), t)
}

/// Bilinear sample of a [`SECTOR_TEXELS`]² row-major layer at `local` in
/// [0, 1)², taps clamped to the layer (the GPU's clamp-to-edge sampler).
pub fn sample_bilinear<T: Copy>(texels: &[T], local: Vec2, lerp: impl Fn(T, T, f32) -> T) -> T {
    let n = SECTOR_TEXELS as i32;
    let p = local * n as f32 - 0.5;
    let p0 = p.floor();
    let f = p - p0;
    let at = |x: i32, y: i32| texels[(y.clamp(0, n - 1) * n + x.clamp(0, n - 1)) as usize];
    let (x, y) = (p0.x as i32, p0.y as i32);
    let top = lerp(at(x, y), at(x + 1, y), f.x);
    let bottom = lerp(at(x, y + 1), at(x + 1, y + 1), f.x);
    lerp(top, bottom, f.y)
}

/// Twin of `sky_occlusion_lookup` (`shaders/sky_occlusion.wgsl`) inside one
/// resident sector: bilinear SH2 and (terrain, fade) heights at `local`,
/// faded for a point at height `y`.
pub fn sector_lookup(sh: &[Vec4], heights: &[Vec2], local: Vec2, y: f32) -> Vec4 {
    let v = sample_bilinear(sh, local, |a, b, t| a.lerp(b, t));
    let h = sample_bilinear(heights, local, |a, b, t| a.lerp(b, t));
    fade_to_visible(v, y, h.x, h.y)
}

/// One sector's output texel: SH2 visibility and (terrain, fade) heights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectorTexel {
    /// SH2 visibility (L00, L1-1, L10, L11).
    pub sh: Vec4,
    /// (terrain, fade) heights in metres.
    pub heights: Vec2,
}

/// Twin of the blur and visibility passes for one rendered height image
/// and its terrain-only image (both [`RENDER_TEXELS`]² with the apron): the
/// sector's inner texels, row-major.
pub fn sector_visibility(
    raw: &HeightImage,
    ground: &HeightImage,
    disk: &[Vec2],
) -> (HeightImage, Vec<SectorTexel>) {
    let blurred = blur(raw);
    let m = (raw.size - SECTOR_TEXELS.min(raw.size)) / 2;
    let inner = raw.size - 2 * m;
    // SH2 over the sector and a SMOOTH_BORDER ring, then a 5x5 binomial
    // smoothing: the per-texel disk rotation leaves ±1/32 noise that shows
    // as streaks on walls.
    let b = SMOOTH_BORDER;
    let ext = inner + 2 * b;
    let mut sh = Vec::with_capacity(ext * ext);
    let mut fade = Vec::with_capacity(ext * ext);
    for y in m - b..m + inner + b {
        for x in m - b..m + inner + b {
            let (f, sum, h_fade) = visibility_at(raw, &blurred, disk, x, y);
            sh.push(sh2_from_visibility(f, sum));
            fade.push(h_fade);
        }
    }
    const W: [f32; 5] = [1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0];
    let mut out = Vec::with_capacity(inner * inner);
    for y in 0..inner {
        for x in 0..inner {
            let mut s = Vec4::ZERO;
            for (j, wj) in W.iter().enumerate() {
                for (i, wi) in W.iter().enumerate() {
                    s += sh[(y + j) * ext + x + i] * (wi * wj);
                }
            }
            out.push(SectorTexel {
                sh: s,
                heights: Vec2::new(
                    ground.h[(y + m) * ground.size + x + m],
                    fade[(y + b) * ext + x + b],
                ),
            });
        }
    }
    (blurred, out)
}

/// Ground truth: the fraction of `rays` uniformly distributed directions of
/// the upper hemisphere at `p` (or cosine-weighted when `cosine`) that
/// escape the analytic height field `height`, marched in 5 cm steps up to
/// `max_distance`. Directions are a stratified (Fibonacci) set, so the
/// result is deterministic.
pub fn ray_traced_visibility(
    height: &dyn Fn(f32, f32) -> f32,
    p: Vec3,
    rays: usize,
    cosine: bool,
    max_distance: f32,
) -> f32 {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let mut visible = 0usize;
    for i in 0..rays {
        let u = (i as f32 + 0.5) / rays as f32;
        // Uniform: cos θ = u; cosine-weighted: cos θ = sqrt(u).
        let cos_t = if cosine { u.sqrt() } else { u };
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = golden * i as f32;
        let d = Vec3::new(sin_t * phi.cos(), cos_t, sin_t * phi.sin());
        let mut t = 0.05;
        let mut hit = false;
        while t < max_distance {
            let a = p + d * t;
            if height(a.x, a.z) > a.y {
                hit = true;
                break;
            }
            t += 0.05;
        }
        if !hit {
            visible += 1;
        }
    }
    visible as f32 / rays as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn open_sky_is_fully_visible_and_unbent() {
        let sh = sh2_open_sky();
        let v = sh2_visibility_cosine(sh, Vec3::Y);
        // Exact by construction: 0.5 (band 0) + 0.5 (band 1); f32 rounding 1e-6.
        assert!((v - 1.0).abs() < 1e-5, "{v}");
        let n = Vec3::new(0.6, 0.8, 0.0);
        assert!(bent_normal_from_sh_visibility(n, sh).distance(n) < 1e-5);
        // A closed point: no visibility, the normal bends fully toward the mean.
        let closed = sh2_from_visibility(0.0, Vec3::X);
        assert_eq!(sh2_visibility_cosine(closed, Vec3::Y), 0.0);
        // Unoccluded: 1 along any normal, no bending.
        for n in [Vec3::Y, Vec3::X, Vec3::new(0.0, -0.6, 0.8)] {
            let v = sh2_visibility_cosine(sh2_unoccluded(), n);
            assert!((v - 1.0).abs() < 1e-5, "{n}: {v}");
            assert!(bent_normal_from_sh_visibility(n, sh2_unoccluded()).distance(n) < 1e-5);
        }
    }

    #[test]
    fn cap_projection_matches_numerical_integration() {
        // L0 and axial L1 of a cap of half angle A about +Y, by quadrature.
        for cos_a in [0.9f32, 0.5, 0.0] {
            let n = 4000;
            let (mut l0, mut l1) = (0.0f64, 0.0f64);
            for i in 0..n {
                let t = cos_a as f64 + (1.0 - cos_a as f64) * (i as f64 + 0.5) / n as f64;
                let dw = std::f64::consts::TAU * (1.0 - cos_a as f64) / n as f64;
                l0 += Y0 as f64 * dw;
                l1 += Y1 as f64 * t * dw;
            }
            let cap = sh2_spherical_cap(cos_a);
            // measured < 2e-6 (f32 constants) on 2026-11-22; threshold 1e-4.
            assert!(
                (cap.x as f64 - l0).abs() < 1e-4,
                "{cos_a}: {} vs {l0}",
                cap.x
            );
            assert!(
                (cap.y as f64 - l1).abs() < 1e-4,
                "{cos_a}: {} vs {l1}",
                cap.y
            );
        }
    }

    #[test]
    fn flat_ground_sees_the_whole_sky() {
        let n = 2 * MARGIN_TEXELS + 8;
        let raw = HeightImage::from_fn(n, TEXEL_SIZE, Vec2::ZERO, |_, _| 3.0);
        let blurred = blur(&raw);
        let disk = poisson_disk(SAMPLES);
        let (f, sum, h_fade) = visibility_at(&raw, &blurred, &disk, n / 2, n / 2);
        assert_eq!(h_fade, 3.0);
        assert_eq!(f, 1.0);
        // Mean of uniform hemisphere directions is about +Y.
        assert!(sum.normalize().y > 0.95, "{sum}");
    }
}
