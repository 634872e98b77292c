//! A3 TAA on buffers other than the final colour (`--aa-buffers ao,motion`):
//! `aa.taa_motion` stabilises the jitter-free motion right after the
//! G-buffer, `aa.taa_ao` accumulates the AO after the STF. Each keeps its
//! own history ring and parameters (the colour TAA's acceptance and tuning).

use bytemuck::Zeroable;

use super::{AaParams, MOTION_FORMAT, TemporalTuning};
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, History, TextureDesc, TextureHandle};
use crate::passes::common::{Step, target};

/// (AO, Z, N) of the AO chain, and the AO history (AO, m0x, m0y).
pub const AO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The buffer TAAs' history rings in the graph's [`History`].
pub const AO_HISTORY: &str = "aa.taa_ao.history";
/// The `aa.taa_motion` ring (stabilised jitter-free motion).
pub const MOTION_HISTORY: &str = "aa.taa_motion.history";

/// Declares both rings for a `size` frame (before the graph is built).
pub fn declare_history(history: &mut History, device: &wgpu::Device, size: (u32, u32)) {
    let ao = TextureDesc::new_2d(size.0, size.1, AO_FORMAT);
    history.declare(device, AO_HISTORY, &ao, 2);
    let motion = TextureDesc::new_2d(size.0, size.1, MOTION_FORMAT);
    history.declare(device, MOTION_HISTORY, &motion, 2);
}

/// The parameters of a buffer TAA: the colour TAA's, with `history_frames`
/// of its own ring and the clamp `tolerance` in the buffer's units (AO; px
/// for motion) in `tuning.y`.
pub fn buffer_params(
    jitter: [f32; 2],
    prev_jitter: [f32; 2],
    history_frames: u32,
    tolerance: f32,
    tuning: &TemporalTuning,
) -> AaParams {
    let mut p = AaParams::new(jitter, prev_jitter, history_frames, 0, tuning);
    p.tuning[1] = tolerance;
    p
}

/// The buffer TAA pipelines and their parameters.
pub struct BufferTaaPass {
    ao_program: Program,
    motion: Step,
    params_ao: wgpu::Buffer,
    params_motion: wgpu::Buffer,
    linear: wgpu::Sampler,
}

impl BufferTaaPass {
    /// Creates both buffer TAA pipelines, their parameter uniforms and the linear sampler.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let ao_program = Program::new(ctx, "passes/aa/temporal/taa_ao.wgsl")?;
        let motion = Step::new(
            ctx,
            "passes/aa/temporal/taa_motion.wgsl",
            "aa.taa_motion",
            MOTION_FORMAT,
            &[],
        )?;
        let linear = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.buffers.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let pass = Self {
            ao_program,
            motion,
            params_ao: uniform_buffer(ctx, "aa.taa_ao.params", &AaParams::zeroed()),
            params_motion: uniform_buffer(ctx, "aa.taa_motion.params", &AaParams::zeroed()),
            linear,
        };
        for jitter_free in [false, true] {
            pass.ao_pipeline(ctx, jitter_free)?;
        }
        Ok(pass)
    }

    /// `aa.taa_ao` by `JITTER_FREE_MOTION`.
    pub fn ao_pipeline(
        &self,
        ctx: &GpuContext,
        jitter_free: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(AO_FORMAT), target(AO_FORMAT)];
        let mut spec = RenderSpec::fullscreen("aa.taa_ao", &targets);
        let constants = [("JITTER_FREE_MOTION", if jitter_free { 1.0 } else { 0.0 })];
        spec.constants = &constants;
        self.ao_program.render_pipeline(ctx, &spec)
    }

    /// Uploads this frame's parameters: sample offsets (px) of this and the
    /// previous frame, the rings' history lengths and the tuning.
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        jitter: [f32; 2],
        prev_jitter: [f32; 2],
        history: &History,
        tuning: &TemporalTuning,
    ) {
        let ao = buffer_params(
            jitter,
            prev_jitter,
            history.frames(AO_HISTORY),
            tuning.ao_tolerance,
            tuning,
        );
        let motion = buffer_params(
            jitter,
            prev_jitter,
            history.frames(MOTION_HISTORY),
            tuning.motion_clamp_px,
            tuning,
        );
        self.update_params(queue, &ao, &motion);
    }

    /// Uploads the parameters of `aa.taa_ao` and `aa.taa_motion` as given.
    pub fn update_params(&self, queue: &wgpu::Queue, ao: &AaParams, motion: &AaParams) {
        queue.write_buffer(&self.params_ao, 0, bytemuck::bytes_of(ao));
        queue.write_buffer(&self.params_motion, 0, bytemuck::bytes_of(motion));
    }

    /// `aa.taa_motion`: the stabilised jitter-free motion (the motion ring's next texture).
    pub fn add_motion<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        motion: TextureHandle,
        history: &'a History,
    ) -> Result<TextureHandle, GpuError> {
        let ring = history
            .import(graph, MOTION_HISTORY)
            .ok_or_else(|| GpuError::Other(format!("{MOTION_HISTORY} was not declared")))?;
        let next = self
            .motion
            .node(graph, "aa.taa_motion")
            .uniform("params", &self.params_motion)
            .read("motion", motion)
            .read("history", ring.previous[0])
            .sampler("linear_sampler", &self.linear)
            .color(ring.next, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw();
        // The history outlives the frame.
        graph.mark_output(next);
        Ok(next)
    }

    /// `aa.taa_ao`: the AO chain's (AO, Z, N) with the accumulated AO; `motion`
    /// is the G-buffer's, or `aa.taa_motion`'s when `jitter_free`.
    pub fn add_ao<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        ao: TextureHandle,
        motion: TextureHandle,
        jitter_free: bool,
        history: &'a History,
    ) -> Result<TextureHandle, GpuError> {
        let size = graph
            .texture_desc(ao)
            .map_or((1, 1), |d| (d.width, d.height));
        let out = graph.create_texture(
            "aa.taa_ao.out",
            TextureDesc::new_2d(size.0, size.1, AO_FORMAT),
        );
        let ring = history
            .import(graph, AO_HISTORY)
            .ok_or_else(|| GpuError::Other(format!("{AO_HISTORY} was not declared")))?;
        let clear = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
        let written = graph
            .fullscreen("aa.taa_ao", &self.ao_program)
            .pipeline(self.ao_pipeline(ctx, jitter_free))
            .uniform("params", &self.params_ao)
            .read("ao", ao)
            .read("history", ring.previous[0])
            .read("motion", motion)
            .sampler("linear_sampler", &self.linear)
            .color(out, clear)
            .color(ring.next, clear)
            .draw_targets();
        graph.mark_output(written.colors[1]);
        Ok(written.colors[0])
    }
}
