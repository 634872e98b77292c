//! Preetham, Shirley & Smits 1999 analytic sky (CPU model and GPU parameters).
//!
//! Radiance in kcd/m^2 (Preetham's Y unit), converted xyY -> XYZ -> linear
//! Rec.709: Y = 1 kcd/m^2 gives luminance 1.0. Constants as in Mitsuba 0.x
//! `src/luminaires/sky.cpp` (the test vectors' source). Twin: `shaders/sky.wgsl`.
//! Extensions beyond the paper (documented in `docs/techniques/L1-preetham.md`):
//! below-horizon fill, twilight fade with a night floor, turbidity clamp.

use glam::Vec3;

use super::sun::{
    SUN_ANGULAR_RADIUS_DEG, smoothstep, sun_disk_solid_angle, sun_illuminance_rgb,
    xyz_to_linear_srgb,
};

/// The sky model's sun is kept at least this far above the horizon:
/// theta_s <= pi/2 - this (rad); Preetham is undefined for a set sun.
pub const THETA_S_MARGIN_RAD: f32 = 0.001;
/// View directions closer to the horizon are clamped (cos theta >= this), as
/// Mitsuba does with theta <= pi/2 - 0.001.
pub const COS_THETA_MIN: f32 = 0.001;
/// Below the horizon the sky fades from the horizon value to the ground value
/// over -dir.y in [0, GROUND_BLEND_Y] (about 6 degrees).
pub const GROUND_BLEND_Y: f32 = 0.1;
/// Ground value = this times the azimuthal mean of the horizon radiance: a dark
/// ground-ish fill for SH lighting; the renderer draws terrain there.
pub const GROUND_FACTOR: f32 = 0.1;
/// Sky radiance scale reached once the sun is TWILIGHT_END_DEG below the
/// horizon (nautical twilight); night is dark but not black.
pub const NIGHT_FLOOR: f32 = 1.0e-4;
/// Sun depression (deg below the horizon) at which the twilight fade reaches [`NIGHT_FLOOR`].
pub const TWILIGHT_END_DEG: f32 = 12.0;
/// Turbidity range of the sky model (Preetham fitted and plotted 2..10; below
/// ~1.23 the zenith luminance formula turns negative).
pub const TURBIDITY_MIN: f32 = 2.0;
/// Highest turbidity of the model (hazy); higher values are clamped.
pub const TURBIDITY_MAX: f32 = 10.0;
/// Sun disk soft edge: the profile 1 - smoothstep(inner, outer, angle) falls
/// to one half at the sun's angular radius.
pub const SUN_DISK_INNER_FACTOR: f32 = 0.5;
/// Outer end of the sun disk's profile, in sun radii (zero beyond).
pub const SUN_DISK_OUTER_FACTOR: f32 = 1.5;

/// Preetham sky for one sun direction and turbidity.
#[derive(Clone, Debug, PartialEq)]
pub struct PreethamSky {
    sun_dir: Vec3,
    sun_dir_model: Vec3,
    theta_s: f32,
    turbidity: f32,
    /// Perez A..E, each as (x, y, Y).
    perez: [Vec3; 5],
    /// Zenith (x, y, Y kcd/m^2).
    zenith: Vec3,
    /// 1 / F(0, theta_s) for (x, y, Y).
    perez_inv_norm: Vec3,
    twilight: f32,
    /// Below-horizon fill, CIE XYZ before the twilight scale.
    ground_xyz: Vec3,
    sun_illuminance: Vec3,
}

/// Uniform-buffer twin of `SkyParams` in `sky.wgsl` (vec4s only, std140-safe).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SkyGpuParams {
    /// Perez coefficients A..E, each (x, y, Y, 0).
    pub perez_a: [f32; 4],
    /// Perez coefficient B (x, y, Y, 0).
    pub perez_b: [f32; 4],
    /// Perez coefficient C (x, y, Y, 0).
    pub perez_c: [f32; 4],
    /// Perez coefficient D (x, y, Y, 0).
    pub perez_d: [f32; 4],
    /// Perez coefficient E (x, y, Y, 0).
    pub perez_e: [f32; 4],
    /// Zenith (x, y, Y kcd/m^2); w = sky radiance scale (twilight factor).
    pub zenith_xyy: [f32; 4],
    /// 1 / F(0, theta_s) for (x, y, Y); w = GROUND_BLEND_Y.
    pub perez_inv_norm: [f32; 4],
    /// Ground fill, CIE XYZ kcd/m^2 before the twilight scale; w unused.
    pub ground_xyz: [f32; 4],
    /// Sun direction used by the sky model (theta_s clamped); w = COS_THETA_MIN.
    pub sun_dir_model: [f32; 4],
    /// True sun direction (unit, towards the sun); w unused.
    pub sun_direction: [f32; 4],
    /// Sun illuminance at the ground, linear RGB klux; w unused.
    pub sun_illuminance: [f32; 4],
    /// Sun disk: inner and outer angle of the soft edge (rad), 1 / solid angle, 0.
    pub sun_disk: [f32; 4],
}

