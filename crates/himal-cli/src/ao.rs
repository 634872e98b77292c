//! AO options shared by `render` and `bench` (TECHNIQUES O1-O4).

use anyhow::{Result, bail};
use clap::Args;
use himal::passes::ao::{AoMode, AoSettings};

#[derive(Args, Debug, Clone)]
pub struct AoArgs {
    /// Screen-space AO: off, hbao (HBAO + bilateral blur), hbao+stf (plus the selective temporal filter),
    /// ssdo (plus Ryse's directional occlusion: contact shadows on the sun and local lights, O4).
    #[arg(
        long,
        default_value = "hbao+stf",
        value_name = "off|hbao|hbao+stf|ssdo",
        allow_hyphen_values = true
    )]
    pub ao: String,
    /// HBAO resolution.
    #[arg(
        long,
        default_value = "half",
        value_name = "half|full",
        allow_hyphen_values = true
    )]
    pub ao_resolution: String,
    /// HBAO radius in metres.
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub ao_radius: Option<f32>,
    /// Blur sampling: adaptive (point inner half, bilinear outer half) or brute force.
    #[arg(
        long,
        default_value = "adaptive",
        value_name = "adaptive|brute",
        allow_hyphen_values = true
    )]
    pub ao_blur: String,
    /// How ao.pack + ao.blur_x run: two full-screen passes (the blur fetching
    /// every tap), or one compute pass packing a shared-memory row tile
    /// once and reading its taps from it (#23; same taps and weights).
    #[arg(
        long,
        default_value = "fragment",
        value_name = "fragment|compute",
        allow_hyphen_values = true
    )]
    pub ao_blur_pass: String,
    /// Blur kernel radius in pixels.
    #[arg(long, value_name = "PIXELS", allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub ao_blur_radius: Option<u32>,
    /// Reflection occlusion of ambient specular (O4): along the reflection vector with
    /// `--ao ssdo`, Lagarde's specular occlusion from AO with the other modes.
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub reflection_occlusion: String,
    /// How much the SSDO directional term darkens the sun and local lights (0..1).
    #[arg(long, value_name = "0..1", allow_hyphen_values = true)]
    pub ssdo_strength: Option<f32>,
    /// O5 AO colour bleeding: ambient diffuse occlusion tinted by the
    /// low-frequency albedo around each pixel (docs/techniques/O5.md; off
    /// by default: it overstates bounce light against a ray-traced estimate).
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub ao_bleed: String,
    /// O6 large-scale AO: the height field within 7.5 m occludes ambient
    /// light at scales the screen cannot see (docs/techniques/O6.md); it
    /// replaces L2's sky visibility, which reads the same height field.
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub ao_large_scale: String,
}

impl AoArgs {
    pub fn settings(&self) -> Result<AoSettings> {
        let mut s = AoSettings {
            mode: self
                .ao
                .parse::<AoMode>()
                .map_err(|e| anyhow::anyhow!("--ao {}: {e}", self.ao))?,
            ..AoSettings::default()
        };
        s.full_resolution = match self.ao_resolution.as_str() {
            "half" => false,
            "full" => true,
            other => bail!("--ao-resolution {other}: expected half or full"),
        };
        s.adaptive_blur = match self.ao_blur.as_str() {
            "adaptive" => true,
            "brute" => false,
            other => bail!("--ao-blur {other}: expected adaptive or brute"),
        };
        s.compute_blur = match self.ao_blur_pass.as_str() {
            "fragment" => false,
            "compute" => true,
            other => bail!("--ao-blur-pass {other}: expected fragment or compute"),
        };
        if let Some(r) = self.ao_radius {
            if !(r.is_finite() && r > 0.0 && r <= 100.0) {
                bail!("--ao-radius {r}: must be a number of metres in (0, 100]");
            }
            s.radius = r;
        }
        s.bleed = match self.ao_bleed.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--ao-bleed {other}: expected on or off"),
        };
        s.large_scale = match self.ao_large_scale.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--ao-large-scale {other}: expected on or off"),
        };
        if let Some(r) = self.ao_blur_radius {
            s.blur_radius = r;
        }
        s.reflection_occlusion = match self.reflection_occlusion.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--reflection-occlusion {other}: expected on or off"),
        };
        if let Some(k) = self.ssdo_strength {
            if !(0.0..=1.0).contains(&k) {
                bail!("--ssdo-strength {k}: must be in [0, 1]");
            }
            s.ssdo_strength = k;
        }
        s.validate().map_err(|e| match self.ao_blur_radius {
            Some(r) => anyhow::anyhow!("--ao-blur-radius {r}: {e}"),
            None => e.into(),
        })?;
        Ok(s)
    }
}
