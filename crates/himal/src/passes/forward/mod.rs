//! Forward passes after lighting and sky (issue #8, docs/gltf.md):
//! `forward.emissive` adds the emission of opaque and mask glTF materials
//! (an additive draw with depth test Equal against the G-buffer depth),
//! `forward.unlit` replaces the deferred result with KHR_materials_unlit
//! surfaces' base colour ([`reference::unlit_radiance`]), `forward.layers` puts their clearcoat and sheen over the deferred base
//! (depth Equal, One / OneMinusSrcAlpha: `layers.wgsl`, shading in
//! `shaders/layers.wgsl`, CPU twin [`reference::layers_shade`]), and
//! `forward.transmission` draws KHR_materials_transmission surfaces over
//! `forward.scene_color` (a copy of the opaque scene and its mip chain,
//! `scene_color.wgsl`), refracted through their KHR_materials_volume and
//! writing depth (`transmission.wgsl`, CPU twin
//! [`reference::transmitted_radiance`]), and
//! `forward.blend` draws alpha BLEND materials back to front (per object,
//! by the distance of its bounds' centre) with premultiplied alpha into the
//! HDR target, lit like the deferred world (issue #22): the sun through its
//! shadow maps at the fragment, the local lights through their atlas, the
//! sky SH, the filtered environment cube and the frame's aerial
//! perspective. Shader `forward.wgsl`, shading in `shaders/forward.wgsl`
//! and `shaders/fog.wgsl`, CPU twins [`reference::forward_shade_premultiplied`]
//! and [`crate::passes::lighting::reference::aerial_perspective`].

pub mod reference;

use glam::Vec3;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, SceneGpu, vertex_layout};
use crate::graph::{Fallback, FrameGraph, TextureHandle};
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::DEPTH_FORMAT;
use crate::passes::lighting::HDR_FORMAT;

/// Which forward pass a permutation belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ForwardKind {
    /// `forward.emissive`: emission added where the G-buffer kept the surface.
    Emissive,
    /// `forward.unlit`: unlit surfaces replace the deferred result.
    Unlit,
    /// `forward.layers`: clearcoat and sheen over the deferred base.
    Layers,
    /// `forward.transmission`: transmissive surfaces over the opaque scene.
    Transmission,
    /// `forward.blend`: alpha BLEND surfaces, premultiplied over.
    Blend,
}

/// A forward permutation: which pass and whether back faces are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ForwardKey {
    /// Which forward pass the pipeline belongs to.
    pub kind: ForwardKind,
    /// Draw back faces too (glTF `doubleSided`): no culling.
    pub double_sided: bool,
    /// E3: roughness widened by normal-map variance (`SPECULAR_AA`); only
    /// for the kinds that shade specular (layers, transmission, blend).
    pub specular_aa: bool,
    /// `forward.blend` reads the sun's and the local lights' shadow maps,
    /// `forward.transmission` the sun's (`SHADOWS`: shadows on and drawn
    /// this frame); other kinds: false.
    pub shadows: bool,
    /// `forward.blend` applies the frame's aerial perspective (`FOG`, as
    /// `LightingKey::fog`); other kinds: false.
    pub fog: bool,
}

impl ForwardKey {
    /// The key of `kind` (`specular_aa` dropped where the pass shades no specular).
    pub fn new(kind: ForwardKind, double_sided: bool, specular_aa: bool) -> Self {
        let shades = !matches!(kind, ForwardKind::Emissive | ForwardKind::Unlit);
        Self {
            kind,
            double_sided,
            specular_aa: specular_aa && shades,
            shadows: false,
            fog: false,
        }
    }

    /// The key with `forward.blend`'s shadows and fog and
    /// `forward.transmission`'s shadows (dropped for other kinds).
    pub fn lit(self, shadows: bool, fog: bool) -> Self {
        let blend = self.kind == ForwardKind::Blend;
        let transmission = self.kind == ForwardKind::Transmission;
        Self {
            shadows: shadows && (blend || transmission),
            fog: fog && blend,
            ..self
        }
    }