/// Soft sun disk: inner and outer angle of the edge (rad), 1 / solid angle, 0.
fn sun_disk_params() -> [f32; 4] {
    let r = SUN_ANGULAR_RADIUS_DEG.to_radians();
    let (inner, outer) = (SUN_DISK_INNER_FACTOR * r, SUN_DISK_OUTER_FACTOR * r);
    [inner, outer, 1.0 / sun_disk_solid_angle(inner, outer), 0.0]
}

/// CIE xyY (Y in kcd/m^2) to XYZ; z clamped at 0 as in Mitsuba.
pub fn xyy_to_xyz(xyy: Vec3) -> Vec3 {
    if xyy.y <= 1e-6 {
        return Vec3::ZERO;
    }
    let y_over = xyy.z / xyy.y;
    Vec3::new(
        xyy.x * y_over,
        xyy.z,
        (1.0 - xyy.x - xyy.y).max(0.0) * y_over,
    )
}

/// CIE XYZ to xyY.
pub fn xyz_to_xyy(xyz: Vec3) -> Vec3 {
    let sum = xyz.x + xyz.y + xyz.z;
    if sum <= 1e-12 {
        return Vec3::ZERO;
    }
    Vec3::new(xyz.x / sum, xyz.y / sum, xyz.y)
}

/// xyY (Y in kcd/m^2) -> XYZ -> linear Rec.709/sRGB (negatives kept).
pub fn xyy_to_linear_srgb(xyy: Vec3) -> Vec3 {
    xyz_to_linear_srgb(xyy_to_xyz(xyy))
}

/// Perez et al. 1993 all-weather luminance distribution for three channels:
/// F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma).
pub fn perez_f(p: &[Vec3; 5], cos_theta: f32, gamma: f32, cos_gamma: f32) -> Vec3 {
    let b_term = (p[1] / cos_theta).exp();
    let d_term = (p[3] * gamma).exp();
    (Vec3::ONE + p[0] * b_term) * (Vec3::ONE + p[2] * d_term + p[4] * (cos_gamma * cos_gamma))
}

/// Twilight scale of the sky radiance for a sun at `elevation_deg`: 1 at and
/// above the horizon, log-linear (smoothstep in the exponent) down to
/// NIGHT_FLOOR at -TWILIGHT_END_DEG.
pub fn twilight_factor(elevation_deg: f32) -> f32 {
    let s = smoothstep(0.0, TWILIGHT_END_DEG, -elevation_deg);
    (NIGHT_FLOOR.ln() * s).exp()
}

