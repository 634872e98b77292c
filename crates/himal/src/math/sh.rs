//! Third-order (9-coefficient) real spherical harmonics for RGB signals.
//!
//! Basis: the standard real SH written on the direction's own components,
//! with no axis remapping (so the "polar" axis of the basis is +Z even though
//! the world is Y-up; that is harmless because a band-limited SH is closed
//! under rotation). Order of coefficients: L00, L1-1, L10, L11, L2-2, L2-1,
//! L20, L21, L22 (Ramamoorthi & Hanrahan 2001; Sloan, "Stupid SH tricks" 2008).
//!
//! Irradiance from radiance is the convolution with the clamped cosine,
//! i.e. per-band factors pi, 2pi/3, pi/4 (R&H 2001 eq. 8-9). See
//! `docs/techniques/L1-preetham.md`.

use glam::Vec3;

/// Number of coefficients of a third-order SH.
pub const SH9_COUNT: usize = 9;

/// Band of each coefficient (0, 1, 1, 1, 2, 2, 2, 2, 2).
pub const SH9_BAND: [usize; SH9_COUNT] = [0, 1, 1, 1, 2, 2, 2, 2, 2];

/// Clamped-cosine convolution factors A_l per band: pi, 2pi/3, pi/4.
pub const SH9_COSINE_BAND_FACTORS: [f32; 3] = [
    std::f32::consts::PI,
    2.0 * std::f32::consts::PI / 3.0,
    std::f32::consts::PI / 4.0,
];

/// Real SH basis Y_lm(d) for a unit direction d, in the order documented above.
pub fn sh9_basis(d: Vec3) -> [f32; SH9_COUNT] {
    let (x, y, z) = (d.x, d.y, d.z);
    [
        0.282_095,
        0.488_603 * y,
        0.488_603 * z,
        0.488_603 * x,
        1.092_548 * x * y,
        1.092_548 * y * z,
        0.315_392 * (3.0 * z * z - 1.0),
        1.092_548 * x * z,
        0.546_274 * (x * x - y * y),
    ]
}

/// Number of coefficients of a second-order SH (bands 0 and 1): L00, L1-1, L10, L11.
pub const SH4_COUNT: usize = 4;

/// The first two bands of [`sh9_basis`].
pub fn sh4_basis(d: Vec3) -> [f32; SH4_COUNT] {
    let b = sh9_basis(d);
    [b[0], b[1], b[2], b[3]]
}

/// Irradiance at normal `n` from second-order radiance coefficients (rgb
/// per coefficient): E(n) = sum_i A_band(i) L_i Y_i(n), clamped at zero.
pub fn sh4_irradiance(l: &[Vec3; SH4_COUNT], n: Vec3) -> Vec3 {
    let y = sh4_basis(n);
    let [a0, a1, _] = SH9_COSINE_BAND_FACTORS;
    (l[0] * (a0 * y[0]) + (l[1] * y[1] + l[2] * y[2] + l[3] * y[3]) * a1).max(Vec3::ZERO)
}

/// Nine RGB coefficients (rgb in a `Vec3` per coefficient).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sh9Rgb {
    /// Coefficients in the order L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22; each holds r, g, b.
    pub c: [Vec3; SH9_COUNT],
}

impl Default for Sh9Rgb {
    fn default() -> Self {
        Self::zero()
    }
}

impl Sh9Rgb {
    /// All coefficients zero.
    pub fn zero() -> Self {
        Self {
            c: [Vec3::ZERO; SH9_COUNT],
        }
    }

    /// Coefficient-wise sum (the SH of the summed signals).
    pub fn add(&self, other: &Sh9Rgb) -> Sh9Rgb {
        Sh9Rgb {
            c: std::array::from_fn(|i| self.c[i] + other.c[i]),
        }
    }