    /// The permutations `scene`'s emissive, layered and blend draws use
    /// (blend with shadows and fog as `lit` says).
    pub fn for_scene(scene: &SceneGpu, specular_aa: bool, lit: (bool, bool)) -> Vec<ForwardKey> {
        let mut keys = Vec::new();
        let Some(m) = &scene.materials else {
            return keys;
        };
        let of = |kind, draws: &[(Draw, usize)]| {
            draws
                .iter()
                .map(move |(_, mat)| (kind, *mat))
                .collect::<Vec<_>>()
        };
        let blend = scene
            .draws_blend
            .iter()
            .map(|(_, mat, _)| (ForwardKind::Blend, *mat));
        let all = (of(ForwardKind::Emissive, &scene.draws_emissive).into_iter())
            .chain(of(ForwardKind::Unlit, &scene.draws_unlit))
            .chain(of(ForwardKind::Layers, &scene.draws_layered))
            .chain(of(ForwardKind::Transmission, &scene.draws_transmissive))
            .chain(blend);
        for (kind, mat) in all {
            if let Some(binding) = m.materials.get(mat) {
                let key =
                    ForwardKey::new(kind, binding.double_sided, specular_aa).lit(lit.0, lit.1);
                if !keys.contains(&key) {
                    keys.push(key);
                }
            }
        }
        keys
    }
}

/// What the forward passes read.
#[derive(Clone, Copy)]
pub struct ForwardInputs<'a> {
    /// The scene's GPU data: meshes, materials and instances to draw.
    pub scene: &'a SceneGpu,
    /// Filtered cube, DFG table and sampler (L4); `env` orders the read
    /// after this frame's filtering.
    pub envmap: &'a EnvMapPass,
    /// The filtered environment cube as a graph handle (see `envmap`).
    pub env: TextureHandle,
    /// The sun's shadow mask (`forward.layers`; `None` without shadows).
    pub shadow_mask: Option<TextureHandle>,
    /// Screen-space AO (`forward.layers`; `None` without SSAO).
    pub ao: Option<TextureHandle>,
    /// The scene's ambient lights (`passes/lighting/ambient.rs`).
    pub ambient_lights: &'a wgpu::Buffer,
    /// The sun's maps this frame (`forward.blend`; `None`: shadows off).
    pub sun_maps: Option<crate::passes::shadows::SunMaps>,
    /// The sun maps' matrices (`ShadowPass::mask_params`).
    pub shadow_params: &'a wgpu::Buffer,
    /// The maps' comparison sampler.
    pub shadow_sampler: &'a wgpu::Sampler,
    /// The local lights (`ShadowPass::local_lights`).
    pub lights: &'a wgpu::Buffer,
    /// Their atlas tiles (`ShadowPass::light_tiles`), read with `sun_maps`' atlas.
    pub light_tiles: &'a wgpu::Buffer,
}

