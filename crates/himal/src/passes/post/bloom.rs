//! H2 Kawase bloom: a quarter-resolution bright pass, then `passes` small
//! blurs with growing offsets (`post.bloom.blur0..`); `post.tonemap` adds the
//! result to the HDR image before tone mapping. CPU twin:
//! [`super::reference::kawase_pass`], [`super::reference::bright_pass`].

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::target;
use crate::passes::lighting::HDR_FORMAT;

/// Size of the bloom chain for a frame of `size` (quarter resolution, at least 1x1).
pub fn bloom_size(size: (u32, u32)) -> (u32, u32) {
    (size.0.div_ceil(4).max(1), size.1.div_ceil(4).max(1))
}

/// What the bloom chain reads besides the HDR image.
#[derive(Clone, Copy)]
pub struct BloomInputs<'a> {
    /// `PostUniform`.
    pub post: &'a wgpu::Buffer,
    /// Exposure: `post.adapt`'s adapted buffer or `post.luminance`'s result.
    pub exposure: BufferHandle,
}

/// H2 bloom: a bright pass and a chain of Kawase blur passes at quarter resolution, added back in the tonemap pass.
pub struct BloomPass {
    program: Program,
    bright: wgpu::RenderPipeline,
    /// Linear, clamp-to-edge: bilinear taps and the upsampling in the composite.
    pub sampler: wgpu::Sampler,
}

impl BloomPass {
    /// Compiles the bright-pass pipeline and makes the sampler; blur pipelines
    /// come from [`Self::blur_pipeline`], one per offset.
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
            sampler,
        })
    }

    /// The Kawase pipeline of offset `k` (one permutation each, `OFFSET`).
    pub fn blur_pipeline(
        &self,
        ctx: &GpuContext,
        k: u32,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("post.bloom.blur", &targets);
        spec.fragment_entry = Some("fs_blur");
        let constants = [("OFFSET", k as f64)];
        spec.constants = &constants;
        self.program.render_pipeline(ctx, &spec)
    }

    /// Bright pass of `hdr` and `passes` Kawase blurs; returns the bloom
    /// texture (quarter resolution, HDR units).
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        inputs: BloomInputs<'a>,
        passes: u32,
    ) -> TextureHandle {
        let size = graph
            .texture_desc(hdr)
            .map(|d| (d.width, d.height))
            .unwrap_or((1, 1));
        let (w, h) = bloom_size(size);
        let bright = graph.create_texture("bloom.bright", TextureDesc::new_2d(w, h, HDR_FORMAT));
        let mut bloom = self.add_bright(graph, hdr, bright, inputs);
        for k in 0..passes {
            let name = format!("bloom.blur{k}");
            let dst = graph.create_texture(&name, TextureDesc::new_2d(w, h, HDR_FORMAT));
            bloom = self.add_blur(ctx, graph, bloom, dst, k, inputs);
        }
        bloom
    }

    /// One node of the chain: `pipeline` from `src` into `dst`.
    fn node<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        id: &str,
        pipeline: Result<wgpu::RenderPipeline, GpuError>,
        src: TextureHandle,
        dst: TextureHandle,
        inputs: BloomInputs<'a>,
    ) -> TextureHandle {
        graph
            .fullscreen(id, &self.program)
            .pipeline(pipeline)
            .uniform("post", inputs.post)
            .read_buffer("exposure", inputs.exposure, BufferAccess::StorageRead)
            .read("src", src)
            .sampler("src_sampler", &self.sampler)
            .color(dst, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }

    /// The bright pass `post.bloom.bright` from `hdr` into `dst` (quarter resolution).
    pub fn add_bright<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        dst: TextureHandle,
        inputs: BloomInputs<'a>,
    ) -> TextureHandle {
        let pipeline = Ok(self.bright.clone());
        self.node(graph, "post.bloom.bright", pipeline, hdr, dst, inputs)
    }

    /// One Kawase pass `post.bloom.blur{k}` from `src` into `dst` (same size).
    pub fn add_blur<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        src: TextureHandle,
        dst: TextureHandle,
        k: u32,
        inputs: BloomInputs<'a>,
    ) -> TextureHandle {
        let pipeline = self.blur_pipeline(ctx, k);
        self.node(
            graph,
            &format!("post.bloom.blur{k}"),
            pipeline,
            src,
            dst,
            inputs,
        )
    }
}
