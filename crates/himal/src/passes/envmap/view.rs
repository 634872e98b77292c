//! `--view env-probe | env-mirror`: what the ambient specular reads from the
//! active environment cube (shader `passes/envmap/view.wgsl`).

use std::collections::HashMap;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, FrameGraph, TextureAccess, TextureHandle};
use crate::passes::common::{record_view, view_pipeline};
use crate::passes::gbuffer::GBuffer;
use crate::passes::post::PostInputs;

/// Environment views; `id` is the shader's `VIEW` constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EnvView {
    /// The prefiltered radiance at the pixel's roughness mip (`env-probe`).
    Probe = 1,
    /// Mip 0 along the reflection vector: the relit cube as a mirror (`env-mirror`).
    Mirror = 2,
}

pub struct EnvViewPass {
    program: Program,
    pipelines: HashMap<(EnvView, wgpu::TextureFormat), wgpu::RenderPipeline>,
}

impl EnvViewPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/envmap/view.wgsl")?,
            pipelines: HashMap::new(),
        })
    }

    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        kind: EnvView,
        format: wgpu::TextureFormat,
    ) -> Result<(), GpuError> {
        if !self.pipelines.contains_key(&(kind, format)) {
            let pipeline = view_pipeline(ctx, &self.program, "envmap.view", kind as u32, format)?;
            self.pipelines.insert((kind, format), pipeline);
        }
        Ok(())
    }

    /// Draws `kind` of the filtered cube (`env`: its handle in the graph) into `output`.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        kind: EnvView,
        gbuffer: GBuffer,
        env: TextureHandle,
        envmap: &'a super::EnvMapPass,
        post: PostInputs<'a>,
        output: TextureHandle,
        view: &'a wgpu::Buffer,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let format = graph.texture_desc(output).map(|d| d.format);
        let pipeline = format.and_then(|f| self.pipelines.get(&(kind, f)));
        let (exposure, exposure_buffer) = post.exposure;
        let mut pass = graph.add_pass("envmap.view");
        for t in [gbuffer.frame, gbuffer.material, gbuffer.depth, env] {
            pass.read(t, TextureAccess::Sampled);
        }
        pass.read_buffer(exposure, BufferAccess::StorageRead);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let what = || format!("environment view {kind:?}");
            record_view(ctx, pipeline, what, output, errors, |ctx| {
                let tv = |h| wgpu::BindingResource::TextureView(ctx.view(h));
                self.program.bind(
                    ctx.device,
                    0,
                    &[
                        ("view", view.as_entire_binding()),
                        ("gbuffer_frame", tv(gbuffer.frame)),
                        ("gbuffer_material", tv(gbuffer.material)),
                        ("depth", tv(gbuffer.depth)),
                        // `env` orders this pass after the filter; the cube view is the pass's own
                        (
                            "env_specular",
                            wgpu::BindingResource::TextureView(&envmap.filtered_cube),
                        ),
                        (
                            "env_sampler",
                            wgpu::BindingResource::Sampler(&envmap.sampler),
                        ),
                        ("exposure", exposure_buffer.as_entire_binding()),
                        ("post", post.post.as_entire_binding()),
                    ],
                )
            });
        });
        output
    }
}
