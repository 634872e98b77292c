//! `--view env-probe | env-mirror`: what the ambient specular reads from the
//! active environment cube (shader `passes/envmap/view.wgsl`).

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, FrameGraph, TextureHandle};
use crate::passes::common::{view_node, view_pipeline};
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

/// The full-screen pass that draws an [`EnvView`].
pub struct EnvViewPass {
    program: Program,
}

impl EnvViewPass {
    /// Compiles the environment view shader; pipelines are made per view and format.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/envmap/view.wgsl")?,
        })
    }

    /// The pipeline of `kind` into `format`.
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        kind: EnvView,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        view_pipeline(ctx, &self.program, "envmap.view", kind as u32, format)
    }

    /// Draws `kind` of the filtered cube (`env`: its handle in the graph) into `output`.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        kind: EnvView,
        gbuffer: GBuffer,
        env: TextureHandle,
        envmap: &'a super::EnvMapPass,
        post: PostInputs<'a>,
        output: TextureHandle,
    ) -> TextureHandle {
        let node = view_node(
            ctx,
            graph,
            &self.program,
            "envmap.view",
            kind as u32,
            output,
        );
        node.read("gbuffer_frame", gbuffer.frame)
            .read("gbuffer_material", gbuffer.material)
            .read("depth", gbuffer.depth)
            .read_cube("env_specular", env)
            .sampler("env_sampler", &envmap.sampler)
            .read_buffer("exposure", post.exposure, BufferAccess::StorageRead)
            .uniform("post", post.post)
            .draw()
    }
}
