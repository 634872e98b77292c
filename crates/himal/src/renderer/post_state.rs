//! The renderer's HDR-post state (H2, H3): the post uniform, the persistent
//! adapted-luminance buffer and the frame-delta clock.

use std::time::Instant;

use crate::Error;
use crate::gpu::GpuContext;
use crate::gpu::pipeline::uniform_buffer;
use crate::passes::debug::DebugView;
use crate::passes::post::{
    self, BloomSettings, FrameDelta, PostFrame, PostUniform, TonemapKey, Tonemapper, adapted_buffer,
};
use crate::renderer::{FrameSettings, ViewBuffer};

/// The post passes' state that outlives a frame.
pub struct PostState {
    /// The `Post` uniform ([`PostUniform`]), rewritten by [`Self::update`] each frame.
    pub uniform: wgpu::Buffer,
    /// The adapted-luminance storage buffer (H3): (log L_a, L_a, L_avg,
    /// frames since reset), luminances in kcd/m^2; only the GPU writes it.
    pub adapted: wgpu::Buffer,
    /// The next frame starts adapted (first frame, camera cut, adaptation was off).
    pub reset: bool,
    last_frame: Option<Instant>,
}

/// What `--view bloom` needs even with bloom off.
fn bloom_passes(settings: &FrameSettings) -> Option<u32> {
    let shown = settings.view == ViewBuffer::Debug(DebugView::Bloom);
    (settings.bloom.enabled || shown).then_some(settings.bloom.passes)
}

/// The tone-map permutation `settings` select: bloom on, a Reinhard white
/// point set, and the tone mapper.
pub fn tonemap_key(settings: &FrameSettings) -> TonemapKey {
    TonemapKey {
        bloom: settings.bloom.enabled,
        white_point: settings.white_point.is_some(),
        mapper: settings.tonemapper,
    }
}

/// Checks the HDR-post settings: a white point (> 0) only with Reinhard,
/// at most [`BloomSettings::MAX_PASSES`] bloom passes, bloom threshold and
/// strength finite and >= 0, adaptation time constants (s) positive, a fixed
/// frame delta (s) finite and >= 0, a finite exposure bias (EV).
pub fn validate(settings: &FrameSettings) -> Result<(), Error> {
    let bad = |m: String| Err(Error::InvalidSettings(m));
    if settings.white_point.is_some() && settings.tonemapper != Tonemapper::Reinhard {
        return bad(format!(
            "a white point is Reinhard's (eq. 4): tone mapper {} has its own",
            settings.tonemapper.name()
        ));
    }
    let b = &settings.bloom;
    if b.passes > BloomSettings::MAX_PASSES {
        return bad(format!(
            "bloom passes {} exceed {}",
            b.passes,
            BloomSettings::MAX_PASSES
        ));
    }
    if !(b.threshold.is_finite()
        && b.threshold >= 0.0
        && b.strength.is_finite()
        && b.strength >= 0.0)
    {
        return bad(format!(
            "bloom threshold {} and strength {} must be finite and >= 0",
            b.threshold, b.strength
        ));
    }
    let a = &settings.adaptation;
    if !(a.tau_brighten > 0.0
        && a.tau_darken > 0.0
        && a.tau_brighten.is_finite()
        && a.tau_darken.is_finite())
    {
        return bad(format!(
            "adaptation time constants {} s and {} s must be positive",
            a.tau_brighten, a.tau_darken
        ));
    }
    if let FrameDelta::Fixed(dt) = a.delta
        && !(dt.is_finite() && dt >= 0.0)
    {
        return bad(format!("frame delta {dt} s must be finite and >= 0"));
    }
    if let Some(w) = settings.white_point
        && !(w.is_finite() && w > 0.0)
    {
        return bad(format!("white point {w} must be positive"));
    }
    if !settings.exposure_ev.is_finite() {
        return bad(format!(
            "exposure {} EV is not finite",
            settings.exposure_ev
        ));
    }
    Ok(())
}

impl PostState {
    /// A zeroed uniform and a fresh adapted-luminance buffer; the first frame
    /// resets adaptation (starts adapted to its own average).
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            uniform: uniform_buffer(ctx, "post", &<PostUniform as bytemuck::Zeroable>::zeroed()),
            adapted: adapted_buffer(&ctx.device),
            reset: true,
            last_frame: None,
        }
    }

    /// Writes this frame's uniform (frame delta, reset flag, knobs).
    pub fn update(&mut self, queue: &wgpu::Queue, settings: &FrameSettings) {
        let now = Instant::now();
        let dt = match settings.adaptation.delta {
            FrameDelta::Fixed(dt) => dt,
            FrameDelta::Real => self
                .last_frame
                .map(|t| now.duration_since(t).as_secs_f32())
                .unwrap_or(0.0),
        };
        self.last_frame = Some(now);
        let uniform = PostUniform::new(
            post::KEY as f32,
            settings.exposure_ev,
            settings.white_point,
            &settings.bloom,
            &settings.adaptation,
            dt,
            self.reset,
        );
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
    }

    /// Called after a frame was submitted.
    pub fn frame_done(&mut self, settings: &FrameSettings) {
        // The adapted state is stale after frames without adaptation.
        self.reset = !settings.adaptation.enabled;
    }

    /// The buffers and per-frame choices the post passes of `frame::build`
    /// need: the buffers, bloom passes (also for `--view bloom` with bloom
    /// off), whether adaptation runs, the tone-map permutation.
    pub fn frame<'a>(&'a self, settings: &FrameSettings) -> PostFrame<'a> {
        PostFrame {
            uniform: &self.uniform,
            adapted: &self.adapted,
            bloom_passes: bloom_passes(settings),
            adaptation: settings.adaptation.enabled,
            tonemap: tonemap_key(settings),
        }
    }
}
