//! Recording helpers shared by the passes.

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, Node, PassContext, TextureHandle};

pub use crate::gpu::pipeline::target;

/// A full-screen program with its one pipeline (a pass step without permutations).
pub struct Step {
    /// The composed shader, for bind groups by name.
    pub program: Program,
    /// Its full-screen pipeline into the step's format.
    pub pipeline: wgpu::RenderPipeline,
}

impl Step {
    /// Composes `path` and fetches its full-screen pipeline into `format`.
    pub fn new(
        ctx: &GpuContext,
        path: &str,
        label: &str,
        format: wgpu::TextureFormat,
        constants: &[(&str, f64)],
    ) -> Result<Self, GpuError> {
        let program = Program::new(ctx, path)?;
        let targets = [target(format)];
        let mut spec = RenderSpec::fullscreen(label, &targets);
        spec.constants = constants;
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self { program, pipeline })
    }

    /// A full-screen node of this step.
    pub fn node<'g, 'a>(&'a self, graph: &'g mut FrameGraph<'a>, id: &str) -> Node<'g, 'a> {
        graph
            .fullscreen(id, &self.program)
            .pipeline(Ok(self.pipeline.clone()))
    }
}

/// Records one full-screen triangle into `target` (for passes that draw
/// more than once; single draws are [`crate::graph::FrameGraph::fullscreen`] nodes).
pub fn draw_fullscreen(
    ctx: &mut PassContext<'_>,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
    target: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) {
    let label = ctx.pass_id().to_string();
    let mut pass = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(0..3, 0..1);
}

/// Clears `target` (declared written by the pass) to `color`.
pub fn clear_target(
    ctx: &mut PassContext<'_>,
    target: TextureHandle,
    color: wgpu::Color,
) -> Result<(), GpuError> {
    let view = ctx
        .try_view(target)
        .map_err(|e| GpuError::Other(e.to_string()))?;
    let label = ctx.pass_id().to_string();
    ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(&label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(color),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    Ok(())
}

/// Whether a debug view written to `format` shows display values (float
/// targets get the raw ones).
pub fn is_display_format(format: wgpu::TextureFormat) -> bool {
    !matches!(
        format,
        wgpu::TextureFormat::Rgba32Float | wgpu::TextureFormat::Rgba16Float
    )
}

/// Pipeline of a debug-view shader (`VIEW` selects the buffer, `DISPLAY`
/// viewable vs raw): float targets get raw values, others display values.
pub fn view_pipeline(
    ctx: &GpuContext,
    program: &Program,
    label: &str,
    view_id: u32,
    format: wgpu::TextureFormat,
) -> Result<wgpu::RenderPipeline, GpuError> {
    let display = is_display_format(format);
    let targets = [target(format)];
    let constants = [
        ("VIEW", view_id as f64),
        ("DISPLAY", if display { 1.0 } else { 0.0 }),
    ];
    let mut spec = RenderSpec::fullscreen(label, &targets);
    spec.constants = &constants;
    program.render_pipeline(ctx, &spec)
}

/// A debug view's full-screen node `id` drawing view `view_id` of
/// `program` into `output` (cleared to black), its pipeline picked by the
/// output's format; the caller binds what the view reads and draws.
pub fn view_node<'g, 'a>(
    ctx: &GpuContext,
    graph: &'g mut FrameGraph<'a>,
    program: &'a Program,
    id: &str,
    view_id: u32,
    output: TextureHandle,
) -> Node<'g, 'a> {
    let pipeline = match graph.texture_desc(output) {
        Some(d) => view_pipeline(ctx, program, id, view_id, d.format),
        None => Err(GpuError::Other(format!(
            "{id}: the output is not in this graph"
        ))),
    };
    graph
        .fullscreen(id, program)
        .pipeline(pipeline)
        .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
}
