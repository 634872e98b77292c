//! The sun: direction from local solar time, latitude and day of year, and
//! colour from Preetham et al. 1999 (Appendix A.2) spectral transmittance.
//!
//! Frame: right-handed, Y up; north = -Z, east = +X. Azimuth is measured from
//! north towards east (90 deg = east), elevation above the horizon.
//! Scale: illuminance at the ground in klux (see `docs/techniques/L1-preetham.md`).

use glam::Vec3;

/// Extraterrestrial solar illuminance (klux); the sun outside the atmosphere
/// is taken as white (1, 1, 1) in linear Rec.709, so the ground illuminance is
/// `SUN_ILLUMINANCE_KLUX * sun_transmittance_rgb`.
pub const SUN_ILLUMINANCE_KLUX: f32 = 127.5;

/// Mean angular radius of the sun disk (half of 0.533 deg).
pub const SUN_ANGULAR_RADIUS_DEG: f32 = 0.2666;

/// Sun elevation (deg) over which the sun light fades in: zero at and below
/// 0 deg, full from this elevation up (smoothstep). Avoids a pop at sunset.
pub const SUN_HORIZON_FADE_DEG: f32 = 2.0;

/// Where the sun stands: direction, elevation and azimuth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunPosition {
    /// Unit vector towards the sun, world space (below the horizon at night).
    pub direction: Vec3,
    /// Degrees above the horizon (negative below).
    pub elevation_deg: f32,
    /// From north (-Z) towards east (+X), in [0, 360).
    pub azimuth_deg: f32,
}

/// Solar declination (rad), Preetham 1999 Appendix A.6:
/// delta = 0.4093 sin(2 pi (J - 81) / 368).
pub fn solar_declination(day_of_year: u32) -> f32 {
    0.4093 * (std::f32::consts::TAU * (day_of_year as f32 - 81.0) / 368.0).sin()
}

/// Sun position for local solar time `time_hours` (12 = solar noon, no
/// equation of time or longitude correction), latitude in degrees (north
/// positive) and day of year (1..=365). Hour angle H = pi (t - 12) / 12; in the
/// local east/north/up frame the sun is
/// up = sin(lat) sin(delta) + cos(lat) cos(delta) cos(H),
/// east = -cos(delta) sin(H),
/// north = cos(lat) sin(delta) - sin(lat) cos(delta) cos(H).
pub fn sun_position(time_hours: f32, latitude_deg: f32, day_of_year: u32) -> SunPosition {
    let delta = solar_declination(day_of_year);
    let lat = latitude_deg.to_radians();
    let h = std::f32::consts::PI * (time_hours - 12.0) / 12.0;
    let (sin_lat, cos_lat) = lat.sin_cos();
    let (sin_d, cos_d) = delta.sin_cos();
    let cos_h = h.cos();
    let up = sin_lat * sin_d + cos_lat * cos_d * cos_h;
    let east = -cos_d * h.sin();
    let north = cos_lat * sin_d - sin_lat * cos_d * cos_h;
    let direction = Vec3::new(east, up, -north).normalize();
    let azimuth = east.atan2(north).to_degrees();
    SunPosition {
        direction,
        elevation_deg: direction.y.clamp(-1.0, 1.0).asin().to_degrees(),
        azimuth_deg: if azimuth < 0.0 {
            azimuth + 360.0
        } else {
            azimuth
        },
    }
}

/// Wavelength grid of the spectral integration: 380..=780 nm every 10 nm.
const LAMBDA_START_NM: f32 = 380.0;
const LAMBDA_STEP_NM: f32 = 10.0;
const LAMBDA_COUNT: usize = 41;

