//! A2 temporal FLIPQUAD resolve (`aa.resolve`), A3 TAA (`aa.taa`), A4 unsharp
//! (`aa.unsharp`), and the history they keep between frames. CPU twins in
//! [`mod@reference`].

pub mod buffers;
pub mod reference;

use bytemuck::{Pod, Zeroable};

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{Fallback, FrameGraph, History, TextureDesc, TextureHandle};
use crate::passes::common::target;

/// Resolved colour and TAA history (linear).
pub const RESOLVED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Jitter-free motion history (previous uv − current uv).
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;

/// Twin of `AaParams` in `shaders/aa.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct AaParams {
    /// xy this frame's sample offset (px, y down), zw the previous frame's.
    pub jitter: [f32; 4],
    /// x consecutive history frames, y phase, z/w TAA new-frame weight at low/high frequency.
    pub state: [f32; 4],
    /// x motion tolerance (px), y colour box tolerance, z unsharp strength, w contrast scale.
    pub tuning: [f32; 4],
}

/// Tuning of the temporal passes (defaults measured on the tests' scenes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalTuning {
    /// Motion coherence: |m_N − m_N−1| below this many pixels.
    pub motion_tolerance_px: f32,
    /// Colour coherence: the N−2 sample (resolve) and the history (TAA) may
    /// lie this far outside the 3x3 box; `f32::INFINITY` turns the colour
    /// test off (the ghosting test's "without").
    pub colour_tolerance: f32,
    /// Weight of the new frame where the 3x3 box is flat (few frames accumulate).
    pub alpha_low_frequency: f32,
    /// Weight of the new frame on edges and detail (many frames accumulate).
    pub alpha_high_frequency: f32,
    /// Display-luma contrast at which the high-frequency weight is reached (1/k).
    pub contrast_scale: f32,
    /// A4 unsharp strength.
    pub unsharp: f32,
    /// `aa.taa_ao`: how far (AO units) the history may lie outside the 3x3 box.
    pub ao_tolerance: f32,
    /// `aa.taa_motion`: how far (px) the history may lie outside the 3x3 box.
    pub motion_clamp_px: f32,
}

impl Default for TemporalTuning {
    fn default() -> Self {
        Self {
            motion_tolerance_px: 0.5,
            colour_tolerance: 2.0 / 255.0,
            alpha_low_frequency: 0.25,
            alpha_high_frequency: 0.1,
            contrast_scale: 4.0,
            unsharp: 0.25,
            ao_tolerance: 0.02,
            // Any widening lets the history drift at lagging edges: 0.05 px
            // gave 1.11x the temporal std of no accumulation, 0 gives 0.48x.
            motion_clamp_px: 0.0,
        }
    }
}

impl AaParams {
    /// Parameters of a frame sampled at `jitter` after one at `prev_jitter`, with `history_frames`
    /// consecutive frames of history and jitter `phase` (0: frame A, 1: B).
    pub fn new(
        jitter: [f32; 2],
        prev_jitter: [f32; 2],
        history_frames: u32,
        phase: u32,
        t: &TemporalTuning,
    ) -> Self {
        Self {
            jitter: [jitter[0], jitter[1], prev_jitter[0], prev_jitter[1]],
            state: [
                history_frames as f32,
                phase as f32,
                t.alpha_low_frequency,
                t.alpha_high_frequency,
            ],
            tuning: [
                t.motion_tolerance_px,
                t.colour_tolerance,
                t.unsharp,
                t.contrast_scale,
            ],
        }
    }
}

/// Resolve permutation (`MODE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ResolveMode {
    /// Colour copied (TAA alone); motion history still written.
    PassThrough = 0,
    /// SMAA T2x: the pixel's own samples of two frames.
    TwoTap = 1,
    /// Temporal FLIPQUAD: own and shared neighbour samples of two frames.
    FlipQuad = 2,
}

