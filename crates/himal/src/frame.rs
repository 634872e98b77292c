//! The whole frame, top to bottom, in one place to read: [`plan`] (each
//! technique's CPU half) and [`build`] (the graph).
//!
//! ```text
//! [skin ─> skin.copy] (skinned meshes posed into the scene's vertex buffer)
//! cull (V6: camera, cascades, static tiles, L2 sectors) ─> instance lists, indirect arguments ─> gbuffer, shadows.cascade0..3
//!   (--occlusion hiz: cull also reads last frame's Hi-Z pyramid; gbuffer, terrain ─> cull.hiz ─> cull.hiz.mipK ─> next frame's cull)
//! [skyocc.terrainN ─>] skyocc.groundN ─> skyocc.heightfieldN ─> skyocc.blur_x/_y ─> skyocc.visibility ─> skyocc.smooth ─┐ (new sectors)
//! envmap.capture | envmap.probeN.* ─> envmap.mipM ─> envmap.filterM ─────────────┤ (when the sky changed)
//! [vegetation.simulate (V2 bones) ─> vegetation.ripple (grass)] before anything draws
//! shadows.cascadeN [─> vegetation.shadowN] [─> terrain.shadowN], shadows.static | .static.tileN/.poolN + terrain.staticN (world), shadows.hero ─┐
//! gbuffer [─> vegetation.gbuffer (cards) ─> vegetation.impostor (V3)] [─> terrain] [─> vegetation.ao (V4: tree volumes multiply the albedo's alpha)] [─> gbuffer.wet]
//! gbuffer ─┬─────────────────────────────────────────┴─> shadows.mask ─┐
//!          ├─> ao.hbao ─> … ─> ao.blur_y_stf ──────────────────────────┴─> lighting.deferred ─> sky ─> [forward.emissive ─> forward.unlit ─> forward.layers ─> forward.scene_color(.mipN) ─> forward.transmission ─> forward.blend] ─┬─> post.luminance ─> post.adapt ─┐
//!          │          (passes/ao/mod.rs)                                     ├─> post.bloom.bright ─> post.bloom.blur0..N ─┐
//!          │                                                                 └──────────────────────> post.tonemap <───────┘─> output
//!          │        (--aa: post.tonemap ─> [aa.smaa.edges ─> .weights ─> .blend] ─> [aa.resolve ─> aa.taa ─> aa.unsharp] ─> output,
//!          │         passes/aa/mod.rs `add_chain`)
//!          └──────────────────────────────────────────────────────────────────────────> debug.view | ao.view ──> output (--view)
//! ```
//! (`post.adapt` feeds the exposure of the bloom bright pass and of the tone map.)
//! With `--aa-buffers`: `aa.taa_motion` right after `gbuffer` (its stabilised
//! motion replaces the G-buffer's for every reader) and `aa.taa_ao` after
//! `ao.blur_y[_stf]` (its AO is what lighting reads).
//! Passes that reach no output are culled by the graph (tone mapping when a
//! debug view is shown).

use glam::{Mat4, Vec3};

use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{LodView, SceneGpu};
use crate::graph::{FrameGraph, History};
use crate::passes::aa::{AaBuffers, AaFrame, AaMode, BufferTaaPass, SmaaPass, TemporalPass};
use crate::passes::ao::bleed::BleedPass;
use crate::passes::ao::large_scale::LargeScaleInputs;
use crate::passes::ao::{AoInputs, AoPass, AoSettings, AoTargets, AoUniform, AoView};
use crate::passes::cull::{CullPass, CullPath, CullView};
use crate::passes::debug::DebugPass;
use crate::passes::envmap::probe::ProbeSet;
use crate::passes::envmap::{EnvMapPass, EnvViewPass};
use crate::passes::forward::{ForwardInputs, ForwardPass};
use crate::passes::gbuffer::{GBuffer, GBufferPass};
use crate::passes::lighting::{LightingInputs, LightingKey, LightingPass};
use crate::passes::post::{
    AdaptPass, BloomInputs, BloomPass, LuminanceBuffers, LuminancePass, PostFrame, PostInputs,
    TonemapPass,
};
use crate::passes::shadows::{ShadowPass, ShadowStats};
use crate::passes::skin::SkinPass;
use crate::passes::sky::SkyPass;
use crate::passes::skyocc::{SkyOccPass, SkyOccStats};
use crate::passes::terrain::{TerrainPass, TerrainStats, TerrainView};
use crate::scene::Camera;
use crate::settings::{Culling, FrameSettings, Occlusion, ViewBuffer};