/// CIE 1931 2-degree observer x, y, z bar at 380..=780 nm, 10 nm steps (CIE 015).
// Digits as published (trailing zeros kept so the table reads like the source).
#[allow(clippy::excessive_precision)]
#[rustfmt::skip]
const CIE_1931_XYZ_BAR: [[f32; 3]; LAMBDA_COUNT] = [
    [0.001368, 0.000039, 0.006450], [0.004243, 0.000120, 0.020050], [0.014310, 0.000396, 0.067850],
    [0.043510, 0.001210, 0.207400], [0.134380, 0.004000, 0.645600], [0.283900, 0.011600, 1.385600],
    [0.348280, 0.023000, 1.747060], [0.336200, 0.038000, 1.772110], [0.290800, 0.060000, 1.669200],
    [0.195360, 0.090980, 1.287640], [0.095640, 0.139020, 0.812950], [0.032010, 0.208020, 0.465180],
    [0.004900, 0.323000, 0.272000], [0.009300, 0.503000, 0.158200], [0.063270, 0.710000, 0.078250],
    [0.165500, 0.862000, 0.042160], [0.290400, 0.954000, 0.020300], [0.433450, 0.994950, 0.008750],
    [0.594500, 0.995000, 0.003900], [0.762100, 0.952000, 0.002100], [0.916300, 0.870000, 0.001650],
    [1.026300, 0.757000, 0.001100], [1.062200, 0.631000, 0.000800], [1.002600, 0.503000, 0.000340],
    [0.854450, 0.381000, 0.000190], [0.642400, 0.265000, 0.000050], [0.447900, 0.175000, 0.000020],
    [0.283500, 0.107000, 0.0], [0.164900, 0.061000, 0.0], [0.087400, 0.032000, 0.0],
    [0.046770, 0.017000, 0.0], [0.022700, 0.008210, 0.0], [0.011359, 0.004102, 0.0],
    [0.005790, 0.002091, 0.0], [0.002899, 0.001047, 0.0], [0.001440, 0.000520, 0.0],
    [0.000690, 0.000249, 0.0], [0.000332, 0.000120, 0.0], [0.000166, 0.000060, 0.0],
    [0.000083, 0.000030, 0.0], [0.000042, 0.000015, 0.0],
];

/// Extraterrestrial solar spectral irradiance at 380..=750 nm, 10 nm steps
/// (W m^-2 um^-1, the table of Preetham's code and Mitsuba/LuxRender; held
/// constant beyond 750 nm where the observer is nearly blind).
#[rustfmt::skip]
const SOLAR_SPECTRUM_380_750: [f32; 38] = [
    165.5, 162.3, 211.2, 258.8, 258.2, 242.3, 267.6, 296.6, 305.4, 300.6,
    306.6, 288.3, 287.1, 278.2, 271.0, 272.3, 263.6, 255.0, 250.6, 253.1,
    253.5, 251.3, 246.3, 241.7, 236.8, 232.1, 228.2, 223.4, 219.7, 215.3,
    211.0, 207.3, 202.4, 198.7, 194.3, 190.7, 186.3, 182.6,
];

/// Ozone absorption k_o (cm^-1), (nm, value), from Iqbal's "An Introduction to
/// Solar Radiation" p. 127 as in Preetham's appendix; only the part that
/// brackets 380..780 nm (355 -> 445 nm is linear in the source too).
#[rustfmt::skip]
const OZONE_K_O: [(f32, f32); 53] = [
    (355.0, 0.0), (445.0, 0.003), (450.0, 0.003), (455.0, 0.004), (460.0, 0.006),
    (465.0, 0.008), (470.0, 0.009), (475.0, 0.012), (480.0, 0.014), (485.0, 0.017),
    (490.0, 0.021), (495.0, 0.025), (500.0, 0.03), (505.0, 0.035), (510.0, 0.04),
    (515.0, 0.045), (520.0, 0.048), (525.0, 0.057), (530.0, 0.063), (535.0, 0.07),
    (540.0, 0.075), (545.0, 0.08), (550.0, 0.085), (555.0, 0.095), (560.0, 0.103),
    (565.0, 0.110), (570.0, 0.12), (575.0, 0.122), (580.0, 0.12), (585.0, 0.118),
    (590.0, 0.115), (595.0, 0.12), (600.0, 0.125), (605.0, 0.130), (610.0, 0.12),
    (620.0, 0.105), (630.0, 0.09), (640.0, 0.079), (650.0, 0.067), (660.0, 0.057),
    (670.0, 0.048), (680.0, 0.036), (690.0, 0.028), (700.0, 0.023), (710.0, 0.018),
    (720.0, 0.014), (730.0, 0.011), (740.0, 0.010), (750.0, 0.009), (760.0, 0.007),
    (770.0, 0.004), (780.0, 0.0), (790.0, 0.0),
];

/// Mixed-gas (O2) absorption k_g (cm^-1), Iqbal p. 130.
const GAS_K_G: [(f32, f32); 4] = [(759.0, 0.0), (760.0, 3.0), (770.0, 0.210), (771.0, 0.0)];

/// Water-vapour absorption k_wa (cm^-1), Iqbal p. 130.
#[rustfmt::skip]
const WATER_K_WA: [(f32, f32); 13] = [
    (689.0, 0.0), (690.0, 0.016), (700.0, 0.024), (710.0, 0.0125), (720.0, 1.0),
    (730.0, 0.87), (740.0, 0.061), (750.0, 0.001), (760.0, 0.00001), (770.0, 0.00001),
    (780.0, 0.0006), (790.0, 0.0175), (800.0, 0.036),
];

/// Ozone layer thickness (cm NTP) and precipitable water (cm), Preetham's values.
const OZONE_L_CM: f32 = 0.35;
const WATER_W_CM: f32 = 2.0;
/// Angstrom wavelength exponent of the aerosols.
const ANGSTROM_ALPHA: f32 = 1.3;

