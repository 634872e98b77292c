//! [`Renderer`]: owns the device, the scene on the GPU, every pass's
//! pipelines and the state kept between frames; renders one frame per call.

mod draw;
pub mod environment;
pub mod post_state;
mod world;
pub use world::{StreamTimes, WorldFrame, WorldState, world_pools};

use std::collections::HashMap;

use glam::Mat4;

use crate::Error;
use crate::frame::{self, FrameInputs, Passes};
use crate::gpu::pipeline::uniform_buffer;
use crate::gpu::{GpuContext, GpuError, TextureData, read_texture};
use crate::gpu_scene::SceneGpu;
use crate::gpu_scene::uniforms::{LightingUniform, ViewUniform};
use crate::graph::{History, PassTimer, PassTiming, TexturePool};
use crate::math::sh::Sh9Gpu;
use crate::passes::ao::AoMode;
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::GBufferKey;
use crate::passes::lighting::LightingKey;
use crate::passes::post::{BloomSettings, LuminanceBuffers};
use crate::passes::shadows::ShadowStats;
use crate::passes::sky::{SkyGpuParams, SkyLight, SkyModel};
use crate::scene::{Camera, Scene, SunDesc};
pub use crate::settings::{
    DEFAULT_SHADOW_RESOLUTION, DISPLAY_FORMAT, FrameSettings, RAW_FORMAT, ViewBuffer,
};
use post_state::PostState;

use draw::prepare_view;
pub use draw::{CpuTimes, DrawnCounts, DrawnFrame, RenderedFrame};

/// GPU resources the frame graph borrows (everything but the pool and timer,
/// which execution borrows mutably).
struct Resources {
    passes: Passes,
    scene: SceneGpu,
    view_buffer: wgpu::Buffer,
    lighting_buffer: wgpu::Buffer,
    sky_buffer: wgpu::Buffer,
    sky_no_disk_buffer: wgpu::Buffer,
    /// The probe feeding ambient specular (L3), `None`: the sky alone.
    active_probe: Option<usize>,
    luminance: Option<((u32, u32), LuminanceBuffers)>,
    post: PostState,
    outputs: HashMap<(u32, u32, wgpu::TextureFormat), wgpu::Texture>,
    /// Every temporal ring (AO, colour TAA, buffer TAA), swapped after submit.
    history: History,
    /// An HDR environment instead of the physical sky (issue #8).
    environment: Option<environment::EnvironmentGpu>,
}

impl Resources {
    fn inputs<'a>(
        &'a self,
        ctx: &'a GpuContext,
        settings: &'a FrameSettings,
        format: wgpu::TextureFormat,
        frame_index: u64,
    ) -> Option<FrameInputs<'a>> {
        let size = (settings.width, settings.height);
        Some(FrameInputs {
            ctx,
            passes: &self.passes,
            scene: &self.scene,
            view: &self.view_buffer,
            lighting: &self.lighting_buffer,
            sky: &self.sky_buffer,
            luminance: &self.luminance.as_ref()?.1,
            post: self.post.frame(settings),
            output: self.outputs.get(&(size.0, size.1, format))?,
            history: &self.history,
            ao: (settings.ao.mode != AoMode::Off).then_some(&settings.ao),
            lighting_key: lighting_key(settings, self.environment.is_some()),
            sky_no_disk: &self.sky_no_disk_buffer,
            probe: self
                .active_probe
                .map(|p| (p, !self.passes.probes.probes[p].captured)),
            aa: crate::frame::FrameAa {
                mode: settings.aa,
                subsample: settings.aa.smaa_subsample(frame_index),
                edge_mask: settings.smaa_edge_mask,
                buffers: settings.aa_buffers.any().then_some(settings.aa_buffers),
            },
        })
    }
}

