//! [`Renderer`]: owns the device, the scene on the GPU, every pass's
//! pipelines and the state kept between frames; renders one frame per call.

pub mod environment;
pub mod post_state;
pub mod scene_gpu;
pub mod settings;
pub mod textures;
pub mod uniforms;

use std::collections::HashMap;

use glam::{Mat4, Vec3, Vec4};

use crate::Error;
use crate::frame::{self, FrameErrors, FrameInputs, Passes};
use crate::gpu::pipeline::uniform_buffer;
use crate::gpu::{GpuContext, GpuError, TextureData, read_texture};
use crate::graph::{PassTimer, PassTiming, TexturePool};
use crate::math::sh::Sh9Gpu;
use crate::passes::ao::{AoHistory, AoMode, AoPass, AoUniform};
use crate::passes::debug::DebugPass;
use crate::passes::envmap::probe::ProbeSet;
use crate::passes::envmap::{ENVMAP_SIZE, EnvMapPass, EnvViewPass};
use crate::passes::gbuffer::{GBufferKey, GBufferPass};
use crate::passes::lighting::{LightingKey, LightingPass};
use crate::passes::post::{
    AdaptPass, BloomPass, BloomSettings, LuminanceBuffers, LuminancePass, TonemapPass,
};
use crate::passes::shadows::{ShadowPass, ShadowStats};
use crate::passes::sky::{SkyGpuParams, SkyLight, SkyModel, SkyPass};
use crate::scene::{Camera, Scene, SunDesc};
use post_state::PostState;
use scene_gpu::SceneGpu;
pub use settings::{
    DEFAULT_SHADOW_RESOLUTION, DISPLAY_FORMAT, FrameSettings, RAW_FORMAT, ViewBuffer,
};
use uniforms::{LightingUniform, ViewUniform};

/// One rendered frame read back to the CPU.
pub struct RenderedFrame {
    pub image: TextureData,
    /// GPU time per pass (empty where the adapter has no timestamps).
    pub timings: Vec<PassTiming>,
    /// Shadow draw calls and what the shadow passes rendered.
    pub shadows: ShadowStats,
    /// Sky occlusion sectors wanted, rendered this frame, resident (L2).
    pub sky_occlusion: crate::passes::skyocc::SkyOccStats,
}

/// Fetches the pipeline that draws `view` into `format` (none for `Final`).
fn prepare_view(
    ctx: &GpuContext,
    passes: &mut Passes,
    view: ViewBuffer,
    format: wgpu::TextureFormat,
) -> Result<(), GpuError> {
    match view {
        ViewBuffer::Debug(v) => passes.debug.prepare(ctx, v, format),
        ViewBuffer::Ao(v) => passes.ao.prepare_view(ctx, v, format),
        ViewBuffer::Shadow(v) => passes.shadows.prepare_view(ctx, v, format),
        ViewBuffer::Env(v) => passes.env_view.prepare(ctx, v, format),
        ViewBuffer::SkyOcc(v) => passes.skyocc.prepare_view(ctx, v, format),
        ViewBuffer::Final => Ok(()),
    }
}

/// One frame drawn into [`Renderer::output`], left on the GPU (a viewer
/// presents it without a read-back).
pub struct DrawnFrame {
    /// GPU time per pass (empty where the adapter has no timestamps).
    pub timings: Vec<PassTiming>,
    /// Shadow draw calls and what the shadow passes rendered.
    pub shadows: ShadowStats,
    /// Sky occlusion sectors wanted, rendered this frame, resident (L2).
    pub sky_occlusion: crate::passes::skyocc::SkyOccStats,
}

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
    shadow_placeholder: wgpu::Texture,
    ao_history: Option<AoHistory>,
    ao_placeholder: wgpu::Texture,
    aa_history: Option<crate::passes::aa::AaHistory>,
    /// History of the TAA on the AO and motion buffers (`--aa-buffers`).
    aa_buffer_history: Option<crate::passes::aa::BufferHistory>,
    /// An HDR environment instead of the physical sky (issue #8).
    environment: Option<environment::EnvironmentGpu>,
}

