//! Sky (L1): Preetham radiance (foundation) or Bruneton precomputed
//! scattering tables ([`SkyModel`]), sun direction and colour, and the sky
//! light projected into third-order SH. See `docs/techniques/L1-preetham.md`
//! and `docs/techniques/L1.md`.

pub mod bruneton;
mod pass;
pub mod preetham;
pub mod reference;
pub mod sun;

pub use pass::SkyPass;
pub use preetham::{PreethamSky, SkyGpuParams, xyy_to_linear_srgb};
pub use reference::{SkyLight, sky_irradiance_sh, sky_radiance_sh};
pub use sun::{
    SUN_ILLUMINANCE_KLUX, SunPosition, sun_illuminance_rgb, sun_position, sun_transmittance_rgb,
};

/// Which sky a frame draws and lights with (`--sky`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SkyModel {
    /// Preetham et al. 1999 analytic sky (the library default: existing
    /// thresholds and goldens were measured with it).
    #[default]
    Preetham,
    /// Bruneton & Neyret 2008 precomputed tables (the CLI default).
    Bruneton,
}

impl std::str::FromStr for SkyModel {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self, crate::Error> {
        match s {
            "preetham" => Ok(SkyModel::Preetham),
            "bruneton" => Ok(SkyModel::Bruneton),
            other => Err(crate::Error::InvalidSettings(format!(
                "unknown sky model \"{other}\" (known: preetham, bruneton)"
            ))),
        }
    }
}
