//! Forward passes after lighting and sky (issue #8, docs/gltf.md):
//! `forward.emissive` adds the emission of opaque and mask glTF materials
//! (an additive draw with depth test Equal against the G-buffer depth), and
//! `forward.blend` draws alpha BLEND materials back to front (per object,
//! by the distance of its bounds' centre) with premultiplied alpha into the
//! HDR target, lit by the unshadowed sun, the sky SH and the filtered
//! environment cube. Shader `forward.wgsl`, shading in `shaders/forward.wgsl`,
//! CPU twin [`reference::forward_shade_premultiplied`].

pub mod reference;

use glam::Vec3;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, SceneGpu, vertex_layout};
use crate::graph::{FrameGraph, TextureHandle};
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::DEPTH_FORMAT;
use crate::passes::lighting::HDR_FORMAT;

/// A forward permutation: which fragment entry and whether back faces are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ForwardKey {
    pub emissive: bool,
    pub double_sided: bool,
}

impl ForwardKey {
    /// The permutations `scene`'s emissive and blend draws use.
    pub fn for_scene(scene: &SceneGpu) -> Vec<ForwardKey> {
        let mut keys = Vec::new();
        let Some(m) = &scene.materials else {
            return keys;
        };
        let emissive = scene.draws_emissive.iter().map(|(_, mat)| (true, *mat));
        let blend = scene.draws_blend.iter().map(|(_, mat, _)| (false, *mat));
        for (emissive, mat) in emissive.chain(blend) {
            if let Some(binding) = m.materials.get(mat) {
                let key = ForwardKey {
                    emissive,
                    double_sided: binding.double_sided,
                };
                if !keys.contains(&key) {
                    keys.push(key);
                }
            }
        }
        keys
    }
}

/// What the forward passes read that outlives the frame.
#[derive(Clone, Copy)]
pub struct ForwardInputs<'a> {
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
    /// `SceneGpu::draws_blend` indices, far to near (see [`ForwardPass::sort`]).
    order: Vec<usize>,
    /// The materials' bind groups, made once per scene.
    pub material_groups: crate::gpu_scene::textures::MaterialGroups,
}

impl ForwardPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self {
            program: Program::new(ctx, "passes/forward/forward.wgsl")?,
            order: Vec::new(),
            material_groups: Default::default(),
        })
    }

    /// The pipeline of permutation `key`, through the shared cache.
    pub fn pipeline(
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
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        inputs: ForwardInputs<'a>,
    ) -> TextureHandle {
        let scene = inputs.scene;
        let mut hdr = hdr;
        if !scene.draws_emissive.is_empty() {
            let draws: Vec<(Draw, usize)> = scene.draws_emissive.clone();
            hdr = self.add_pass(
                ctx,
                graph,
                "forward.emissive",
                true,
                hdr,
                depth,
                draws,
                inputs,
            );
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
            hdr = self.add_pass(
                ctx,
                graph,
                "forward.blend",
                false,
                hdr,
                depth,
                draws,
                inputs,
            );
        }
        hdr
    }

    /// One forward node over `draws` (view and lighting are frame constants).
    #[allow(clippy::too_many_arguments)]
    fn add_pass<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        id: &str,
        emissive: bool,
        hdr: TextureHandle,
        depth: TextureHandle,
        draws: Vec<(Draw, usize)>,
        inputs: ForwardInputs<'a>,
    ) -> TextureHandle {
        let scene = inputs.scene;
        // The permutations these draws use, from the shared cache.
        let mut pipelines: Vec<(ForwardKey, Result<wgpu::RenderPipeline, GpuError>)> = Vec::new();
        if let Some(m) = &scene.materials {
            for (_, material) in &draws {
                if let Some(binding) = m.materials.get(*material) {
                    let key = ForwardKey {
                        emissive,
                        double_sided: binding.double_sided,
                    };
                    if !pipelines.iter().any(|(k, _)| *k == key) {
                        pipelines.push((key, self.pipeline(ctx, key)));
                    }
                }
            }
        }
        graph
            .raster(id, &self.program)
            .uniform("objects", &scene.objects)
            .uniform("instances", &scene.instances)
            .read_cube("env_specular", inputs.env)
            .sampler("env_sampler", &inputs.envmap.sampler)
            .external("dfg_lut", &inputs.envmap.dfg_view)
            .external_group(1)
            .color(hdr, wgpu::LoadOp::Load)
            .depth_test(depth)
            .record(move |ctx, rp| {
                let Some(m) = &scene.materials else {
                    return Ok(());
                };
                let groups = (self.material_groups).get(scene.id, m, &self.program, ctx.device)?;
                scene.bind_geometry(rp);
                for (draw, material) in &draws {
                    let Some((group, binding)) =
                        groups.get(*material).zip(m.materials.get(*material))
                    else {
                        continue;
                    };
                    let key = ForwardKey {
                        emissive,
                        double_sided: binding.double_sided,
                    };
                    match pipelines.iter().find(|(k, _)| *k == key) {
                        Some((_, Ok(p))) => rp.set_pipeline(p),
                        Some((_, Err(e))) => {
                            return Err(GpuError::Other(format!(
                                "forward permutation {key:?}: {e}"
                            )));
                        }
                        None => {
                            return Err(GpuError::Other(format!(
                                "forward permutation {key:?} was not fetched"
                            )));
                        }
                    }
                    rp.set_bind_group(1, group, &[]);
                    scene.draw_list(rp, std::slice::from_ref(draw));
                }
                Ok(())
            })
            .colors[0]
    }
}