    /// Every coefficient multiplied by `s`.
    pub fn scale(&self, s: f32) -> Sh9Rgb {
        Sh9Rgb {
            c: std::array::from_fn(|i| self.c[i] * s),
        }
    }

    /// Evaluates the stored coefficients as-is at direction `dir` (unit).
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        let y = sh9_basis(dir);
        self.c
            .iter()
            .zip(y.iter())
            .fold(Vec3::ZERO, |acc, (c, y)| acc + *c * *y)
    }

    /// Projects `f` onto the basis with a deterministic product quadrature in
    /// t = d.y (the world up axis) and azimuth: Gauss-Legendre in t on each
    /// hemisphere separately (`ceil(n/2)` nodes on [-1, 0] and on [0, 1], so a
    /// kink at the horizon t = 0 costs no accuracy) times `2n` uniform azimuths,
    /// `n = samples_per_axis`. Exact (to rounding) for band-limited inputs up
    /// to degree 2 ceil(n/2) - 1 in t; accuracy on skies measured in `tests/sky.rs`.
    pub fn project<F: Fn(Vec3) -> Vec3>(f: F, samples_per_axis: u32) -> Self {
        let n = samples_per_axis.max(2);
        let half = n.div_ceil(2) as usize;
        let n_phi = 2 * n;
        let gl = gauss_legendre(half);
        // Rotate each azimuth step by a complex multiply instead of calling
        // sin/cos per sample (in f64 so it stays on the circle).
        let dphi = std::f64::consts::TAU / n_phi as f64;
        let (s_step, c_step) = dphi.sin_cos();
        let (s0, c0) = (0.5 * dphi).sin_cos();
        let mut acc = [glam::DVec3::ZERO; SH9_COUNT];
        for hemisphere in [-1.0f64, 1.0] {
            for &(x, w) in &gl {
                // Map [-1, 1] to [0, 1] (upper) or [-1, 0] (lower); dt = 1/2.
                let t = hemisphere * 0.5 * (x + 1.0);
                let r = (1.0 - t * t).max(0.0).sqrt();
                let (mut s, mut c) = (s0, c0);
                let mut row = [Vec3::ZERO; SH9_COUNT];
                for _ in 0..n_phi {
                    let d = Vec3::new((r * c) as f32, t as f32, (r * s) as f32);
                    let v = f(d);
                    let y = sh9_basis(d);
                    for k in 0..SH9_COUNT {
                        row[k] += v * y[k];
                    }
                    (s, c) = (s * c_step + c * s_step, c * c_step - s * s_step);
                }
                let row_weight = 0.5 * w * dphi;
                for k in 0..SH9_COUNT {
                    acc[k] += row[k].as_dvec3() * row_weight;
                }
            }
        }
        Sh9Rgb {
            c: std::array::from_fn(|k| acc[k].as_vec3()),
        }
    }

    /// Coefficients of the irradiance E(n) = integral L(w) max(0, n.w) dw,
    /// i.e. each band scaled by pi, 2pi/3, pi/4.
    pub fn radiance_to_irradiance_coeffs(&self) -> Sh9Rgb {
        Sh9Rgb {
            c: std::array::from_fn(|i| self.c[i] * SH9_COSINE_BAND_FACTORS[SH9_BAND[i]]),
        }
    }

    /// Irradiance at normal `n` for the radiance these coefficients represent.
    pub fn irradiance(&self, n: Vec3) -> Vec3 {
        self.radiance_to_irradiance_coeffs().eval(n)
    }

    /// The inverse of [`Sh9Rgb::radiance_to_irradiance_coeffs`] evaluated at
    /// `d`: band-limited radiance from irradiance coefficients (the Bruneton
    /// sky's fog colour). Twin of `sh9_eval_radiance_from_irradiance`.
    pub fn radiance_from_irradiance_eval(&self, d: Vec3) -> Vec3 {
        let y = sh9_basis(d);
        (0..9).fold(Vec3::ZERO, |acc, i| {
            acc + self.c[i] * (y[i] / SH9_COSINE_BAND_FACTORS[SH9_BAND[i]])
        })
    }
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre
/// recurrence, as in Numerical Recipes' gauleg), ascending nodes.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    let mut out = vec![(0.0, 0.0); n];
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            // P_n(x) and its derivative by the three-term recurrence.
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                (p0, p1) = (p1, p2);
            }
            dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
            let dx = p1 / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        out[i] = (-x, w);
        out[n - 1 - i] = (x, w);
    }
    out
}

