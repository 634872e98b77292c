//! A2 temporal FLIPQUAD resolve (`aa.resolve`), A3 TAA (`aa.taa`), A4 unsharp
//! (`aa.unsharp`), and the history they keep between frames. CPU twins in
//! [`reference`].

pub mod buffers;
pub mod reference;

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{draw_fullscreen, target};

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

/// Textures kept between frames, owned by the renderer.
pub struct AaHistory {
    pub size: (u32, u32),
    /// Each frame's anti-aliased samples before the resolve (N, N−1, N−2 rotate).
    raw: [wgpu::Texture; 3],
    motion: [wgpu::Texture; 2],
    taa: [wgpu::Texture; 2],
    /// Frame counter of the ring.
    frame: usize,
    /// Consecutive frames written since the last cut.
    pub frames: u32,
    /// Jitter of the last frame written.
    pub last_jitter: [f32; 2],
}

/// The textures one frame reads and writes.
pub struct HistoryFrame<'a> {
    pub raw: &'a wgpu::Texture,
    pub raw_prev: &'a wgpu::Texture,
    pub raw_prev2: &'a wgpu::Texture,
    pub motion: &'a wgpu::Texture,
    pub motion_prev: &'a wgpu::Texture,
    pub taa: &'a wgpu::Texture,
    pub taa_prev: &'a wgpu::Texture,
}

impl AaHistory {
    pub fn new(device: &wgpu::Device, size: (u32, u32), raw_format: wgpu::TextureFormat) -> Self {
        let make = |label: &str, format| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
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
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        Self {
            size,
            raw: [0, 1, 2].map(|i| make(&format!("aa.raw.{i}"), raw_format)),
            motion: [0, 1].map(|i| make(&format!("aa.motion.{i}"), MOTION_FORMAT)),
            taa: [0, 1].map(|i| make(&format!("aa.taa.{i}"), RESOLVED_FORMAT)),
            frame: 0,
            frames: 0,
            last_jitter: [0.0, 0.0],
        }
    }

    /// Forgets the history (camera cut, mode change).
    pub fn invalidate(&mut self) {
        self.frames = 0;
    }

    pub fn frame(&self) -> HistoryFrame<'_> {
        let f = self.frame;
        HistoryFrame {
            raw: &self.raw[f % 3],
            raw_prev: &self.raw[(f + 2) % 3],
            raw_prev2: &self.raw[(f + 1) % 3],
            motion: &self.motion[f % 2],
            motion_prev: &self.motion[(f + 1) % 2],
            taa: &self.taa[f % 2],
            taa_prev: &self.taa[(f + 1) % 2],
        }
    }

    /// After a frame was submitted with sample offset `jitter`.
    pub fn advance(&mut self, jitter: [f32; 2]) {
        self.frame += 1;
        self.frames = self.frames.saturating_add(1);
        self.last_jitter = jitter;
    }

    pub fn bytes(&self) -> u64 {
        let px = self.size.0 as u64 * self.size.1 as u64;
        px * (3 * 4 + 2 * 4 + 2 * 8)
    }
}

/// The temporal pipelines.
pub struct TemporalPass {
    resolve_program: Program,
    taa_program: Program,
    unsharp_program: Program,
    /// By (mode, motion input already jitter-free).
    resolve: HashMap<(ResolveMode, bool), wgpu::RenderPipeline>,
    taa: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    unsharp: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    params: wgpu::Buffer,
    linear: wgpu::Sampler,
}