/// Piecewise-linear lookup, zero outside the table.
fn table_lerp(table: &[(f32, f32)], lambda: f32) -> f32 {
    let Some(i) = table
        .windows(2)
        .position(|w| lambda >= w[0].0 && lambda <= w[1].0)
    else {
        return 0.0;
    };
    let ((l0, v0), (l1, v1)) = (table[i], table[i + 1]);
    v0 + (v1 - v0) * (lambda - l0) / (l1 - l0)
}

/// Relative optical air mass (Kasten 1966, Preetham A.2), theta_s in radians,
/// clamped to the horizon where the formula ends.
pub fn relative_optical_mass(theta_s: f32) -> f32 {
    let theta = theta_s.min(std::f32::consts::FRAC_PI_2);
    1.0 / (theta.cos() + 0.15 * (93.885 - theta.to_degrees()).powf(-1.253))
}

/// Spectral transmittance of the atmosphere along the sun ray (Preetham 1999
/// Appendix A.2): Rayleigh, Angstrom aerosols with beta from turbidity, ozone,
/// mixed gases and water vapour. `lambda_nm` in nanometres, `m` the air mass.
pub fn sun_spectral_transmittance(lambda_nm: f32, m: f32, turbidity: f32) -> f32 {
    let lambda_um = lambda_nm / 1000.0;
    // T = 1 is a pure Rayleigh atmosphere; below it beta would turn negative.
    let beta = 0.046_083_66 * turbidity.max(1.0) - 0.045_860_26;
    let tau_r = (-m * 0.008735 * lambda_um.powf(-4.08)).exp();
    let tau_a = (-m * beta * lambda_um.powf(-ANGSTROM_ALPHA)).exp();
    let tau_o = (-m * table_lerp(&OZONE_K_O, lambda_nm) * OZONE_L_CM).exp();
    let k_g = table_lerp(&GAS_K_G, lambda_nm);
    let tau_g = (-1.41 * k_g * m / (1.0 + 118.93 * k_g * m).powf(0.45)).exp();
    let k_wa = table_lerp(&WATER_K_WA, lambda_nm) * WATER_W_CM * m;
    let tau_wa = (-0.2385 * k_wa / (1.0 + 20.07 * k_wa).powf(0.45)).exp();
    tau_r * tau_a * tau_o * tau_g * tau_wa
}

/// CIE XYZ to linear Rec.709 / sRGB (D65), IEC 61966-2-1.
pub fn xyz_to_linear_srgb(xyz: Vec3) -> Vec3 {
    Vec3::new(
        3.240_454_2 * xyz.x - 1.537_138_5 * xyz.y - 0.498_531_4 * xyz.z,
        -0.969_266 * xyz.x + 1.876_010_8 * xyz.y + 0.041_556 * xyz.z,
        0.055_643_4 * xyz.x - 0.204_025_9 * xyz.y + 1.057_225_2 * xyz.z,
    )
}

/// Linear RGB of the solar spectrum times `tau(lambda)`, integrated against
/// the CIE 1931 observer on the 10 nm grid (exact colourimetry; may be negative
/// out of gamut).
fn solar_rgb_colorimetric(tau: impl Fn(f32) -> f32) -> Vec3 {
    let mut xyz = Vec3::ZERO;
    for (i, cmf) in CIE_1931_XYZ_BAR.iter().enumerate() {
        xyz += Vec3::from_array(*cmf) * (solar_spectrum(i) * tau(wavelength_nm(i)));
    }
    xyz_to_linear_srgb(xyz)
}

fn wavelength_nm(i: usize) -> f32 {
    LAMBDA_START_NM + LAMBDA_STEP_NM * i as f32
}

fn solar_spectrum(i: usize) -> f32 {
    SOLAR_SPECTRUM_380_750[i.min(SOLAR_SPECTRUM_380_750.len() - 1)]
}

/// Per-channel weighted mean of `tau` over the solar spectrum, the weights
/// being the Rec.709 colour-matching functions (M * xyz_bar) with their
/// negative lobes removed: a sensor with non-negative channel responses.
fn solar_rgb_mean(tau: impl Fn(f32) -> f32) -> Vec3 {
    let (mut num, mut den) = (Vec3::ZERO, Vec3::ZERO);
    for (i, cmf) in CIE_1931_XYZ_BAR.iter().enumerate() {
        let w = xyz_to_linear_srgb(Vec3::from_array(*cmf)).max(Vec3::ZERO) * solar_spectrum(i);
        num += w * tau(wavelength_nm(i));
        den += w;
    }
    num / den
}

