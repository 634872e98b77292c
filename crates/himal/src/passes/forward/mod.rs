//! Forward passes after lighting and sky (issue #8, docs/gltf.md):
//! `forward.emissive` adds the emission of opaque and mask glTF materials
//! (an additive draw with depth test Equal against the G-buffer depth), and
//! `forward.blend` draws alpha BLEND materials back to front (per object,
//! by the distance of its bounds' centre) with premultiplied alpha into the
//! HDR target, lit by the unshadowed sun, the sky SH and the filtered
//! environment cube. Shader `forward.wgsl`, shading in `shaders/forward.wgsl`,
//! CPU twin [`reference::forward_shade_premultiplied`].

pub mod reference;

use std::collections::HashMap;

use glam::Vec3;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, SceneGpu, vertex_layout};
use crate::graph::{FrameGraph, TextureAccess, TextureHandle};
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::DEPTH_FORMAT;
use crate::passes::lighting::HDR_FORMAT;

/// A forward permutation: which fragment entry and whether back faces are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ForwardKey {
    pub emissive: bool,
    pub double_sided: bool,
}

/// What the forward passes read that outlives the frame.
#[derive(Clone, Copy)]
pub struct ForwardInputs<'a> {
    pub view: &'a wgpu::Buffer,
    pub lighting: &'a wgpu::Buffer,
    pub scene: &'a SceneGpu,
    /// Filtered cube, DFG table and sampler (L4); `env` orders the read
    /// after this frame's filtering.
    pub envmap: &'a EnvMapPass,
    pub env: TextureHandle,
}

/// Indices of `centres` ordered far to near from `camera` (ties keep their order).
pub fn back_to_front(centres: &[Vec3], camera: Vec3) -> Vec<usize> {
    let mut order: Vec<usize> = (0..centres.len()).collect();
    order.sort_by(|&a, &b| {
        let (da, db) = (
            centres[a].distance_squared(camera),
            centres[b].distance_squared(camera),
        );
        db.total_cmp(&da)
    });
    order
}

pub struct ForwardPass {
    program: Program,
    pipelines: HashMap<ForwardKey, wgpu::RenderPipeline>,
    /// `SceneGpu::draws_blend` indices, far to near (see [`ForwardPass::sort`]).
    order: Vec<usize>,
}

