//! AO settings (`himal render --ao ...`), the uniform twin of `AoParams` in
//! `shaders/ao.wgsl`, and the 4x4 jitter pattern.

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use crate::Error;

/// Which AO runs (`--ao off|hbao|hbao+stf|ssdo`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum AoMode {
    /// No AO pass runs; lighting reads AO = 1 (unoccluded).
    Off,
    /// HBAO and the cross-bilateral blur.
    Hbao,
    /// HBAO, the blur and the selective temporal filter (Battlefield 3).
    #[default]
    HbaoStf,
    /// Ryse's screen-space directional occlusion (O4): `HbaoStf` plus a
    /// directional term (first harmonic of the horizon rise) that occludes
    /// the sun and local lights and, with reflection occlusion, ambient specular.
    Ssdo,
}

impl AoMode {
    /// The `--ao` spellings, in variant order (what `from_str` accepts).
    pub const NAMES: [&'static str; 4] = ["off", "hbao", "hbao+stf", "ssdo"];

    /// The selective temporal filter runs (with its history ring).
    pub fn temporal(self) -> bool {
        matches!(self, AoMode::HbaoStf | AoMode::Ssdo)
    }

    /// The directional term is computed (O4).
    pub fn directional(self) -> bool {
        self == AoMode::Ssdo
    }
}

impl std::str::FromStr for AoMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s {
            "off" => Ok(AoMode::Off),
            "hbao" => Ok(AoMode::Hbao),
            "hbao+stf" => Ok(AoMode::HbaoStf),
            "ssdo" => Ok(AoMode::Ssdo),
            other => Err(Error::InvalidSettings(format!(
                "unknown AO mode \"{other}\" (known: {})",
                AoMode::NAMES.join(", ")
            ))),
        }
    }
}

/// Every AO parameter; defaults are the talk's where it gives one.
#[derive(Clone, Debug, PartialEq)]
pub struct AoSettings {
    /// Which AO runs; [`AoMode::Off`] skips the passes.
    pub mode: AoMode,
    /// HBAO at full instead of half resolution.
    pub full_resolution: bool,
    /// Radius R of the horizon search (m, > 0); W(r) = 1 - r^2 / R^2 beyond which samples count 0.
    pub radius: f32,
    /// Directions D of the horizon search (1..=32).
    pub directions: u32,
    /// Steps S per direction (1..=32).
    pub steps: u32,
    /// Occlusion multiplier (1 = the integral as is).
    pub strength: f32,
    /// Tangent-plane angle bias (degrees) against self-occlusion of tessellated surfaces.
    pub angle_bias_deg: f32,
    /// Cap on the projected radius (AO pixels) so close-ups stay bounded in cost.
    pub max_radius_px: f32,
    /// Cross-bilateral kernel radius (full-resolution pixels, at most 32);
    /// the Gaussian's sigma is (radius + 1) / 2.
    pub blur_radius: u32,
    /// Depth sharpness of the blur: dz = sharpness (z - z0) / z0.
    pub blur_sharpness: f32,
    /// Adaptive sampling (inner half point taps, outer half bilinear step 2) vs brute force.
    pub adaptive_blur: bool,
    /// `ao.pack` and `ao.blur_x` as one compute pass that packs a
    /// shared-memory row tile once and reads its taps from it
    /// (`--ao-blur-pass compute`, #23), instead of a packed texture written
    /// by one full-screen pass and fetched per tap by another; the same taps
    /// and weights (the tile keeps f32 where the packed texture was f16).
    pub compute_blur: bool,
    /// Disocclusion threshold epsilon on |1 - w_i / w_(i-1)| (>= 0).
    pub epsilon: f32,
    /// N_max, the most frames accumulated (>= 1).
    pub n_max: f32,
    /// Continuity distance L (m, > 0): view-space neighbours farther apart
    /// than this mark the pixel discontinuous (unstable).
    pub continuity: f32,
    /// Filter only unstable pixels (the talk); false filters every pixel.
    pub selective: bool,
    /// O4: how much the directional term occludes the sun and local lights
    /// (0 = not at all, 1 = fully; `--ssdo-strength`).
    pub ssdo_strength: f32,
    /// O4: penumbra width below the horizon (sine of elevation, > 0).
    pub ssdo_softness: f32,
    /// O4: gain from the directional harmonic to the horizon's rise (2/pi of
    /// a half-plane's rise, and W's falloff, measured in O4.md; >= 0).
    pub ssdo_gain: f32,
    /// O4: extra penumbra width per unit of perceptual roughness for the
    /// reflection vector (a rough lobe sees past the horizon; >= 0).
    pub ssdo_roughness_softness: f32,
    /// Reflection occlusion (`--reflection-occlusion`): ambient specular times
    /// Lagarde's specular occlusion from AO and, with ssdo, times the
    /// directional term along the reflection vector; off: times AO, as diffuse.
    pub reflection_occlusion: bool,
    /// O5 colour bleeding: ambient diffuse occlusion tinted by the
    /// low-frequency albedo around the pixel (`passes/ao/bleed`). Off by
    /// default: measured against a one-bounce ray-traced estimate it lifts
    /// the occlusion too much except in near-white surroundings (O5.md).
    pub bleed: bool,
    /// O6 large-scale AO: the screen-space AO times the occlusion of the
    /// height field (L2's sector pool) within 7.5 m (`--ao-large-scale`,
    /// off by default; it replaces L2's sky visibility in lighting, which
    /// reads the same height field).
    pub large_scale: bool,
}