/// The lighting permutation a frame with `settings` draws with.
/// (Aerial perspective fades toward the Preetham sky: none under an HDR environment.)
fn lighting_key(settings: &FrameSettings, environment: bool) -> LightingKey {
    LightingKey {
        shadows: settings.shadow_resolution > 0,
        fog: settings.aerial_extinction > 0.0 && !environment,
        ssao: settings.ao.mode != AoMode::Off,
        env_specular: settings.environment_specular,
        // O6 occludes the sky from the same height field: not twice.
        sky_occlusion: settings.sky_occlusion && !settings.ao.large_scale_on(),
        ssdo: settings.ao.mode.directional(),
        reflection_occlusion: settings.ao.reflection_occlusion,
        ao_bleed: settings.ao.mode != AoMode::Off && settings.ao.bleed,
        // L5 transfers the analytic sky and sun, or an HDR environment's upper half.
        indirect: settings.indirect,
        indirect_view: matches!(settings.view, crate::settings::ViewBuffer::Indirect(_)),
    }
}

/// The renderer: the GPU context, the scene uploaded to it, every pass
/// and the state carried between frames (previous view-projection and
/// jitter, anti-aliasing history, sky tables, the streamed world).
pub struct Renderer {
    ctx: GpuContext,
    res: Resources,
    pool: TexturePool,
    timer: Option<PassTimer>,
    prev_view_proj: Option<Mat4>,
    /// Sample offset (px) inside `prev_view_proj`: passes that reproject
    /// with the matrices take it out (jitter-free motion).
    prev_jitter: [f32; 2],
    /// Animation time of the previous frame (`None`: first frame or after a cut).
    prev_time: Option<f32>,
    frame_index: u64,
    sky_light: Option<(SunDesc, SkyModel, SkyLight)>,
    /// GPU times of the sky tables / SH projection run before the next frame (L1).
    sky_timings: Vec<PassTiming>,
    /// Submit each pass alone and time it by the wall clock (bench).
    isolate_passes: bool,
    /// Directory of the Bruneton table cache file (`None`: compute each run).
    sky_table_cache: Option<std::path::PathBuf>,
    sky_table_sizes: crate::passes::sky::bruneton::TableSizes,
    /// Anti-aliasing mode of the previous frame (a change restarts the history).
    aa_last: Option<crate::passes::aa::AaMode>,
    /// Sample offset of the last frame written to the colour TAA's ring.
    aa_last_jitter: [f32; 2],
    /// The streamed open world (`Renderer::with_world`).
    world: Option<world::WorldState>,
}

/// The largest single texture the renderer asks a driver for (bytes).
const MAX_TEXTURE_BYTES: u64 = 2 << 30;

impl Renderer {
    /// Creates every pipeline and uploads the scene.
    pub fn new(ctx: GpuContext, scene: &Scene) -> Result<Self, Error> {
        let scene_gpu = SceneGpu::upload(&ctx, scene)?;
        Self::from_upload(ctx, scene, scene_gpu)
    }

