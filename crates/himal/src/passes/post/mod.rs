//! Tone mapping (TECHNIQUES H3, without adaptation yet): log-average
//! luminance reduced on the GPU, then Reinhard `L/(1+L)` at key 0.18.
//! CPU twin: [`reference`].

pub mod reference;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, FrameGraph, TextureAccess, TextureHandle};
use crate::passes::common::{draw_fullscreen, target};

/// Tile edge in pixels of `post.luminance` (16x16 threads, 4x4 pixels each).
pub const TILE: u32 = 64;
pub const KEY: f64 = 0.18;

/// Buffers of the luminance reduction, sized for a maximum frame size.
pub struct LuminanceBuffers {
    pub partials: wgpu::Buffer,
    /// (log average, average, tiles, pixels)
    pub result: wgpu::Buffer,
}

impl LuminanceBuffers {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let tiles = size.0.div_ceil(TILE) as u64 * size.1.div_ceil(TILE) as u64;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        Self {
            partials: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("post.luminance.partials"),
                size: tiles * 8,
                usage: storage,
                mapped_at_creation: false,
            }),
            result: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("post.luminance.result"),
                size: 16,
                usage: storage,
                mapped_at_creation: false,
            }),
        }
    }
}

pub struct LuminancePass {
    program: Program,
    partial: wgpu::ComputePipeline,
    last: wgpu::ComputePipeline,
}

impl LuminancePass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/post/luminance.wgsl")?;
        let partial = program.compute_pipeline(ctx, "cs_partial", &[])?;
        let last = program.compute_pipeline(ctx, "cs_final", &[])?;
        Ok(Self {
            program,
            partial,
            last,
        })
    }

    /// Reduces `hdr` into `buffers.result`; returns its handle.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        size: (u32, u32),
        buffers: &'a LuminanceBuffers,
        errors: &'a FrameErrors,
    ) -> BufferHandle {
        let partials = graph.import_buffer("luminance.partials", &buffers.partials);
        let result = graph.import_buffer("luminance.result", &buffers.result);
        let mut pass = graph.add_pass("post.luminance");
        pass.read(hdr, TextureAccess::Sampled);
        pass.write_buffer(partials, BufferAccess::StorageWrite);
        let result = pass.write_buffer(result, BufferAccess::StorageWrite);
        pass.execute(move |ctx| {
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("hdr", wgpu::BindingResource::TextureView(ctx.view(hdr))),
                    ("partials", buffers.partials.as_entire_binding()),
                    ("result", buffers.result.as_entire_binding()),
                ],
            );
            let Some(bg) = errors.record(bind_group) else {
                return;
            };
            let mut cp = ctx
                .encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("post.luminance"),
                    timestamp_writes: None,
                });
            cp.set_bind_group(0, &bg, &[]);
            cp.set_pipeline(&self.partial);
            cp.dispatch_workgroups(size.0.div_ceil(TILE), size.1.div_ceil(TILE), 1);
            cp.set_pipeline(&self.last);
            cp.dispatch_workgroups(1, 1, 1);
        });
        result
    }
}

pub struct TonemapPass {
    program: Program,
    pipeline: wgpu::RenderPipeline,
}

impl TonemapPass {
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/post/tonemap.wgsl")?;
        let targets = [target(output_format)];
        let mut spec = RenderSpec::fullscreen("post.tonemap", &targets);
        let constants = [("KEY", KEY)];
        spec.constants = &constants;
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self { program, pipeline })
    }

    /// Tone-maps `hdr` into `output` (imported LDR target); returns its new version.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        exposure: BufferHandle,
        output: TextureHandle,
        view: &'a wgpu::Buffer,
        exposure_buffer: &'a wgpu::Buffer,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let mut pass = graph.add_pass("post.tonemap");
        pass.read(hdr, TextureAccess::Sampled);
        pass.read_buffer(exposure, BufferAccess::StorageRead);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", view.as_entire_binding()),
                    ("hdr", wgpu::BindingResource::TextureView(ctx.view(hdr))),
                    ("exposure", exposure_buffer.as_entire_binding()),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let target = ctx.view(output);
                draw_fullscreen(
                    ctx,
                    &self.pipeline,
                    &bg,
                    target,
                    wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    None,
                );
            }
        });
        output
    }
}
