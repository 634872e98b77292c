//! G-buffer pass (TECHNIQUES M1-M3): scene geometry into albedo, a
//! quaternion tangent frame (Rgb10a2), material parameters, motion, depth.
//! Layout per DESIGN.md; the packing lives in `shaders/tangent_frame.wgsl`
//! with its CPU twin in `math/quat_frame.rs`. Opaque objects draw first with
//! back-face culling and no discard (early-Z); vegetation follows with the
//! same shader specialised by `VEGETATION` (alpha test, sway, no culling).
//! Pipelines are permutations keyed by [`GBufferKey`] (E1's material-type
//! axis), created for the material types the scene uses.

use std::sync::Arc;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, SceneGpu, VisibleLists, vertex_layout};
use crate::graph::{FrameGraph, Node, TextureDesc, TextureHandle, Written};
use crate::passes::common::target;
use crate::passes::cull::{ALL, Culled, FADING, List, STEADY, bind_instances};
use crate::scene::lod::MAX_LODS;

/// Draws by level, each at its level ([`SceneGpu::split_at_lod`]).
type LevelDraws = [Vec<Draw>; MAX_LODS];

/// Albedo target: rgb linear albedo (stored sRGB-encoded), a material AO.
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Tangent-frame target: the frame's quaternion packed as its smallest three components plus the index of the largest (M3).
pub const FRAME_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgb10a2Unorm;
/// Material target: glossiness, reflectance, metallic|foliage
/// ([`encode_metallic_foliage`]), anisotropy, each in \[0,1\] (M1, V5).
pub const MATERIAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The material target's blue channel as stored (code / 255; twin of
/// `shaders/gbuffer_material.wgsl` `gbuffer_metallic_foliage`): codes
/// 0..127 hold `metallic` in 7 bits, codes 128..255 mark a foliage pixel
/// (`foliage` > 0) with its leaf amount in 7 bits and metallic 0 (V5).
pub fn encode_metallic_foliage(metallic: f32, foliage: f32) -> f32 {
    if foliage > 0.0 {
        (128.0 + (127.0 * foliage.clamp(0.0, 1.0)).round()) / 255.0
    } else {
        (127.0 * metallic.clamp(0.0, 1.0)).round() / 255.0
    }
}

/// (metallic, leaf amount) of a stored blue channel (twin of
/// `gbuffer_metallic`, `gbuffer_foliage`).
pub fn decode_metallic_foliage(z: f32) -> (f32, f32) {
    let c = (z.clamp(0.0, 1.0) * 255.0).round();
    if c > 127.5 {
        (0.0, (c - 128.0) / 127.0)
    } else {
        (c / 127.0, 0.0)
    }
}
/// Motion target: previous minus current screen uv (y down), in uv units.
pub const MOTION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// Depth target: reverse-Z, 1 at the near plane and 0 at the far one (infinity for a perspective camera).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Handles of the G-buffer targets after the pass.
#[derive(Clone, Copy, Debug)]
pub struct GBuffer {
    /// Albedo and material AO ([`ALBEDO_FORMAT`]).
    pub albedo: TextureHandle,
    /// Packed tangent frame ([`FRAME_FORMAT`]).
    pub frame: TextureHandle,
    /// Material parameters ([`MATERIAL_FORMAT`]).
    pub material: TextureHandle,
    /// Screen motion ([`MOTION_FORMAT`]).
    pub motion: TextureHandle,
    /// Depth ([`DEPTH_FORMAT`]).
    pub depth: TextureHandle,
}

impl GBuffer {
    /// `node` drawing into these targets after the node that wrote them
    /// (colours and depth loaded, in the G-buffer's order).
    pub fn load_into<'g, 'a>(self, node: Node<'g, 'a>) -> Node<'g, 'a> {
        let load = wgpu::LoadOp::Load;
        let depth = wgpu::Operations {
            load: wgpu::LoadOp::Load,
            store: wgpu::StoreOp::Store,
        };
        (node.color(self.albedo, load))
            .color(self.frame, load)
            .color(self.material, load)
            .color(self.motion, load)
            .depth(self.depth, None, depth)
    }