/// Every pass's pipelines, created once.
pub struct Passes {
    /// Skinned meshes posed before anything draws them.
    pub skin: SkinPass,
    /// V6: per-instance frustum culling on the GPU.
    pub cull: CullPass,
    /// S1-S4: cascades, static map, hero map, local-light atlas and the mask.
    pub shadows: ShadowPass,
    /// The deferred G-buffer (per-vertex and textured glTF materials).
    pub gbuffer: GBufferPass,
    /// B1: HBAO, its stability mask, and the bilateral blurs.
    pub ao: AoPass,
    /// O5: the low-frequency albedo the AO is tinted with.
    pub ao_bleed: BleedPass,
    /// E3's screen-space filter behind an edit of the G-buffer's roughness:
    /// the wetness example (`--wetness`).
    pub wet: crate::passes::wet::WetPass,
    /// L3/L4: the environment cube captured and GGX-filtered.
    pub envmap: EnvMapPass,
    /// `--view env-probe` / `env-mirror`: the filtered cube shown.
    pub env_view: EnvViewPass,
    /// L3: the environment probes and their relit cubes.
    pub probes: ProbeSet,
    /// Deferred lighting, one pipeline per `LightingKey`.
    pub lighting: LightingPass,
    /// L1: the sky behind the geometry (Bruneton or Preetham).
    pub sky: SkyPass,
    /// L2: sky-occlusion sectors and their visibility.
    pub skyocc: SkyOccPass,
    /// L5: radiance-transfer probes streamed in cells, the clip map.
    pub indirect: crate::passes::indirect::IndirectPass,
    /// glTF emission and alpha-blended surfaces after lighting.
    pub forward: ForwardPass,
    /// V2: the trees' bones moved by the wind.
    pub vegetation: crate::passes::vegetation::VegetationPass,
    /// E4: the scene's particles, simulated, lit and drawn.
    pub particles: crate::passes::particles::ParticlesPass,
    /// H2: the log-average luminance.
    pub luminance: LuminancePass,
    /// H2: light adaptation on the GPU.
    pub adapt: AdaptPass,
    /// H3: the Kawase bloom chain.
    pub bloom: BloomPass,
    /// H1: the tone mappers and the bloom composite.
    pub tonemap: TonemapPass,
    /// A1/A2: SMAA edges, weights and blend.
    pub smaa: SmaaPass,
    /// A2/A3: temporal resolve, TAA and unsharp mask.
    pub temporal: TemporalPass,
    /// A3 TAA on the AO and the motion vectors (`--aa-buffers`).
    pub aa_buffers: BufferTaaPass,
    /// Debug views of the G-buffer, depth, HDR and bloom (`--view`).
    pub debug: DebugPass,
    /// The world's CDLOD terrain (`--scene world`; `None` for plain scenes).
    pub terrain: Option<TerrainPass>,
    /// V4: the trees' occlusion volumes as a deferred decal.
    pub tree_ao: crate::passes::tree_ao::TreeAoPass,
}

impl Passes {
    /// Every pass of the frame, its pipelines fetched for `scene`'s lights,
    /// probes and sky-occlusion extent, and its culling layout for `gpu`
    /// (the scene uploaded); output passes write `DISPLAY_FORMAT`.
    pub fn new(
        ctx: &GpuContext,
        scene: &crate::scene::Scene,
        gpu: &SceneGpu,
    ) -> Result<Self, GpuError> {
        use crate::passes::envmap::ENVMAP_SIZE;
        use crate::settings::DISPLAY_FORMAT;
        Ok(Self {
            skin: SkinPass::new(ctx)?,
            cull: CullPass::new(ctx, gpu)?,
            shadows: ShadowPass::new(ctx, scene)?,
            gbuffer: GBufferPass::new(ctx)?,
            ao: AoPass::new(ctx)?,
            ao_bleed: BleedPass::new(ctx)?,
            wet: crate::passes::wet::WetPass::new(ctx)?,
            envmap: EnvMapPass::new(ctx, ENVMAP_SIZE)?,
            env_view: EnvViewPass::new(ctx)?,
            probes: ProbeSet::new(ctx, &scene.probes, ENVMAP_SIZE)?,
            lighting: LightingPass::new(ctx, scene)?,
            sky: SkyPass::new(ctx)?,
            skyocc: SkyOccPass::new(ctx, scene)?,
            indirect: crate::passes::indirect::IndirectPass::new(ctx)?,
            forward: ForwardPass::new(ctx)?,
            vegetation: crate::passes::vegetation::VegetationPass::new(ctx, scene.wind_field())?,
            particles: crate::passes::particles::ParticlesPass::new(ctx, scene)?,
            luminance: LuminancePass::new(ctx)?,
            adapt: AdaptPass::new(ctx)?,
            bloom: BloomPass::new(ctx)?,
            tonemap: TonemapPass::new(ctx, DISPLAY_FORMAT)?,
            smaa: SmaaPass::new(ctx, DISPLAY_FORMAT)?,
            temporal: TemporalPass::new(ctx, DISPLAY_FORMAT)?,
            aa_buffers: BufferTaaPass::new(ctx)?,
            debug: DebugPass::new(ctx)?,
            terrain: None,
            tree_ao: crate::passes::tree_ao::TreeAoPass::new(ctx)?,
        })
    }
}