/// The temporal passes' history rings in the graph's [`History`]: each
/// frame's anti-aliased samples before the resolve (N, N−1, N−2), the
/// jitter-free motion and the TAA colour.
pub const RAW_HISTORY: &str = "aa.raw";
/// The ring of the jitter-free motion ([`MOTION_FORMAT`]).
pub const MOTION_HISTORY: &str = "aa.motion";
/// The ring of the TAA colour ([`RESOLVED_FORMAT`]).
pub const TAA_HISTORY: &str = "aa.taa";

/// Declares the three rings for a `size` frame whose samples are `raw_format`.
pub fn declare_history(
    history: &mut History,
    device: &wgpu::Device,
    size: (u32, u32),
    raw_format: wgpu::TextureFormat,
) {
    let desc = |format| TextureDesc::new_2d(size.0, size.1, format);
    history.declare(device, RAW_HISTORY, &desc(raw_format), 3);
    history.declare(device, MOTION_HISTORY, &desc(MOTION_FORMAT), 2);
    history.declare(device, TAA_HISTORY, &desc(RESOLVED_FORMAT), 2);
}

/// The history rings restart (a camera cut or a change of mode).
pub fn reset_history(history: &mut History) {
    for name in [RAW_HISTORY, MOTION_HISTORY, TAA_HISTORY] {
        history.reset_one(name);
    }
}

/// The temporal pipelines.
pub struct TemporalPass {
    resolve_program: Program,
    taa_program: Program,
    unsharp_program: Program,
    params: wgpu::Buffer,
    linear: wgpu::Sampler,
}

