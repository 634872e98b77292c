//! A3 TAA on buffers other than the final colour (`--aa-buffers ao,motion`):
//! `aa.taa_motion` stabilises the jitter-free motion right after the
//! G-buffer, `aa.taa_ao` accumulates the AO after the STF. Each keeps its
//! own history ring and parameters (the colour TAA's acceptance and tuning).

use std::collections::HashMap;

use bytemuck::Zeroable;

use super::{AaParams, MOTION_FORMAT, TemporalTuning, draw_mrt};
use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::aa::settings::AaBuffers;
use crate::passes::common::target;

/// (AO, Z, N) of the AO chain, and the AO history (AO, m0x, m0y).
pub const AO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The history rings of the buffer TAAs, owned by the renderer.
pub struct BufferHistory {
    pub size: (u32, u32),
    ao: [wgpu::Texture; 2],
    motion: [wgpu::Texture; 2],
    frame: usize,
    /// Consecutive frames each ring was written since a cut (0: no history).
    pub frames_ao: u32,
    pub frames_motion: u32,
}

impl BufferHistory {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let make = |label: String, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&label),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            })
        };
        Self {
            size,
            ao: [0, 1].map(|i| make(format!("aa.taa_ao.history.{i}"), AO_FORMAT)),
            motion: [0, 1].map(|i| make(format!("aa.taa_motion.history.{i}"), MOTION_FORMAT)),
            frame: 0,
            frames_ao: 0,
            frames_motion: 0,
        }
    }

    /// Forgets both histories (camera cut).
    pub fn invalidate(&mut self) {
        self.frames_ao = 0;
        self.frames_motion = 0;
    }

    /// (previous, next) of the AO ring.
    pub fn ao(&self) -> (&wgpu::Texture, &wgpu::Texture) {
        (&self.ao[(self.frame + 1) % 2], &self.ao[self.frame % 2])
    }

    /// (previous, next) of the motion ring.
    pub fn motion(&self) -> (&wgpu::Texture, &wgpu::Texture) {
        (
            &self.motion[(self.frame + 1) % 2],
            &self.motion[self.frame % 2],
        )
    }

    /// After a frame with `buffers` was submitted: a ring that was not
    /// written loses its history.
    pub fn advance(&mut self, buffers: AaBuffers) {
        self.frame += 1;
        let count = |on: bool, n: u32| if on { n.saturating_add(1) } else { 0 };
        self.frames_ao = count(buffers.ao, self.frames_ao);
        self.frames_motion = count(buffers.motion, self.frames_motion);
    }

    pub fn bytes(&self) -> u64 {
        self.size.0 as u64 * self.size.1 as u64 * (2 * 8 + 2 * 4)
    }
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
    motion_program: Program,
    /// `aa.taa_ao` by JITTER_FREE_MOTION.
    ao: HashMap<bool, wgpu::RenderPipeline>,
    motion: wgpu::RenderPipeline,
    params_ao: wgpu::Buffer,
    params_motion: wgpu::Buffer,
    linear: wgpu::Sampler,
}

impl BufferTaaPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let ao_program = Program::new(ctx, "passes/aa/temporal/taa_ao.wgsl")?;
        let motion_program = Program::new(ctx, "passes/aa/temporal/taa_motion.wgsl")?;
        let mut ao = HashMap::new();
        for jitter_free in [false, true] {
            let targets = [target(AO_FORMAT), target(AO_FORMAT)];
            let mut spec = RenderSpec::fullscreen("aa.taa_ao", &targets);
            let constants = [("JITTER_FREE_MOTION", if jitter_free { 1.0 } else { 0.0 })];
            spec.constants = &constants;
            ao.insert(jitter_free, ao_program.render_pipeline(ctx, &spec)?);
        }
        let targets = [target(MOTION_FORMAT)];
        let spec = RenderSpec::fullscreen("aa.taa_motion", &targets);
        let motion = motion_program.render_pipeline(ctx, &spec)?;
        let linear = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.buffers.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            ao_program,
            motion_program,
            ao,
            motion,
            params_ao: uniform_buffer(ctx, "aa.taa_ao.params", &AaParams::zeroed()),
            params_motion: uniform_buffer(ctx, "aa.taa_motion.params", &AaParams::zeroed()),
            linear,
        })
    }

    /// Uploads this frame's parameters: sample offsets (px) of this and the
    /// previous frame, the rings' history lengths and the tuning.
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        jitter: [f32; 2],
        prev_jitter: [f32; 2],
        history: &BufferHistory,
        tuning: &TemporalTuning,
    ) {
        let ao = buffer_params(
            jitter,
            prev_jitter,
            history.frames_ao,
            tuning.ao_tolerance,
            tuning,
        );
        let motion = buffer_params(
            jitter,
            prev_jitter,
            history.frames_motion,
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
        history: &'a BufferHistory,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let (prev, next) = history.motion();
        let prev = graph.import_texture("aa.taa_motion.prev", prev);
        let next = graph.import_texture("aa.taa_motion.next", next);
        let mut pass = graph.add_pass("aa.taa_motion");
        pass.read(motion, TextureAccess::Sampled);
        pass.read(prev, TextureAccess::Sampled);
        let next = pass.write(next, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
            let bg = self.motion_program.bind(
                ctx.device,
                0,
                &[
                    ("params", self.params_motion.as_entire_binding()),
                    ("motion", tv(motion)),
                    ("history", tv(prev)),
                    (
                        "linear_sampler",
                        wgpu::BindingResource::Sampler(&self.linear),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bg) {
                draw_mrt(ctx, &self.motion, &bg, &[next]);
            }
        });
        // The history outlives the frame.
        graph.mark_output(next);
        next
    }

    /// `aa.taa_ao`: the AO chain's (AO, Z, N) with the accumulated AO; `motion`
    /// is the G-buffer's, or `aa.taa_motion`'s when `jitter_free`.
    pub fn add_ao<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        ao: TextureHandle,
        motion: TextureHandle,
        jitter_free: bool,
        history: &'a BufferHistory,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let size = graph
            .texture_desc(ao)
            .map_or((1, 1), |d| (d.width, d.height));
        let out = graph.create_texture(
            "aa.taa_ao.out",
            TextureDesc::new_2d(size.0, size.1, AO_FORMAT),
        );
        let (prev, next) = history.ao();
        let prev = graph.import_texture("aa.taa_ao.prev", prev);
        let next = graph.import_texture("aa.taa_ao.next", next);
        let mut pass = graph.add_pass("aa.taa_ao");
        for h in [ao, motion, prev] {
            pass.read(h, TextureAccess::Sampled);
        }
        let out = pass.write(out, TextureAccess::ColorAttachment);
        let next = pass.write(next, TextureAccess::ColorAttachment);
        let pipeline = self.ao.get(&jitter_free);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other("aa.taa_ao missing".into())));
                return;
            };
            let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
            let bg = self.ao_program.bind(
                ctx.device,
                0,
                &[
                    ("params", self.params_ao.as_entire_binding()),
                    ("ao", tv(ao)),
                    ("history", tv(prev)),
                    ("motion", tv(motion)),
                    (
                        "linear_sampler",
                        wgpu::BindingResource::Sampler(&self.linear),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bg) {
                draw_mrt(ctx, pipeline, &bg, &[out, next]);
            }
        });
        graph.mark_output(next);
        out
    }
}