/// What the forward passes leave: the HDR target and the depth, written by
/// the transmissive surfaces (later readers must use this version).
#[derive(Clone, Copy, Debug)]
pub struct ForwardOut {
    /// The HDR radiance target (kcd/m², [`HDR_FORMAT`]) with the forward
    /// surfaces composited.
    pub hdr: TextureHandle,
    /// The reverse-Z depth after the transmissive surfaces' writes.
    pub depth: TextureHandle,
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

/// The forward passes: their programs, the blend order and the sheen table.
pub struct ForwardPass {
    program: Program,
    layers: Program,
    transmission: Program,
    /// `forward.scene_color`: the copy and the box mips (`scene_color.wgsl`).
    scene_color: Program,
    copy: wgpu::ComputePipeline,
    downsample: wgpu::ComputePipeline,
    /// `SceneGpu::draws_blend` indices, far to near (see [`ForwardPass::sort`]).
    order: Vec<usize>,
    /// The materials' bind groups of `forward.wgsl`, made once per scene.
    pub material_groups: crate::gpu_scene::textures::MaterialGroups,
    /// The same for `layers.wgsl`.
    pub layer_groups: crate::gpu_scene::textures::MaterialGroups,
    /// The same for `transmission.wgsl`.
    pub transmission_groups: crate::gpu_scene::textures::MaterialGroups,
    /// E(n.v, roughness) of the sheen lobe ([`reference::sheen_albedo_table`]), R32Float.
    sheen_albedo: wgpu::TextureView,
    /// E3 specular anti-aliasing this frame (`FrameSettings::specular_aa`,
    /// set by the renderer before planning).
    pub specular_aa: bool,
    /// Aerial perspective on `forward.blend` this frame (`LightingKey::fog`,
    /// set by the renderer before planning).
    pub fog: bool,
}

impl ForwardPass {
    /// Loads the forward shaders and uploads the sheen albedo table (an
    /// error if a shader does not compile).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        use wgpu::util::DeviceExt;
        let n = reference::SHEEN_TABLE_SIZE as u32;
        let table = ctx.device.create_texture_with_data(
            &ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("forward.sheen_albedo"),
                size: wgpu::Extent3d {
                    width: n,
                    height: n,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(reference::sheen_albedo_table()),
        );
        let scene_color = Program::new(ctx, "passes/forward/scene_color.wgsl")?;
        Ok(Self {
            program: Program::new(ctx, "passes/forward/forward.wgsl")?,
            layers: Program::new(ctx, "passes/forward/layers.wgsl")?,
            transmission: Program::new(ctx, "passes/forward/transmission.wgsl")?,
            copy: scene_color.compute_pipeline(ctx, "cs_copy", &[])?,
            downsample: scene_color.compute_pipeline(ctx, "cs_downsample", &[])?,
            scene_color,
            order: Vec::new(),
            material_groups: Default::default(),
            layer_groups: Default::default(),
            transmission_groups: Default::default(),
            specular_aa: true,
            fog: true,
            sheen_albedo: table.create_view(&Default::default()),
        })
    }