impl ForwardPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/forward/forward.wgsl")?,
            pipelines: HashMap::new(),
            order: Vec::new(),
        })
    }

    /// Fetches the pipelines `scene`'s emissive and blend draws need.
    pub fn prepare(&mut self, ctx: &GpuContext, scene: &SceneGpu) -> Result<(), GpuError> {
        let Some(m) = &scene.materials else {
            return Ok(());
        };
        let emissive = scene.draws_emissive.iter().map(|(_, mat)| (true, *mat));
        let blend = scene.draws_blend.iter().map(|(_, mat, _)| (false, *mat));
        for (is_emissive, mat) in emissive.chain(blend) {
            let Some(binding) = m.materials.get(mat) else {
                continue;
            };
            let key = ForwardKey {
                emissive: is_emissive,
                double_sided: binding.double_sided,
            };
            if !self.pipelines.contains_key(&key) {
                let pipeline = self.pipeline(ctx, key)?;
                self.pipelines.insert(key, pipeline);
            }
        }
        Ok(())
    }

    fn pipeline(
        &self,
        ctx: &GpuContext,
        key: ForwardKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        use wgpu::{BlendComponent as C, BlendFactor as F, BlendOperation as Op};
        let (blend, compare, entry, label) = if key.emissive {
            // Add colour, keep the HDR alpha.
            let add = C {
                src_factor: F::One,
                dst_factor: F::One,
                operation: Op::Add,
            };
            let keep = C {
                src_factor: F::Zero,
                dst_factor: F::One,
                operation: Op::Add,
            };
            let state = wgpu::BlendState {
                color: add,
                alpha: keep,
            };
            (
                state,
                wgpu::CompareFunction::Equal,
                "fs_emissive",
                "forward.emissive",
            )
        } else {
            let state = wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING;
            // reverse-Z: nearer is larger
            (
                state,
                wgpu::CompareFunction::Greater,
                "fs_blend",
                "forward.blend",
            )
        };
        let targets = [Some(wgpu::ColorTargetState {
            format: HDR_FORMAT,
            blend: Some(blend),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let buffers = [Some(vertex_layout())];
        let spec = RenderSpec {
            label,
            vertex_entry: "vs_main",
            fragment_entry: Some(entry),
            vertex_buffers: &buffers,
            targets: &targets,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            primitive: wgpu::PrimitiveState {
                cull_mode: if key.double_sided {
                    None
                } else {
                    Some(wgpu::Face::Back)
                },
                ..Default::default()
            },
            constants: &[],
        };
        self.program.render_pipeline(ctx, &spec)
    }

    /// Orders the blend draws far to near from `camera` (call before the frame).
    pub fn sort(&mut self, scene: &SceneGpu, camera: Vec3) {
        let centres: Vec<Vec3> = scene.draws_blend.iter().map(|(_, _, c)| *c).collect();
        self.order = back_to_front(&centres, camera);
    }

    /// Adds `forward.emissive` and `forward.blend` (each only when the scene
    /// has such draws) on top of `hdr`; returns the new HDR version.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        inputs: ForwardInputs<'a>,
    ) -> TextureHandle {
        let scene = inputs.scene;
        let mut hdr = hdr;
        if !scene.draws_emissive.is_empty() {
            let draws: Vec<(Draw, usize)> = scene.draws_emissive.clone();
            hdr = self.add_pass(graph, "forward.emissive", true, hdr, depth, draws, inputs);
        }
        if !scene.draws_blend.is_empty() {
            let mut draws: Vec<(Draw, usize)> = self
                .order
                .iter()
                .filter_map(|&i| scene.draws_blend.get(i))
                .map(|(d, m, _)| (d.clone(), *m))
                .collect();
            if draws.len() != scene.draws_blend.len() {
                // Not sorted for this scene: draw in scene order.
                draws = scene
                    .draws_blend
                    .iter()
                    .map(|(d, m, _)| (d.clone(), *m))
                    .collect();
            }
            hdr = self.add_pass(graph, "forward.blend", false, hdr, depth, draws, inputs);
        }
        hdr
    }

    #[allow(clippy::too_many_arguments)]
    fn add_pass<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        id: &str,
        emissive: bool,
        hdr: TextureHandle,
        depth: TextureHandle,
        draws: Vec<(Draw, usize)>,
        inputs: ForwardInputs<'a>,
    ) -> TextureHandle {
        let mut pass = graph.add_pass(id);
        pass.read(depth, TextureAccess::DepthRead);
        if !emissive {
            pass.read(inputs.env, TextureAccess::Sampled);
        }
        let hdr = pass.write(hdr, TextureAccess::ColorAttachment);
        let pipelines = &self.pipelines;
        pass.execute(move |ctx| {
            let scene = inputs.scene;
            let Some(m) = &scene.materials else {
                return Ok(());
            };
            let groups = m.bind_groups(&self.program, ctx.device)?;
            let frame_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", inputs.view.as_entire_binding()),
                    ("objects", scene.objects.as_entire_binding()),
                    ("lighting", inputs.lighting.as_entire_binding()),
                    (
                        "env_specular",
                        wgpu::BindingResource::TextureView(&inputs.envmap.filtered_cube),
                    ),
                    (
                        "env_sampler",
                        wgpu::BindingResource::Sampler(&inputs.envmap.sampler),
                    ),
                    (
                        "dfg_lut",
                        wgpu::BindingResource::TextureView(&inputs.envmap.dfg_view),
                    ),
                ],
            )?;
            let label = ctx.pass_id().to_string();
            let (target, depth_view) = (ctx.view(hdr), ctx.view(depth));
            let mut rp = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: depth_view,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_bind_group(0, &frame_group, &[]);
            scene.bind_geometry(&mut rp);
            for (draw, material) in &draws {
                let Some((group, binding)) = groups.get(*material).zip(m.materials.get(*material))
                else {
                    continue;
                };
                let key = ForwardKey {
                    emissive,
                    double_sided: binding.double_sided,
                };
                let Some(pipeline) = pipelines.get(&key) else {
                    return Err(GpuError::Other(format!(
                        "forward permutation {key:?} was not prepared"
                    )));
                };
                rp.set_pipeline(pipeline);
                rp.set_bind_group(1, group, &[]);
                SceneGpu::draw_list(&mut rp, std::slice::from_ref(draw));
            }
            Ok(())
        });
        hdr
    }
}
