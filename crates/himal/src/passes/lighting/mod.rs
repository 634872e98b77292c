//! Deferred lighting (TECHNIQUES M1, M2, L1 foundation): sun with the
//! anisotropic GGX BRDF, SH9 sky irradiance, split-sum ambient specular,
//! aerial perspective. CPU twin: [`reference::shade`].

pub mod reference;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{draw_fullscreen, target};
use crate::passes::gbuffer::GBuffer;

pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Uniform buffers the lighting pass reads (owned by the renderer).
pub struct LightingInputs<'a> {
    pub view: &'a wgpu::Buffer,
    pub lighting: &'a wgpu::Buffer,
    pub sky: &'a wgpu::Buffer,
    /// Shadow mask of `shadows.mask`, R = sun visibility (1x1 white when off).
    pub shadow_mask: TextureHandle,
    /// Screen-space AO (`.x`); a 1x1 white placeholder when AO is off.
    pub ao: TextureHandle,
    /// Point and spot lights (`LocalLights` in `shaders/shadow.wgsl`, S3).
    pub lights: &'a wgpu::Buffer,
}

pub struct LightingPass {
    program: Program,
    pipeline: wgpu::RenderPipeline,
}

impl LightingPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/lighting/deferred.wgsl")?;
        let targets = [target(HDR_FORMAT)];
        let pipeline =
            program.render_pipeline(ctx, &RenderSpec::fullscreen("lighting.deferred", &targets))?;
        Ok(Self { program, pipeline })
    }

    /// Shades the G-buffer into a new HDR target (sky pixels stay black).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        inputs: LightingInputs<'a>,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let hdr = graph.create_texture("hdr", TextureDesc::new_2d(size.0, size.1, HDR_FORMAT));
        let mut pass = graph.add_pass("lighting.deferred");
        for t in [
            gbuffer.albedo,
            gbuffer.frame,
            gbuffer.material,
            gbuffer.depth,
            inputs.shadow_mask,
            inputs.ao,
        ] {
            pass.read(t, TextureAccess::Sampled);
        }
        let hdr = pass.write(hdr, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", inputs.view.as_entire_binding()),
                    ("lighting", inputs.lighting.as_entire_binding()),
                    ("sky", inputs.sky.as_entire_binding()),
                    (
                        "gbuffer_albedo",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.albedo)),
                    ),
                    (
                        "gbuffer_frame",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.frame)),
                    ),
                    (
                        "gbuffer_material",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.material)),
                    ),
                    (
                        "depth",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.depth)),
                    ),
                    (
                        "shadow_mask",
                        wgpu::BindingResource::TextureView(ctx.view(inputs.shadow_mask)),
                    ),
                    (
                        "ao",
                        wgpu::BindingResource::TextureView(ctx.view(inputs.ao)),
                    ),
                    ("lights", inputs.lights.as_entire_binding()),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let target = ctx.view(hdr);
                draw_fullscreen(
                    ctx,
                    &self.pipeline,
                    &bg,
                    target,
                    wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    None,
                );
            }
        });
        hdr
    }
}