impl PreethamSky {
    /// `sun_dir`: towards the sun (any length > 0); `turbidity` clamped to
    /// [TURBIDITY_MIN, TURBIDITY_MAX].
    pub fn new(sun_dir: Vec3, turbidity: f32) -> Self {
        let sun = sun_dir.try_normalize().unwrap_or(Vec3::Y);
        let t = turbidity.clamp(TURBIDITY_MIN, TURBIDITY_MAX);
        let theta_s = sun
            .y
            .clamp(-1.0, 1.0)
            .acos()
            .min(std::f32::consts::FRAC_PI_2 - THETA_S_MARGIN_RAD);
        let azimuth = Vec3::new(sun.x, 0.0, sun.z)
            .try_normalize()
            .unwrap_or(Vec3::NEG_Z);
        let sun_dir_model = azimuth * theta_s.sin() + Vec3::Y * theta_s.cos();

        let (t2, th, th2, th3) = (t * t, theta_s, theta_s * theta_s, theta_s.powi(3));
        let zenith_x = (0.00165 * th3 - 0.00374 * th2 + 0.00208 * th) * t2
            + (-0.02902 * th3 + 0.06377 * th2 - 0.03202 * th + 0.00394) * t
            + (0.11693 * th3 - 0.21196 * th2 + 0.06052 * th + 0.25885);
        let zenith_y = (0.00275 * th3 - 0.00610 * th2 + 0.00316 * th) * t2
            + (-0.04214 * th3 + 0.08970 * th2 - 0.04153 * th + 0.00515) * t
            + (0.15346 * th3 - 0.26756 * th2 + 0.06669 * th + 0.26688);
        let chi = (4.0 / 9.0 - t / 120.0) * (std::f32::consts::PI - 2.0 * th);
        let zenith_lum = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;

        // Perez A..E as linear functions of turbidity, per (x, y, Y).
        let lin = |x: [f32; 2], y: [f32; 2], l: [f32; 2]| {
            Vec3::new(x[0] * t + x[1], y[0] * t + y[1], l[0] * t + l[1])
        };
        let perez = [
            lin(
                [-0.01925, -0.25922],
                [-0.01669, -0.26078],
                [0.17872, -1.46303],
            ),
            lin(
                [-0.06651, 0.00081],
                [-0.09495, 0.00921],
                [-0.35540, 0.42749],
            ),
            lin(
                [-0.00041, 0.21247],
                [-0.00792, 0.21023],
                [-0.02266, 5.32505],
            ),
            lin(
                [-0.06409, -0.89887],
                [-0.04405, -1.65369],
                [0.12064, -2.57705],
            ),
            lin(
                [-0.00325, 0.04517],
                [-0.01092, 0.05291],
                [-0.06696, 0.37027],
            ),
        ];
        let f0 = perez_f(&perez, 1.0, theta_s, theta_s.cos());
        let elevation_deg = sun.y.clamp(-1.0, 1.0).asin().to_degrees();
        let mut sky = PreethamSky {
            sun_dir: sun,
            sun_dir_model,
            theta_s,
            turbidity: t,
            perez,
            zenith: Vec3::new(zenith_x, zenith_y, zenith_lum),
            perez_inv_norm: Vec3::ONE / f0,
            twilight: twilight_factor(elevation_deg),
            ground_xyz: Vec3::ZERO,
            sun_illuminance: sun_illuminance_rgb(sun, turbidity),
        };
        sky.ground_xyz = sky.mean_horizon_xyz() * GROUND_FACTOR;
        sky
    }

    /// Model xyY above the horizon, before the twilight scale.
    fn model_xyy(&self, dir: Vec3) -> Vec3 {
        let cos_theta = dir.y.max(COS_THETA_MIN);
        let cos_gamma = dir.dot(self.sun_dir_model).clamp(-1.0, 1.0);
        let f = perez_f(&self.perez, cos_theta, cos_gamma.acos(), cos_gamma);
        self.zenith * f * self.perez_inv_norm
    }

    fn mean_horizon_xyz(&self) -> Vec3 {
        const N: usize = 64;
        let sum = (0..N).fold(Vec3::ZERO, |acc, i| {
            let phi = (i as f32 + 0.5) * std::f32::consts::TAU / N as f32;
            acc + xyy_to_xyz(self.model_xyy(Vec3::new(phi.cos(), 0.0, phi.sin())))
        });
        sum / N as f32
    }

    /// CIE XYZ (kcd/m^2) towards unit direction `dir`, twilight applied.
    /// Below the horizon: the horizon value at the same azimuth blended into
    /// the ground fill over -dir.y in [0, GROUND_BLEND_Y].
    pub fn xyz(&self, dir: Vec3) -> Vec3 {
        let xyz = if dir.y >= 0.0 {
            xyy_to_xyz(self.model_xyy(dir))
        } else {
            let blend = smoothstep(0.0, GROUND_BLEND_Y, -dir.y);
            let horizon = Vec3::new(dir.x, 0.0, dir.z)
                .try_normalize()
                .map_or(Vec3::ZERO, |h| xyy_to_xyz(self.model_xyy(h)));
            horizon.lerp(self.ground_xyz, blend)
        };
        xyz * self.twilight
    }

    /// (x, y, Y kcd/m^2) towards unit direction `dir` (twilight applied).
    pub fn xyy(&self, dir: Vec3) -> Vec3 {
        if dir.y >= 0.0 {
            let xyy = self.model_xyy(dir);
            Vec3::new(xyy.x, xyy.y, xyy.z * self.twilight)
        } else {
            xyz_to_xyy(self.xyz(dir))
        }
    }