/// smoothstep as in WGSL.
pub(crate) fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Air mass and horizon fade for a sun direction; None at and below the horizon.
fn air_mass_and_fade(sun_dir: Vec3) -> Option<(f32, f32)> {
    let d = sun_dir.try_normalize()?;
    let elevation_deg = d.y.clamp(-1.0, 1.0).asin().to_degrees();
    let fade = smoothstep(0.0, SUN_HORIZON_FADE_DEG, elevation_deg);
    (fade > 0.0).then(|| (relative_optical_mass(d.y.clamp(-1.0, 1.0).acos()), fade))
}

/// Sun transmittance per linear-RGB channel, in (0, 1]: the mean of the
/// spectral transmittance tau(lambda) over the solar spectrum weighted by each
/// channel's spectral response (Rec.709 colour-matching functions, negative
/// lobes removed), so the sun above the atmosphere is white (1, 1, 1).
///
/// Why not exact colourimetry ([`sun_transmittance_rgb_colorimetric`]): the
/// low sun's spectrum falls outside the Rec.709 gamut (blue turns negative
/// below ~2 deg at T = 2, ~5 deg at T = 6), while a weighted mean of tau is
/// always in (0, 1] and reddens monotonically. With the sun above 60 deg the
/// two differ by at most 6.3% per channel (T = 6; measured in `tests/sky.rs`),
/// the mean being a little less saturated. Why not three "RGB wavelengths": the
/// exponential falls fastest in the blue, so single wavelengths overstate the
/// reddening of broad channels.
///
/// Zero at and below the horizon, with a smoothstep fade over the first
/// [`SUN_HORIZON_FADE_DEG`] of elevation.
pub fn sun_transmittance_rgb(sun_dir: Vec3, turbidity: f32) -> Vec3 {
    let Some((m, fade)) = air_mass_and_fade(sun_dir) else {
        return Vec3::ZERO;
    };
    solar_rgb_mean(|l| sun_spectral_transmittance(l, m, turbidity)).min(Vec3::ONE) * fade
}

/// Exact colourimetric sun transmittance (transmitted over extraterrestrial
/// solar RGB, per channel), unclamped: negative where out of gamut. For
/// comparison with [`sun_transmittance_rgb`]; same horizon fade.
pub fn sun_transmittance_rgb_colorimetric(sun_dir: Vec3, turbidity: f32) -> Vec3 {
    let Some((m, fade)) = air_mass_and_fade(sun_dir) else {
        return Vec3::ZERO;
    };
    let transmitted = solar_rgb_colorimetric(|l| sun_spectral_transmittance(l, m, turbidity));
    transmitted / solar_rgb_colorimetric(|_| 1.0) * fade
}

/// Sun illuminance at the ground on a plane facing the sun, linear RGB klux.
pub fn sun_illuminance_rgb(sun_dir: Vec3, turbidity: f32) -> Vec3 {
    SUN_ILLUMINANCE_KLUX * sun_transmittance_rgb(sun_dir, turbidity)
}

/// Solid angle (sr) of the soft sun disk profile 1 - smoothstep(a, b, theta),
/// small-angle form: pi (a^2 + a w + 0.3 w^2) with w = b - a.
pub fn sun_disk_solid_angle(inner_rad: f32, outer_rad: f32) -> f32 {
    let w = outer_rad - inner_rad;
    std::f32::consts::PI * (inner_rad * inner_rad + inner_rad * w + 0.3 * w * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn disk_solid_angle_matches_quadrature() {
        let r = SUN_ANGULAR_RADIUS_DEG.to_radians();
        let (a, b) = (0.5 * r, 1.5 * r);
        let n = 20_000;
        let mut omega = 0.0f64;
        for i in 0..n {
            let theta = (i as f64 + 0.5) / n as f64 * b as f64;
            let p = 1.0 - smoothstep(a, b, theta as f32) as f64;
            omega += std::f64::consts::TAU * p * theta.sin() * (b as f64 / n as f64);
        }
        let rel = (sun_disk_solid_angle(a, b) as f64 / omega - 1.0).abs();
        println!("sun disk solid angle, small-angle form vs quadrature: rel {rel:.2e}");
        // Measured 2.3e-6 on 2026-11-22 (small-angle form); threshold 1e-4.
        assert!(rel < 1e-4, "relative error {rel}");
    }

    #[test]
    fn table_lerp_interpolates_and_is_zero_outside() {
        assert_eq!(table_lerp(&GAS_K_G, 700.0), 0.0);
        assert!((table_lerp(&OZONE_K_O, 400.0) - 0.0015).abs() < 1e-7);
        assert!((table_lerp(&OZONE_K_O, 575.0) - 0.122).abs() < 1e-7);
    }
}
