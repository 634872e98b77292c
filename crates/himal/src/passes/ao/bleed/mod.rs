//! O5 AO colour bleeding (Ryse): a low-frequency copy of the G-buffer
//! albedo that lighting tints the ambient occlusion with
//! (`occlColor = occl^(1 - min(3 bleed, 0.7))`, `shaders/ao_bleed.wgsl`).
//!
//! ```text
//! albedo, depth ─> ao.bleed (1/4 res, coverage-weighted) ─> ao.bleed_x ─> ao.bleed_y ─> lighting.deferred
//! ```
//! CPU twin: [`mod@reference`]. Math and measurements: `docs/techniques/O5.md`.

pub mod reference;

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::{Step, view_node};

/// Bleed texture: rgb = albedo sum / 16, a = coverage (both blurred).
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Full-resolution pixels per bleed texel along each axis.
pub const SCALE: u32 = 4;

/// The bleed texture's size for a `full` frame.
pub fn size(full: (u32, u32)) -> (u32, u32) {
    (full.0.div_ceil(SCALE), full.1.div_ceil(SCALE))
}

/// O5's bleed passes: the 4x4 downsample and the two blur steps (one
/// shader, `STEP` 0/1/2) and the `--view ao-bleed` program.
pub struct BleedPass {
    downsample: Step,
    blur_x: Step,
    blur_y: Step,
    view_program: Program,
}

impl BleedPass {
    /// Compiles the three steps' pipelines (all into [`FORMAT`]) and the view program.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let path = "passes/ao/bleed/bleed.wgsl";
        let step = |label, s: f64| Step::new(ctx, path, label, FORMAT, &[("STEP", s)]);
        Ok(Self {
            downsample: step("ao.bleed", 0.0)?,
            blur_x: step("ao.bleed_x", 1.0)?,
            blur_y: step("ao.bleed_y", 2.0)?,
            view_program: Program::new(ctx, "passes/ao/bleed/view.wgsl")?,
        })
    }

    /// The bleed texture of a `size` frame's G-buffer albedo.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        albedo: TextureHandle,
        depth: TextureHandle,
    ) -> TextureHandle {
        let (w, h) = self::size(size);
        let desc = TextureDesc::new_2d(w, h, FORMAT);
        let clear = wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT);
        let mut source = albedo;
        // Every step binds depth (one shader); only the downsample reads it.
        for (step, id) in [
            (&self.downsample, "ao.bleed"),
            (&self.blur_x, "ao.bleed_x"),
            (&self.blur_y, "ao.bleed_y"),
        ] {
            let out = graph.create_texture(id, desc.clone());
            source = step
                .node(graph, id)
                .read("source", source)
                .read("depth", depth)
                .color(out, clear)
                .draw();
        }
        source
    }

    /// `--view ao-bleed` into `output`.
    pub fn add_view<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        bleed: TextureHandle,
        output: TextureHandle,
    ) -> TextureHandle {
        view_node(ctx, graph, &self.view_program, "ao.bleed.view", 4, output)
            .read("bleed", bleed)
            .draw()
    }
}
