//! Recording helpers shared by the passes.

use crate::frame::FrameErrors;
use crate::gpu::GpuError;
use crate::graph::{PassContext, TextureHandle};

/// Depth attachment of a full-screen pass that only tests against depth.
pub struct DepthTest<'v> {
    pub view: &'v wgpu::TextureView,
}

/// Records one full-screen triangle into `target`.
pub fn draw_fullscreen(
    ctx: &mut PassContext<'_>,
    pipeline: &wgpu::RenderPipeline,
    bind_group: &wgpu::BindGroup,
    target: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
    depth: Option<DepthTest<'_>>,
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
        depth_stencil_attachment: depth.map(|d| wgpu::RenderPassDepthStencilAttachment {
            view: d.view,
            depth_ops: None,
            stencil_ops: None,
        }),
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    });
    pass.set_pipeline(pipeline);
    pass.set_bind_group(0, bind_group, &[]);
    pass.draw(0..3, 0..1);
}

/// Records a debug view (`--view ...`): one full-screen draw of the view's
/// pipeline into `output`, cleared to black, with the group `bind` builds.
/// `pipeline` is `None` when the view was not prepared for the output's
/// format: an error naming the view (`what`) is recorded instead.
pub fn record_view<'e>(
    ctx: &mut PassContext<'e>,
    pipeline: Option<&wgpu::RenderPipeline>,
    what: impl FnOnce() -> String,
    output: TextureHandle,
    errors: &FrameErrors,
    bind: impl FnOnce(&PassContext<'e>) -> Result<wgpu::BindGroup, GpuError>,
) {
    let Some(pipeline) = pipeline else {
        errors.record::<()>(Err(GpuError::Other(format!("{} was not prepared", what()))));
        return;
    };
    if let Some(bg) = errors.record(bind(ctx)) {
        let target = ctx.view(output);
        let clear = wgpu::LoadOp::Clear(wgpu::Color::BLACK);
        draw_fullscreen(ctx, pipeline, &bg, target, clear, None);
    }
}

/// A colour target state without blending.
pub fn target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// Pipeline of a debug-view shader (`VIEW` selects the buffer, `DISPLAY`
/// viewable vs raw): float targets get raw values, others display values.
pub fn view_pipeline(
    ctx: &crate::gpu::GpuContext,
    program: &crate::gpu::pipeline::Program,
    label: &str,
    view_id: u32,
    format: wgpu::TextureFormat,
) -> Result<wgpu::RenderPipeline, crate::gpu::GpuError> {
    let display = !matches!(
        format,
        wgpu::TextureFormat::Rgba32Float | wgpu::TextureFormat::Rgba16Float
    );
    let targets = [target(format)];
    let constants = [
        ("VIEW", view_id as f64),
        ("DISPLAY", if display { 1.0 } else { 0.0 }),
    ];
    let mut spec = crate::gpu::pipeline::RenderSpec::fullscreen(label, &targets);
    spec.constants = &constants;
    program.render_pipeline(ctx, &spec)
}