impl TemporalPass {
    /// Builds every permutation for output format `output_format`.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let resolve_program = Program::new(ctx, "passes/aa/temporal/resolve.wgsl")?;
        let taa_program = Program::new(ctx, "passes/aa/temporal/taa.wgsl")?;
        let unsharp_program = Program::new(ctx, "passes/aa/temporal/unsharp.wgsl")?;
        let mut resolve = HashMap::new();
        for mode in [
            ResolveMode::PassThrough,
            ResolveMode::TwoTap,
            ResolveMode::FlipQuad,
        ] {
            for jitter_free in [false, true] {
                let targets = [target(RESOLVED_FORMAT), target(MOTION_FORMAT)];
                let mut spec = RenderSpec::fullscreen("aa.resolve", &targets);
                let constants = [
                    ("MODE", mode as u32 as f64),
                    ("JITTER_FREE_MOTION", if jitter_free { 1.0 } else { 0.0 }),
                ];
                spec.constants = &constants;
                let pipeline = resolve_program.render_pipeline(ctx, &spec)?;
                resolve.insert((mode, jitter_free), pipeline);
            }
        }
        let mut taa = HashMap::new();
        let mut unsharp = HashMap::new();
        for format in [RESOLVED_FORMAT, output_format] {
            let targets = [target(RESOLVED_FORMAT), target(format)];
            let spec = RenderSpec::fullscreen("aa.taa", &targets);
            taa.insert(format, taa_program.render_pipeline(ctx, &spec)?);
            let targets = [target(format)];
            let spec = RenderSpec::fullscreen("aa.unsharp", &targets);
            unsharp.insert(format, unsharp_program.render_pipeline(ctx, &spec)?);
        }
        let params = crate::gpu::pipeline::uniform_buffer(ctx, "aa.params", &AaParams::zeroed());
        let linear = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            resolve_program,
            taa_program,
            unsharp_program,
            resolve,
            taa,
            unsharp,
            params,
            linear,
        })
    }

    /// Uploads this frame's parameters.
    pub fn update(&self, queue: &wgpu::Queue, params: &AaParams) {
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(params));
    }

    /// `aa.resolve`: (resolved colour, motion history next). `motion` is the
    /// G-buffer's, or already jitter-free (`aa.taa_motion`) when `jitter_free`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_resolve<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        (mode, jitter_free): (ResolveMode, bool),
        current: TextureHandle,
        previous: (TextureHandle, TextureHandle),
        motion: TextureHandle,
        motion_prev: TextureHandle,
        motion_next: TextureHandle,
        errors: &'a FrameErrors,
    ) -> (TextureHandle, TextureHandle) {
        let size = graph
            .texture_desc(current)
            .map_or((1, 1), |d| (d.width, d.height));
        let out = graph.create_texture(
            "aa.resolved",
            TextureDesc::new_2d(size.0, size.1, RESOLVED_FORMAT),
        );
        let mut pass = graph.add_pass("aa.resolve");
        for h in [current, previous.0, previous.1, motion, motion_prev] {
            pass.read(h, TextureAccess::Sampled);
        }
        let out = pass.write(out, TextureAccess::ColorAttachment);
        let motion_next = pass.write(motion_next, TextureAccess::ColorAttachment);
        let pipeline = self.resolve.get(&(mode, jitter_free));
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!("aa.resolve {mode:?} missing"))));
                return;
            };
            let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
            let bg = self.resolve_program.bind(
                ctx.device,
                0,
                &[
                    ("params", self.params.as_entire_binding()),
                    ("current", tv(current)),
                    ("previous", tv(previous.0)),
                    ("previous2", tv(previous.1)),
                    ("motion", tv(motion)),
                    ("previous_motion", tv(motion_prev)),
                ],
            );
            if let Some(bg) = errors.record(bg) {
                draw_mrt(ctx, pipeline, &bg, &[out, motion_next]);
            }
        });
        (out, motion_next)
    }

    /// `aa.taa`: returns (history next, colour) — colour written into `color_out`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_taa<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        input: TextureHandle,
        history_prev: TextureHandle,
        history_next: TextureHandle,
        motion: TextureHandle,
        motion_prev: TextureHandle,
        color_out: TextureHandle,
        errors: &'a FrameErrors,
    ) -> (TextureHandle, TextureHandle) {
        let format = graph.texture_desc(color_out).map(|d| d.format);
        let pipeline = format.and_then(|f| self.taa.get(&f));
        let mut pass = graph.add_pass("aa.taa");
        for h in [input, history_prev, motion, motion_prev] {
            pass.read(h, TextureAccess::Sampled);
        }
        let history_next = pass.write(history_next, TextureAccess::ColorAttachment);
        let color_out = pass.write(color_out, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!(
                    "aa.taa for {format:?} missing"
                ))));
                return;
            };
            let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
            let bg = self.taa_program.bind(
                ctx.device,
                0,
                &[
                    ("params", self.params.as_entire_binding()),
                    ("input", tv(input)),
                    ("history", tv(history_prev)),
                    ("motion", tv(motion)),
                    ("previous_motion", tv(motion_prev)),
                    (
                        "linear_sampler",
                        wgpu::BindingResource::Sampler(&self.linear),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bg) {
                draw_mrt(ctx, pipeline, &bg, &[history_next, color_out]);
            }
        });
        (history_next, color_out)
    }

    /// `aa.unsharp` from `input` into `output`.
    pub fn add_unsharp<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        input: TextureHandle,
        output: TextureHandle,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let format = graph.texture_desc(output).map(|d| d.format);
        let pipeline = format.and_then(|f| self.unsharp.get(&f));
        let mut pass = graph.add_pass("aa.unsharp");
        pass.read(input, TextureAccess::Sampled);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!(
                    "aa.unsharp for {format:?} missing"
                ))));
                return;
            };
            let bg = self.unsharp_program.bind(
                ctx.device,
                0,
                &[
                    ("params", self.params.as_entire_binding()),
                    ("input", wgpu::BindingResource::TextureView(ctx.view(input))),
                ],
            );
            if let Some(bg) = errors.record(bg) {
                let load = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
                draw_fullscreen(ctx, pipeline, &bg, ctx.view(output), load, None);
            }
        });
        output
    }
}

/// One full-screen triangle into several colour targets.
pub(crate) fn draw_mrt(
    ctx: &mut crate::graph::PassContext<'_>,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
    targets: &[TextureHandle],
) {
    let label = ctx.pass_id().to_string();
    let views: Vec<&wgpu::TextureView> = targets.iter().map(|&h| ctx.view(h)).collect();
    let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
        .iter()
        .map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })
        })
        .collect();
    let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&label),
        color_attachments: &attachments,
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(0..3, 0..1);
}