    /// The targets' new versions after a node bound by [`Self::load_into`].
    pub fn after(self, written: &Written) -> GBuffer {
        let colour = |i: usize, h: TextureHandle| written.colors.get(i).copied().unwrap_or(h);
        GBuffer {
            albedo: colour(0, self.albedo),
            frame: colour(1, self.frame),
            material: colour(2, self.material),
            motion: colour(3, self.motion),
            depth: written.depth.unwrap_or(self.depth),
        }
    }
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
    /// Which shader and specialisation draws.
    pub material: MaterialType,
    /// No back-face culling (glTF `doubleSided`, vegetation cards).
    pub double_sided: bool,
    /// Textured materials sample with mip bias -0.5.
    pub mip_bias: bool,
    /// E2: the per-vertex pipeline of the GPU lists fading between levels
    /// (screen-door discard; the plain one keeps early-Z).
    pub dither: bool,
    /// `--view lod`: the level these draws are at, shown as the albedo's hue.
    pub lod_view: Option<u8>,
    /// E3: textured materials widen roughness by their normal maps'
    /// variance (`SPECULAR_AA`; false for the other material types).
    pub specular_aa: bool,
    /// V3 `--view impostor`: vegetation tints impostor pixels by capture
    /// (`IMPOSTOR_VIEW`; false for the other material types).
    pub impostor_view: bool,
}

/// Mip bias of textured materials under temporal anti-aliasing (A2).
pub const TEMPORAL_AA_MIP_BIAS: f32 = -0.5;

impl GBufferKey {
    /// Opaque per-vertex materials: back faces culled, no discard.
    pub const VERTEX: Self = Self {
        material: MaterialType::Vertex,
        double_sided: false,
        mip_bias: false,
        dither: false,
        lod_view: None,
        specular_aa: false,
        impostor_view: false,
    };
    /// E2 transitions of per-vertex objects.
    pub const VERTEX_DITHER: Self = Self {
        dither: true,
        ..Self::VERTEX
    };
    /// Cards are seen from both sides.
    pub const VEGETATION: Self = Self {
        material: MaterialType::Vegetation,
        double_sided: true,
        mip_bias: false,
        dither: false,
        lod_view: None,
        specular_aa: false,
        impostor_view: false,
    };

    /// A glTF material's permutation: `double_sided` as the material says, `mip_bias` under TAA, `specular_aa` for E3.
    pub const fn textured(double_sided: bool, mip_bias: bool, specular_aa: bool) -> Self {
        Self {
            material: MaterialType::Textured,
            double_sided,
            mip_bias,
            dither: false,
            lod_view: None,
            specular_aa,
            impostor_view: false,
        }
    }

    /// This permutation for `--view lod` at `level`.
    pub const fn at_level(self, level: u8) -> Self {
        Self {
            lod_view: Some(level),
            ..self
        }
    }

    /// This permutation under `--view impostor` (vegetation only).
    pub const fn impostor_view(self, on: bool) -> Self {
        Self {
            impostor_view: on && matches!(self.material, MaterialType::Vegetation),
            ..self
        }
    }

    /// The permutations `scene` draws with (the per-vertex one always: it
    /// also clears the targets when nothing else draws); `mip_bias`: under
    /// temporal anti-aliasing; `specular_aa`: E3 on.
    pub fn for_scene(scene: &SceneGpu, mip_bias: bool, specular_aa: bool) -> Vec<GBufferKey> {
        Self::for_view(scene, mip_bias, specular_aa, false)
    }

    /// [`Self::for_scene`], with `lod_view`: every permutation at every
    /// level instead (`--view lod`; vegetation too, V1's leaf levels).
    pub fn for_view(
        scene: &SceneGpu,
        mip_bias: bool,
        specular_aa: bool,
        lod_view: bool,
    ) -> Vec<GBufferKey> {
        let mut keys = Self::base_keys(scene, mip_bias, specular_aa);
        if lod_view {
            let levels = if scene.has_lods { MAX_LODS as u8 } else { 1 };
            keys = keys
                .into_iter()
                .flat_map(|k| (0..levels).map(move |l| k.at_level(l)))
                .collect();
        }
        keys
    }

    fn base_keys(scene: &SceneGpu, mip_bias: bool, specular_aa: bool) -> Vec<GBufferKey> {
        let mut keys = vec![Self::VERTEX];
        if scene.has_lods {
            keys.push(Self::VERTEX_DITHER);
        }
        if scene.has_vegetation() {
            keys.push(Self::VEGETATION);
        }
        if let Some(m) = &scene.materials {
            for (_, material) in &scene.draws_textured {
                if let Some(binding) = m.materials.get(*material) {
                    let key = Self::textured(binding.double_sided, mip_bias, specular_aa);
                    if !keys.contains(&key) {
                        keys.push(key);
                    }
                }
            }
        }
        keys
    }
}

