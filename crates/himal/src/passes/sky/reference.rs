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
    /// The Preetham sky model of this time of day (radiance, GPU parameters).
    pub sky: PreethamSky,
    /// Sky and ground-bounce irradiance SH (sun excluded; it is a separate
    /// directional light). See [`sky_and_ground_irradiance_sh`].
    pub irradiance_sh: Sh9Rgb,
}

/// Albedo of the ground that bounces sun and sky light back up (a grassy
/// valley: Jacobs & Stein's meadow albedo is about 0.15-0.25, greenish).
pub const GROUND_ALBEDO: Vec3 = Vec3::new(0.16, 0.19, 0.11);

/// Irradiance SH of the sky above the horizon and, below it, of a Lambertian
/// ground lit by the sun and the sky: L_g = albedo / pi * (E_sun * max(sun.y, 0) + E_sky(up)).
/// Without it, surfaces facing down (and metals reflecting the ground) see
/// only the dim below-horizon fill of the sky model.
pub fn sky_and_ground_irradiance_sh(
    sky: &PreethamSky,
    sun_direction: Vec3,
    sun_illuminance: Vec3,
) -> Sh9Rgb {
    let e_up = sky_irradiance_sh(sky).eval(Vec3::Y).max(Vec3::ZERO)
        + sun_illuminance * sun_direction.y.max(0.0);
    let l_ground = GROUND_ALBEDO * e_up / std::f32::consts::PI;
    let radiance = |d: Vec3| {
        if d.y >= 0.0 {
            return sky.radiance(d);
        }
        let blend = smoothstep(0.0, super::preetham::GROUND_BLEND_Y, -d.y);
        sky.radiance(d).lerp(l_ground, blend)
    };
    Sh9Rgb::project(radiance, SKY_SH_SAMPLES_PER_AXIS).radiance_to_irradiance_coeffs()
}

fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl SkyLight {
    /// Sky light at local solar time `time_hours`, `latitude_deg` (north
    /// positive), `day_of_year` (1..=365) and atmospheric `turbidity`.
    pub fn new(time_hours: f32, latitude_deg: f32, day_of_year: u32, turbidity: f32) -> SkyLight {
        let sun = sun_position(time_hours, latitude_deg, day_of_year);
        Self::towards(
            sun.direction,
            sun_illuminance_rgb(sun.direction, turbidity),
            turbidity,
        )
    }

    /// The sky light of `sun`: its time and place, or its directional
    /// light where it has one (the sky drawn for that sun direction).
    pub fn of_sun(sun: &crate::scene::SunDesc) -> SkyLight {
        match &sun.light {
            Some(l) => Self::towards(l.to_light, l.illuminance_klux, sun.turbidity),
            None => Self::new(
                sun.time_hours,
                sun.latitude_deg,
                sun.day_of_year,
                sun.turbidity,
            ),
        }
    }

    fn towards(sun_direction: Vec3, sun_illuminance: Vec3, turbidity: f32) -> SkyLight {
        let sky = PreethamSky::new(sun_direction, turbidity);
        SkyLight {
            sun_direction,
            sun_illuminance,
            irradiance_sh: sky_and_ground_irradiance_sh(&sky, sun_direction, sun_illuminance),
            sky,
        }
    }
}