    /// Creates every pipeline for `scene`, uploaded as `scene_gpu`.
    fn from_upload(ctx: GpuContext, scene: &Scene, scene_gpu: SceneGpu) -> Result<Self, Error> {
        let mut passes = Passes::new(&ctx, scene, &scene_gpu)?;
        // Pre-warm the scene's permutations: a bad one fails here, not mid-frame.
        for key in crate::passes::forward::ForwardKey::for_scene(&scene_gpu, true, (true, true)) {
            passes.forward.pipeline(&ctx, key)?;
        }
        for key in GBufferKey::for_scene(&scene_gpu, false, true) {
            passes.gbuffer.pipeline(&ctx, key)?;
        }
        if !scene.probes.is_empty() {
            passes.lighting.pipeline(&ctx, LightingKey::RELIGHT)?;
        }
        let environment = match &scene.environment {
            Some(desc) => {
                let env = environment::EnvironmentGpu::new(&ctx, desc, &mut passes.envmap)?;
                passes
                    .sky
                    .set_environment(&ctx, &env.view, &env.sampler, env.rotation)?;
                Some(env)
            }
            None => None,
        };
        let view_buffer =
            uniform_buffer(&ctx, "view", &bytemuck::Zeroable::zeroed() as &ViewUniform);
        let lighting_buffer = uniform_buffer(
            &ctx,
            "lighting",
            &bytemuck::Zeroable::zeroed() as &LightingUniform,
        );
        // Filled by `update_sky` before the first frame.
        let sky_buffer =
            uniform_buffer(&ctx, "sky", &<SkyGpuParams as bytemuck::Zeroable>::zeroed());
        let sky_no_disk_buffer = uniform_buffer(
            &ctx,
            "sky.no_disk",
            &<SkyGpuParams as bytemuck::Zeroable>::zeroed(),
        );
        // A probe capture adds 30 passes (6 faces x G-buffer, store, relight,
        // sky, mirror) and 13 for mips and filter, sky occlusion up to 36
        // (two height fields per sector), to the shadow, AO, lighting and
        // post passes.
        let timer = PassTimer::new(&ctx.device, &ctx.queue, 256);
        let post = PostState::new(&ctx);
        Ok(Self {
            ctx,
            res: Resources {
                passes,
                scene: scene_gpu,
                view_buffer,
                lighting_buffer,
                sky_buffer,
                sky_no_disk_buffer,
                active_probe: None,
                luminance: None,
                post,
                outputs: HashMap::new(),
                history: History::new(),
                environment,
            },
            pool: TexturePool::new(),
            timer,
            prev_view_proj: None,
            prev_jitter: [0.0, 0.0],
            prev_time: None,
            frame_index: 0,
            sky_light: None,
            sky_timings: Vec::new(),
            isolate_passes: false,
            sky_table_cache: None,
            sky_table_sizes: crate::passes::sky::bruneton::TableSizes::DEFAULT,
            aa_last: None,
            aa_last_jitter: [0.0, 0.0],
            world: None,
        })
    }

    /// The sky occlusion pass (L2), for tests and tools.
    pub fn sky_occlusion(&self) -> &crate::passes::skyocc::SkyOccPass {
        &self.res.passes.skyocc
    }

    /// The sun shadows (S1-S4), for tests and tools.
    pub fn shadows(&self) -> &crate::passes::shadows::ShadowPass {
        &self.res.passes.shadows
    }

    /// The particles (E4): their simulation and buffers, for tests and tools.
    pub fn particles(&self) -> &crate::passes::particles::ParticlesPass {
        &self.res.passes.particles
    }

    /// The world's terrain (`None`: a plain scene), for tests and tools.
    pub fn terrain(&self) -> Option<&crate::passes::terrain::TerrainPass> {
        self.res.passes.terrain.as_ref()
    }

    /// The environment cube and DFG table (L4), for tests and tools.
    /// The environment-map pass (filtered cube, DFG table), for tests and
    /// tools that read its textures.
    pub fn envmap(&self) -> &EnvMapPass {
        &self.res.passes.envmap
    }

    /// The device and queue the renderer draws with.
    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    /// Triangles of every scene object at LOD0 (the uploaded scene, before
    /// culling or LOD selection).
    pub fn scene_triangles(&self) -> u64 {
        self.res.scene.triangles
    }

