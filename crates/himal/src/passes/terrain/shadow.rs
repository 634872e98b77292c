//! Shadows: the terrain's patches into the sun cascades (`terrain.shadow{i}`)
//! and the world's static map (`terrain.static{i}`).

use super::layout::patch_layout;
use super::{MAX_VIEWS, TerrainPass, other};
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureHandle};

impl TerrainPass {
    /// Records shadow view `cascade`'s patches into the caller's depth pass
    /// (a cascade layer, [`SHADOW_DEPTH_FORMAT`](super::SHADOW_DEPTH_FORMAT), standard depth):
    /// `shadow_view` is the cascade's `ShadowViewGpu` buffer (its
    /// `light_view_proj` is read). Sets its own pipeline, bind group 0 and
    /// vertex/index buffers: the caller sets its own again after. Returns
    /// the patches drawn.
    pub fn draw_shadow(
        &self,
        device: &wgpu::Device,
        rp: &mut wgpu::RenderPass<'_>,
        shadow_view: &wgpu::Buffer,
        cascade: usize,
    ) -> Result<u32, GpuError> {
        self.draw_sun_view(device, rp, shadow_view, cascade, &self.shadow_pipeline)
    }

    /// [`Self::draw_shadow`] with `pipeline` (its depth format).
    fn draw_sun_view(
        &self,
        device: &wgpu::Device,
        rp: &mut wgpu::RenderPass<'_>,
        shadow_view: &wgpu::Buffer,
        cascade: usize,
        pipeline: &wgpu::RenderPipeline,
    ) -> Result<u32, GpuError> {
        let view = cascade + 1;
        if view >= MAX_VIEWS {
            return Err(other(format!(
                "terrain: shadow view {cascade} (at most {})",
                MAX_VIEWS - 1
            )));
        }
        if self.count(view) == 0 {
            return Ok(0);
        }
        let group = self.shadow_program.bind(
            device,
            0,
            &[
                ("shadow", shadow_view.as_entire_binding()),
                ("terrain", self.params.as_entire_binding()),
                (
                    "coarse_load",
                    wgpu::BindingResource::TextureView(&self.coarse_view),
                ),
                (
                    "fine_load",
                    wgpu::BindingResource::TextureView(&self.fine_view),
                ),
                (
                    "pages",
                    wgpu::BindingResource::TextureView(&self.pages_view),
                ),
            ],
        )?;
        rp.set_pipeline(pipeline);
        rp.set_bind_group(0, &group, &[]);
        Ok(self.draw_view(rp, view))
    }

    /// A node `terrain.shadow{cascade}` drawing [`Self::draw_shadow`] into
    /// layer `layer` of `cascades` (depth loaded: after the cascade's own
    /// node). Returns the new version of `cascades`.
    pub fn add_shadow<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        cascades: TextureHandle,
        layer: u32,
        shadow_view: &'a wgpu::Buffer,
        cascade: usize,
    ) -> TextureHandle {
        let view = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..Default::default()
        };
        let written = graph
            .raster(&format!("terrain.shadow{cascade}"), &self.shadow_program)
            .external_group(0)
            .depth(
                cascades,
                Some(view),
                wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            )
            .record(move |ctx, rp| {
                self.draw_shadow(ctx.device, rp, shadow_view, cascade)
                    .map(|_| ())
            });
        written.depth.unwrap_or(cascades)
    }
}

impl crate::passes::shadows::CascadeCaster for TerrainPass {
    fn add_cascade<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        cascades: TextureHandle,
        layer: u32,
        view: &'a wgpu::Buffer,
    ) -> TextureHandle {
        self.add_shadow(graph, cascades, layer, view, layer as usize)
    }

    fn add_static_tile<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        map: TextureHandle,
        index: usize,
        view: &'a wgpu::Buffer,
        rect: [u32; 4],
    ) -> TextureHandle {
        let written = graph
            .raster(&format!("terrain.static{index}"), &self.shadow_program)
            .external_group(0)
            .depth(
                map,
                None,
                wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            )
            .side_effect()
            .record(move |ctx, rp| {
                crate::passes::shadows::depth::set_rect(rp, rect);
                let pipeline = &self.static_pipeline;
                (self.draw_sun_view(ctx.device, rp, view, index, pipeline)).map(|_| ())
            });
        written.depth.unwrap_or(map)
    }
}

/// The sun-view pipeline writing `format` (cascades: 32-bit, the world's
/// static map: 16-bit).
pub(super) fn sun_view_pipeline(
    ctx: &GpuContext,
    program: &Program,
    format: wgpu::TextureFormat,
) -> Result<wgpu::RenderPipeline, GpuError> {
    program.render_pipeline(
        ctx,
        &RenderSpec {
            label: "terrain.shadow",
            vertex_entry: "vs_main",
            fragment_entry: None,
            vertex_buffers: &[Some(patch_layout())],
            targets: &[],
            // As the scene's casters.
            depth_stencil: Some(crate::passes::shadows::depth::caster_depth(format)),
            // Both faces cast: the sun may see the ground from below the horizon line.
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            constants: &[],
        },
    )
}