/// What each technique's CPU planning reads from the renderer this frame.
pub struct PlanInputs<'a> {
    /// The device and queue.
    pub ctx: &'a GpuContext,
    /// The scene as uploaded.
    pub scene: &'a SceneGpu,
    /// This frame's settings.
    pub settings: &'a FrameSettings,
    /// This frame's camera.
    pub camera: &'a Camera,
    /// Jittered projection (A2) and the frame's and last frame's jitter (px).
    pub proj: Mat4,
    /// This frame's jitter (px).
    pub jitter: [f32; 2],
    /// The previous frame's jitter (px).
    pub prev_jitter: [f32; 2],
    /// Unit vector towards the sun.
    pub sun_direction: Vec3,
    /// The temporal rings (AO, colour, buffer TAA).
    pub history: &'a History,
}

/// What the CPU half measured.
pub struct Planned {
    /// What the shadow planning chose (casters, draws, static slice).
    pub shadows: ShadowStats,
    /// Sky-occlusion sectors planned and rendered.
    pub sky_occlusion: SkyOccStats,
    /// L5 probe cells resident, uploaded and released.
    pub indirect: crate::passes::indirect::IndirectStats,
    /// The world's terrain selection (`None`: no terrain).
    pub terrain: Option<TerrainStats>,
    /// Wall milliseconds of culling: the camera's lists, the shadow fits
    /// and caster lists, and the GPU culling's plan.
    pub cull_ms: f64,
}

/// E2: the levels every pass draws at, seen from `camera`.
pub fn lod_view(camera: &crate::scene::Camera, settings: &FrameSettings) -> LodView {
    use crate::scene::lod;
    LodView {
        eye: camera.position,
        selection: lod::Selection {
            // Orthographic: a triangle's size does not fall with distance;
            // every object is drawn at LOD0.
            scale: if camera.orthographic.is_some() {
                0.0
            } else {
                lod::distance_scale(camera.fov_y_deg, settings.height, settings.lod_threshold_px)
            },
            focal_px: lod::focal_px(camera.fov_y_deg, settings.height),
            max_error_px: settings.lod_error_px,
            band: settings.lod_band,
            object_scale: if settings.lod_object_px > 0.0 && camera.orthographic.is_none() {
                lod::focal_px(camera.fov_y_deg, settings.height) / settings.lod_object_px
            } else {
                0.0
            },
        },
    }
}