impl AoSettings {
    /// O6 runs: large-scale AO asked for and an AO pass to merge it into.
    pub fn large_scale_on(&self) -> bool {
        self.large_scale && self.mode != AoMode::Off
    }
}

impl Default for AoSettings {
    fn default() -> Self {
        Self {
            mode: AoMode::HbaoStf,
            full_resolution: false,
            radius: 1.5,
            directions: 8,
            steps: 4,
            strength: 1.0,
            angle_bias_deg: 10.0,
            max_radius_px: 48.0,
            blur_radius: 8,
            blur_sharpness: 16.0,
            adaptive_blur: true,
            compute_blur: false,
            epsilon: 0.1,
            n_max: 8.0,
            continuity: 0.1,
            selective: true,
            ssdo_strength: 1.0,
            ssdo_softness: 0.4,
            ssdo_gain: 1.5,
            ssdo_roughness_softness: 1.0,
            reflection_occlusion: false,
            bleed: false,
            large_scale: false,
        }
    }
}

impl AoSettings {
    /// Checks the ranges given on the fields; the error
    /// (`Error::InvalidSettings`, "AO: ...") says which check failed.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidSettings(format!("AO: {what}")));
        if !(self.radius > 0.0 && self.radius.is_finite()) {
            return bad("radius must be a positive number of metres");
        }
        if !(1..=32).contains(&self.directions) || !(1..=32).contains(&self.steps) {
            return bad("directions and steps must be in 1..=32");
        }
        if self.blur_radius > 32 {
            return bad("blur radius must be at most 32 pixels");
        }
        let ok = self.n_max >= 1.0 && self.epsilon >= 0.0 && self.continuity > 0.0;
        if !ok {
            return bad("N_max >= 1, epsilon >= 0 and L > 0 are required");
        }
        if !(0.0..=1.0).contains(&self.ssdo_strength) {
            return bad("SSDO strength must be in [0, 1]");
        }
        let soft = self.ssdo_softness > 0.0 && self.ssdo_roughness_softness >= 0.0;
        let finite = self.ssdo_softness.is_finite() && self.ssdo_roughness_softness.is_finite();
        if !(soft && finite && self.ssdo_gain >= 0.0 && self.ssdo_gain.is_finite()) {
            return bad("SSDO softness must be positive");
        }
        Ok(())
    }

    /// Full-resolution pixels per AO pixel.
    pub fn scale(&self) -> u32 {
        if self.full_resolution { 1 } else { 2 }
    }

    /// AO resolution for a `full` frame: AO texel q holds full pixel q * scale.
    pub fn ao_size(&self, full: (u32, u32)) -> (u32, u32) {
        let s = self.scale();
        (full.0.div_ceil(s), full.1.div_ceil(s))
    }
}

