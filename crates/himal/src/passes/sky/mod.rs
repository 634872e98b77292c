//! Sky (L1 foundation): Preetham sky radiance, sun direction and colour, and
//! the sky light projected into third-order SH. See `docs/techniques/L1-preetham.md`.

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
