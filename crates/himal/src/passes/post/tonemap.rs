//! `post.tonemap`: bloom composite and Reinhard, one pipeline per
//! [`TonemapKey`] (override constants `BLOOM`, `WHITE_POINT`).

use std::collections::HashMap;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, FrameGraph, TextureAccess, TextureHandle};
use crate::passes::common::{draw_fullscreen, target};

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
pub struct PostInputs<'a> {
    pub post: &'a wgpu::Buffer,
    /// Adapted luminance or this frame's log-average (handle and buffer).
    pub exposure: (BufferHandle, &'a wgpu::Buffer),
    /// Bloom chain output; `None` binds `placeholder` (the shader skips it).
    pub bloom: Option<TextureHandle>,
    pub placeholder: &'a wgpu::Texture,
    pub sampler: &'a wgpu::Sampler,
}

pub struct TonemapPass {
    program: Program,
    format: wgpu::TextureFormat,
    /// Pipelines already fetched from the cache, by permutation (the pass's handles).
    pipelines: HashMap<TonemapKey, wgpu::RenderPipeline>,
}

impl TonemapPass {
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let mut pass = Self {
            program: Program::new(ctx, "passes/post/tonemap.wgsl")?,
            format: output_format,
            pipelines: HashMap::new(),
        };
        pass.prepare(ctx, TonemapKey::default())?;
        Ok(pass)
    }

    /// Fetches the pipeline of permutation `key` (memory, disk or compile).
    pub fn prepare(&mut self, ctx: &GpuContext, key: TonemapKey) -> Result<(), GpuError> {
        if self.pipelines.contains_key(&key) {
            return Ok(());
        }
        let targets = [target(self.format)];
        let mut spec = RenderSpec::fullscreen("post.tonemap", &targets);
        let constants = key.constants();
        spec.constants = &constants;
        let pipeline = self.program.render_pipeline(ctx, &spec)?;
        self.pipelines.insert(key, pipeline);
        Ok(())
    }

    /// Tone-maps `hdr` (plus bloom) into `output` (imported LDR target); returns its new version.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        key: TonemapKey,
        hdr: TextureHandle,
        inputs: PostInputs<'a>,
        output: TextureHandle,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let pipeline = self.pipelines.get(&key);
        let bloom = match inputs.bloom {
            Some(b) => b,
            None => graph.import_texture("bloom.off", inputs.placeholder),
        };
        let (exposure, exposure_buffer) = inputs.exposure;
        let mut pass = graph.add_pass("post.tonemap");
        pass.read(hdr, TextureAccess::Sampled);
        pass.read(bloom, TextureAccess::Sampled);
        pass.read_buffer(exposure, BufferAccess::StorageRead);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!(
                    "tone-map permutation {key:?} was not prepared"
                ))));
                return;
            };
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("post", inputs.post.as_entire_binding()),
                    ("hdr", wgpu::BindingResource::TextureView(ctx.view(hdr))),
                    ("exposure", exposure_buffer.as_entire_binding()),
                    ("bloom", wgpu::BindingResource::TextureView(ctx.view(bloom))),
                    (
                        "bloom_sampler",
                        wgpu::BindingResource::Sampler(inputs.sampler),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let target = ctx.view(output);
                let load = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
                draw_fullscreen(ctx, pipeline, &bg, target, load, None);
            }
        });
        output
    }
}