    /// Linear Rec.709 radiance (kcd/m^2 scale) towards unit direction `dir`;
    /// out-of-gamut negatives clamped to zero.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        xyz_to_linear_srgb(self.xyz(dir)).max(Vec3::ZERO)
    }

    /// Radiance of the soft sun disk (linear RGB, kcd/m^2), zero outside it;
    /// its integral over the sphere is the sun illuminance.
    pub fn sun_disk_radiance(&self, dir: Vec3) -> Vec3 {
        let [inner, outer, inv_solid_angle, _] = sun_disk_params();
        if dir.dot(self.sun_dir) <= 0.0 {
            return Vec3::ZERO;
        }
        // asin(|d x s|) keeps precision at tiny angles where acos(dot) does not.
        let angle = dir.cross(self.sun_dir).length().min(1.0).asin();
        let profile = 1.0 - smoothstep(inner, outer, angle);
        self.sun_illuminance * (profile * inv_solid_angle)
    }

    /// Preetham zenith (x, y, Y kcd/m^2), before the twilight scale.
    pub fn zenith_xyy(&self) -> Vec3 {
        self.zenith
    }

    /// Perez A..E of the luminance Y.
    pub fn perez_y(&self) -> [f32; 5] {
        self.perez.map(|c| c.z)
    }

    /// Perez A..E of the chromaticities x and y.
    pub fn perez_chromaticity(&self) -> ([f32; 5], [f32; 5]) {
        (self.perez.map(|c| c.x), self.perez.map(|c| c.y))
    }

    /// Unit vector towards the true sun (not clamped above the horizon).
    pub fn sun_direction(&self) -> Vec3 {
        self.sun_dir
    }

    /// Sun zenith angle used by the model (clamped below 90 deg).
    pub fn theta_s(&self) -> f32 {
        self.theta_s
    }

    /// Turbidity of the model, clamped to [`TURBIDITY_MIN`]..=[`TURBIDITY_MAX`].
    pub fn turbidity(&self) -> f32 {
        self.turbidity
    }

    /// Sky radiance scale for the sun's elevation (1 by day, NIGHT_FLOOR at night).
    pub fn twilight(&self) -> f32 {
        self.twilight
    }

    /// Sun illuminance at the ground, linear RGB klux.
    pub fn sun_illuminance(&self) -> Vec3 {
        self.sun_illuminance
    }

    /// The uniform of `sky.wgsl`'s `SkyParams` for this sky.
    pub fn gpu_params(&self) -> SkyGpuParams {
        let v4 = |v: Vec3, w: f32| v.extend(w).to_array();
        SkyGpuParams {
            perez_a: v4(self.perez[0], 0.0),
            perez_b: v4(self.perez[1], 0.0),
            perez_c: v4(self.perez[2], 0.0),
            perez_d: v4(self.perez[3], 0.0),
            perez_e: v4(self.perez[4], 0.0),
            zenith_xyy: v4(self.zenith, self.twilight),
            perez_inv_norm: v4(self.perez_inv_norm, GROUND_BLEND_Y),
            ground_xyz: v4(self.ground_xyz, 0.0),
            sun_dir_model: v4(self.sun_dir_model, COS_THETA_MIN),
            sun_direction: v4(self.sun_dir, 0.0),
            sun_illuminance: v4(self.sun_illuminance, 0.0),
            sun_disk: sun_disk_params(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sky_is_continuous_across_the_horizon() {
        let sky = PreethamSky::new(Vec3::new(0.3, 0.5, -0.8), 3.0);
        let mut worst = 0.0f32;
        for i in 0..16 {
            let phi = i as f32 * 0.4;
            let (c, s) = (phi.cos(), phi.sin());
            let above = sky.radiance(Vec3::new(c, 1e-4, s).normalize());
            let below = sky.radiance(Vec3::new(c, -1e-4, s).normalize());
            worst = worst.max((above - below).length() / above.length());
        }
        println!("horizon step, relative: {worst:.2e}");
        // Measured 1.35e-4 on 2026-11-22 (the 1e-4 rad step itself); threshold 1e-3.
        assert!(worst < 1e-3, "{worst}");
    }

    #[test]
    fn twilight_fades_to_the_night_floor() {
        assert_eq!(twilight_factor(10.0), 1.0);
        assert_eq!(twilight_factor(0.0), 1.0);
        assert!((twilight_factor(-30.0) - NIGHT_FLOOR).abs() < 1e-9);
        let mut prev = 1.0;
        for i in 1..=24 {
            let f = twilight_factor(-0.5 * i as f32);
            assert!(f < prev && f >= NIGHT_FLOOR * 0.999);
            prev = f;
        }
    }

    #[test]
    fn gpu_params_size_is_192_bytes() {
        assert_eq!(std::mem::size_of::<SkyGpuParams>(), 12 * 16);
    }
}