    /// The pipeline of permutation `key`, through the shared cache.
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        key: ForwardKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        use wgpu::{BlendFactor as F, CompareFunction as Z};
        // Colour src_factor * src + dst_factor * dst; the HDR alpha kept.
        let keep_alpha = |src_factor, dst_factor| wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor,
                dst_factor,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: F::Zero,
                dst_factor: F::One,
                operation: wgpu::BlendOperation::Add,
            },
        };
        let (program, blend, compare, entry, label) = match key.kind {
            ForwardKind::Emissive => {
                let add = keep_alpha(F::One, F::One);
                (
                    &self.program,
                    add,
                    Z::Equal,
                    "fs_emissive",
                    "forward.emissive",
                )
            }
            ForwardKind::Unlit => {
                let replace = keep_alpha(F::One, F::Zero);
                (
                    &self.program,
                    replace,
                    Z::Equal,
                    "fs_unlit",
                    "forward.unlit",
                )
            }
            ForwardKind::Layers => {
                // out = layers + base (1 - a)
                let over = keep_alpha(F::One, F::OneMinusSrcAlpha);
                (&self.layers, over, Z::Equal, "fs_layers", "forward.layers")
            }
            ForwardKind::Transmission => {
                let state = wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING;
                (
                    &self.transmission,
                    state,
                    Z::Greater,
                    "fs_transmission",
                    "forward.transmission",
                )
            }
            ForwardKind::Blend => {
                let state = wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING;
                // reverse-Z: nearer is larger
                (
                    &self.program,
                    state,
                    Z::Greater,
                    "fs_blend",
                    "forward.blend",
                )
            }
        };
        let targets = [Some(wgpu::ColorTargetState {
            format: HDR_FORMAT,
            blend: Some(blend),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        let buffers = [Some(vertex_layout())];
        let b = |on: bool| f64::from(u8::from(on));
        let mut constants = vec![("SPECULAR_AA", b(key.specular_aa))];
        if std::ptr::eq(program, &self.program) {
            constants.extend([("SHADOWS", b(key.shadows)), ("FOG", b(key.fog))]);
        } else if std::ptr::eq(program, &self.transmission) {
            constants.push(("SHADOWS", b(key.shadows)));
        }
        let spec = RenderSpec {
            label,
            vertex_entry: "vs_main",
            fragment_entry: Some(entry),
            vertex_buffers: &buffers,
            targets: &targets,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                // Transmissive surfaces are the nearest opaque-like ones
                // later passes (blend, TAA, views) must see.
                depth_write_enabled: Some(key.kind == ForwardKind::Transmission),
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
            constants: &constants,
        };
        program.render_pipeline(ctx, &spec)
    }

    /// Orders the blend draws far to near from `camera` (call before the frame).
    pub fn sort(&mut self, scene: &SceneGpu, camera: Vec3) {
        let centres: Vec<Vec3> = scene.draws_blend.iter().map(|(_, _, c)| *c).collect();
        self.order = back_to_front(&centres, camera);
    }

    /// Adds `forward.emissive`, `forward.unlit`, `forward.layers`,
    /// `forward.scene_color` and `forward.transmission`, and `forward.blend`
    /// (each only when the scene has such draws) on top of `hdr`; returns
    /// the new HDR and depth versions.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        inputs: ForwardInputs<'a>,
    ) -> ForwardOut {
        let scene = inputs.scene;
        let mut out = ForwardOut { hdr, depth };
        if !scene.draws_emissive.is_empty() {
            let draws: &'a [(Draw, usize)] = &scene.draws_emissive;
            let node = graph.raster("forward.emissive", &self.program);
            out = self.add_pass(ctx, node, ForwardKind::Emissive, out, draws, inputs);
        }
        if !scene.draws_unlit.is_empty() {
            let draws: &'a [(Draw, usize)] = &scene.draws_unlit;
            let node = graph.raster("forward.unlit", &self.program);
            out = self.add_pass(ctx, node, ForwardKind::Unlit, out, draws, inputs);
        }
        if !scene.draws_layered.is_empty() {
            let draws: &'a [(Draw, usize)] = &scene.draws_layered;
            let node = (graph.raster("forward.layers", &self.layers))
                .optional("shadow_mask", inputs.shadow_mask, Fallback::White)
                .optional("ao", inputs.ao, Fallback::White)
                .external("sheen_albedo_load", &self.sheen_albedo);
            out = self.add_pass(ctx, node, ForwardKind::Layers, out, draws, inputs);
        }
        if !scene.draws_transmissive.is_empty() {
            let behind = self.add_scene_color(graph, out.hdr);
            let draws: &'a [(Draw, usize)] = &scene.draws_transmissive;
            let node = (graph.raster("forward.transmission", &self.transmission))
                .read("scene_color", behind);
            out = self.add_pass(ctx, node, ForwardKind::Transmission, out, draws, inputs);
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
            let node = graph.raster("forward.blend", &self.program);
            out = self.add_pass(ctx, node, ForwardKind::Blend, out, draws, inputs);
        }
        out
    }

    /// `forward.scene_color` (a copy of `hdr`, the opaque scene, into mip 0)
    /// and `forward.scene_color.mipN` (its box mips, each from its parent);
    /// returns the chain.
    fn add_scene_color<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
    ) -> TextureHandle {
        let size = graph
            .texture_desc(hdr)
            .map_or((1, 1), |d| (d.width, d.height));
        let levels = 32 - size.0.max(size.1).max(1).leading_zeros();
        let desc = crate::graph::TextureDesc {
            mip_levels: levels,
            ..crate::graph::TextureDesc::new_2d(size.0, size.1, HDR_FORMAT)
        };
        let chain = graph.create_texture("forward.scene_color", desc);
        let mip = |level| wgpu::TextureViewDescriptor {
            base_mip_level: level,
            mip_level_count: Some(1),
            ..Default::default()
        };
        let groups = |level: u32| {
            let (w, h) = ((size.0 >> level).max(1), (size.1 >> level).max(1));
            [w.div_ceil(8), h.div_ceil(8), 1]
        };
        let written = (graph.compute("forward.scene_color", &self.scene_color))
            .compute_pipeline(Ok(self.copy.clone()))
            .read("parent", hdr)
            .storage_view("child", chain, mip(0))
            .dispatch(groups(0));
        let mut chain = written.storage.first().copied().unwrap_or(chain);
        for level in 1..levels {
            let written = (graph.compute(
                &format!("forward.scene_color.mip{level}"),
                &self.scene_color,
            ))
            .compute_pipeline(Ok(self.downsample.clone()))
            .read_view("parent", chain, mip(level - 1))
            .storage_view("child", chain, mip(level))
            .dispatch(groups(level));
            chain = written.storage.first().copied().unwrap_or(chain);
        }
        chain
    }

    /// Completes forward node `node` over `draws` (view and lighting are
    /// frame constants) and returns its HDR output.
    #[allow(clippy::too_many_arguments)]
    fn add_pass<'a>(
        &'a self,
        ctx: &GpuContext,
        node: crate::graph::Node<'_, 'a>,
        kind: ForwardKind,
        targets: ForwardOut,
        draws: impl AsRef<[(Draw, usize)]> + 'a,
        inputs: ForwardInputs<'a>,
    ) -> ForwardOut {
        let scene = inputs.scene;
        let (program, groups) = match kind {
            ForwardKind::Layers => (&self.layers, &self.layer_groups),
            ForwardKind::Transmission => (&self.transmission, &self.transmission_groups),
            _ => (&self.program, &self.material_groups),
        };
        // The permutations these draws use, from the shared cache.
        let specular_aa = self.specular_aa;
        let (shadows, fog) = (inputs.sun_maps.is_some(), self.fog);
        let mut pipelines: Vec<(ForwardKey, Result<wgpu::RenderPipeline, GpuError>)> = Vec::new();
        if let Some(m) = &scene.materials {
            for (_, material) in draws.as_ref() {
                if let Some(binding) = m.materials.get(*material) {
                    let key =
                        ForwardKey::new(kind, binding.double_sided, specular_aa).lit(shadows, fog);
                    if !pipelines.iter().any(|(k, _)| *k == key) {
                        pipelines.push((key, self.pipeline(ctx, key)));
                    }
                }
            }
        }
        let node = node
            .uniform("objects", &scene.objects)
            .uniform("instances", &scene.instances)
            .uniform("ambient_lights", inputs.ambient_lights)
            .read_cube("env_specular", inputs.env)
            .sampler("env_sampler", &inputs.envmap.sampler)
            .external("dfg_lut", &inputs.envmap.dfg_view)
            .external_group(1)
            .color(targets.hdr, wgpu::LoadOp::Load);
        // The sun's maps (fs_blend, fs_transmission) and the local lights
        // with their atlas (fs_blend).
        let maps = inputs.sun_maps;
        let far = Fallback::DepthFar;
        let node = if kind == ForwardKind::Layers {
            node
        } else {
            node.uniform("shadow_params", inputs.shadow_params)
                .optional_array("cascades", maps.and_then(|m| m.cascades), far)
                .optional_array("static_map", maps.and_then(|m| m.static_map), far)
                .sampler("shadow_sampler", inputs.shadow_sampler)
        };
        let node = if std::ptr::eq(program, &self.program) {
            node.optional_array("atlas", maps.and_then(|m| m.atlas), far)
                .uniform("lights", inputs.lights)
                .uniform("light_tiles", inputs.light_tiles)
        } else {
            node
        };
        let node = if kind == ForwardKind::Transmission {
            let ops = wgpu::Operations {
                load: wgpu::LoadOp::Load,
                store: wgpu::StoreOp::Store,
            };
            node.depth(targets.depth, None, ops)
        } else {
            node.depth_test(targets.depth)
        };
        let written = node.record(move |ctx, rp| {
            let Some(m) = &scene.materials else {
                return Ok(());
            };
            let groups = groups.get(scene.id, m, program, ctx.device)?;
            scene.bind_geometry(rp);
            for (draw, material) in draws.as_ref() {
                let Some((group, binding)) = groups.get(*material).zip(m.materials.get(*material))
                else {
                    continue;
                };
                let key =
                    ForwardKey::new(kind, binding.double_sided, specular_aa).lit(shadows, fog);
                match pipelines.iter().find(|(k, _)| *k == key) {
                    Some((_, Ok(p))) => rp.set_pipeline(p),
                    Some((_, Err(e))) => {
                        return Err(GpuError::Other(format!("forward permutation {key:?}: {e}")));
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
        });
        ForwardOut {
            hdr: written.colors[0],
            depth: written.depth.unwrap_or(targets.depth),
        }
    }
}