/// Ramamoorthi & Hanrahan 2001, eq. 13: irradiance at normal `n` from radiance
/// coefficients `l` = [L00, L1-1, L10, L11, L2-2, L2-1, L20, L21, L22].
/// Same math as [`Sh9Rgb::irradiance`], written in the paper's quadratic form.
pub fn irradiance_rh2001(l: &[Vec3; 9], n: Vec3) -> Vec3 {
    const C1: f32 = 0.429_043;
    const C2: f32 = 0.511_664;
    const C3: f32 = 0.743_125;
    const C4: f32 = 0.886_227;
    const C5: f32 = 0.247_708;
    let (x, y, z) = (n.x, n.y, n.z);
    let [l00, l1m1, l10, l11, l2m2, l2m1, l20, l21, l22] = *l;
    C1 * l22 * (x * x - y * y) + C3 * l20 * z * z + C4 * l00 - C5 * l20
        + 2.0 * C1 * (l2m2 * x * y + l21 * x * z + l2m1 * y * z)
        + 2.0 * C2 * (l11 * x + l1m1 * y + l10 * z)
}

/// GPU layout of [`Sh9Rgb`]: rgb in xyz, w unused. Twin of `Sh9` in `sh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Sh9Gpu {
    /// Coefficients in [`Sh9Rgb`]'s order, rgb in xyz and w = 0.
    pub c: [[f32; 4]; SH9_COUNT],
}

impl From<&Sh9Rgb> for Sh9Gpu {
    fn from(sh: &Sh9Rgb) -> Self {
        Sh9Gpu {
            c: std::array::from_fn(|i| sh.c[i].extend(0.0).to_array()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_under_the_quadrature() {
        // Project each basis function; the result must be the unit vector
        // (exact up to rounding from n = 6: 3 Gauss-Legendre nodes per
        // hemisphere integrate the degree-4 products).
        let mut worst = 0.0f32;
        for n in [6, 32] {
            for k in 0..SH9_COUNT {
                let sh = Sh9Rgb::project(|d| Vec3::splat(sh9_basis(d)[k]), n);
                for (j, c) in sh.c.iter().enumerate() {
                    let expect = if j == k { 1.0 } else { 0.0 };
                    worst = worst.max((c.x - expect).abs());
                }
            }
        }
        println!("basis orthonormality max error {worst:.2e}");
        // Measured 2.7e-6 on 2026-11-22 (f32 rounding); threshold 1e-5.
        assert!(worst < 1e-5, "{worst}");
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        for n in [1usize, 2, 3, 8, 17, 256] {
            let gl = gauss_legendre(n);
            for k in 0..(2 * n).min(12) {
                let got: f64 = gl.iter().map(|(x, w)| w * x.powi(k as i32)).sum();
                let want = if k % 2 == 0 {
                    2.0 / (k as f64 + 1.0)
                } else {
                    0.0
                };
                // f64 rounding: measured < 1e-14 on 2026-11-22; threshold 1e-12.
                assert!((got - want).abs() < 1e-12, "n={n} k={k}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn gpu_layout_is_144_bytes() {
        assert_eq!(std::mem::size_of::<Sh9Gpu>(), 144);
        let mut sh = Sh9Rgb::zero();
        sh.c[8] = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(Sh9Gpu::from(&sh).c[8], [1.0, 2.0, 3.0, 0.0]);
    }
}