impl TemporalPass {
    /// Fetches every permutation for output format `output_format`.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let params = crate::gpu::pipeline::uniform_buffer(ctx, "aa.params", &AaParams::zeroed());
        let linear = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let pass = Self {
            resolve_program: Program::new(ctx, "passes/aa/temporal/resolve.wgsl")?,
            taa_program: Program::new(ctx, "passes/aa/temporal/taa.wgsl")?,
            unsharp_program: Program::new(ctx, "passes/aa/temporal/unsharp.wgsl")?,
            params,
            linear,
        };
        for mode in [
            ResolveMode::PassThrough,
            ResolveMode::TwoTap,
            ResolveMode::FlipQuad,
        ] {
            for jitter_free in [false, true] {
                for reactive in [false, true] {
                    pass.resolve_pipeline(ctx, mode, jitter_free, reactive)?;
                }
            }
        }
        for format in [RESOLVED_FORMAT, output_format] {
            for reactive in [false, true] {
                pass.taa_pipeline(ctx, format, reactive)?;
            }
            pass.unsharp_pipeline(ctx, format)?;
        }
        Ok(pass)
    }

    /// `aa.resolve` of `mode`; `jitter_free`: the motion input is already
    /// jitter-free; `reactive`: reads the particles' coverage (E4).
    pub fn resolve_pipeline(
        &self,
        ctx: &GpuContext,
        mode: ResolveMode,
        jitter_free: bool,
        reactive: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(RESOLVED_FORMAT), target(MOTION_FORMAT)];
        let mut spec = RenderSpec::fullscreen("aa.resolve", &targets);
        let constants = [
            ("MODE", mode as u32 as f64),
            ("JITTER_FREE_MOTION", if jitter_free { 1.0 } else { 0.0 }),
            ("REACTIVE", if reactive { 1.0 } else { 0.0 }),
        ];
        spec.constants = &constants;
        self.resolve_program.render_pipeline(ctx, &spec)
    }

    /// `aa.taa` writing its colour in `format`; `reactive`: reads the
    /// particles' coverage (E4, `REACTIVE`).
    pub fn taa_pipeline(
        &self,
        ctx: &GpuContext,
        format: wgpu::TextureFormat,
        reactive: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(RESOLVED_FORMAT), target(format)];
        let mut spec = RenderSpec::fullscreen("aa.taa", &targets);
        let constants = [("REACTIVE", if reactive { 1.0 } else { 0.0 })];
        spec.constants = &constants;
        self.taa_program.render_pipeline(ctx, &spec)
    }

    /// `aa.unsharp` into `format`.
    pub fn unsharp_pipeline(
        &self,
        ctx: &GpuContext,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(format)];
        let spec = RenderSpec::fullscreen("aa.unsharp", &targets);
        self.unsharp_program.render_pipeline(ctx, &spec)
    }

    /// Uploads this frame's parameters.
    pub fn update(&self, queue: &wgpu::Queue, params: &AaParams) {
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(params));
    }

    /// `aa.resolve`: (resolved colour, motion history next). `motion` is the
    /// G-buffer's, or already jitter-free (`aa.taa_motion`) when `jitter_free`.
    /// `reactive`: the particles' coverage and the TAA's previous history
    /// (its alpha: last frame's coverage), E4.
    #[allow(clippy::too_many_arguments)]
    pub fn add_resolve<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        (mode, jitter_free): (ResolveMode, bool),
        current: TextureHandle,
        previous: (TextureHandle, TextureHandle),
        motion: TextureHandle,
        motion_prev: TextureHandle,
        motion_next: TextureHandle,
        reactive: Option<(TextureHandle, TextureHandle)>,
    ) -> (TextureHandle, TextureHandle) {
        let size = graph
            .texture_desc(current)
            .map_or((1, 1), |d| (d.width, d.height));
        let out = graph.create_texture(
            "aa.resolved",
            TextureDesc::new_2d(size.0, size.1, RESOLVED_FORMAT),
        );
        let black = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
        let w = graph
            .fullscreen("aa.resolve", &self.resolve_program)
            .pipeline(self.resolve_pipeline(ctx, mode, jitter_free, reactive.is_some()))
            .uniform("params", &self.params)
            .read("current", current)
            .read("previous", previous.0)
            .read("previous2", previous.1)
            .read("motion", motion)
            .read("previous_motion", motion_prev)
            .optional("reactive", reactive.map(|r| r.0), Fallback::Black)
            .optional("taa_history", reactive.map(|r| r.1), Fallback::Black)
            .sampler("linear_sampler", &self.linear)
            .color(out, black)
            .color(motion_next, black)
            .draw_targets();
        (w.colors[0], w.colors[1])
    }

    /// `aa.taa`: returns (history next, colour) — colour written into
    /// `color_out`. `reactive`: the particles' coverage (E4), if any.
    #[allow(clippy::too_many_arguments)]
    pub fn add_taa<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        input: TextureHandle,
        (history_prev, history_next): (TextureHandle, TextureHandle),
        motion: TextureHandle,
        motion_prev: TextureHandle,
        reactive: Option<TextureHandle>,
        color_out: TextureHandle,
    ) -> (TextureHandle, TextureHandle) {
        let pipeline = match graph.texture_desc(color_out) {
            Some(d) => self.taa_pipeline(ctx, d.format, reactive.is_some()),
            None => Err(GpuError::Other("aa.taa: unknown output".into())),
        };
        let black = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
        let w = graph
            .fullscreen("aa.taa", &self.taa_program)
            .pipeline(pipeline)
            .uniform("params", &self.params)
            .read("input", input)
            .read("history", history_prev)
            .read("motion", motion)
            .read("previous_motion", motion_prev)
            .sampler("linear_sampler", &self.linear)
            .optional("reactive", reactive, Fallback::Black)
            .color(history_next, black)
            .color(color_out, black)
            .draw_targets();
        (w.colors[0], w.colors[1])
    }

    /// `aa.unsharp` from `input` into `output`.
    pub fn add_unsharp<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        input: TextureHandle,
        output: TextureHandle,
    ) -> TextureHandle {
        let pipeline = match graph.texture_desc(output) {
            Some(d) => self.unsharp_pipeline(ctx, d.format),
            None => Err(GpuError::Other("aa.unsharp: unknown output".into())),
        };
        graph
            .fullscreen("aa.unsharp", &self.unsharp_program)
            .pipeline(pipeline)
            .uniform("params", &self.params)
            .read("input", input)
            .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }
}
