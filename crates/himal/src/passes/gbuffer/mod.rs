//! G-buffer pass (TECHNIQUES M1-M3): scene geometry into albedo, a
//! quaternion tangent frame (Rgb10a2), material parameters, motion, depth.
//! Layout per DESIGN.md; the packing lives in `shaders/tangent_frame.wgsl`
//! with its CPU twin in `math/quat_frame.rs`. Opaque objects draw first with
//! back-face culling and no discard (early-Z); vegetation follows with the
//! same shader specialised by `VEGETATION` (alpha test, sway, no culling).
//! Pipelines are permutations keyed by [`GBufferKey`] (E1's material-type
//! axis), created for the material types the scene uses.

use std::collections::HashMap;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{SceneGpu, vertex_layout};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::target;

pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgb10a2Unorm;
pub const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Handles of the G-buffer targets after the pass.
#[derive(Clone, Copy, Debug)]
pub struct GBuffer {
    pub albedo: TextureHandle,
    pub frame: TextureHandle,
    pub material: TextureHandle,
    pub motion: TextureHandle,
    pub depth: TextureHandle,
}

/// Material type: which shader and specialisation draws an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaterialType {
    /// Per-vertex materials (`gbuffer.wgsl`): the demo world.
    Vertex,
    /// Alpha-tested, swaying cards (`gbuffer.wgsl`, `VEGETATION`).
    Vegetation,
    /// glTF metal-rough materials with textures (`textured.wgsl`).
    Textured,
}

/// A G-buffer permutation: material type x usage (double-sided) x
/// environment (texture mip bias under temporal anti-aliasing, A2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GBufferKey {
    pub material: MaterialType,
    pub double_sided: bool,
    /// Textured materials sample with mip bias -0.5.
    pub mip_bias: bool,
}

/// Mip bias of textured materials under temporal anti-aliasing (A2).
pub const TEMPORAL_AA_MIP_BIAS: f32 = -0.5;

impl GBufferKey {
    pub const VERTEX: Self = Self {
        material: MaterialType::Vertex,
        double_sided: false,
        mip_bias: false,
    };
    /// Cards are seen from both sides.
    pub const VEGETATION: Self = Self {
        material: MaterialType::Vegetation,
        double_sided: true,
        mip_bias: false,
    };

    pub const fn textured(double_sided: bool, mip_bias: bool) -> Self {
        Self {
            material: MaterialType::Textured,
            double_sided,
            mip_bias,
        }
    }

    /// The permutations `scene` draws with (the per-vertex one always: it
    /// also clears the targets when nothing else draws); `mip_bias`: under
    /// temporal anti-aliasing.
    pub fn for_scene(scene: &SceneGpu, mip_bias: bool) -> Vec<GBufferKey> {
        let mut keys = vec![Self::VERTEX];
        if !scene.draws_vegetation.is_empty() {
            keys.push(Self::VEGETATION);
        }
        if let Some(m) = &scene.materials {
            for (_, material) in &scene.draws_textured {
                if let Some(binding) = m.materials.get(*material) {
                    let key = Self::textured(binding.double_sided, mip_bias);
                    if !keys.contains(&key) {
                        keys.push(key);
                    }
                }
            }
        }
        keys
    }
}

pub struct GBufferPass {
    program: Program,
    /// glTF materials (`textured.wgsl`).
    textured: Program,
    pipelines: HashMap<GBufferKey, wgpu::RenderPipeline>,
}