    /// Bytes held by the scene's buffers, the transient texture pool,
    /// each history ring (by its name), the probes' and the particles'
    /// persistent buffers.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let mut rows = vec![
            ("scene buffers".to_string(), self.res.scene.bytes),
            (
                "frame targets (pool)".to_string(),
                self.pool.allocated_bytes(),
            ),
        ];
        rows.extend(self.res.history.memory());
        let hiz = self.res.passes.cull.hiz.bytes();
        if hiz > 0 {
            rows.push(("cull.hiz (2 pyramids)".to_string(), hiz));
        }
        rows.extend(self.res.passes.indirect.memory());
        rows.extend(self.res.passes.particles.memory());
        rows
    }

    /// Plays glTF animation `name` from the next frame on (`None`: the rest
    /// pose); see [`crate::scene::Scene::set_animation`], whose check of the
    /// name the caller makes.
    pub fn set_animation(&mut self, name: Option<&str>) {
        self.res.scene.set_animation(name);
        self.res.passes.particles.sim.set_animation(name);
    }

    /// Forgets the previous frame (camera cut): motion vectors become zero,
    /// the next frame starts adapted, every history ring starts again.
    pub fn reset_history(&mut self) {
        self.prev_view_proj = None;
        self.prev_time = None;
        self.res.post.reset = true;
        self.res.history.reset();
        self.res.passes.cull.hiz.reset();
        self.res.passes.vegetation.reset();
    }

    /// E1 pre-warm: fetches every pipeline permutation a frame of this
    /// renderer can ask for (tone-map and lighting variants, bloom passes,
    /// debug views in both formats; the G-buffer permutations of the scene's
    /// material types were fetched by [`Renderer::new`]), so none compiles
    /// mid-sequence. Save the cache after it
    /// with [`GpuContext::save_pipeline_cache`].
    pub fn prewarm(&mut self) -> Result<(), Error> {
        let (ctx, passes) = (&self.ctx, &mut self.res.passes);
        for key in crate::passes::post::TonemapKey::all() {
            passes.tonemap.pipeline(ctx, key)?;
        }
        for k in 0..BloomSettings::MAX_PASSES {
            passes.bloom.blur_pipeline(ctx, k)?;
        }
        for key in LightingKey::all() {
            passes.lighting.pipeline(ctx, key)?;
        }
        // O4: `--ao ssdo`'s steps (otherwise made on its first frame).
        passes.ao.prewarm_ssdo(ctx)?;
        // E3: `--specular-aa on|off` both ready (the renderer made the on ones).
        for specular_aa in [true, false] {
            for key in GBufferKey::for_scene(&self.res.scene, true, specular_aa) {
                passes.gbuffer.pipeline(ctx, key)?;
            }
            // forward.blend: shadows and fog on or off.
            for lit in [(true, true), (true, false), (false, true), (false, false)] {
                let keys = crate::passes::forward::ForwardKey::for_scene(
                    &self.res.scene,
                    specular_aa,
                    lit,
                );
                for key in keys {
                    passes.forward.pipeline(ctx, key)?;
                }
            }
        }
        // E4: per-particle and per-pixel lighting, white or not, either ambient.
        for key in crate::passes::particles::ParticleKey::all() {
            passes.particles.draw_pipeline(ctx, key)?;
        }
        // V4: the decal into the G-buffer albedo and into its view's factor.
        for format in [
            crate::passes::gbuffer::ALBEDO_FORMAT,
            crate::passes::tree_ao::FACTOR_FORMAT,
        ] {
            passes.tree_ao.pipeline(ctx, format)?;
        }
        for name in ViewBuffer::NAMES {
            for format in [DISPLAY_FORMAT, RAW_FORMAT] {
                prepare_view(ctx, passes, name.parse()?, format)?;
            }
        }
        Ok(())
    }

    /// Reads back the exposure state (outside the frame; for tests and logs):
    /// (last frame's log-average luminance, adapted luminance). The adapted
    /// value is the last adapted frame's (stale while adaptation is off).
    pub fn exposure_state(&self) -> Result<(f32, f32), Error> {
        let read = |buffer: &wgpu::Buffer, i: usize| -> Result<f32, Error> {
            let bytes = crate::gpu::read_buffer(&self.ctx, buffer)?;
            let v: &[f32] = bytemuck::try_cast_slice(&bytes[..16])
                .map_err(|e| Error::InvalidSettings(format!("exposure buffer: {e}")))?;
            Ok(v[i])
        };
        let l_avg = match &self.res.luminance {
            Some((_, buffers)) => read(&buffers.result, 1)?,
            None => 0.0,
        };
        Ok((l_avg, read(&self.res.post.adapted, 1)?))
    }

    fn validate(&self, settings: &FrameSettings) -> Result<(), Error> {
        // Every size that becomes a texture edge, against this adapter's limit.
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        if settings.width == 0
            || settings.height == 0
            || settings.width > max
            || settings.height > max
        {
            return Err(Error::InvalidSettings(format!(
                "frame size {}x{} is outside 1x1..{max}x{max} (this adapter's \
                 largest 2D texture is {max} texels on a side)",
                settings.width, settings.height
            )));
        }
        settings.ao.validate()?;
        settings.shadows.validate()?;
        let shadows = [
            ("shadow resolution", settings.shadow_resolution),
            (
                "static shadow resolution",
                settings.shadows.static_resolution,
            ),
        ];
        for (what, edge) in shadows {
            if edge > max {
                return Err(Error::InvalidSettings(format!(
                    "{what} {edge} exceeds this adapter's limit of {max} texels on a side"
                )));
            }
        }
        // The four cascades are one Depth32Float array: drivers refuse (or
        // fail to back) single allocations past a few GiB.
        let cascades = 4 * 4 * u64::from(settings.shadow_resolution).pow(2);
        if cascades > MAX_TEXTURE_BYTES {
            return Err(Error::InvalidSettings(format!(
                "shadow resolution {} needs {:.1} GiB for the four cascades (one texture), \
                 above the {} GiB one texture may take; use at most {}",
                settings.shadow_resolution,
                cascades as f64 / f64::from(1u32 << 30),
                MAX_TEXTURE_BYTES >> 30,
                ((MAX_TEXTURE_BYTES / 16) as f64).sqrt() as u64,
            )));
        }
        let shadows_off = settings.shadow_resolution == 0
            || settings.shadows.mode == crate::passes::shadows::ShadowMode::Off;
        if matches!(settings.view, ViewBuffer::Shadow(_)) && shadows_off {
            return Err(Error::InvalidSettings(
                "the shadow views need shadows on (--shadows csm or csm+static)".into(),
            ));
        }
        if matches!(settings.view, ViewBuffer::Ao(_)) && settings.ao.mode == AoMode::Off {
            return Err(Error::InvalidSettings(
                "the AO views need AO on (--ao hbao or hbao+stf)".into(),
            ));
        }
        post_state::validate(settings)
    }

    fn update_sky(&mut self, sun: &SunDesc, model: SkyModel) -> Result<(), Error> {
        self.res.passes.sky.model = model;
        if self
            .sky_light
            .as_ref()
            .is_some_and(|(k, m, _)| k == sun && *m == model)
        {
            return Ok(());
        }
        let mut light = SkyLight::of_sun(sun);
        // L1: Bruneton tables once per renderer, their sky SH (and the moon) per time of day.
        if model == SkyModel::Bruneton && self.res.environment.is_none() {
            self.prepare_bruneton()?;
            if let Some(b) = self.res.passes.sky.bruneton() {
                let t = b.update_light(&self.ctx, &mut light, self.timer.as_mut())?;
                self.sky_timings.extend(t);
            }
            // A stand-in light stays itself (no moon when it points up).
            if let Some(l) = &sun.light {
                light.sun_direction = l.to_light;
                light.sun_illuminance = l.illuminance_klux;
            }
        }
        let params = light.sky.gpu_params();
        self.ctx
            .queue
            .write_buffer(&self.res.sky_buffer, 0, bytemuck::bytes_of(&params));
        let mut no_disk = params;
        no_disk.sun_disk[2] = 0.0;
        self.ctx.queue.write_buffer(
            &self.res.sky_no_disk_buffer,
            0,
            bytemuck::bytes_of(&no_disk),
        );
        // L5: the sky (or the environment) and sun the probes transfer, and the ground they replace.
        let indirect = match &self.res.environment {
            Some(env) => crate::passes::indirect::IndirectLight::of_environment(
                &env.above_horizon,
                &env.ground_irradiance,
                light.sun_direction,
                if env.sun {
                    light.sun_illuminance
                } else {
                    glam::Vec3::ZERO
                },
            ),
            None => crate::passes::indirect::IndirectLight::of_sky(&light),
        };
        self.res.passes.indirect.set_light(indirect);
        self.sky_light = Some((sun.clone(), model, light));
        self.res.passes.envmap.dirty = true;
        Ok(())
    }

    /// L5: the probe cells set with [`Renderer::set_probe_cells`].
    pub fn probe_cells(&self) -> Option<&std::sync::Arc<dyn crate::passes::indirect::CellSource>> {
        self.res.passes.indirect.store()
    }

    /// L5: the probe cells to stream indirect light from (a scene's
    /// `ProbeStore::bake`, or the world's `WorldProbes`); `None` turns it
    /// off whatever the settings say.
    pub fn set_probe_cells(
        &mut self,
        store: Option<std::sync::Arc<dyn crate::passes::indirect::CellSource>>,
    ) {
        self.res.passes.indirect.set_store(store);
    }

    /// L1: draws and lights the Bruneton sky from `tables` (made on this
    /// renderer's context) instead of computing the default tables on first use.
    pub fn set_bruneton_tables(
        &mut self,
        tables: crate::passes::sky::bruneton::BrunetonTables,
    ) -> Result<(), Error> {
        self.sky_table_sizes = tables.config.sizes;
        self.res.passes.sky.set_bruneton(&self.ctx, tables)?;
        self.sky_light = None;
        Ok(())
    }

    /// With `on`, each following frame submits every pass alone, waits for
    /// it and reports its wall time in [`DrawnFrame::isolated`] (a
    /// measurement for compute passes whose timestamps are not credible;
    /// the frame is slower, its image the same).
    pub fn set_isolated_timing(&mut self, on: bool) {
        self.isolate_passes = on;
    }

    /// L1: the Bruneton table sizes (default [`TableSizes::DEFAULT`]); other
    /// sizes are loaded from the table cache or computed at the next frame.
    ///
    /// [`TableSizes::DEFAULT`]: crate::passes::sky::bruneton::TableSizes::DEFAULT
    pub fn set_sky_table_sizes(&mut self, sizes: crate::passes::sky::bruneton::TableSizes) {
        if sizes != self.sky_table_sizes {
            self.sky_table_sizes = sizes;
            self.sky_light = None;
        }
    }

    /// L1: loads / stores the Bruneton tables in `dir` (e.g. the pipeline
    /// cache directory) instead of computing them in every process.
    pub fn set_sky_table_cache(&mut self, dir: Option<std::path::PathBuf>) {
        self.sky_table_cache = dir;
    }

    /// L1: loads (from the table cache) or computes the Bruneton tables once
    /// and creates the sky pass's Bruneton pipelines (`himal prewarm`; the
    /// first Bruneton frame does it otherwise).
    pub fn prepare_bruneton(&mut self) -> Result<(), Error> {
        let cache = self.sky_table_cache.as_deref();
        let sizes = self.sky_table_sizes;
        let sky = &mut self.res.passes.sky;
        let t = sky.prepare_bruneton(&self.ctx, sizes, cache, self.timer.as_mut())?;
        self.sky_timings.extend(t);
        Ok(())
    }

    /// The Bruneton tables once computed or set (L1).
    pub fn bruneton_tables(&self) -> Option<&crate::passes::sky::bruneton::BrunetonTables> {
        self.res.passes.sky.bruneton().map(|b| &b.tables)
    }

    /// The sky light of the last frame (L1): sun and sky SH, for tests and tools.
    pub fn sky_light(&self) -> Option<&SkyLight> {
        self.sky_light.as_ref().map(|(_, _, l)| l)
    }

    /// The compiled pass list of the first frame with these settings from
    /// a camera at the origin looking down -Z (`himal render --graph`): the
    /// same planning as [`Renderer::draw`], nothing submitted.
    pub fn describe_graph(&mut self, settings: &FrameSettings) -> Result<String, Error> {
        self.validate(settings)?;
        let size = (settings.width, settings.height);
        let camera = Camera::look_at(glam::Vec3::ZERO, glam::Vec3::NEG_Z, 60.0);
        let format = self.plan_frame(&camera, settings)?.format;
        let inputs = self
            .res
            .inputs(&self.ctx, settings, format, self.frame_index)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        let listing = frame::build(inputs, size, settings.view)
            .map_err(Error::from)
            .and_then(|g| Ok(g.compile()?.describe()));
        // Nothing ran: the planned sky-occlusion sectors and history stay unwritten.
        self.res.history.discard();
        self.res.passes.skyocc.invalidate();
        listing
    }
}