/// The CPU half of the frame: each technique's planning (parameters,
/// culling, atlas layout, sector jobs, sorting), in frame order.
/// [`crate::Renderer::draw`], `describe_graph` and the bench all run it
/// before [`build`].
pub fn plan(passes: &mut Passes, p: PlanInputs<'_>) -> Planned {
    let (ctx, scene, settings, camera) = (p.ctx, p.scene, p.settings, p.camera);
    let (jitter, prev_jitter) = (p.jitter, p.prev_jitter);
    // V6: every pass's draw lists merge into instanced draws (or not).
    scene
        .instancing
        .store(settings.instancing, std::sync::atomic::Ordering::Relaxed);
    scene
        .vegetation
        .store(settings.vegetation, std::sync::atomic::Ordering::Relaxed);
    // V3: impostor levels drawn, or LOD2 to the end (both culling paths).
    scene
        .impostors
        .store(settings.impostors, std::sync::atomic::Ordering::Relaxed);
    passes.cull.set_impostors(&ctx.queue, settings.impostors);
    // V4: the trees' volumes darken the sky light where the trees are drawn.
    passes.tree_ao.on = settings.tree_ao && settings.vegetation;
    // The world's trees: their pool regions list nothing without vegetation.
    passes
        .cull
        .show_pool_vegetation(&ctx.queue, settings.vegetation);
    // The GPU culling's lists hold every object: without vegetation the CPU culls.
    let hide_vegetation = !settings.vegetation && scene.vegetation_objects.contains(&true);
    let size = (settings.width, settings.height);
    let aspect = size.0 as f32 / size.1 as f32;
    // V6: the G-buffer's objects inside the camera's frustum, culled on the
    // GPU (view 0; the cascades are views 1..) or on the CPU; runs of one
    // mesh's objects merge into instanced draws.
    let view_proj = p.proj * camera.view();
    let lod = lod_view(camera, settings);
    if let Ok(mut l) = scene.lod.lock() {
        *l = lod;
    }
    let gpu_cull = settings.culling == Culling::Gpu
        && settings.instancing
        && !hide_vegetation
        && passes.cull.supported().is_ok();
    let layout = &passes.cull.layout;
    let gpu_calls = gpu_cull.then(|| (layout.draw_calls(true), layout.draw_calls(false)));
    // The streamed world's pool is culled per view on every path: on the
    // GPU, or by the CPU twin (its lists drawn directly) where that is off.
    let streamed = !layout.pool_batches.is_empty();
    let per_view = gpu_cull || streamed;
    let cull_view = (settings.culling != Culling::Off).then_some(view_proj);
    let t_cull = std::time::Instant::now();
    passes.gbuffer.visible = scene.visible(cull_view, gpu_calls.map(|(g, _)| (0, g)));
    let mut cull_ms = t_cull.elapsed().as_secs_f64() * 1e3;
    // B1: reconstruction from depth and reprojection with this jitter.
    let ao = AoUniform::new(&settings.ao, p.proj, camera.near, size);
    passes
        .ao
        .update(&ctx.queue, &ao.with_jitter(jitter, prev_jitter));
    // A3 on the AO and the motion vectors.
    if settings.aa_buffers.any() {
        let tuning = &settings.aa_tuning;
        (passes.aa_buffers).update(&ctx.queue, jitter, prev_jitter, p.history, tuning);
    }
    // S1-S4: cascade fits, static slice, hero, atlas; culled caster lists.
    let t_cull = std::time::Instant::now();
    let shadows = passes.shadows.update(
        ctx,
        scene,
        camera,
        aspect,
        p.sun_direction,
        settings.shadow_resolution,
        Some(&settings.shadows),
        settings.time_s,
        gpu_calls.map(|(_, shadow)| shadow),
        streamed,
    );
    cull_ms += t_cull.elapsed().as_secs_f64() * 1e3;
    // L2: the sectors the camera wants; jobs for the ones not resident.
    // O6 samples the same pool's heights.
    let skyocc_on = settings.sky_occlusion
        || settings.ao.large_scale_on()
        || matches!(settings.view, ViewBuffer::SkyOcc(_));
    if settings.sky_occlusion_every_frame {
        passes.skyocc.invalidate();
    }
    let sky_occlusion = passes.skyocc.update(ctx, scene, camera, aspect, skyocc_on);
    // L5: the probe cells around the camera streamed into the pool.
    passes.indirect.view = match settings.view {
        ViewBuffer::Indirect(v) => v as u32,
        _ => 0,
    };
    let indirect = match settings.indirect {
        true => passes
            .indirect
            .update(ctx, glam::Vec2::new(camera.position.x, camera.position.z)),
        false => Default::default(),
    };
    let mut views = Vec::new();
    if per_view {
        views.push(match settings.culling {
            Culling::Off => CullView::ALL,
            _ => CullView::clip(view_proj),
        });
        // The cascades, then the world's static-map tiles (S2; ShadowPass
        // names them 1 + cascades + k).
        let sun_views = shadows.fits.iter().map(|f| &f.light_view_proj);
        let sun_views = sun_views.chain(&shadows.static_tiles);
        views.extend(sun_views.map(|m| CullView::caster(*m)));
    }
    // L2 in a streamed world: the pool instances under this frame's sectors.
    passes.skyocc.culled_view = None;
    let room = views.len() < crate::passes::cull::MAX_VIEWS;
    if let Some(v) = passes.skyocc.cull_view().filter(|_| streamed && room) {
        passes.skyocc.culled_view = Some(views.len() as u32);
        views.push(v);
    }
    let path = match gpu_cull {
        true => CullPath::Gpu,
        false => CullPath::Cpu {
            instanced: settings.instancing,
        },
    };
    // V6 Hi-Z: the camera's view against last frame's depth, on the GPU
    // path alone (the CPU path has no previous depth on the CPU).
    let hiz = settings.occlusion == Occlusion::Hiz && gpu_cull;
    passes.cull.hiz.prepare(&ctx.device, size, hiz);
    let t_cull = std::time::Instant::now();
    passes.cull.plan(ctx, &views, lod, path);
    cull_ms += t_cull.elapsed().as_secs_f64() * 1e3;
    // The pool's own draws: the sun maps' pool views, and the camera's
    // where the CPU twin's lists are drawn directly (on the GPU path they
    // are in its multi-draws).
    let mut shadows = shadows;
    let cull = &passes.cull;
    shadows.draws += (passes.shadows.pool_views())
        .map(|v| cull.pool_calls(v, crate::passes::cull::SHADOW))
        .sum::<u32>();
    if !gpu_cull {
        let kinds = [crate::passes::cull::STEADY, crate::passes::cull::FADING];
        passes.gbuffer.visible.pool_calls = kinds.into_iter().map(|k| cull.pool_calls(0, k)).sum();
    }
    // The world's terrain: CDLOD patches for the camera, the cascades at its levels.
    let lod_view = settings.view == ViewBuffer::Debug(crate::passes::debug::DebugView::Lod);
    passes.gbuffer.lod_view = lod_view;
    passes.gbuffer.impostor_view =
        settings.view == ViewBuffer::Debug(crate::passes::debug::DebugView::Impostor);
    let terrain = passes.terrain.as_mut().map(|t| {
        t.lod_view = lod_view;
        t.specular_aa = settings.specular_aa;
        let fits = shadows.fits.iter().map(|f| f.light_view_proj);
        let sun_views: Vec<Mat4> = fits.chain(shadows.static_tiles.iter().copied()).collect();
        t.prepare(
            &ctx.queue,
            &TerrainView::from_camera(camera, size),
            &sun_views,
        )
    });
    // Ambient lights on or off (their count).
    (passes.lighting.ambient_lights).enable(&ctx.queue, settings.ambient_lights);
    // Alpha BLEND objects draw far to near from this camera.
    passes.forward.sort(scene, camera.position);
    // V2: this frame's tree simulation steps.
    (passes.vegetation).plan(
        ctx,
        scene,
        settings.time_s,
        (settings.vegetation, settings.vegetation_motion),
        settings.wind,
    );
    (passes.vegetation).plan_ripple(
        ctx,
        scene,
        settings.time_s,
        camera.position,
        settings.vegetation
            && settings.vegetation_motion != crate::passes::vegetation::VegetationMotion::Off,
    );
    // E4: this frame's particle steps (births, pre-warm after a reset).
    // V2: particles follow the same global wind (`--wind` or the scene's).
    passes.particles.sim.wind = settings.wind.unwrap_or(passes.vegetation.wind.global);
    (passes.particles).plan(ctx, settings.time_s, settings.particles);
    passes.particles.sort(camera.position);
    Planned {
        shadows,
        sky_occlusion,
        indirect,
        terrain,
        cull_ms,
    }
}