/// Rasterises the visible scene into the G-buffer targets, one pipeline per [`GBufferKey`].
pub struct GBufferPass {
    /// The camera's visible objects this frame (`frame::plan`).
    pub visible: VisibleLists,
    /// `--view lod` this frame: albedo shows each draw's level (`frame::plan`).
    pub lod_view: bool,
    /// `--view impostor` this frame: impostor pixels tinted by capture (`frame::plan`).
    pub impostor_view: bool,
    /// E3 specular anti-aliasing this frame (`FrameSettings::specular_aa`,
    /// set by the renderer before planning).
    pub specular_aa: bool,
    /// Skinned vertices' motion vectors from their previous pose
    /// (`FrameSettings::deform_motion`, set by the renderer before planning).
    pub deform_motion: bool,
    program: Program,
    /// glTF materials (`textured.wgsl`).
    textured: Program,
    /// Their bind groups, made once per scene.
    pub material_groups: crate::gpu_scene::textures::MaterialGroups,
}

impl GBufferPass {
    /// Compiles the per-vertex and textured G-buffer shaders; pipelines are made per key as the scene needs them.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let pass = Self {
            visible: VisibleLists::default(),
            lod_view: false,
            impostor_view: false,
            specular_aa: true,
            deform_motion: true,
            program: Program::new(ctx, "passes/gbuffer/gbuffer.wgsl")?,
            textured: Program::new(ctx, "passes/gbuffer/textured.wgsl")?,
            material_groups: Default::default(),
        };
        pass.pipeline(ctx, GBufferKey::VERTEX)?;
        Ok(pass)
    }

    /// The pipeline of permutation `key`, through the shared cache (memory,
    /// disk or compile).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        key: GBufferKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
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
        let lod: Vec<(&str, f64)> = key
            .lod_view
            .map(|l| ("LOD_VIEW", f64::from(l)))
            .into_iter()
            .collect();
        let with_lod = |c: &[(&'static str, f64)]| -> Vec<(&str, f64)> {
            c.iter().copied().chain(lod.iter().copied()).collect()
        };
        match key.material {
            MaterialType::Vertex if key.dither => self.program.render_pipeline(
                ctx,
                &spec("gbuffer.dither", cull, &with_lod(&[("DITHER", 1.0)])),
            ),
            MaterialType::Vertex => self
                .program
                .render_pipeline(ctx, &spec("gbuffer", cull, &with_lod(&[]))),
            MaterialType::Vegetation => self.program.render_pipeline(
                ctx,
                &spec(
                    "gbuffer.vegetation",
                    cull,
                    &with_lod(&[
                        ("VEGETATION", 1.0),
                        ("IMPOSTOR_VIEW", f64::from(u8::from(key.impostor_view))),
                    ]),
                ),
            ),
            MaterialType::Textured => {
                let bias = if key.mip_bias {
                    TEMPORAL_AA_MIP_BIAS
                } else {
                    0.0
                };
                let aa = f64::from(u8::from(key.specular_aa));
                self.textured.render_pipeline(
                    ctx,
                    &spec(
                        "gbuffer.textured",
                        cull,
                        &with_lod(&[("MIP_BIAS", f64::from(bias)), ("SPECULAR_AA", aa)]),
                    ),
                )
            }
        }
    }

    /// The `gbuffer` node: clears the targets, then draws opaque per-vertex
    /// objects and glTF materials (`view` is the frame constant; vegetation
    /// follows in [`Self::add_vegetation`]'s nodes):
    /// `lists`, or every object of `scene` (probe cubes) when `None`. With
    /// `culled` (V6 GPU culling: the lists, view), opaque and vegetation
    /// objects come from the GPU's list of that view and `lists` holds only
    /// the glTF draws.
    #[allow(clippy::too_many_arguments)]
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        scene: &'a SceneGpu,
        lists: Option<&'a VisibleLists>,
        culled: Option<(Culled<'a>, u32)>,
        mip_bias: bool,
    ) -> GBuffer {
        let (opaque, textured) = match lists {
            Some(l) => (&l.opaque, &l.textured),
            None => (&scene.draws_opaque, &scene.draws_textured),
        };
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
        // The permutations this scene draws with, from the shared cache
        // (vegetation's in its own nodes).
        let pipelines: Vec<(GBufferKey, Result<wgpu::RenderPipeline, GpuError>)> =
            GBufferKey::for_view(scene, mip_bias, self.specular_aa, self.lod_view)
                .into_iter()
                .filter(|key| key.material != MaterialType::Vegetation)
                .map(|key| (key, self.pipeline(ctx, key)))
                .collect();
        let clear = wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT);
        let (lod_view, specular_aa) = (self.lod_view, self.specular_aa);
        let node = self.scene_node(graph, "gbuffer", scene, culled.as_ref().map(|(c, _)| c));
        let written = node
            .color(albedo, clear)
            .color(frame, clear)
            .color(material, clear)
            .color(motion, clear)
            .depth(
                depth,
                None,
                wgpu::Operations {
                    load: wgpu::LoadOp::Clear(0.0),
                    store: wgpu::StoreOp::Store,
                },
            )
            .record(move |ctx, rp| {
                let pipeline = |key: GBufferKey| match pipelines.iter().find(|(k, _)| *k == key) {
                    Some((_, Ok(p))) => Ok(p),
                    Some((_, Err(e))) => Err(GpuError::Other(format!(
                        "G-buffer permutation {key:?}: {e}"
                    ))),
                    None => Err(GpuError::Other(format!(
                        "G-buffer permutation {key:?} is not one this scene draws with"
                    ))),
                };
                // `--view lod`: every level's draws with that level's pipeline.
                let levels = match (lod_view, scene.has_lods) {
                    (false, _) => vec![None],
                    (true, false) => vec![Some(0u8)],
                    (true, true) => (0..MAX_LODS as u8).map(Some).collect(),
                };
                let at = |key: GBufferKey, level: Option<u8>| match level {
                    Some(l) => key.at_level(l),
                    None => key,
                };
                let by_level = lod_view.then(|| scene.split_levels(opaque));
                scene.bind_geometry(rp);
                for &level in &levels {
                    rp.set_pipeline(pipeline(at(GBufferKey::VERTEX, level))?);
                    match (&by_level, level) {
                        (Some(split), Some(l)) => scene.draw_list(rp, &split[l as usize]),
                        _ => scene.draw_list(rp, opaque),
                    }
                    if let Some((c, view)) = culled {
                        let draw = |rp: &mut wgpu::RenderPass<'_>, kinds| match level {
                            Some(l) => c.draw_levels(
                                rp,
                                ctx,
                                view,
                                List::Opaque,
                                kinds,
                                u32::from(l)..u32::from(l) + 1,
                            ),
                            None => c.draw(rp, ctx, view, List::Opaque, kinds),
                        };
                        draw(rp, STEADY);
                        if c.has_lods {
                            rp.set_pipeline(pipeline(at(GBufferKey::VERTEX_DITHER, level))?);
                            draw(rp, FADING);
                        }
                    }
                }
                if let Some(m) = &scene.materials {
                    let groups =
                        (self.material_groups).get(scene.id, m, &self.textured, ctx.device)?;
                    for (material, draws) in crate::gpu_scene::material_runs(textured) {
                        let Some((group, binding)) =
                            groups.get(material).zip(m.materials.get(material))
                        else {
                            continue;
                        };
                        let key = GBufferKey::textured(binding.double_sided, mip_bias, specular_aa);
                        rp.set_bind_group(1, group, &[]);
                        if !lod_view {
                            // Objects of one mesh in the run draw instanced.
                            rp.set_pipeline(pipeline(key)?);
                            scene.draw_list(rp, &draws);
                            continue;
                        }
                        // `--view lod`: each draw with its level's pipeline.
                        for draw in &draws {
                            let one = std::slice::from_ref(draw);
                            let split = scene.split_levels(one);
                            let level = split.iter().position(|l| !l.is_empty()).unwrap_or(0);
                            rp.set_pipeline(pipeline(at(key, Some(level as u8)))?);
                            scene.draw_list(rp, one);
                        }
                    }
                }
                Ok(())
            });
        // The node declared four colour targets, in this order.
        let colour = |i: usize| written.colors.get(i).copied();
        GBuffer {
            albedo: colour(0).unwrap_or(albedo),
            frame: colour(1).unwrap_or(frame),
            material: colour(2).unwrap_or(material),
            motion: colour(3).unwrap_or(motion),
            depth: written.depth.unwrap_or(depth),
        }
    }

    /// The vegetation's G-buffer nodes after [`Self::add`] (targets loaded):
    /// `vegetation.gbuffer` draws the alpha-tested cards (LOD0-2 and any
    /// vegetation without levels), `vegetation.impostor` V3's impostor
    /// levels, each a pass of its own so the bench times them (issue #18).
    /// The same lists as `add` (`lists`, `culled`); nothing without
    /// vegetation.
    #[allow(clippy::too_many_arguments)]
    pub fn add_vegetation<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        lists: Option<&'a VisibleLists>,
        culled: Option<(Culled<'a>, u32)>,
        gbuffer: GBuffer,
    ) -> GBuffer {
        let impostors = crate::scene::tree::impostor_level::frame_levels();
        let any_impostor = scene.impostor_mesh.iter().any(|&i| i)
            && scene.impostors.load(std::sync::atomic::Ordering::Relaxed);
        let cards = match any_impostor {
            true => 0..impostors.start,
            false => 0..MAX_LODS as u32,
        };
        // The scene's lists (CPU path): each object's level chosen once for
        // both nodes.
        let vegetation = lists.map_or(&scene.draws_vegetation, |l| &l.vegetation);
        let split = std::sync::Arc::new(scene.split_at_lod(vegetation));
        let nodes = [
            ("vegetation.gbuffer", cards),
            ("vegetation.impostor", impostors),
        ];
        let mut gbuffer = gbuffer;
        for (id, levels) in nodes.into_iter().take(1 + usize::from(any_impostor)) {
            let lists = (split.clone(), culled);
            gbuffer = self.vegetation_node(ctx, (graph, id), scene, lists, gbuffer, levels);
        }
        gbuffer
    }

    /// One vegetation node (`id`): `levels` of the scene's vegetation
    /// (`split`, placed at their levels) and of the culled lists into
    /// `gbuffer` (loaded), per level under `--view lod`.
    fn vegetation_node<'a>(
        &'a self,
        ctx: &GpuContext,
        (graph, id): (&mut FrameGraph<'a>, &str),
        scene: &'a SceneGpu,
        (split, culled): (Arc<LevelDraws>, Option<(Culled<'a>, u32)>),
        gbuffer: GBuffer,
        levels: std::ops::Range<u32>,
    ) -> GBuffer {
        let culled = culled.filter(|_| scene.has_vegetation());
        let scene_draws = levels.clone().any(|l| !split[l as usize].is_empty());
        if !scene_draws && culled.is_none() {
            return gbuffer;
        }
        let key = GBufferKey::VEGETATION.impostor_view(self.impostor_view);
        // `--view lod`: a pipeline per level, else one for all.
        let keys: Vec<Option<u32>> = match self.lod_view {
            true => levels.clone().map(Some).collect(),
            false => vec![None],
        };
        let pipelines: Vec<(Option<u32>, Result<wgpu::RenderPipeline, GpuError>)> = (keys.iter())
            .map(|&l| {
                (
                    l,
                    self.pipeline(ctx, l.map_or(key, |l| key.at_level(l as u8))),
                )
            })
            .collect();
        let node = self.scene_node(graph, id, scene, culled.as_ref().map(|(c, _)| c));
        let written = gbuffer.load_into(node).record(move |ctx, rp| {
            scene.bind_geometry(rp);
            for (level, pipeline) in &pipelines {
                let pipeline = pipeline.as_ref().map_err(|e| {
                    GpuError::Other(format!("G-buffer vegetation permutation: {e}"))
                })?;
                rp.set_pipeline(pipeline);
                let drawn = level.map_or(levels.clone(), |l| l..l + 1);
                for l in drawn.clone() {
                    scene.draw_placed(rp, &split[l as usize]);
                }
                if let Some((c, view)) = culled {
                    c.draw_levels(rp, ctx, view, List::Vegetation, ALL, drawn);
                }
            }
            Ok(())
        });
        gbuffer.after(&written)
    }

    /// A node `id` of this pass's program with the scene's bindings: the
    /// objects, the ripple grid, the deformation's previous positions, the
    /// impostor atlas and the instances (`culled`'s lists, or the identity).
    fn scene_node<'g, 'a>(
        &'a self,
        graph: &'g mut FrameGraph<'a>,
        id: &str,
        scene: &'a SceneGpu,
        culled: Option<&Culled<'a>>,
    ) -> Node<'g, 'a> {
        let node = graph
            .raster(id, &self.program)
            .uniform("objects", &scene.objects)
            .uniform("ripple", &scene.ripple)
            .uniform("deform_prev", scene.deform_prev(self.deform_motion))
            .external("impostor_color_load", &scene.impostor_atlas.color)
            .external("impostor_normal_load", &scene.impostor_atlas.normal)
            .external("impostor_depth_load", &scene.impostor_atlas.depth);
        bind_instances(node, culled, &scene.instances)
    }
}
