//! CPU sky light: Preetham sky projected into third-order SH, plus the sun.
//! This is what the renderer recomputes when the time of day changes.

use glam::Vec3;

use super::preetham::PreethamSky;
use super::sun::{sun_illuminance_rgb, sun_position};
use crate::math::sh::Sh9Rgb;

/// Quadrature resolution of the sky SH projection (`n` bands in cos theta times
/// `2n` azimuths). Chosen by measurement in `tests/sky.rs`
/// (`sky_sh_quadrature_convergence`): the irradiance differs from an n = 512
/// projection by at most 0.19% at n = 32 over five skies (0.36% at n = 24,
/// 1.4% at n = 16); n = 32 is 2048 radiance evaluations, ~0.2 ms.
pub const SKY_SH_SAMPLES_PER_AXIS: u32 = 32;

/// Radiance SH of the sky over the full sphere (lower hemisphere = the
/// below-horizon fill of [`PreethamSky::radiance`]); sun disk excluded.
pub fn sky_radiance_sh(sky: &PreethamSky) -> Sh9Rgb {
    Sh9Rgb::project(|d| sky.radiance(d), SKY_SH_SAMPLES_PER_AXIS)
}

/// Irradiance SH of the sky (cosine-convolved): `eval(n)` gives E(n) in klux.
pub fn sky_irradiance_sh(sky: &PreethamSky) -> Sh9Rgb {
    sky_radiance_sh(sky).radiance_to_irradiance_coeffs()
}

/// Everything the renderer needs for sky lighting at one time of day.
#[derive(Clone, Debug, PartialEq)]
pub struct SkyLight {
    /// Unit vector towards the sun (below the horizon at night).
    pub sun_direction: Vec3,
    /// Sun illuminance at the ground, linear RGB klux (zero at night).
    pub sun_illuminance: Vec3,
    pub sky: PreethamSky,
    /// Sky irradiance SH (sun excluded; it is a separate directional light).
    pub irradiance_sh: Sh9Rgb,
}

impl SkyLight {
    /// Sky light at local solar time `time_hours`, `latitude_deg` (north
    /// positive), `day_of_year` (1..=365) and atmospheric `turbidity`.
    pub fn new(time_hours: f32, latitude_deg: f32, day_of_year: u32, turbidity: f32) -> SkyLight {
        let sun = sun_position(time_hours, latitude_deg, day_of_year);
        let sky = PreethamSky::new(sun.direction, turbidity);
        SkyLight {
            sun_direction: sun.direction,
            sun_illuminance: sun_illuminance_rgb(sun.direction, turbidity),
            irradiance_sh: sky_irradiance_sh(&sky),
            sky,
        }
    }
}
