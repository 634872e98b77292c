//! Sky pass (TECHNIQUES L1 foundation): Preetham radiance and the sun disk
//! drawn where the G-buffer left depth at its cleared value (reverse-Z 0).
//! Shader: `passes/sky/draw.wgsl`; CPU twin: `passes/sky/preetham.rs`.

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureHandle};
use crate::passes::common::{DepthTest, draw_fullscreen, target};
use crate::passes::gbuffer::DEPTH_FORMAT;
use crate::passes::lighting::HDR_FORMAT;

pub struct SkyPass {
    program: Program,
    pipeline: wgpu::RenderPipeline,
}

impl SkyPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/sky/draw.wgsl")?;
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("sky", &targets);
        spec.depth_stencil = Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            // the triangle sits at depth 0: passes only where nothing was drawn
            depth_compare: Some(wgpu::CompareFunction::Equal),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self { program, pipeline })
    }

    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        view: &'a wgpu::Buffer,
        sky: &'a wgpu::Buffer,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let mut pass = graph.add_pass("sky");
        pass.read(depth, TextureAccess::DepthRead);
        let hdr = pass.write(hdr, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", view.as_entire_binding()),
                    ("sky", sky.as_entire_binding()),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let (target, depth) = (ctx.view(hdr), ctx.view(depth));
                draw_fullscreen(
                    ctx,
                    &self.pipeline,
                    &bg,
                    target,
                    wgpu::LoadOp::Load,
                    Some(DepthTest { view: depth }),
                );
            }
        });
        hdr
    }
}
