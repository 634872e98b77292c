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
    /// An HDR environment drawn instead of the Preetham sky (issue #8):
    /// its pipeline (`ENVIRONMENT`, `ENV_ROTATION`), image view and sampler.
    environment: Option<(wgpu::RenderPipeline, wgpu::TextureView, wgpu::Sampler)>,
    /// 1x1 image bound while the Preetham sky is drawn.
    placeholder: (wgpu::TextureView, wgpu::Sampler),
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
        let placeholder = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("sky.environment.off"),
            size: wgpu::Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        Ok(Self {
            program,
            pipeline,
            environment: None,
            placeholder: (
                placeholder.create_view(&Default::default()),
                ctx.device.create_sampler(&Default::default()),
            ),
        })
    }

    /// Draws `image` (equirectangular, turned by `rotation` radians about +Y)
    /// as the background instead of the Preetham sky.
    pub fn set_environment(
        &mut self,
        ctx: &GpuContext,
        image: &wgpu::TextureView,
        sampler: &wgpu::Sampler,
        rotation: f32,
    ) -> Result<(), GpuError> {
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("sky.environment", &targets);
        spec.depth_stencil = Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Equal),
            stencil: Default::default(),
            bias: Default::default(),
        });
        let constants = [("ENVIRONMENT", 1.0), ("ENV_ROTATION", f64::from(rotation))];
        spec.constants = &constants;
        let pipeline = self.program.render_pipeline(ctx, &spec)?;
        self.environment = Some((pipeline, image.clone(), sampler.clone()));
        Ok(())
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
            let (pipeline, image, sampler) = match &self.environment {
                Some((p, i, s)) => (p, i, s),
                None => (&self.pipeline, &self.placeholder.0, &self.placeholder.1),
            };
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", view.as_entire_binding()),
                    ("sky", sky.as_entire_binding()),
                    ("environment", wgpu::BindingResource::TextureView(image)),
                    (
                        "environment_sampler",
                        wgpu::BindingResource::Sampler(sampler),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let (target, depth) = (ctx.view(hdr), ctx.view(depth));
                draw_fullscreen(
                    ctx,
                    pipeline,
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