impl Resources {
    fn inputs<'a>(
        &'a self,
        settings: &'a FrameSettings,
        format: wgpu::TextureFormat,
        frame_index: u64,
        errors: &'a FrameErrors,
    ) -> Option<FrameInputs<'a>> {
        let size = (settings.width, settings.height);
        Some(FrameInputs {
            passes: &self.passes,
            scene: &self.scene,
            view: &self.view_buffer,
            lighting: &self.lighting_buffer,
            sky: &self.sky_buffer,
            luminance: &self.luminance.as_ref()?.1,
            post: self.post.frame(settings),
            output: self.outputs.get(&(size.0, size.1, format))?,
            shadow_placeholder: &self.shadow_placeholder,
            ao: match (settings.ao.mode, &self.ao_history) {
                (AoMode::Off, _) | (_, None) => None,
                (_, Some(h)) => Some((&settings.ao, h)),
            },
            ao_placeholder: &self.ao_placeholder,
            lighting_key: lighting_key(settings, self.environment.is_some()),
            sky_no_disk: &self.sky_no_disk_buffer,
            probe: self
                .active_probe
                .map(|p| (p, !self.passes.probes.probes[p].captured)),
            aa: crate::frame::FrameAa {
                mode: settings.aa,
                subsample: settings.aa.smaa_subsample(frame_index),
                history: self.aa_history.as_ref().filter(|_| settings.aa.temporal()),
                buffers: self
                    .aa_buffer_history
                    .as_ref()
                    .filter(|_| settings.aa_buffers.any())
                    .map(|h| (settings.aa_buffers, h)),
            },
            errors,
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
        sky_occlusion: settings.sky_occlusion,
    }
}

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
    sky_light: Option<(SunKey, SkyModel, SkyLight)>,
    /// GPU times of the sky tables / SH projection run before the next frame (L1).
    sky_timings: Vec<PassTiming>,
    /// Directory of the Bruneton table cache file (`None`: compute each run).
    sky_table_cache: Option<std::path::PathBuf>,
    /// Anti-aliasing mode of the previous frame (a change restarts the history).
    aa_last: Option<crate::passes::aa::AaMode>,
}

#[derive(Clone, Copy, PartialEq)]
struct SunKey(f32, f32, u32, f32);

