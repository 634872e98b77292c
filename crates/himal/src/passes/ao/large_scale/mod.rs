//! O6 large-scale AO (Ryse): the height field around a pixel occludes its
//! ambient light at a scale the screen cannot see (valleys, house
//! interiors, the far side of a wall off screen).
//!
//! ```text
//! ao.hbao ─> ao.large_scale (AO res; L2 pool heights, G-buffer normal) ─> ao.stability, ao.pack ...
//! ```
//! The height field is the L2 sector pool's (`passes/skyocc`): rendered
//! top-down per 64 m sector at 25 cm when a sector comes into range,
//! time-sliced like the static shadow map, streamed with the world's
//! sectors. Shared WGSL: `shaders/ao_large_scale.wgsl`. CPU twin:
//! [`mod@reference`]. Math and measurements: `docs/techniques/O6.md`.

pub mod reference;

use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::Step;

/// What `ao.large_scale` reads besides the AO.
pub struct LargeScaleInputs<'a> {
    /// Full-resolution device depth.
    pub depth: TextureHandle,
    /// The G-buffer's packed tangent frame (the normal).
    pub frame: TextureHandle,
    /// The L2 pool's sector table (`SkyOccBindings::table`).
    pub table: &'a wgpu::TextureView,
    /// The L2 pool's (terrain, fade) heights, one layer per sector.
    pub heights: TextureHandle,
}

/// The pass: one step per AO format (plain, SSDO).
pub struct LargeScalePass {
    plain: Step,
    ssdo: Step,
}

impl LargeScalePass {
    /// Compiles the step for both AO formats.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let path = "passes/ao/large_scale/large_scale.wgsl";
        Ok(Self {
            plain: Step::new(ctx, path, "ao.large_scale", super::RAW_FORMAT, &[])?,
            ssdo: Step::new(ctx, path, "ao.large_scale_ssdo", super::SSDO_FORMAT, &[])?,
        })
    }

    /// `raw` (ao.hbao's output, `size` texels) times the large-scale AO.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        ssdo: bool,
        params: &'a wgpu::Buffer,
        jitter: TextureHandle,
        raw: TextureHandle,
        inputs: LargeScaleInputs<'a>,
    ) -> TextureHandle {
        let (step, format) = if ssdo {
            (&self.ssdo, super::SSDO_FORMAT)
        } else {
            (&self.plain, super::RAW_FORMAT)
        };
        let out = graph.create_texture(
            "ao.raw_large_scale",
            TextureDesc::new_2d(size.0, size.1, format),
        );
        step.node(graph, "ao.large_scale")
            .uniform("params", params)
            .read("depth", inputs.depth)
            .read("gbuffer_frame", inputs.frame)
            .read("jitter_load", jitter)
            .read("raw", raw)
            .external("skyocc_table", inputs.table)
            .read_array("skyocc_heights_load", inputs.heights)
            .color(out, wgpu::LoadOp::Clear(wgpu::Color::WHITE))
            .draw()
    }
}