impl GBufferPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let mut pass = Self {
            program: Program::new(ctx, "passes/gbuffer/gbuffer.wgsl")?,
            textured: Program::new(ctx, "passes/gbuffer/textured.wgsl")?,
            pipelines: HashMap::new(),
        };
        pass.prepare(ctx, GBufferKey::VERTEX)?;
        Ok(pass)
    }

    /// Fetches the pipeline of permutation `key` (memory, disk or compile).
    pub fn prepare(&mut self, ctx: &GpuContext, key: GBufferKey) -> Result<(), GpuError> {
        if self.pipelines.contains_key(&key) {
            return Ok(());
        }
        let targets = [
            target(ALBEDO_FORMAT),
            target(FRAME_FORMAT),
            target(MATERIAL_FORMAT),
            target(MOTION_FORMAT),
        ];
        let buffers = [Some(vertex_layout())];
        let spec = |label, cull_mode, constants| RenderSpec {
            label,
            vertex_entry: "vs_main",
            fragment_entry: Some("fs_main"),
            vertex_buffers: &buffers,
            targets: &targets,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                // reverse-Z: nearer is larger
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            primitive: wgpu::PrimitiveState {
                cull_mode,
                ..Default::default()
            },
            constants,
        };
        let cull = if key.double_sided {
            None
        } else {
            Some(wgpu::Face::Back)
        };
        let pipeline = match key.material {
            MaterialType::Vertex => self
                .program
                .render_pipeline(ctx, &spec("gbuffer", cull, &[]))?,
            MaterialType::Vegetation => self.program.render_pipeline(
                ctx,
                &spec("gbuffer.vegetation", cull, &[("VEGETATION", 1.0)]),
            )?,
            MaterialType::Textured => {
                let bias = if key.mip_bias {
                    TEMPORAL_AA_MIP_BIAS
                } else {
                    0.0
                };
                self.textured.render_pipeline(
                    ctx,
                    &spec("gbuffer.textured", cull, &[("MIP_BIAS", f64::from(bias))]),
                )?
            }
        };
        self.pipelines.insert(key, pipeline);
        Ok(())
    }

    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        view: &'a wgpu::Buffer,
        scene: &'a SceneGpu,
        mip_bias: bool,
    ) -> GBuffer {
        let (w, h) = size;
        let albedo =
            graph.create_texture("gbuffer.albedo", TextureDesc::new_2d(w, h, ALBEDO_FORMAT));
        let frame = graph.create_texture("gbuffer.frame", TextureDesc::new_2d(w, h, FRAME_FORMAT));
        let material = graph.create_texture(
            "gbuffer.material",
            TextureDesc::new_2d(w, h, MATERIAL_FORMAT),
        );
        let motion = graph.create_texture("motion", TextureDesc::new_2d(w, h, MOTION_FORMAT));
        let depth = graph.create_texture("depth", TextureDesc::new_2d(w, h, DEPTH_FORMAT));
        let mut pass = graph.add_pass("gbuffer");
        let out = GBuffer {
            albedo: pass.write(albedo, TextureAccess::ColorAttachment),
            frame: pass.write(frame, TextureAccess::ColorAttachment),
            material: pass.write(material, TextureAccess::ColorAttachment),
            motion: pass.write(motion, TextureAccess::ColorAttachment),
            depth: pass.write(depth, TextureAccess::DepthAttachment),
        };
        let pipelines = &self.pipelines;
        pass.execute(move |ctx| {
            let Some(vertex) = pipelines.get(&GBufferKey::VERTEX) else {
                return Err(GpuError::Other("G-buffer pipeline not prepared".into()));
            };
            let materials = match &scene.materials {
                Some(m) => m.bind_groups(&self.textured, ctx.device)?,
                None => Vec::new(),
            };
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", view.as_entire_binding()),
                    ("objects", scene.objects.as_entire_binding()),
                ],
            )?;
            let colour = |v| {
                Some(wgpu::RenderPassColorAttachment {
                    view: v,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let attachments = [
                colour(ctx.view(out.albedo)),
                colour(ctx.view(out.frame)),
                colour(ctx.view(out.material)),
                colour(ctx.view(out.motion)),
            ];
            let depth_view = ctx.view(out.depth);
            let mut rp = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("gbuffer"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(vertex);
            rp.set_bind_group(0, &bind_group, &[]);
            scene.bind_geometry(&mut rp);
            SceneGpu::draw_list(&mut rp, &scene.draws_opaque);
            if let Some(m) = &scene.materials {
                for (draw, material) in &scene.draws_textured {
                    let Some((group, binding)) =
                        materials.get(*material).zip(m.materials.get(*material))
                    else {
                        continue;
                    };
                    let key = GBufferKey::textured(binding.double_sided, mip_bias);
                    let Some(pipeline) = pipelines.get(&key) else {
                        return Err(GpuError::Other(format!(
                            "G-buffer permutation {key:?} was not prepared"
                        )));
                    };
                    rp.set_pipeline(pipeline);
                    rp.set_bind_group(1, group, &[]);
                    SceneGpu::draw_list(&mut rp, std::slice::from_ref(draw));
                }
            }
            if !scene.draws_vegetation.is_empty() {
                let Some(pipeline) = pipelines.get(&GBufferKey::VEGETATION) else {
                    return Err(GpuError::Other(
                        "G-buffer vegetation permutation was not prepared".into(),
                    ));
                };
                rp.set_pipeline(pipeline);
                rp.set_bind_group(0, &bind_group, &[]);
                SceneGpu::draw_list(&mut rp, &scene.draws_vegetation);
            }
            Ok(())
        });
        out
    }
}