/// Twin of `AoParams` in `shaders/ao.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct AoUniform {
    /// 1/P00, 1/P11 (NDC to view-space x/z, y/z), near plane (m), focal
    /// length in AO pixels (0.5 AO height P11: metres at depth z to pixels).
    pub proj: [f32; 4],
    /// AO-resolution width, height (texels), 1/width, 1/height.
    pub ao_size: [f32; 4],
    /// Full-resolution width, height (pixels), 1/width, 1/height.
    pub full_size: [f32; 4],
    /// Radius R (m), 1/R^2 (the falloff W), strength, angle bias (radians).
    pub hbao: [f32; 4],
    /// Directions D, steps S, full pixels per AO texel (1 or 2), cap on the
    /// projected radius (AO pixels).
    pub hbao_steps: [f32; 4],
    /// Blur kernel radius (full-res pixels), Gaussian falloff 1/(2 sigma^2),
    /// depth sharpness, 1 = adaptive sampling.
    pub blur: [f32; 4],
    /// STF: epsilon, N_max, continuity L (m), 1 = selective (filter only
    /// unstable pixels).
    pub stf: [f32; 4],
    /// xy this frame's sample offset (px, y down), zw the previous frame's:
    /// the view matrices carry them, the STF's reprojection takes them out.
    pub jitter: [f32; 4],
    /// The projection's depth rows: P22, P23 (clip z), P32, P33 (clip w);
    /// perspective (0, near, -1, 0) and orthographic cameras alike.
    pub depth: [f32; 4],
    /// O4: strength on lights, penumbra width, width per roughness, gain.
    pub ssdo: [f32; 4],
}

impl AoUniform {
    /// `proj` is the camera projection (reverse-Z: infinite far plane, or
    /// orthographic), `near` its near plane.
    pub fn new(s: &AoSettings, proj: Mat4, near: f32, full: (u32, u32)) -> Self {
        let ao = s.ao_size(full);
        let size = |(w, h): (u32, u32)| [w as f32, h as f32, 1.0 / w as f32, 1.0 / h as f32];
        let sigma = (s.blur_radius as f32 + 1.0) * 0.5;
        Self {
            proj: [
                1.0 / proj.x_axis.x,
                1.0 / proj.y_axis.y,
                near,
                0.5 * ao.1 as f32 * proj.y_axis.y,
            ],
            ao_size: size(ao),
            full_size: size(full),
            hbao: [
                s.radius,
                1.0 / (s.radius * s.radius),
                s.strength,
                s.angle_bias_deg.to_radians(),
            ],
            hbao_steps: [
                s.directions as f32,
                s.steps as f32,
                s.scale() as f32,
                s.max_radius_px,
            ],
            blur: [
                s.blur_radius as f32,
                1.0 / (2.0 * sigma * sigma),
                s.blur_sharpness,
                if s.adaptive_blur { 1.0 } else { 0.0 },
            ],
            stf: [
                s.epsilon,
                s.n_max,
                s.continuity,
                if s.selective { 1.0 } else { 0.0 },
            ],
            jitter: [0.0; 4],
            depth: [proj.z_axis.z, proj.w_axis.z, proj.z_axis.w, proj.w_axis.w],
            ssdo: [
                s.ssdo_strength,
                s.ssdo_softness,
                s.ssdo_roughness_softness,
                s.ssdo_gain,
            ],
        }
    }

    /// With the projection jitter of this and the previous frame (px, y down).
    pub fn with_jitter(mut self, jitter: [f32; 2], prev_jitter: [f32; 2]) -> Self {
        self.jitter = [jitter[0], jitter[1], prev_jitter[0], prev_jitter[1]];
        self
    }
}

/// The AO debug views; `id` is `VIEW` in `passes/ao/view.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum AoView {
    /// Blurred and filtered AO (raw: AO, Z, N).
    Ao = 1,
    /// HBAO before blur and filter (raw: AO, continuity).
    Raw = 2,
    /// 1 = stable (continuous over 4x4: temporal filter off), 0 = unstable.
    Stability = 3,
    /// O4 directional term (raw: AO, c1, c2).
    Directional = 4,
    /// O5 bleed colour (raw: rgb, coverage; `passes/ao/bleed/view.wgsl`).
    Bleed = 5,
}

/// 4x4 Bayer order: neighbouring pixels get far-apart rotations.
const BAYER_4X4: [u32; 16] = [0, 8, 2, 10, 12, 4, 14, 6, 3, 11, 1, 9, 15, 7, 13, 5];

/// The 4x4 jitter texture, row-major: (rotation as a fraction of one direction
/// sector, first-step offset as a fraction of a step, 0, 0). Frame independent,
/// as in the talk; rotation follows the Bayer order, the offset a second
/// permutation of it so the two do not correlate.
pub fn jitter_4x4() -> [[f32; 4]; 16] {
    std::array::from_fn(|i| {
        let rotation = (BAYER_4X4[i] as f32 + 0.5) / 16.0;
        let offset = (BAYER_4X4[(i * 7 + 5) % 16] as f32 + 0.5) / 16.0;
        [rotation, offset, 0.0, 0.0]
    })
}
