//! Debug views (`himal render --view BUFFER`): one G-buffer channel or the
//! HDR lighting buffer, as a viewable image (PNG) or raw values (EXR).

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, Fallback, FrameGraph, TextureHandle};
use crate::passes::common::{view_node, view_pipeline};
use crate::passes::gbuffer::GBuffer;
use crate::passes::post::PostInputs;

/// Buffers a debug view can show; `id` is the shader's `VIEW` constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DebugView {
    /// The G-buffer's linear albedo, black for the sky.
    Albedo = 1,
    /// World-space shading normal: raw in \[-1,1\], displayed as n * 0.5 + 0.5.
    Normal = 2,
    /// World-space tangent (the anisotropy direction), mapped like the normal.
    Tangent = 3,
    /// Glossiness in \[0,1\] as grey.
    Glossiness = 4,
    /// Dielectric reflectance (F0) in \[0,1\] as grey.
    Reflectance = 5,
    /// Metalness in \[0,1\] as grey.
    Metallic = 6,
    /// Anisotropy in \[0,1\] as grey.
    Anisotropy = 7,
    /// Depth: raw as stored (reverse-Z, 0 = far); displayed as log distance, white at 1 m to black at 4 km.
    Depth = 8,
    /// Screen motion in pixels (raw); displayed with grey 0.5 as still, ±8 px to 0 and 1.
    Motion = 9,
    /// The HDR lighting buffer: raw values, or exposure-scaled and clamped without a tone curve.
    Lighting = 10,
    /// Per-pixel luminance around the exposure (H3), log scale.
    Luminance = 11,
    /// The bloom chain's output (H2), upsampled.
    Bloom = 12,
    /// The world's 64 m sectors (V6): one hue per sector over the albedo, edges dark.
    Sectors = 13,
    /// Each surface's LOD level (E2) or terrain quadtree level, as a hue
    /// over its albedo (the G-buffer draws each level with its own pipeline).
    Lod = 14,
    /// V3: the albedo, impostor pixels in the hue of their nearest capture
    /// around (lighter toward the top one).
    Impostor = 15,
    /// V5: the leaf amount in \[0,1\] as grey (1 on grass, bush and leaf
    /// cards, the leaf fraction on impostors, 0 elsewhere).
    Foliage = 16,
}

/// The full-screen pass that draws a [`DebugView`] of the frame's buffers.
pub struct DebugPass {
    program: Program,
}

impl DebugPass {
    /// Compiles the debug view shader; pipelines are made per view and format.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/debug/view.wgsl")?,
        })
    }

    /// The pipeline of `view` into `format` (float formats get raw values).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        view: DebugView,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        view_pipeline(ctx, &self.program, "debug.view", view as u32, format)
    }

    /// Draws `view_kind` of the G-buffer, HDR or bloom into `output`.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        view_kind: DebugView,
        gbuffer: GBuffer,
        hdr: TextureHandle,
        post: PostInputs<'a>,
        output: TextureHandle,
    ) -> TextureHandle {
        let id = view_kind as u32;
        let node = view_node(ctx, graph, &self.program, "debug.view", id, output);
        node.read("gbuffer_albedo", gbuffer.albedo)
            .read("gbuffer_frame", gbuffer.frame)
            .read("gbuffer_material", gbuffer.material)
            .read("motion", gbuffer.motion)
            .read("depth", gbuffer.depth)
            .read("hdr", hdr)
            .read_buffer("exposure", post.exposure, BufferAccess::StorageRead)
            .uniform("post", post.post)
            .optional("bloom", post.bloom, Fallback::Black)
            .sampler("bloom_sampler", post.sampler)
            .draw()
    }
}
