//! H2 Kawase bloom: a quarter-resolution bright pass, then `passes` small
//! blurs with growing offsets (`post.bloom.blur0..`); `post.tonemap` adds the
//! result to the HDR image before tone mapping. CPU twin:
//! [`super::reference::kawase_pass`], [`super::reference::bright_pass`].

use std::collections::HashMap;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{
    BufferAccess, BufferHandle, FrameGraph, TextureAccess, TextureDesc, TextureHandle,
};
use crate::passes::common::{draw_fullscreen, target};
use crate::passes::lighting::HDR_FORMAT;

/// Size of the bloom chain for a frame of `size` (quarter resolution, at least 1x1).
pub fn bloom_size(size: (u32, u32)) -> (u32, u32) {
    (size.0.div_ceil(4).max(1), size.1.div_ceil(4).max(1))
}

/// Buffers the bloom chain reads (owned by the renderer).
#[derive(Clone, Copy)]
pub struct BloomInputs<'a> {
    /// `PostUniform`.
    pub post: &'a wgpu::Buffer,
    /// Exposure: `post.adapt`'s adapted buffer or `post.luminance`'s result.
    pub exposure: &'a wgpu::Buffer,
}

pub struct BloomPass {
    program: Program,
    bright: wgpu::RenderPipeline,
    /// Kawase pass pipelines by offset k (`OFFSET` override constant).
    blur: HashMap<u32, wgpu::RenderPipeline>,
    /// Linear, clamp-to-edge: bilinear taps and the upsampling in the composite.
    pub sampler: wgpu::Sampler,
}

impl BloomPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/post/bloom.wgsl")?;
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("post.bloom.bright", &targets);
        spec.fragment_entry = Some("fs_bright");
        let bright = program.render_pipeline(ctx, &spec)?;
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("post.bloom.sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            program,
            bright,
            blur: HashMap::new(),
            sampler,
        })
    }

    /// Builds the Kawase pipelines for offsets `0..passes` (one permutation each).
    pub fn prepare(&mut self, ctx: &GpuContext, passes: u32) -> Result<(), GpuError> {
        let targets = [target(HDR_FORMAT)];
        for k in 0..passes {
            if self.blur.contains_key(&k) {
                continue;
            }
            let mut spec = RenderSpec::fullscreen("post.bloom.blur", &targets);
            spec.fragment_entry = Some("fs_blur");
            let constants = [("OFFSET", k as f64)];
            spec.constants = &constants;
            let pipeline = self.program.render_pipeline(ctx, &spec)?;
            self.blur.insert(k, pipeline);
        }
        Ok(())
    }

    /// Bright pass of `hdr` and `passes` Kawase blurs; returns the bloom
    /// texture (quarter resolution, HDR units).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        exposure: BufferHandle,
        inputs: BloomInputs<'a>,
        passes: u32,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let size = graph
            .texture_desc(hdr)
            .map(|d| (d.width, d.height))
            .unwrap_or((1, 1));
        let (w, h) = bloom_size(size);
        let bright = graph.create_texture("bloom.bright", TextureDesc::new_2d(w, h, HDR_FORMAT));
        let mut bloom = self.add_bright(graph, hdr, exposure, bright, inputs, errors);
        for k in 0..passes {
            let name = format!("bloom.blur{k}");
            let dst = graph.create_texture(&name, TextureDesc::new_2d(w, h, HDR_FORMAT));
            bloom = self.add_blur(graph, bloom, dst, k, inputs, errors);
        }
        bloom
    }

    fn bind(
        &self,
        ctx: &crate::graph::PassContext<'_>,
        inputs: BloomInputs<'_>,
        src: TextureHandle,
    ) -> Result<wgpu::BindGroup, GpuError> {
        self.program.bind(
            ctx.device,
            0,
            &[
                ("post", inputs.post.as_entire_binding()),
                ("exposure", inputs.exposure.as_entire_binding()),
                ("src", wgpu::BindingResource::TextureView(ctx.view(src))),
                ("src_sampler", wgpu::BindingResource::Sampler(&self.sampler)),
            ],
        )
    }

    /// The bright pass `post.bloom.bright` from `hdr` into `dst` (quarter resolution).
    pub fn add_bright<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        exposure: BufferHandle,
        dst: TextureHandle,
        inputs: BloomInputs<'a>,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let mut pass = graph.add_pass("post.bloom.bright");
        pass.read(hdr, TextureAccess::Sampled);
        pass.read_buffer(exposure, BufferAccess::StorageRead);
        let dst = pass.write(dst, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            if let Some(bg) = errors.record(self.bind(ctx, inputs, hdr)) {
                let target = ctx.view(dst);
                let load = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
                draw_fullscreen(ctx, &self.bright, &bg, target, load, None);
            }
        });
        dst
    }

    /// One Kawase pass `post.bloom.blur{k}` from `src` into `dst` (same size).
    pub fn add_blur<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        src: TextureHandle,
        dst: TextureHandle,
        k: u32,
        inputs: BloomInputs<'a>,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let pipeline = self.blur.get(&k);
        let mut pass = graph.add_pass(&format!("post.bloom.blur{k}"));
        pass.read(src, TextureAccess::Sampled);
        let dst = pass.write(dst, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!(
                    "bloom pass {k} was not prepared"
                ))));
                return;
            };
            if let Some(bg) = errors.record(self.bind(ctx, inputs, src)) {
                let target = ctx.view(dst);
                let load = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
                draw_fullscreen(ctx, pipeline, &bg, target, load, None);
            }
        });
        dst
    }
}
