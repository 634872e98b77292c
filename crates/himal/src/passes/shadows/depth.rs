//! Depth rendering of one sun view (cascade, static map, hero map):
//! pipelines per depth format and the recording of a draw list.

use std::sync::Arc;

use glam::Mat4;

use super::casters::DrawLists;
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::textures::MaterialGroups;
use crate::gpu_scene::{Draw, SceneGpu, VERTEX_ATTRIBUTES, material_runs, vertex_layout};
use crate::passes::cull::{Culled, List, SHADOW};

/// Position, uv and uv1 of [`crate::scene::Vertex`]: what an alpha-tested
/// glTF caster samples its base colour with.
const MASKED_ATTRIBUTES: [wgpu::VertexAttribute; 3] = [
    VERTEX_ATTRIBUTES[0],
    VERTEX_ATTRIBUTES[3],
    VERTEX_ATTRIBUTES[6],
];

/// `depth_masked.wgsl` (glTF MASK and BLEND casters, alpha-tested) and its
/// material bind groups, shared by the pipelines of every depth format.
pub struct MaskedProgram {
    program: Program,
    groups: MaterialGroups,
}

impl MaskedProgram {
    /// Compiles `depth_masked.wgsl`.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/shadows/depth_masked.wgsl")?,
            groups: MaterialGroups::default(),
        })
    }
}

/// Position and uv of [`crate::scene::Vertex`] (locations as in gbuffer.wgsl).
const VEGETATION_ATTRIBUTES: [wgpu::VertexAttribute; 4] = [
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 0,
        shader_location: 0,
    },
    // V3 impostor vertices: tangent.w = R, uv1.x = -1 - layer.
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x4,
        offset: 24,
        shader_location: 2,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x2,
        offset: 40,
        shader_location: 3,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x2,
        offset: 80,
        shader_location: 6,
    },
];

/// Opaque casters: position, and uv1 (V2: a trunk's bone and weight).
const OPAQUE_ATTRIBUTES: [wgpu::VertexAttribute; 2] =
    [VEGETATION_ATTRIBUTES[0], VEGETATION_ATTRIBUTES[3]];

/// Twin of `ShadowView` in `depth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowViewGpu {
    /// World to the light's clip space (a sun cascade, static or hero map, or a local-light projector; column-major).
    pub light_view_proj: [[f32; 4]; 4],
    /// x animation time (s)
    pub time: [f32; 4],
}

impl ShadowViewGpu {
    /// The uniform for one light view at animation time `time_s` (seconds, for swaying vegetation).
    pub fn new(light_view_proj: Mat4, time_s: f32) -> Self {
        Self {
            light_view_proj: light_view_proj.to_cols_array_2d(),
            time: [time_s, 0.0, 0.0, 0.0],
        }
    }
}

/// Which casters a depth pass draws: all, or the opaque ones and the
/// vegetation in separate passes (`vegetation.shadow*`, timed apart).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Every caster.
    All,
    /// Everything but the vegetation.
    Opaque,
    /// The vegetation alone (alpha-tested cards, impostors).
    Vegetation,
}

/// Opaque and vegetation pipelines writing one depth format.
pub struct DepthPipelines {
    /// Opaque casters: position only, no fragment stage, both faces.
    pub opaque: wgpu::RenderPipeline,
    /// Alpha-tested, swaying vegetation: blades cast shadows, not cards.
    pub vegetation: wgpu::RenderPipeline,
    /// Writes the far plane over the viewport (one tile of a map).
    pub clear: wgpu::RenderPipeline,
    /// glTF MASK and BLEND casters (`depth_masked.wgsl`), when the scene has any.
    pub masked: Option<(wgpu::RenderPipeline, Arc<MaskedProgram>)>,
}