/// What the frame reads that outlives it.
pub struct FrameInputs<'a> {
    /// The device and queue.
    pub ctx: &'a GpuContext,
    /// Every pass's pipelines.
    pub passes: &'a Passes,
    /// The scene as uploaded.
    pub scene: &'a SceneGpu,
    /// Frame constants: bound wherever a shader names them.
    pub view: &'a wgpu::Buffer,
    /// The lighting uniform (`passes::lighting`), bound by name.
    pub lighting: &'a wgpu::Buffer,
    /// The sky uniform (with the sun disk), bound by name.
    pub sky: &'a wgpu::Buffer,
    /// Sky parameters without the sun disk (environment maps: the sun is lit analytically).
    pub sky_no_disk: &'a wgpu::Buffer,
    /// The probe whose relit cube feeds ambient specular (L3), and whether
    /// its G-buffer cube must be captured this frame; `None`: the sky alone.
    pub probe: Option<(usize, bool)>,
    /// The luminance reduction's buffers.
    pub luminance: &'a LuminanceBuffers,
    /// The post uniform, the adapted luminance and the bloom chain length.
    pub post: PostFrame<'a>,
    /// The texture the frame ends in.
    pub output: &'a wgpu::Texture,
    /// Every temporal ring (AO, colour and buffer TAA), declared beforehand.
    pub history: &'a History,
    /// AO settings; `None` = AO off.
    pub ao: Option<&'a AoSettings>,
    /// Lighting permutation.
    pub lighting_key: LightingKey,
    /// Anti-aliasing after tone mapping.
    pub aa: FrameAa,
}

/// The anti-aliasing of one frame (mode, SMAA subsample, buffer TAAs).
#[derive(Clone, Copy)]
pub struct FrameAa {
    /// The anti-aliasing mode.
    pub mode: AaMode,
    /// SMAA T2x: which of the two subsamples this frame renders.
    pub subsample: u32,
    /// SMAA blending weights only on edge pixels (`FrameSettings::smaa_edge_mask`).
    pub edge_mask: bool,
    /// Buffers with their own TAA (`None`: none).
    pub buffers: Option<AaBuffers>,
}

