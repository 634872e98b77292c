//! `gbuffer.wet`: a wetness example of roughness changed in the G-buffer
//! after texturing (up-facing surfaces get a smooth water film and darken),
//! and E3's screen-space normal-variance filter that keeps the new, glossier
//! surfaces from aliasing (Ryse). Runs only with `--wetness` above 0; writes
//! new albedo and material targets that replace the G-buffer's for every
//! later reader. CPU twin: [`reference::wet_texel`]. Math and measurements:
//! `docs/techniques/E3.md`, "Roughness changed in the G-buffer".

pub mod reference;

use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureDesc};
use crate::passes::common::target;
use crate::passes::gbuffer::{ALBEDO_FORMAT, GBuffer, MATERIAL_FORMAT};

/// The wetness pass: its program, the uniform of its amount, and this
/// frame's settings (set by the renderer before the frame is built).
pub struct WetPass {
    program: Program,
    params: wgpu::Buffer,
    /// Wetness in [0, 1] (`FrameSettings::wetness`); 0: the frame skips the pass.
    pub amount: f32,
    /// E3's screen-space filter (`FrameSettings::specular_aa`).
    pub specular_aa: bool,
}

impl WetPass {
    /// Compiles `passes/wet/wet.wgsl` (both permutations on first use).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/wet/wet.wgsl")?,
            params: uniform_buffer(ctx, "gbuffer.wet.params", &[0.0f32; 4]),
            amount: 0.0,
            specular_aa: true,
        })
    }

    /// The pipeline; `specular_aa`: E3's screen-space filter (`SPECULAR_AA`).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        specular_aa: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(ALBEDO_FORMAT), target(MATERIAL_FORMAT)];
        let mut spec = RenderSpec::fullscreen("gbuffer.wet", &targets);
        let constants = [("SPECULAR_AA", if specular_aa { 1.0 } else { 0.0 })];
        spec.constants = &constants;
        self.program.render_pipeline(ctx, &spec)
    }

    /// Wets `gbuffer` by [`Self::amount`]: new albedo and material targets,
    /// the rest unchanged.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
    ) -> GBuffer {
        let (amount, specular_aa) = (self.amount, self.specular_aa);
        ctx.queue.write_buffer(
            &self.params,
            0,
            bytemuck::cast_slice(&[amount.clamp(0.0, 1.0), 0.0, 0.0, 0.0]),
        );
        let albedo = graph.create_texture(
            "gbuffer.albedo_wet",
            TextureDesc::new_2d(size.0, size.1, ALBEDO_FORMAT),
        );
        let material = graph.create_texture(
            "gbuffer.material_wet",
            TextureDesc::new_2d(size.0, size.1, MATERIAL_FORMAT),
        );
        let written = graph
            .fullscreen("gbuffer.wet", &self.program)
            .pipeline(self.pipeline(ctx, specular_aa))
            .read("gbuffer_albedo", gbuffer.albedo)
            .read("gbuffer_frame", gbuffer.frame)
            .read("gbuffer_material", gbuffer.material)
            .read("depth", gbuffer.depth)
            .uniform("wet", &self.params)
            .color(albedo, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .color(material, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw_targets();
        GBuffer {
            albedo: written.colors[0],
            material: written.colors[1],
            ..gbuffer
        }
    }
}
