//! The G-buffer side: the pipeline, the instanced patch draw and the
//! `terrain` node.

use super::layout::patch_layout;
use super::reference::Patch;
use super::{MAX_PATCHES, TerrainPass};
use crate::gpu::pipeline::{RenderSpec, target};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::FrameGraph;
use crate::passes::gbuffer::{
    ALBEDO_FORMAT, DEPTH_FORMAT, FRAME_FORMAT, GBuffer, MATERIAL_FORMAT, MOTION_FORMAT,
};

impl TerrainPass {
    /// The G-buffer pipeline, through the shared cache (`lod_view`: albedo
    /// shows each patch's level, `--view lod`; `specular_aa`: E3, the
    /// detail normals' variance widens roughness).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        lod_view: bool,
        specular_aa: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        let constants = [("LOD_VIEW", b(lod_view)), ("SPECULAR_AA", b(specular_aa))];
        let targets = [
            target(ALBEDO_FORMAT),
            target(FRAME_FORMAT),
            target(MATERIAL_FORMAT),
            target(MOTION_FORMAT),
        ];
        self.program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "terrain",
                vertex_entry: "vs_main",
                fragment_entry: Some("fs_main"),
                vertex_buffers: &[Some(patch_layout())],
                targets: &targets,
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    // reverse-Z: nearer is larger; equal keeps ties with objects drawn first
                    depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                primitive: wgpu::PrimitiveState {
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                constants: &constants,
            },
        )
    }

    pub(super) fn draw_view(&self, rp: &mut wgpu::RenderPass<'_>, view: usize) -> u32 {
        let count = self.count(view);
        if count > 0 {
            let size = std::mem::size_of::<Patch>() as u64;
            let start = (view * MAX_PATCHES) as u64 * size;
            rp.set_vertex_buffer(
                0,
                self.instances.slice(start..start + u64::from(count) * size),
            );
            rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
            rp.draw_indexed(0..self.index_count, 0, 0..count);
        }
        count
    }

    /// The `terrain` node: the camera's patches into `gbuffer` (after the
    /// `gbuffer` node; targets loaded, depth GreaterEqual), seen through
    /// `view` (the frame's view uniform: view_proj, prev_view_proj).
    /// Returns the G-buffer's new versions.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        gbuffer: GBuffer,
        view: &'a wgpu::Buffer,
    ) -> GBuffer {
        let pipeline = self.pipeline(ctx, self.lod_view, self.specular_aa);
        let node = graph
            .raster("terrain", &self.program)
            .pipeline(pipeline)
            .uniform("view", view)
            .uniform("terrain", &self.params)
            .uniform("layers", &self.layers)
            .external("coarse_load", &self.coarse_view)
            .external("fine_load", &self.fine_view)
            .external("pages", &self.pages_view)
            .external("detail_albedo", &self.detail_albedo)
            .external("detail_normal", &self.detail_normal)
            .sampler("detail_sampler", &self.sampler);
        let written = gbuffer.load_into(node).record(move |_, rp| {
            self.draw_view(rp, 0);
            Ok(())
        });
        gbuffer.after(&written)
    }
}