impl Renderer {
    /// Creates every pipeline and uploads the scene.
    pub fn new(ctx: GpuContext, scene: &Scene) -> Result<Self, Error> {
        let mut passes = Passes {
            shadows: ShadowPass::new(&ctx, scene)?,
            gbuffer: GBufferPass::new(&ctx)?,
            ao: AoPass::new(&ctx)?,
            envmap: EnvMapPass::new(&ctx, ENVMAP_SIZE)?,
            env_view: EnvViewPass::new(&ctx)?,
            probes: ProbeSet::new(&ctx, &scene.probes, ENVMAP_SIZE)?,
            lighting: LightingPass::new(&ctx)?,
            sky: SkyPass::new(&ctx)?,
            skyocc: crate::passes::skyocc::SkyOccPass::new(&ctx, scene)?,
            forward: crate::passes::forward::ForwardPass::new(&ctx)?,
            luminance: LuminancePass::new(&ctx)?,
            adapt: AdaptPass::new(&ctx)?,
            bloom: BloomPass::new(&ctx)?,
            tonemap: TonemapPass::new(&ctx, DISPLAY_FORMAT)?,
            smaa: crate::passes::aa::SmaaPass::new(&ctx, DISPLAY_FORMAT)?,
            temporal: crate::passes::aa::TemporalPass::new(&ctx, DISPLAY_FORMAT)?,
            aa_buffers: crate::passes::aa::BufferTaaPass::new(&ctx)?,
            debug: DebugPass::new(&ctx)?,
        };
        let scene_gpu = SceneGpu::upload(&ctx, scene)?;
        passes.forward.prepare(&ctx, &scene_gpu)?;
        for key in GBufferKey::for_scene(&scene_gpu, false) {
            passes.gbuffer.prepare(&ctx, key)?;
        }
        if !scene.probes.is_empty() {
            passes.lighting.prepare(&ctx, LightingKey::RELIGHT)?;
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
        // sky, mirror) to the shadow, AO, lighting and post passes.
        let timer = PassTimer::new(&ctx.device, &ctx.queue, 128);
        let white = |label| {
            use wgpu::util::DeviceExt;
            ctx.device.create_texture_with_data(
                &ctx.queue,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: 1,
                        height: 1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Rgba8Unorm,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                &[255; 4],
            )
        };
        // 1x1 white: the shadow mask when shadows are off, AO when AO is off.
        let shadow_placeholder = white("shadow.off");
        let ao_placeholder = white("ao.off");
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
                shadow_placeholder,
                ao_history: None,
                ao_placeholder,
                aa_history: None,
                aa_buffer_history: None,
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
            sky_table_cache: None,
            aa_last: None,
        })
    }

    /// The sky occlusion pass (L2), for tests and tools.
    pub fn sky_occlusion(&self) -> &crate::passes::skyocc::SkyOccPass {
        &self.res.passes.skyocc
    }

    /// The environment cube and DFG table (L4), for tests and tools.
    pub fn envmap(&self) -> &EnvMapPass {
        &self.res.passes.envmap
    }

    pub fn context(&self) -> &GpuContext {
        &self.ctx
    }

    pub fn scene_triangles(&self) -> u64 {
        self.res.scene.triangles
    }

    /// Bytes held by the scene's buffers and the transient texture pool.
    pub fn memory(&self) -> Vec<(&'static str, u64)> {
        vec![
            ("scene buffers", self.res.scene.bytes),
            ("frame targets (pool)", self.pool.allocated_bytes()),
            (
                "AO history",
                self.res.ao_history.as_ref().map_or(0, AoHistory::bytes),
            ),
            (
                "AA history",
                self.res
                    .aa_history
                    .as_ref()
                    .map_or(0, crate::passes::aa::AaHistory::bytes),
            ),
            (
                "AA buffer history",
                self.res
                    .aa_buffer_history
                    .as_ref()
                    .map_or(0, crate::passes::aa::BufferHistory::bytes),
            ),
        ]
    }

    /// Forgets the previous frame (camera cut): motion vectors become zero,
    /// the next frame starts adapted.
    pub fn reset_history(&mut self) {
        self.prev_view_proj = None;
        if let Some(h) = &mut self.res.ao_history {
            h.invalidate();
        }
        self.prev_time = None;
        self.res.post.reset = true;
        if let Some(h) = &mut self.res.aa_history {
            h.invalidate();
        }
        if let Some(h) = &mut self.res.aa_buffer_history {
            h.invalidate();
        }
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
            passes.tonemap.prepare(ctx, key)?;
        }
        passes.bloom.prepare(ctx, BloomSettings::MAX_PASSES)?;
        for key in LightingKey::all() {
            passes.lighting.prepare(ctx, key)?;
        }
        for key in GBufferKey::for_scene(&self.res.scene, true) {
            passes.gbuffer.prepare(ctx, key)?;
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

    fn validate(settings: &FrameSettings) -> Result<(), Error> {
        let max = 16384;
        if settings.width == 0
            || settings.height == 0
            || settings.width > max
            || settings.height > max
        {
            return Err(Error::InvalidSettings(format!(
                "frame size {}x{} is outside 1x1..{max}x{max}",
                settings.width, settings.height
            )));
        }
        settings.ao.validate()?;
        settings.shadows.validate()?;
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
        let key = SunKey(
            sun.time_hours,
            sun.latitude_deg,
            sun.day_of_year,
            sun.turbidity,
        );
        self.res.passes.sky.model = model;
        if self
            .sky_light
            .as_ref()
            .is_some_and(|(k, m, _)| *k == key && *m == model)
        {
            return Ok(());
        }
        let mut light = SkyLight::new(
            sun.time_hours,
            sun.latitude_deg,
            sun.day_of_year,
            sun.turbidity,
        );
        // L1: Bruneton tables once per renderer, their sky SH (and the moon) per time of day.
        if model == SkyModel::Bruneton && self.res.environment.is_none() {
            self.prepare_bruneton()?;
            if let Some(b) = self.res.passes.sky.bruneton() {
                let t = b.update_light(&self.ctx, &mut light, self.timer.as_mut())?;
                self.sky_timings.extend(t);
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
        self.sky_light = Some((key, model, light));
        self.res.passes.envmap.dirty = true;
        Ok(())
    }

    /// L1: draws and lights the Bruneton sky from `tables` (made on this
    /// renderer's context) instead of computing the default tables on first use.
    pub fn set_bruneton_tables(
        &mut self,
        tables: crate::passes::sky::bruneton::BrunetonTables,
    ) -> Result<(), Error> {
        self.res.passes.sky.set_bruneton(&self.ctx, tables)?;
        self.sky_light = None;
        Ok(())
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
        let t = (self.res.passes.sky).prepare_bruneton(&self.ctx, cache, self.timer.as_mut())?;
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

    /// The compiled pass list for these settings (`himal render --graph`).
    pub fn describe_graph(&mut self, settings: &FrameSettings) -> Result<String, Error> {
        Self::validate(settings)?;
        let size = (settings.width, settings.height);
        let format = self.prepare_output(settings)?;
        // Plan the shadow passes as a frame would (from a camera at the origin).
        self.update_sky(&settings.sun, settings.sky_model)?;
        if let Some((_, _, light)) = &self.sky_light {
            let camera = Camera::look_at(glam::Vec3::ZERO, glam::Vec3::NEG_Z, 60.0);
            self.res.passes.shadows.update(
                &self.ctx,
                &self.res.scene,
                &camera,
                size.0 as f32 / size.1 as f32,
                light.sun_direction,
                settings.shadow_resolution,
                Some(&settings.shadows),
                settings.time_s,
            );
        }
        let errors = FrameErrors::default();
        let inputs = self
            .res
            .inputs(settings, format, self.frame_index, &errors)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        Ok(frame::build(inputs, size, settings.view)
            .compile()?
            .describe())
    }

    fn output_format(settings: &FrameSettings) -> wgpu::TextureFormat {
        match settings.view {
            ViewBuffer::Final => DISPLAY_FORMAT,
            _ if settings.raw => RAW_FORMAT,
            _ => DISPLAY_FORMAT,
        }
    }

    /// Creates size-dependent resources and the debug pipeline if needed.
    fn prepare_output(&mut self, settings: &FrameSettings) -> Result<wgpu::TextureFormat, Error> {
        let size = (settings.width, settings.height);
        let format = Self::output_format(settings);
        prepare_view(&self.ctx, &mut self.res.passes, settings.view, format)?;
        if settings.aa.temporal() && self.res.aa_history.as_ref().is_none_or(|h| h.size != size) {
            let h = crate::passes::aa::AaHistory::new(&self.ctx.device, size, DISPLAY_FORMAT);
            self.res.aa_history = Some(h);
        }
        if settings.aa_buffers.any()
            && self
                .res
                .aa_buffer_history
                .as_ref()
                .is_none_or(|h| h.size != size)
        {
            let h = crate::passes::aa::BufferHistory::new(&self.ctx.device, size);
            self.res.aa_buffer_history = Some(h);
        }
        if self.res.ao_history.as_ref().is_none_or(|h| h.size != size) {
            self.res.ao_history = Some(AoHistory::new(&self.ctx.device, size));
        }
        let passes = &mut self.res.passes;
        passes
            .tonemap
            .prepare(&self.ctx, post_state::tonemap_key(settings))?;
        passes.bloom.prepare(&self.ctx, settings.bloom.passes)?;
        let key = lighting_key(settings, self.res.environment.is_some());
        passes.lighting.prepare(&self.ctx, key)?;
        for key in GBufferKey::for_scene(&self.res.scene, settings.aa.temporal()) {
            passes.gbuffer.prepare(&self.ctx, key)?;
        }
        if self.res.luminance.as_ref().is_none_or(|(s, _)| *s != size) {
            self.res.luminance = Some((size, LuminanceBuffers::new(&self.ctx.device, size)));
        }
        let device = &self.ctx.device;
        self.res
            .outputs
            .entry((size.0, size.1, format))
            .or_insert_with(|| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("output"),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::COPY_SRC
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    // himal::present reads the display-encoded bytes as they are
                    view_formats: if format.is_srgb() {
                        &[wgpu::TextureFormat::Rgba8Unorm]
                    } else {
                        &[]
                    },
                })
            });
        Ok(format)
    }

    /// Restarts the AA history on a mode change and uploads the temporal
    /// passes' parameters for a frame sampled at `jitter`.
    fn prepare_aa_history(&mut self, settings: &FrameSettings, jitter: [f32; 2]) {
        if self.aa_last != Some(settings.aa) {
            if let Some(h) = &mut self.res.aa_history {
                h.invalidate();
            }
            self.aa_last = Some(settings.aa);
        }
        if let Some(h) = &self.res.aa_history {
            let params = crate::passes::aa::AaParams::new(
                jitter,
                h.last_jitter,
                h.frames,
                (self.frame_index % 2) as u32,
                &settings.aa_tuning,
            );
            self.res.passes.temporal.update(&self.ctx.queue, &params);
        }
    }

    /// Renders one frame from `camera` and reads the output back.
    pub fn render(
        &mut self,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> Result<RenderedFrame, Error> {
        let DrawnFrame {
            timings,
            shadows,
            sky_occlusion,
        } = self.draw(camera, settings)?;
        let output = self
            .output(settings)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        Ok(RenderedFrame {
            image: read_texture(&self.ctx, output, 0, 0)?,
            timings,
            shadows,
            sky_occlusion,
        })
    }

    /// The texture the last [`Renderer::draw`] with these settings' size and
    /// output format wrote (display frames: `Rgba8UnormSrgb`).
    pub fn output(&self, settings: &FrameSettings) -> Option<&wgpu::Texture> {
        let format = Self::output_format(settings);
        self.res
            .outputs
            .get(&(settings.width, settings.height, format))
    }

    /// Renders one frame from `camera` into [`Renderer::output`] and waits for
    /// the GPU timings; the image stays on the GPU.
    pub fn draw(&mut self, camera: &Camera, settings: &FrameSettings) -> Result<DrawnFrame, Error> {
        Self::validate(settings)?;
        let size = (settings.width, settings.height);
        let format = self.prepare_output(settings)?;
        self.update_sky(&settings.sun, settings.sky_model)?;
        let probe = if settings.environment_probes && self.res.environment.is_none() {
            self.res.passes.probes.nearest(camera.position)
        } else {
            None
        };
        if probe != self.res.active_probe {
            self.res.active_probe = probe;
            self.res.passes.envmap.dirty = true;
        }
        if settings.envmap_every_frame {
            self.res.passes.envmap.dirty = true;
        }
        self.res.post.update(&self.ctx.queue, settings);
        let aspect = size.0 as f32 / size.1 as f32;
        let (view, proj) = (camera.view(), camera.projection(aspect));
        // Projection jitter (A2, A3): the matrices carry it, so passes that
        // reconstruct positions from depth stay exact; View.jitter.xy repeats
        // it in clip units. Sample offset j (px, y down) = image shifted by -j.
        // Debug views show the G-buffer as rasterised: no jitter there; the
        // AO views show the AO that lighting gets, jittered like the frame,
        // and the motion view the stabilised motion of `--aa-buffers motion`.
        let stable_motion_view = settings.aa_buffers.motion
            && settings.view == ViewBuffer::Debug(crate::passes::debug::DebugView::Motion);
        let jitter = match settings.view {
            ViewBuffer::Final | ViewBuffer::Ao(_) => settings.aa.jitter(self.frame_index),
            _ if stable_motion_view => settings.aa.jitter(self.frame_index),
            _ => [0.0, 0.0],
        };
        let jitter_clip = Vec3::new(
            -2.0 * jitter[0] / size.0 as f32,
            2.0 * jitter[1] / size.1 as f32,
            0.0,
        );
        let proj = Mat4::from_translation(jitter_clip) * proj;
        self.prepare_aa_history(settings, jitter);
        let view_proj = proj * view;
        let prev = self.prev_view_proj.unwrap_or(view_proj);
        let prev_time = self.prev_time.unwrap_or(settings.time_s);
        let uniform = ViewUniform::new(
            view,
            proj,
            prev,
            camera.position,
            camera.near,
            size,
            self.frame_index,
            settings.exposure_ev,
        )
        .with_times(settings.time_s, prev_time)
        .with_jitter(jitter_clip.x, jitter_clip.y);
        self.res
            .scene
            .update_objects(&self.ctx.queue, settings.time_s, prev_time);
        self.ctx
            .queue
            .write_buffer(&self.res.view_buffer, 0, bytemuck::bytes_of(&uniform));
        let prev_jitter = if self.prev_view_proj.is_some() {
            self.prev_jitter
        } else {
            jitter
        };
        self.res.passes.ao.update(
            &self.ctx.queue,
            &AoUniform::new(&settings.ao, proj, camera.near, size).with_jitter(jitter, prev_jitter),
        );
        if let Some(h) = &self.res.aa_buffer_history {
            let (queue, tuning) = (&self.ctx.queue, &settings.aa_tuning);
            let buffers = &self.res.passes.aa_buffers;
            buffers.update(queue, jitter, prev_jitter, h, tuning);
        }
        let Some((_, _, light)) = &self.sky_light else {
            return Err(Error::InvalidSettings("sky light missing".into()));
        };
        let (sun_illuminance, sky_irradiance) = match &self.res.environment {
            Some(env) => (
                if env.sun {
                    light.sun_illuminance
                } else {
                    glam::Vec3::ZERO
                },
                Sh9Gpu::from(&env.irradiance_sh),
            ),
            None => (light.sun_illuminance, Sh9Gpu::from(&light.irradiance_sh)),
        };
        let lighting = LightingUniform::new(
            light.sun_direction,
            sun_illuminance,
            sky_irradiance,
            Vec4::new(
                settings.aerial_extinction,
                if settings.aerial_extinction > 0.0 {
                    1.0
                } else {
                    0.0
                },
                // fog colour from the sky SH under the Bruneton sky (deferred.wgsl)
                if self.res.passes.sky.draws_bruneton() {
                    1.0
                } else {
                    0.0
                },
                0.0,
            ),
        );
        let shadow_stats = self.res.passes.shadows.update(
            &self.ctx,
            &self.res.scene,
            camera,
            aspect,
            light.sun_direction,
            settings.shadow_resolution,
            Some(&settings.shadows),
            settings.time_s,
        );
        self.ctx
            .queue
            .write_buffer(&self.res.lighting_buffer, 0, bytemuck::bytes_of(&lighting));
        let skyocc_on = settings.sky_occlusion || matches!(settings.view, ViewBuffer::SkyOcc(_));
        if settings.sky_occlusion_every_frame {
            self.res.passes.skyocc.invalidate();
        }
        let skyocc_stats =
            self.res
                .passes
                .skyocc
                .update(&self.ctx, &self.res.scene, camera, aspect, skyocc_on);

        // Alpha BLEND objects draw far to near from this camera.
        self.res
            .passes
            .forward
            .sort(&self.res.scene, camera.position);
        let errors = FrameErrors::default();
        let Self {
            ctx,
            res,
            pool,
            timer,
            frame_index,
            sky_timings,
            ..
        } = self;
        let inputs = res
            .inputs(settings, format, *frame_index, &errors)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        let compiled = frame::build(inputs, size, settings.view).compile()?;
        let commands = compiled.execute(&ctx.device, pool, timer.as_mut())?;
        if let Some(e) = errors.take_first() {
            return Err(e.into());
        }
        ctx.queue.submit([commands]);
        ctx.check("frame")?;
        let mut timings = std::mem::take(sky_timings);
        if let Some(t) = timer.as_mut() {
            timings.extend(t.read_timings(&ctx.device)?);
        }
        self.prev_view_proj = Some(view_proj);
        self.prev_jitter = jitter;
        self.prev_time = Some(settings.time_s);
        self.res.post.frame_done(settings);
        if self.res.passes.envmap.dirty
            && let Some(p) = self.res.active_probe
        {
            self.res.passes.probes.probes[p].captured = true;
        }
        self.res.passes.envmap.dirty = false;
        self.frame_index += 1;
        if let Some(h) = self
            .res
            .aa_history
            .as_mut()
            .filter(|_| settings.aa.temporal())
        {
            h.advance(jitter);
        }
        if let Some(h) = &mut self.res.aa_buffer_history {
            h.advance(settings.aa_buffers);
        }
        if let Some(h) = &mut self.res.ao_history {
            // Only the filter writes the history; any other mode leaves it stale.
            if settings.ao.mode == AoMode::HbaoStf {
                h.advance();
            } else {
                h.invalidate();
            }
        }
        Ok(DrawnFrame {
            timings,
            shadows: shadow_stats,
            sky_occlusion: skyocc_stats,
        })
    }
}
