//! `post.tonemap`: bloom composite and Reinhard, one pipeline per
//! [`TonemapKey`] (override constants `BLOOM`, `WHITE_POINT`).

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, Fallback, FrameGraph, TextureHandle};
use crate::passes::common::target;

/// The tone-map permutation: which code the shader keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct TonemapKey {
    pub bloom: bool,
    pub white_point: bool,
}

impl TonemapKey {
    /// Every permutation (for pre-warming).
    pub fn all() -> [TonemapKey; 4] {
        [(false, false), (true, false), (false, true), (true, true)]
            .map(|(bloom, white_point)| TonemapKey { bloom, white_point })
    }

    fn constants(self) -> [(&'static str, f64); 2] {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        [
            ("BLOOM", b(self.bloom)),
            ("WHITE_POINT", b(self.white_point)),
        ]
    }
}

/// What `post.tonemap` and the debug views read besides the HDR image.
#[derive(Clone, Copy)]
pub struct PostInputs<'a> {
    pub post: &'a wgpu::Buffer,
    /// Adapted luminance or this frame's log-average.
    pub exposure: BufferHandle,
    /// Bloom chain output; `None`: no bloom (the shader skips it).
    pub bloom: Option<TextureHandle>,
    pub sampler: &'a wgpu::Sampler,
}

pub struct TonemapPass {
    program: Program,
    format: wgpu::TextureFormat,
}

impl TonemapPass {
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let pass = Self {
            program: Program::new(ctx, "passes/post/tonemap.wgsl")?,
            format: output_format,
        };
        pass.pipeline(ctx, TonemapKey::default())?;
        Ok(pass)
    }

    /// The pipeline of permutation `key` (memory, disk or compile).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        key: TonemapKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(self.format)];
        let mut spec = RenderSpec::fullscreen("post.tonemap", &targets);
        let constants = key.constants();
        spec.constants = &constants;
        self.program.render_pipeline(ctx, &spec)
    }

    /// Tone-maps `hdr` (plus bloom) into `output` (imported LDR target); returns its new version.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        key: TonemapKey,
        hdr: TextureHandle,
        inputs: PostInputs<'a>,
        output: TextureHandle,
    ) -> TextureHandle {
        graph
            .fullscreen("post.tonemap", &self.program)
            .pipeline(self.pipeline(ctx, key))
            .uniform("post", inputs.post)
            .read("hdr", hdr)
            .read_buffer("exposure", inputs.exposure, BufferAccess::StorageRead)
            .optional("bloom", inputs.bloom, Fallback::Black)
            .sampler("bloom_sampler", inputs.sampler)
            .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }
}