/// Builds the frame graph; a debug `shown` view replaces tone mapping.
pub fn build<'a>(
    inputs: FrameInputs<'a>,
    size: (u32, u32),
    shown: ViewBuffer,
) -> Result<FrameGraph<'a>, GpuError> {
    let FrameInputs {
        ctx,
        passes,
        scene,
        view,
        lighting,
        sky,
        luminance,
        post,
        output,
        history,
        ao,
        lighting_key,
        sky_no_disk,
        probe,
        aa,
    } = inputs;
    let mut g = FrameGraph::new();
    let constants = [("view", view), ("lighting", lighting), ("sky", sky)];
    g.set_frame_constants(&constants);
    let mip_bias = aa.mode.temporal();
    // V2: the trees' bones before anything draws them.
    passes.vegetation.add(&mut g, scene);
    // Skinned meshes posed into the scene's vertex buffer first.
    passes.skin.add(&mut g, scene);
    // V6: the camera's and the cascades' objects, culled on the GPU.
    // `cull` reads last frame's Hi-Z pyramid (`cull.hiz` writes the other).
    let hiz = passes.cull.hiz.import_read(&mut g);
    let culled = passes.cull.add(&mut g, hiz);
    let visible = Some(&passes.gbuffer.visible);
    // The camera's view: GPU lists, or the CPU twin's pool lists alone.
    let camera_list = culled.filter(|c| {
        let cpu = matches!(c.args, crate::passes::cull::CulledArgs::Cpu { .. });
        passes.gbuffer.visible.gpu_view.is_some() || cpu
    });
    let gbuffer = (passes.gbuffer).add(
        ctx,
        &mut g,
        size,
        scene,
        visible,
        camera_list.map(|c| (c, 0)),
        mip_bias,
    );
    // V1/V3: the alpha-tested cards, then the impostors, each a pass.
    let gbuffer = (passes.gbuffer).add_vegetation(
        ctx,
        &mut g,
        scene,
        visible,
        camera_list.map(|c| (c, 0)),
        gbuffer,
    );
    // The world's terrain after the objects, into the same targets.
    let gbuffer = match &passes.terrain {
        Some(t) => t.add(ctx, &mut g, gbuffer, view),
        None => gbuffer,
    };
    // V4: every tree's occlusion volume multiplies the albedo's alpha (the
    // occlusion of the sky and ambient light) inside its box.
    let gbuffer = match passes.tree_ao.on {
        true => GBuffer {
            albedo: (passes.tree_ao).add(ctx, &mut g, scene, gbuffer.albedo, gbuffer.depth),
            ..gbuffer
        },
        false => gbuffer,
    };
    // Roughness edited after texturing, with E3's screen-space filter: the
    // wet albedo and material replace the G-buffer's for every later reader.
    let gbuffer = if passes.wet.amount > 0.0 {
        passes.wet.add(ctx, &mut g, size, gbuffer)
    } else {
        gbuffer
    };
    // V6 Hi-Z: the pyramid of this depth, for the next frame's `cull`.
    passes.cull.hiz.add(&mut g, gbuffer.depth);
    let terrain = passes
        .terrain
        .as_ref()
        .map(|t| t as &dyn crate::passes::shadows::CascadeCaster);
    let sun_maps = passes
        .shadows
        .add_maps(&mut g, size, gbuffer, scene, culled, terrain);
    let shadow_mask = sun_maps.and_then(|m| m.mask);
    // A3 on other buffers: the stabilised motion replaces the G-buffer's for
    // every later reader (AO TAA, resolve, `--view motion`).
    let stable_motion = match aa.buffers {
        Some(b) if b.motion => Some(passes.aa_buffers.add_motion(
            &mut g,
            gbuffer.motion,
            history,
        )?),
        _ => None,
    };
    let gbuffer = GBuffer {
        motion: stable_motion.unwrap_or(gbuffer.motion),
        ..gbuffer
    };
    // L2: new sectors' height fields and SH2 visibility (side effect: the
    // pool; O6 reads its heights); in a world over the terrain, with the culled pool instances.
    let sources = crate::passes::skyocc::SkyOccSources {
        culled,
        terrain: passes.terrain.as_ref().map(|t| t.heights()),
    };
    let skyocc = passes.skyocc.add(&mut g, scene, sources);
    let ao_targets = match ao {
        Some(settings) => {
            let large_scale = settings.large_scale.then(|| LargeScaleInputs {
                depth: gbuffer.depth,
                frame: gbuffer.frame,
                table: passes.skyocc.bindings().table,
                heights: skyocc.heights,
            });
            let inputs = AoInputs {
                settings,
                depth: gbuffer.depth,
                history,
                large_scale,
            };
            let t = passes.ao.add(ctx, &mut g, size, inputs)?;
            Some(match aa.buffers {
                Some(b) if b.ao => {
                    let jitter_free = stable_motion.is_some();
                    let motion = gbuffer.motion;
                    let ao = passes.aa_buffers.add_ao(
                        ctx,
                        &mut g,
                        t.ao,
                        motion,
                        jitter_free,
                        history,
                    )?;
                    AoTargets { ao, ..t }
                }
                _ => t,
            })
        }
        None => None,
    };
    // O5: the low-frequency albedo for the coloured occlusion (or its view).
    let ao_bleed = ao
        .filter(|s| s.bleed || shown == ViewBuffer::Ao(AoView::Bleed))
        .map(|_| (passes.ao_bleed).add(&mut g, size, gbuffer.albedo, gbuffer.depth));
    // L5: SH probes for this sky and sun, injected around the camera (the
    // relit environment cube reads them too).
    let indirect = match lighting_key.indirect {
        true => passes.indirect.add(&mut g).map(|f| (&passes.indirect, f)),
        false => None,
    };
    let env = match probe {
        // L3: the probe's G-buffer cube relit with the lighting and sky
        // passes (sun unshadowed, sky unoccluded), then mipped and filtered.
        Some(probe) if passes.envmap.dirty => {
            let edge = (passes.probes.size, passes.probes.size);
            let gbuffer = |g: &mut FrameGraph<'a>| {
                let opaque = passes.gbuffer.add(ctx, g, edge, scene, None, None, false);
                passes
                    .gbuffer
                    .add_vegetation(ctx, g, scene, None, None, opaque)
            };
            let relight = |g: &mut FrameGraph<'a>, stored: GBuffer, env_before| {
                let inputs = LightingInputs {
                    shadow_mask: None,
                    ao: None,
                    ao_dir: None,
                    ao_params: passes.ao.params(),
                    ao_bleed: None,
                    lights: &passes.shadows.local_lights,
                    envmap: &passes.envmap,
                    env: env_before,
                    skyocc: &passes.skyocc,
                    skyocc_frame: skyocc,
                    // L3 + L5: the talk's "indirect light from the nearest
                    // probe" - here the clip map at each cube texel.
                    indirect,
                    key: LightingKey {
                        indirect: indirect.is_some(),
                        ..LightingKey::RELIGHT
                    },
                };
                let hdr = passes.lighting.add(ctx, g, edge, stored, inputs);
                passes.sky.add(g, hdr, stored.depth, Some(sky_no_disk))
            };
            let envmap = &passes.envmap;
            passes
                .probes
                .add_relight(&mut g, envmap, probe, gbuffer, relight)
        }
        // L1: the Bruneton sky is captured by the sky pass from its tables.
        _ if passes.envmap.dirty && !passes.envmap.fixed_source && passes.sky.draws_bruneton() => {
            let source = passes.envmap.import_source(&mut g);
            let edge = passes.envmap.size;
            let source = passes.sky.add_capture(&mut g, source, edge, sky_no_disk)?;
            passes.envmap.add_mips_and_filter(&mut g, source)
        }
        _ => passes.envmap.add(&mut g, sky_no_disk),
    };
    if matches!(shown, ViewBuffer::Indirect(_)) && indirect.is_none() {
        return Err(GpuError::Other(
            "--view indirect, probe-cells and clipmap need --indirect on and baked probe cells"
                .into(),
        ));
    }
    let lighting_key = LightingKey {
        indirect: indirect.is_some(),
        indirect_view: indirect.is_some() && lighting_key.indirect_view,
        ..lighting_key
    };
    let lighting_inputs = LightingInputs {
        shadow_mask,
        ao: ao_targets.map(|t| t.ao),
        ao_dir: ao_targets.and_then(|t| t.dir),
        ao_params: passes.ao.params(),
        ao_bleed,
        lights: &passes.shadows.local_lights,
        envmap: &passes.envmap,
        env,
        skyocc: &passes.skyocc,
        skyocc_frame: skyocc,
        indirect,
        key: lighting_key,
    };
    let hdr = passes
        .lighting
        .add(ctx, &mut g, size, gbuffer, lighting_inputs);
    let hdr = passes.sky.add(&mut g, hdr, gbuffer.depth, None);
    // glTF emission, layers, transmission and alpha BLEND surfaces (passes/forward).
    let forward = ForwardInputs {
        scene,
        envmap: &passes.envmap,
        env,
        shadow_mask,
        ao: ao_targets.map(|t| t.ao),
        ambient_lights: &passes.lighting.ambient_lights.buffer,
        sun_maps,
        shadow_params: passes.shadows.mask_params(),
        shadow_sampler: &passes.shadows.sampler,
        lights: &passes.shadows.local_lights,
        light_tiles: passes.shadows.light_tiles(),
    };
    let forward = passes.forward.add(ctx, &mut g, hdr, gbuffer.depth, forward);
    let hdr = forward.hdr;
    // E4: particles simulated (their state outlives the frame), lit once
    // each, drawn over the HDR after the forward surfaces.
    let particle_inputs = crate::passes::particles::ParticleInputs {
        lights: &passes.shadows.local_lights,
        light_tiles: passes.shadows.light_tiles(),
        shadow_params: passes.shadows.mask_params(),
        shadow_sampler: &passes.shadows.sampler,
        sun_maps,
        envmap: &passes.envmap,
        env,
        ambient_lights: &passes.lighting.ambient_lights.buffer,
    };
    let (hdr, reactive) = match passes.particles.add_simulate(&mut g) {
        Some(state) => {
            let p = &passes.particles;
            match p.add_light(&mut g, state, particle_inputs) {
                Some(light) => {
                    let order = p.add_sort(&mut g, state).unwrap_or(state);
                    let buffers = (state, light, order);
                    p.add_draw(ctx, &mut g, hdr, forward.depth, buffers, particle_inputs)
                }
                None => (hdr, None),
            }
        }
        None => (hdr, None),
    };
    // Transmissive surfaces wrote their depth: later readers see them.
    let gbuffer = GBuffer {
        depth: forward.depth,
        ..gbuffer
    };
    let measured = passes.luminance.add(&mut g, hdr, size, luminance);
    let exposure = if post.adaptation {
        passes
            .adapt
            .add(&mut g, measured, post.adapted, post.uniform)
    } else {
        measured
    };
    let bloom_inputs = BloomInputs {
        post: post.uniform,
        exposure,
    };
    let bloom = post
        .bloom_passes
        .map(|n| passes.bloom.add(ctx, &mut g, hdr, bloom_inputs, n));
    let post_inputs = PostInputs {
        post: post.uniform,
        exposure,
        bloom,
        sampler: &passes.bloom.sampler,
    };
    let out = g.import_texture("output", output);
    let out = match shown {
        ViewBuffer::Final | ViewBuffer::ParticleLighting => {
            let chain = AaFrame {
                mode: aa.mode,
                subsample: aa.subsample,
                edge_mask: aa.edge_mask,
                history,
                smaa: &passes.smaa,
                temporal: &passes.temporal,
                depth: gbuffer.depth,
                normals: gbuffer.frame,
                motion: gbuffer.motion,
                motion_jitter_free: stable_motion.is_some(),
                reactive: reactive.filter(|_| passes.particles.reactive),
            };
            let tonemap = |g: &mut FrameGraph<'a>, target| {
                passes
                    .tonemap
                    .add(ctx, g, post.tonemap, hdr, post_inputs, target)
            };
            crate::passes::aa::add_chain(ctx, &mut g, chain, out, tonemap)?
        }
        ViewBuffer::Ao(AoView::Bleed) => {
            let b = ao_bleed.ok_or_else(|| {
                GpuError::Other("--view ao-bleed needs AO on (--ao hbao or hbao+stf)".into())
            })?;
            passes.ao_bleed.add_view(ctx, &mut g, b, out)
        }
        ViewBuffer::Ao(v) => {
            let t = ao_targets.ok_or_else(|| {
                GpuError::Other("AO views need AO on (--ao hbao or hbao+stf)".into())
            })?;
            passes.ao.add_view(ctx, &mut g, v, t, out)
        }
        ViewBuffer::Shadow(v) => {
            let m = shadow_mask.ok_or_else(|| {
                GpuError::Other("shadow views need shadows on (--shadows csm or csm+static)".into())
            })?;
            passes
                .shadows
                .add_view(ctx, &mut g, v, m, gbuffer.depth, out)
        }
        ViewBuffer::Env(v) => {
            let envmap = &passes.envmap;
            passes
                .env_view
                .add(ctx, &mut g, v, gbuffer, env, envmap, post_inputs, out)
        }
        ViewBuffer::SkyOcc(v) => passes.skyocc.add_view(ctx, &mut g, v, skyocc, gbuffer, out),
        ViewBuffer::Debug(v) => passes
            .debug
            .add(ctx, &mut g, v, gbuffer, hdr, post_inputs, out),
        ViewBuffer::TreeAo => (passes.tree_ao).add_view(ctx, &mut g, scene, gbuffer.depth, out),
        // The lighting pass wrote the probes' irradiance (INDIRECT_VIEW).
        ViewBuffer::Indirect(_) => {
            let lighting = crate::passes::debug::DebugView::Lighting;
            (passes.debug).add(ctx, &mut g, lighting, gbuffer, hdr, post_inputs, out)
        }
    };
    g.mark_output(out);
    Ok(g)
}
