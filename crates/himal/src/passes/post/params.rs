//! Post-processing settings (part of `FrameSettings`) and their uniform,
//! the CPU twin of `shaders/post.wgsl` `Post`.

use bytemuck::{Pod, Zeroable};

/// H2 Kawase bloom.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BloomSettings {
    /// Bloom on; off skips the chain and the composite (unless `--view bloom` shows it).
    pub enabled: bool,
    /// Bright-pass threshold in scaled luminance (`L = key / L_exposure * L_w`):
    /// 1.0 is the level Reinhard maps to display 0.5.
    pub threshold: f32,
    /// Weight of the bloom added to the HDR image before tone mapping.
    pub strength: f32,
    /// Kawase passes at quarter resolution; pass k samples at offset k + 1/2.
    pub passes: u32,
}

impl BloomSettings {
    /// Most Kawase passes accepted (one pipeline per offset).
    pub const MAX_PASSES: u32 = 8;
}

impl Default for BloomSettings {
    fn default() -> Self {
        // Reinhard at key 0.18 leaves the demo's daylight under L = 1 except the
        // sky around the sun: threshold 0.8 (display 0.44) blooms that and not
        // the lit walls; strength 0.3 chosen by eye on the demo cameras.
        Self {
            enabled: true,
            threshold: 0.8,
            strength: 0.3,
            passes: 5,
        }
    }
}

/// How the frame's time step is taken for light adaptation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FrameDelta {
    /// A fixed step in seconds (sequences, tests: deterministic).
    Fixed(f32),
    /// Wall-clock time since the previous `render` call (interactive use).
    Real,
}

/// H3 light adaptation: the adapted luminance converges exponentially
/// toward the frame's log-average luminance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptationSettings {
    /// Off: every frame is exposed for its own log-average (instant metering).
    pub enabled: bool,
    /// Time constant in seconds when the scene gets brighter.
    pub tau_brighten: f32,
    /// Time constant in seconds when the scene gets darker.
    pub tau_darken: f32,
    /// The time step adaptation advances by each frame.
    pub delta: FrameDelta,
}

impl Default for AdaptationSettings {
    fn default() -> Self {
        // The eye adapts to light faster than to dark; 0.5 s / 2 s are common
        // game choices (not from the talk), fixed 1/30 s keeps sequences deterministic.
        Self {
            enabled: true,
            tau_brighten: 0.5,
            tau_darken: 2.0,
            delta: FrameDelta::Fixed(1.0 / 30.0),
        }
    }
}

/// CPU twin of `Post` in `shaders/post.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct PostUniform {
    /// frame delta (s), tau brighten, tau darken, reset (1 = start adapted)
    pub adapt: [f32; 4],
    /// threshold, strength
    pub bloom: [f32; 4],
    /// key, white point (0 = none), 2^EV
    pub tone: [f32; 4],
}

impl PostUniform {
    /// Packs the frame's post parameters: `key` (display value of the average),
    /// exposure bias in EV, white point, bloom and adaptation settings, the time
    /// step in seconds and whether adaptation restarts from this frame's average.
    pub fn new(
        key: f32,
        exposure_ev: f32,
        white_point: Option<f32>,
        bloom: &BloomSettings,
        adaptation: &AdaptationSettings,
        delta_seconds: f32,
        reset: bool,
    ) -> Self {
        Self {
            adapt: [
                delta_seconds,
                adaptation.tau_brighten,
                adaptation.tau_darken,
                if reset { 1.0 } else { 0.0 },
            ],
            bloom: [bloom.threshold, bloom.strength, 0.0, 0.0],
            tone: [key, white_point.unwrap_or(0.0), exposure_ev.exp2(), 0.0],
        }
    }
}
