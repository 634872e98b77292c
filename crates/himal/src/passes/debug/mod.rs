//! Debug views (`himal render --view BUFFER`): one G-buffer channel or the
//! HDR lighting buffer, as a viewable image (PNG) or raw values (EXR).

use std::collections::HashMap;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, FrameGraph, TextureAccess, TextureHandle};
use crate::passes::common::{record_view, view_pipeline};
use crate::passes::gbuffer::GBuffer;
use crate::passes::post::PostInputs;

/// Buffers a debug view can show; `id` is the shader's `VIEW` constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DebugView {
    Albedo = 1,
    Normal = 2,
    Tangent = 3,
    Glossiness = 4,
    Reflectance = 5,
    Metallic = 6,
    Anisotropy = 7,
    Depth = 8,
    Motion = 9,
    Lighting = 10,
    /// Per-pixel luminance around the exposure (H3), log scale.
    Luminance = 11,
    /// The bloom chain's output (H2), upsampled.
    Bloom = 12,
}

pub struct DebugPass {
    program: Program,
    pipelines: HashMap<(DebugView, wgpu::TextureFormat), wgpu::RenderPipeline>,
}

impl DebugPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/debug/view.wgsl")?,
            pipelines: HashMap::new(),
        })
    }

    /// Builds the pipeline for `view` into `format` (float formats get raw values).
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: DebugView,
        format: wgpu::TextureFormat,
    ) -> Result<(), GpuError> {
        if self.pipelines.contains_key(&(view, format)) {
            return Ok(());
        }
        let pipeline = view_pipeline(ctx, &self.program, "debug.view", view as u32, format)?;
        self.pipelines.insert((view, format), pipeline);
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        view_kind: DebugView,
        gbuffer: GBuffer,
        hdr: TextureHandle,
        post: PostInputs<'a>,
        output: TextureHandle,
        view: &'a wgpu::Buffer,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let bloom = match post.bloom {
            Some(b) => b,
            None => graph.import_texture("bloom.off", post.placeholder),
        };
        let (exposure, exposure_buffer) = post.exposure;
        let format = graph.texture_desc(output).map(|d| d.format);
        let pipeline = format.and_then(|f| self.pipelines.get(&(view_kind, f)));
        let mut pass = graph.add_pass("debug.view");
        for t in [
            gbuffer.albedo,
            gbuffer.frame,
            gbuffer.material,
            gbuffer.motion,
            gbuffer.depth,
            hdr,
            bloom,
        ] {
            pass.read(t, TextureAccess::Sampled);
        }
        pass.read_buffer(exposure, BufferAccess::StorageRead);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let what = || format!("debug view {view_kind:?}");
            record_view(ctx, pipeline, what, output, errors, |ctx| {
                let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
                self.program.bind(
                    ctx.device,
                    0,
                    &[
                        ("view", view.as_entire_binding()),
                        ("gbuffer_albedo", tv(gbuffer.albedo)),
                        ("gbuffer_frame", tv(gbuffer.frame)),
                        ("gbuffer_material", tv(gbuffer.material)),
                        ("motion", tv(gbuffer.motion)),
                        ("depth", tv(gbuffer.depth)),
                        ("hdr", tv(hdr)),
                        ("exposure", exposure_buffer.as_entire_binding()),
                        ("post", post.post.as_entire_binding()),
                        ("bloom", tv(bloom)),
                        (
                            "bloom_sampler",
                            wgpu::BindingResource::Sampler(post.sampler),
                        ),
                    ],
                )
            });
        });
        output
    }
}
