//! V4 in the frame (issue #18; Far Cry 4's vegetation talk, `seeds/000_...`):
//! the trees' baked occlusion volumes (`scene/tree/ao.rs`) applied as a
//! deferred decal, `vegetation.ao`: one instanced draw of every tree's
//! volume box after the G-buffer (and the terrain), which multiplies the
//! G-buffer albedo's alpha, the occlusion lighting applies to the sky and
//! ambient light, by the volume's sample at each pixel's position. The
//! trees (every LOD and the impostor) and the ground or anything else
//! inside a box darken alike. The volumes, the box list and the atlas are
//! uploaded once with the scene (`gpu_scene/tree_ao.rs`); per frame the
//! CPU records one draw. CPU twin: [`reference`]. Method and figures:
//! `docs/techniques/V4.md` "In the frame".

pub mod reference;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::SceneGpu;
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{clear_target, is_display_format, target};

/// The `--view tree-ao` factor target (white where no box writes).
pub const FACTOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// The decal and its view.
pub struct TreeAoPass {
    program: Program,
    view_program: Program,
    sampler: wgpu::Sampler,
    /// Whether this frame applies the volumes (`FrameSettings::tree_ao`
    /// with vegetation drawn; set by `frame::plan`).
    pub on: bool,
}

/// dst * src on every channel the target writes.
const MULTIPLY: wgpu::BlendComponent = wgpu::BlendComponent {
    src_factor: wgpu::BlendFactor::Zero,
    dst_factor: wgpu::BlendFactor::Src,
    operation: wgpu::BlendOperation::Add,
};

impl TreeAoPass {
    /// Compiles the decal and the view; pipelines are made per target format.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("tree_ao.sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        Ok(Self {
            program: Program::new(ctx, "passes/tree_ao/decal.wgsl")?,
            view_program: Program::new(ctx, "passes/tree_ao/view.wgsl")?,
            sampler,
            on: true,
        })
    }

    /// The decal's pipeline into `format`: the G-buffer albedo (its alpha
    /// alone written) or the [`FACTOR_FORMAT`] view target.
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let write_mask = match format {
            FACTOR_FORMAT => wgpu::ColorWrites::RED,
            _ => wgpu::ColorWrites::ALPHA,
        };
        let targets = [Some(wgpu::ColorTargetState {
            format,
            blend: Some(wgpu::BlendState {
                color: MULTIPLY,
                alpha: MULTIPLY,
            }),
            write_mask,
        })];
        let mut spec = RenderSpec::fullscreen("vegetation.ao", &targets);
        // Back faces only: one fragment per pixel a box covers.
        spec.primitive.cull_mode = Some(wgpu::Face::Front);
        // Reverse-Z: a back face at or behind the pixel's surface (the
        // surface may lie inside the box); surfaces beyond it are skipped
        // before the fragment runs (read-only depth).
        spec.depth_stencil = Some(wgpu::DepthStencilState {
            format: crate::passes::gbuffer::DEPTH_FORMAT,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: Default::default(),
            bias: Default::default(),
        });
        self.program.render_pipeline(ctx, &spec)
    }

    /// Multiplies `target` (the G-buffer albedo, or a factor target) by
    /// every tree's volume at the pixels `depth` places inside its box;
    /// `target` unchanged when no tree has a volume.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        g: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        target: TextureHandle,
        depth: TextureHandle,
    ) -> TextureHandle {
        self.decal("vegetation.ao", ctx, g, scene, target, depth)
    }

    fn decal<'a>(
        &'a self,
        id: &str,
        ctx: &GpuContext,
        g: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        target: TextureHandle,
        depth: TextureHandle,
    ) -> TextureHandle {
        let volumes = &scene.tree_ao;
        if volumes.count == 0 {
            return target;
        }
        let pipeline = match g.texture_desc(target) {
            Some(d) => self.pipeline(ctx, d.format),
            None => Err(GpuError::Other(format!(
                "{id}: the target is not in this graph"
            ))),
        };
        let count = volumes.count;
        let written = g
            .raster(id, &self.program)
            .pipeline(pipeline)
            .uniform("objects", &scene.objects)
            .uniform("trees", &volumes.trees)
            .uniform("volumes", &volumes.volumes)
            .external("atlas", &volumes.atlas)
            .sampler("atlas_sampler", &self.sampler)
            .read("depth", depth)
            .color(target, wgpu::LoadOp::Load)
            .depth_test(depth)
            .record(move |_, rp| {
                rp.draw(0..36, 0..count);
                Ok(())
            });
        written.colors[0]
    }

    /// `--view tree-ao`: the factor alone (a white target the decal
    /// multiplies, when the frame applies the volumes), shown in grey.
    pub fn add_view<'a>(
        &'a self,
        ctx: &GpuContext,
        g: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        depth: TextureHandle,
        output: TextureHandle,
    ) -> TextureHandle {
        let size = g
            .texture_desc(depth)
            .map_or((1, 1), |d| (d.width, d.height));
        let factor = g.create_texture(
            "vegetation.ao.factor",
            TextureDesc::new_2d(size.0, size.1, FACTOR_FORMAT),
        );
        let mut pass = g.add_pass("vegetation.ao.clear");
        let factor = pass.write(factor, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| clear_target(ctx, factor, wgpu::Color::WHITE));
        let factor = match self.on {
            true => self.decal("vegetation.ao.factor", ctx, g, scene, factor, depth),
            false => factor,
        };
        let pipeline = match g.texture_desc(output) {
            Some(d) => self.view_pipeline(ctx, d.format),
            None => Err(GpuError::Other(
                "vegetation.ao.view: the output is not in this graph".into(),
            )),
        };
        g.fullscreen("vegetation.ao.view", &self.view_program)
            .pipeline(pipeline)
            .read("factor", factor)
            .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }

    /// The view's pipeline into `format` (float formats get the raw factor).
    pub fn view_pipeline(
        &self,
        ctx: &GpuContext,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let display = is_display_format(format);
        let targets = [target(format)];
        let constants = [("DISPLAY", if display { 1.0 } else { 0.0 })];
        let mut spec = RenderSpec::fullscreen("vegetation.ao.view", &targets);
        spec.constants = &constants;
        self.view_program.render_pipeline(ctx, &spec)
    }
}