impl DepthPipelines {
    /// The pipelines of `program` writing depth of `format` (32-bit
    /// cascades or the 16-bit static map), with `masked`'s for alpha-tested glTF casters.
    pub fn new(
        ctx: &GpuContext,
        program: &Program,
        masked: Option<&Arc<MaskedProgram>>,
        format: wgpu::TextureFormat,
    ) -> Result<Self, GpuError> {
        let mut layout = vertex_layout();
        layout.attributes = &OPAQUE_ATTRIBUTES;
        let mut veg_layout = vertex_layout();
        veg_layout.attributes = &VEGETATION_ATTRIBUTES;
        let depth_stencil = caster_depth(format);
        // Both faces cast: the terrain is single-sided.
        let primitive = wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        };
        let vegetation = program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "shadows.depth.vegetation",
                vertex_entry: "vs_vegetation",
                fragment_entry: Some("fs_vegetation"),
                vertex_buffers: &[Some(veg_layout)],
                targets: &[],
                depth_stencil: Some(depth_stencil.clone()),
                primitive,
                constants: &[],
            },
        )?;
        let clear = program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "shadows.depth.clear",
                vertex_entry: "vs_clear",
                fragment_entry: None,
                vertex_buffers: &[],
                targets: &[],
                depth_stencil: Some(wgpu::DepthStencilState {
                    format,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Always),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                primitive: Default::default(),
                constants: &[],
            },
        )?;
        let opaque = program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "shadows.depth",
                vertex_entry: "vs_main",
                fragment_entry: None,
                vertex_buffers: &[Some(layout)],
                targets: &[],
                depth_stencil: Some(depth_stencil),
                primitive,
                constants: &[],
            },
        )?;
        let masked = match masked {
            Some(m) => {
                let layout = wgpu::VertexBufferLayout {
                    attributes: &MASKED_ATTRIBUTES,
                    ..vertex_layout()
                };
                let pipeline = m.program.render_pipeline(
                    ctx,
                    &RenderSpec {
                        label: "shadows.depth.masked",
                        vertex_entry: "vs_masked",
                        fragment_entry: Some("fs_masked"),
                        vertex_buffers: &[Some(layout)],
                        targets: &[],
                        depth_stencil: Some(caster_depth(format)),
                        primitive,
                        constants: &[],
                    },
                )?;
                Some((pipeline, m.clone()))
            }
            None => None,
        };
        Ok(Self {
            opaque,
            vegetation,
            clear,
            masked,
        })
    }

    /// Draws `lists` (the pass's view group is set).
    pub fn draw(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        scene: &SceneGpu,
        lists: &DrawLists,
        device: (&wgpu::Device, bool),
    ) -> Result<(), GpuError> {
        scene.bind_geometry(rp);
        self.draw_pipelines(rp, scene, lists, device, Part::All)
    }

    /// Draws `part` of `lists` and, with `culled` (and the pass recording
    /// it), of the GPU-culled view the lists name (V6).
    pub fn draw_culled(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        scene: &SceneGpu,
        lists: &DrawLists,
        culled: Option<(&Culled<'_>, &crate::graph::PassContext<'_>)>,
        device: (&wgpu::Device, bool),
        part: Part,
    ) -> Result<(), GpuError> {
        scene.bind_geometry(rp);
        self.draw_pipelines(rp, scene, lists, device, part)?;
        let (opaque, vegetation) = (part != Part::Vegetation, part != Part::Opaque);
        if let (Some((view, _)), Some((c, ctx))) = (lists.gpu_view, culled) {
            if opaque {
                rp.set_pipeline(&self.opaque);
                c.draw(rp, ctx, view, List::Opaque, SHADOW);
            }
            if vegetation {
                rp.set_pipeline(&self.vegetation);
                c.draw(rp, ctx, view, List::Vegetation, SHADOW);
            }
        }
        if let (Some(view), Some((c, ctx))) = (lists.pool_view, culled) {
            if opaque {
                rp.set_pipeline(&self.opaque);
                c.draw_pool(rp, ctx, view, List::Opaque, SHADOW);
            }
            if vegetation && c.has_pool(List::Vegetation) {
                rp.set_pipeline(&self.vegetation);
                c.draw_pool(rp, ctx, view, List::Vegetation, SHADOW);
            }
        }
        Ok(())
    }

    /// Clears texel rectangle `rect` (x, y, w, h) to the far plane and
    /// leaves it as the viewport and scissor of what follows.
    pub fn clear_rect(&self, rp: &mut wgpu::RenderPass<'_>, rect: [u32; 4]) {
        set_rect(rp, rect);
        rp.set_pipeline(&self.clear);
        rp.draw(0..3, 0..1);
    }

    /// Draws `lists` with the geometry already bound: the opaque list's
    /// alpha-tested glTF objects ([`SceneGpu::alpha_caster`]) last, a
    /// material bind group per run. `(device, alpha_test)`: without
    /// `alpha_test` they draw as opaque ([`super::ShadowSettings::alpha_test`]).
    pub fn draw_pipelines(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        scene: &SceneGpu,
        lists: &DrawLists,
        (device, alpha_test): (&wgpu::Device, bool),
        part: Part,
    ) -> Result<(), GpuError> {
        if part == Part::Vegetation {
            if !lists.vegetation.is_empty() {
                rp.set_pipeline(&self.vegetation);
                scene.draw_list(rp, &lists.vegetation);
            }
            return Ok(());
        }
        let on = alpha_test && self.masked.is_some();
        let alpha = |d: &Draw| scene.alpha_caster(d.object).filter(|_| on);
        let any_alpha = lists.opaque.iter().any(|d| alpha(d).is_some());
        if any_alpha {
            let plain: Vec<Draw> = (lists.opaque.iter())
                .filter(|d| alpha(d).is_none())
                .cloned()
                .collect();
            if !plain.is_empty() {
                rp.set_pipeline(&self.opaque);
                scene.draw_list(rp, &plain);
            }
        } else if !lists.opaque.is_empty() {
            rp.set_pipeline(&self.opaque);
            scene.draw_list(rp, &lists.opaque);
        }
        if part == Part::All && !lists.vegetation.is_empty() {
            rp.set_pipeline(&self.vegetation);
            scene.draw_list(rp, &lists.vegetation);
        }
        if let (true, Some((pipeline, m)), Some(materials)) =
            (any_alpha, &self.masked, &scene.materials)
        {
            let masked: Vec<(Draw, usize)> = (lists.opaque.iter())
                .filter_map(|d| alpha(d).map(|material| (d.clone(), material)))
                .collect();
            let groups = m.groups.get(scene.id, materials, &m.program, device)?;
            rp.set_pipeline(pipeline);
            for (material, draws) in material_runs(&masked) {
                if let Some(group) = groups.get(material) {
                    rp.set_bind_group(1, group, &[]);
                    scene.draw_list(rp, &draws);
                }
            }
        }
        Ok(())
    }
}

/// Depth state of every sun-view caster (scene objects, terrain) in
/// `format`: standard depth, slope-scaled bias against acne on surfaces
/// grazing the sun.
pub fn caster_depth(format: wgpu::TextureFormat) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format,
        depth_write_enabled: Some(true),
        depth_compare: Some(wgpu::CompareFunction::LessEqual),
        stencil: Default::default(),
        bias: wgpu::DepthBiasState {
            constant: 0,
            slope_scale: 1.5,
            clamp: 0.0,
        },
    }
}

/// Viewport and scissor on texel rectangle `rect` (x, y, w, h).
pub fn set_rect(rp: &mut wgpu::RenderPass<'_>, rect: [u32; 4]) {
    let [x, y, w, h] = rect;
    rp.set_viewport(x as f32, y as f32, w as f32, h as f32, 0.0, 1.0);
    rp.set_scissor_rect(x, y, w, h);
}

/// A uniform buffer for one sun view.
pub fn view_buffer(ctx: &GpuContext, label: &str) -> wgpu::Buffer {
    uniform_buffer(ctx, label, &ShadowViewGpu::new(Mat4::IDENTITY, 0.0))
}
