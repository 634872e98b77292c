//! `himal render`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use himal::image_io::ImageKind;
use himal::passes::post::Tonemapper;
use himal::passes::sky::bruneton::TableSizes;
use himal::scene::Scene;
use himal::{FrameSettings, Renderer, ViewBuffer};

use crate::GpuArgs;
use crate::scene_source::{is_gltf, load_scene, open_renderer};
// The view helpers moved to `camera.rs`; their old paths keep working.
pub use crate::camera::{apply_environment, pick_camera, view_camera};

#[derive(Args, Clone, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML; one with a `[world]` table is a streamed world),
    /// `demo` (the valley) or `world` (the streamed 10 km world).
    #[arg(
        long,
        default_value = "demo",
        value_name = "FILE|demo|world",
        allow_hyphen_values = true
    )]
    pub scene: String,
    /// A glTF model (.gltf or .glb) instead of --scene, framed by an automatic camera.
    #[arg(long, value_name = "FILE", allow_hyphen_values = true)]
    pub gltf: Option<String>,
    /// An equirectangular HDR environment (.hdr or .exr) lighting the scene
    /// instead of the physical sky (replaces the scene's `[environment]`);
    /// `studio`: the built-in neutral studio (the default with --gltf);
    /// `sky`: the physical sky.
    #[arg(long, value_name = "FILE|studio|sky", allow_hyphen_values = true)]
    pub env: Option<String>,
    /// Orbit camera around the scene's bounds: degrees about +Y from the
    /// front (+Z, positive toward +X), degrees above the horizon, and the
    /// distance in metres (default: the bounds fill the view). A bare
    /// --gltf opens at 35,20.
    #[arg(long, value_name = "YAW,PITCH[,DISTANCE]", allow_hyphen_values = true)]
    pub orbit: Option<String>,
    /// With --gltf: the KHR_materials_variants variant to show (by name).
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub variant: Option<String>,
    /// glTF animation to play, by name (`none`: the rest pose; default: each
    /// file's first); an unknown name is an error listing the scene's.
    #[arg(long, value_name = "NAME|none", allow_hyphen_values = true)]
    pub animation: Option<String>,
    /// Animation clock of the first frame in seconds (later frames add 1/30 s each).
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "SECONDS",
        allow_hyphen_values = true
    )]
    pub at: f32,
    /// Vertical field of view in degrees (replaces the camera's).
    #[arg(long, value_name = "DEG", allow_hyphen_values = true)]
    pub fov: Option<f32>,
    /// Radiance scale of --env.
    #[arg(
        long,
        default_value_t = 1.0,
        value_name = "X",
        allow_hyphen_values = true
    )]
    pub env_intensity: f32,
    /// Named camera of the scene (default: its first camera).
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Time of day, HH:MM (default: the scene's).
    #[arg(long, value_name = "HH:MM", allow_hyphen_values = true)]
    pub time: Option<String>,
    /// Time-lapse: with --frames N, the sun moves from the first time to the
    /// second over the sequence while the camera stays put (each frame is a cut).
    #[arg(long, value_name = "HH:MM..HH:MM", allow_hyphen_values = true)]
    pub time_lapse: Option<String>,
    /// Image size.
    #[arg(
        long,
        default_value = "1280x720",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Frames to render; more than one writes a numbered sequence while the camera dollies forward.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub frames: u32,
    /// Camera travel per frame in metres along its view direction (sequences).
    #[arg(long, default_value_t = 0.25, allow_hyphen_values = true)]
    pub speed: f32,
    /// Buffer to write: final or a debug view.
    #[arg(
        long,
        default_value = "final",
        value_name = "BUFFER",
        allow_hyphen_values = true
    )]
    pub view: String,
    /// Output file (.png or .exr); sequences insert _NNNN before the extension.
    #[arg(long, default_value = "out/demo.png")]
    pub out: PathBuf,
    #[command(flatten)]
    pub post: PostArgs,
    #[command(flatten)]
    pub shadows: ShadowArgs,
    /// Print each frame's log-average and adapted luminance (read back after the frame).
    #[arg(long)]
    pub print_exposure: bool,
    /// Print the compiled frame graph (passes, reads, writes) and exit.
    #[arg(long)]
    pub graph: bool,
    #[command(flatten)]
    pub ao: crate::ao::AoArgs,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// HDR post options shared by render, bench and prewarm (H2, H3).
#[derive(Args, Clone, Debug)]
pub struct PostArgs {
    /// auto: light adaptation (the first frame starts adapted); EV: each frame
    /// exposed for its own log-average luminance, biased by EV stops.
    #[arg(
        long,
        default_value = "auto",
        value_name = "auto|EV",
        allow_hyphen_values = true
    )]
    pub exposure: String,
    /// Kawase bloom, composited in HDR before tone mapping.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub bloom: String,
    /// Bloom bright-pass threshold in scaled luminance (1 = display 0.5).
    #[arg(long, value_name = "L", allow_hyphen_values = true)]
    pub bloom_threshold: Option<f32>,
    /// Bloom strength (weight of the bloom added to the HDR image).
    #[arg(long, value_name = "W", allow_hyphen_values = true)]
    pub bloom_strength: Option<f32>,
    /// Kawase blur passes at quarter resolution (0..8).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub bloom_passes: Option<u32>,
    /// Reinhard white point in scaled luminance (maps to white); default: L/(1+L).
    #[arg(long, value_name = "L", allow_hyphen_values = true)]
    pub white_point: Option<f32>,
    /// Tone mapper: reinhard (the talk's, default), neutral (Khronos PBR
    /// Neutral), aces (Hill's fit) or agx (Blender's base), to compare
    /// with other viewers.
    #[arg(
        long,
        default_value = "reinhard",
        value_name = "reinhard|neutral|aces|agx",
        allow_hyphen_values = true
    )]
    pub tonemap: String,
    /// Ambient specular from the GGX-filtered sky cube (L4, M4); off: SH
    /// irradiance along the reflection vector.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub env_specular: String,
    /// L3: ambient specular from the relit cube of the probe nearest the
    /// camera (scenes with `[[probe]]`); off: the sky cube.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub env_probes: String,
    /// L2 height-field sky occlusion (SH2 visibility, bent normals).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub sky_occlusion: String,
    /// L5 indirect light from radiance-transfer probes (baked on first use
    /// into the cache; `himal bake --probes` ahead of time).
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub indirect: String,
    /// L2: sky light along the bent normal (off: along the surface normal).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub bent_normals: String,
    /// Anti-aliasing after tone mapping; hraa = SMAA + temporal FLIPQUAD + TAA + unsharp.
    #[arg(
        long,
        default_value = "hraa",
        value_name = "none|smaa|smaa-t2x|tfq|taa|hraa"
    )]
    pub aa: String,
    /// A3 TAA on other buffers: the AO result and/or the motion vectors
    /// (comma-separated; bench rows aa.taa_ao, aa.taa_motion).
    #[arg(
        long,
        default_value = "none",
        value_name = "none|ao|motion|ao,motion",
        allow_hyphen_values = true
    )]
    pub aa_buffers: String,
    /// V6: draw runs of one mesh's consecutive objects as one instanced draw
    /// (off: one draw per object, for comparisons).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub instancing: String,
    /// E3 specular anti-aliasing: glTF roughness widened by the normal
    /// variance baked into normal-map mips (Toksvig); off: plain roughness.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub specular_aa: String,
    /// V1 vegetation: trees, bushes and grass drawn (off: skipped in every
    /// pass; the frame then culls on the CPU).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub vegetation: String,
    /// R4: Burley's remapped roughness in the visibility term of the sun
    /// and local lights (less specular on rough surfaces at grazing light).
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub visibility_remap: String,
    /// The scene's `[[ambient_light]]` volumes (Ryse's multiplicative
    /// ambient lights, docs/ambient-lights.md); off: ignored.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub ambient_lights: String,
    /// Wetness of up-facing surfaces, 0..1 (a water film: darker albedo,
    /// smooth roughness; E3's screen-space normal-variance filter keeps it
    /// from aliasing under --specular-aa on). 0: dry, no pass.
    #[arg(
        long,
        default_value_t = 0.0,
        value_name = "0..1",
        allow_hyphen_values = true
    )]
    pub wetness: f32,
    /// E4 particles: the scene's `[[emitter]]`s simulated, lit and drawn
    /// (scenes without emitters are unchanged either way).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub particles: String,
    /// E4 particle lighting: once per particle (vertex, Ryse's) or at every
    /// pixel (pixel, the reference it is measured against).
    #[arg(
        long,
        default_value = "vertex",
        value_name = "vertex|pixel",
        allow_hyphen_values = true
    )]
    pub particle_lighting: String,
    /// E4 particles' sun shadow: static (the static map, else the cascade,
    /// 4 x 4 gather once per particle, Ryse's) or cascaded (the world's
    /// per-pixel lookup: the reference it is measured against).
    #[arg(
        long,
        default_value = "static",
        value_name = "static|cascaded",
        allow_hyphen_values = true
    )]
    pub particle_shadows: String,
    /// E4 reactive mask: particles' coverage shortens the TAA history and
    /// the temporal resolve where they drew this frame or the last (no
    /// trails behind moving smoke; `off`: they accumulate like the rest).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub particle_reactive: String,
    /// E4: each emitter's particles drawn far to near (a GPU bitonic sort
    /// per emitter, rings up to 1024 slots) or, off, in ring order.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub particle_sort: String,
    /// E4 particles' ambient: sky (the sky irradiance the world's surfaces
    /// get) or probe (the environment cube's lowest specular mip, Ryse's).
    #[arg(
        long,
        default_value = "sky",
        value_name = "sky|probe",
        allow_hyphen_values = true
    )]
    pub particle_ambient: String,
    /// V6 frustum culling of the G-buffer and the sun cascades: gpu (per
    /// instance in a compute pass, drawn indirectly; the CPU path where the
    /// adapter cannot), cpu (per object on the render thread), off (the
    /// G-buffer draws every object).
    #[arg(
        long,
        default_value = "gpu",
        value_name = "gpu|cpu|off",
        allow_hyphen_values = true
    )]
    pub culling: String,
    /// V6 Hi-Z occlusion culling of the camera's objects against the
    /// previous frame's depth (GPU culling only): hiz or off. Objects that
    /// come out from behind an occluder appear one frame late.
    #[arg(
        long,
        default_value = "off",
        value_name = "hiz|off",
        allow_hyphen_values = true
    )]
    pub occlusion: String,
    /// E2 LOD by triangle size: an object switches to its next level where
    /// its mean triangle covers fewer than PX pixels (later levels at
    /// multiples of that distance); off: every object at full detail.
    #[arg(
        long,
        default_value = "4",
        value_name = "PX|off",
        allow_hyphen_values = true
    )]
    pub lod_threshold: String,
    /// E2 comparison: choose levels by object size instead (the first
    /// switch where an object's bounding radius covers fewer than PX
    /// pixels); off: by triangle size (--lod-threshold).
    #[arg(
        long,
        default_value = "off",
        value_name = "PX|off",
        allow_hyphen_values = true
    )]
    pub lod_object: String,
    /// L1 sky: bruneton (precomputed scattering tables) or preetham (analytic).
    #[arg(
        long,
        default_value = "bruneton",
        value_name = "preetham|bruneton",
        allow_hyphen_values = true
    )]
    pub sky: String,
    /// L1 Bruneton table sizes: default (fast) or reference (Bruneton 2017's;
    /// minutes on a software rasteriser: bake them first with `himal bake`).
    #[arg(
        long,
        default_value = "default",
        value_name = "default|reference",
        allow_hyphen_values = true
    )]
    pub sky_tables: String,
}

impl PostArgs {
    /// The Bruneton table sizes of `--sky-tables`.
    pub fn table_sizes(&self) -> Result<TableSizes> {
        parse_table_sizes(&self.sky_tables).map_err(|e| anyhow::anyhow!("--sky-tables {e}"))
    }

    /// Sets the renderer's sky table cache (`gpu`'s cache directory) and
    /// sizes; says so when reference tables will be computed (minutes on a
    /// software rasteriser).
    pub fn configure(
        &self,
        renderer: &mut Renderer,
        gpu: &crate::GpuArgs,
        scene: &Scene,
    ) -> Result<()> {
        if on_off("--indirect", &self.indirect)? {
            crate::scene_source::attach_probes(renderer, scene, gpu.cache_dir().as_deref())?;
        }
        let sizes = self.table_sizes()?;
        let config = himal::passes::sky::bruneton::AtmosphereConfig::earth(sizes);
        let cached = gpu
            .cache_dir()
            .is_some_and(|d| himal::passes::sky::bruneton::cache_file(&d, &config).exists());
        if sizes == TableSizes::REFERENCE && self.sky == "bruneton" && !cached {
            eprintln!(
                "note: computing the reference sky tables (not baked; minutes on a software \
                 rasteriser); `himal bake --tables reference` keeps them"
            );
        }
        renderer.set_sky_table_cache(gpu.cache_dir());
        renderer.set_sky_table_sizes(sizes);
        Ok(())
    }

    /// Applies the options to `settings` (the library checks the ranges).
    pub fn apply(&self, settings: &mut FrameSettings) -> Result<()> {
        settings.sky_model = self
            .sky
            .parse()
            .map_err(|e| anyhow::anyhow!("--sky {}: {e}", self.sky))?;
        settings.aa = himal::passes::aa::AaMode::parse(&self.aa)
            .map_err(|e| anyhow::anyhow!("--aa {}: {e}", self.aa))?;
        settings.aa_buffers = himal::passes::aa::AaBuffers::parse(&self.aa_buffers)
            .map_err(|e| anyhow::anyhow!("--aa-buffers {}: {e}", self.aa_buffers))?;
        match self.exposure.as_str() {
            "auto" => {
                settings.adaptation.enabled = true;
                settings.exposure_ev = 0.0;
            }
            ev => {
                let v: f32 = ev
                    .parse()
                    .ok()
                    .filter(|v: &f32| v.is_finite() && v.abs() <= 64.0)
                    .with_context(|| {
                        format!("--exposure {ev}: expected auto or a number of EV in -64..=64 (e.g. -1.5)")
                    })?;
                settings.adaptation.enabled = false;
                settings.exposure_ev = v;
            }
        }
        settings.bloom.enabled = on_off("--bloom", &self.bloom)?;
        let finite = |v: f32, name: &str, lo: f32, hi: f32| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(anyhow::anyhow!(
                    "{name} {v}: must be a finite number in {lo}..={hi}"
                ))
            }
        };
        if let Some(t) = self.bloom_threshold {
            settings.bloom.threshold = finite(t, "--bloom-threshold", 0.0, 1e6)?;
        }
        if let Some(s) = self.bloom_strength {
            settings.bloom.strength = finite(s, "--bloom-strength", 0.0, 100.0)?;
        }
        if let Some(n) = self.bloom_passes {
            if n > himal::passes::post::BloomSettings::MAX_PASSES {
                bail!(
                    "--bloom-passes {n}: at most {} Kawase passes",
                    himal::passes::post::BloomSettings::MAX_PASSES
                );
            }
            settings.bloom.passes = n;
        }
        if let Some(w) = self.white_point
            && !(w.is_finite() && w > 0.0 && w <= 1e6)
        {
            bail!("--white-point {w}: must be a positive finite luminance up to 1e6");
        }
        settings.white_point = self.white_point;
        settings.tonemapper = self
            .tonemap
            .parse()
            .map_err(|e| anyhow::anyhow!("--tonemap {}: {e}", self.tonemap))?;
        if self.white_point.is_some() && settings.tonemapper != Tonemapper::Reinhard {
            bail!(
                "--white-point is Reinhard's: leave it out with --tonemap {}",
                self.tonemap
            );
        }
        settings.environment_specular = on_off("--env-specular", &self.env_specular)?;
        settings.environment_probes = on_off("--env-probes", &self.env_probes)?;
        settings.sky_occlusion = on_off("--sky-occlusion", &self.sky_occlusion)?;
        settings.indirect = on_off("--indirect", &self.indirect)?;
        settings.bent_normals = on_off("--bent-normals", &self.bent_normals)?;
        settings.instancing = on_off("--instancing", &self.instancing)?;
        settings.specular_aa = on_off("--specular-aa", &self.specular_aa)?;
        settings.vegetation = on_off("--vegetation", &self.vegetation)?;
        settings.visibility_remap = on_off("--visibility-remap", &self.visibility_remap)?;
        settings.ambient_lights = on_off("--ambient-lights", &self.ambient_lights)?;
        if !(0.0..=1.0).contains(&self.wetness) {
            bail!("--wetness {}: must be in [0, 1]", self.wetness);
        }
        settings.wetness = self.wetness;
        settings.particles = on_off("--particles", &self.particles)?;
        settings.particles_per_pixel = match self.particle_lighting.as_str() {
            "vertex" => false,
            "pixel" => true,
            other => bail!("--particle-lighting {other}: expected vertex or pixel"),
        };
        settings.particles_sort = on_off("--particle-sort", &self.particle_sort)?;
        settings.particles_reactive = on_off("--particle-reactive", &self.particle_reactive)?;
        settings.particles_cascaded_shadows = match self.particle_shadows.as_str() {
            "static" => false,
            "cascaded" => true,
            other => bail!("--particle-shadows {other}: expected static or cascaded"),
        };
        settings.particles_probe_ambient = match self.particle_ambient.as_str() {
            "sky" => false,
            "probe" => true,
            other => bail!("--particle-ambient {other}: expected sky or probe"),
        };
        let pixels = |flag: &str, v: &str| -> Result<f32> {
            match v {
                "off" => Ok(0.0),
                v => match v.parse::<f32>() {
                    Ok(px) if px.is_finite() && (0.01..=1.0e6).contains(&px) => Ok(px),
                    _ => bail!("{flag} {v}: expected pixels in 0.01..1000000, or off"),
                },
            }
        };
        settings.lod_threshold_px = pixels("--lod-threshold", &self.lod_threshold)?;
        settings.lod_object_px = pixels("--lod-object", &self.lod_object)?;
        settings.culling = match self.culling.as_str() {
            "gpu" => himal::Culling::Gpu,
            "cpu" => himal::Culling::Cpu,
            "off" => himal::Culling::Off,
            other => bail!("--culling {other}: expected gpu, cpu or off"),
        };
        settings.occlusion = match self.occlusion.as_str() {
            "hiz" => himal::Occlusion::Hiz,
            "off" => himal::Occlusion::Off,
            other => bail!("--occlusion {other}: expected hiz or off"),
        };
        Ok(())
    }
}

/// `on` / `off` of option `name`.
fn on_off(name: &str, value: &str) -> Result<bool> {
    match value {
        "on" => Ok(true),
        "off" => Ok(false),
        other => bail!("{name} {other}: expected on or off"),
    }
}

/// Parses `HH:MM..HH:MM` into hours.
fn parse_time_lapse(s: &str) -> Result<(f32, f32)> {
    let (a, b) = s
        .split_once("..")
        .with_context(|| format!("--time-lapse {s}: expected HH:MM..HH:MM"))?;
    let parse =
        |t: &str| himal::scene::parse_time(t).map_err(|e| anyhow::anyhow!("--time-lapse {s}: {e}"));
    Ok((parse(a)?, parse(b)?))
}

/// Parses `WxH`.
pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size \"{s}\": expected WxH, e.g. 1280x720"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size \"{s}\": bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size \"{s}\": bad height"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--size {s}: width and height must be within 1..16384");
    }
    Ok((w, h))
}

/// Shadow options shared by render and bench (S1-S4).
#[derive(Args, Clone, Debug)]
pub struct ShadowArgs {
    /// Sun shadows: off, csm (4 cascades), csm+static (far cascade from the static map); `sun` = csm.
    #[arg(
        long,
        default_value = "csm",
        value_name = "off|csm|csm+static",
        allow_hyphen_values = true
    )]
    pub shadows: String,
    /// Edge of each sun cascade in texels.
    #[arg(long, default_value_t = himal::renderer::DEFAULT_SHADOW_RESOLUTION, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub shadow_resolution: u32,
    /// Edge of the static shadow map in texels (csm+static).
    #[arg(long, default_value_t = 8192, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub static_resolution: u32,
    /// Object with the hero shadow map, or off (default: the first moving object).
    #[arg(long, value_name = "NAME|off", allow_hyphen_values = true)]
    pub hero: Option<String>,
    /// R3: the scene's or the camera's `cinematic_shadows` (author-set near
    /// and far, logarithmic splits); off: the default cascades.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub cinematic_shadows: String,
    /// Local lights with no shadow caster in their reach: skip (no atlas
    /// tile, projector pass or mask channel) or keep (render them anyway,
    /// to measure the saving).
    #[arg(
        long,
        default_value = "skip",
        value_name = "skip|keep",
        allow_hyphen_values = true
    )]
    pub casterless_shadows: String,
    /// The mask's hero pass only inside the screen rectangle of the hero
    /// map's box (exact), or over the whole screen (to measure the saving).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub shadow_hero_scissor: String,
    /// Classify each 16 x 16 tile of the shadow mask first: a map lit or
    /// shadowed over the whole tile costs no filter tap (exact); off
    /// (default): filter every pixel (on lavapipe the cheaper of the two).
    #[arg(
        long,
        default_value = "off",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub shadow_mask_tiles: String,
}

impl ShadowArgs {
    /// Writes the shadow options into `settings` (cascade edge 0 = off).
    pub fn apply(&self, settings: &mut FrameSettings) -> Result<()> {
        let mode: himal::passes::shadows::ShadowMode = self
            .shadows
            .parse()
            .map_err(|e| anyhow::anyhow!("--shadows {}: {e}", self.shadows))?;
        let n = self.shadow_resolution;
        if !(16..=16384).contains(&n) {
            bail!("--shadow-resolution {n}: expected 16..16384");
        }
        let st = self.static_resolution;
        if !(16..=16384).contains(&st) {
            bail!("--static-resolution {st}: expected 16..16384");
        }
        settings.shadow_resolution = if mode == himal::passes::shadows::ShadowMode::Off {
            0
        } else {
            n
        };
        let s = &mut settings.shadows;
        s.mode = mode;
        s.static_resolution = self.static_resolution;
        match self.hero.as_deref() {
            Some("off") => s.hero_resolution = 0,
            Some(name) => s.hero = Some(name.to_string()),
            None => {}
        }
        s.skip_casterless = match self.casterless_shadows.as_str() {
            "skip" => true,
            "keep" => false,
            other => bail!("--casterless-shadows {other}: expected skip or keep"),
        };
        s.hero_scissor = match self.shadow_hero_scissor.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--shadow-hero-scissor {other}: expected on or off"),
        };
        s.mask_tiles = match self.shadow_mask_tiles.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--shadow-mask-tiles {other}: expected on or off"),
        };
        s.validate()?;
        Ok(())
    }

    /// R3: camera `camera`'s cinematic shadows (else the scene's, else the
    /// first camera's when `camera` is `None`) under `--cinematic-shadows on`.
    pub fn apply_cinematic(
        &self,
        settings: &mut FrameSettings,
        scene: &himal::scene::Scene,
        camera: Option<&str>,
    ) -> Result<()> {
        let on = on_off("--cinematic-shadows", &self.cinematic_shadows)?;
        let name = camera.or_else(|| scene.cameras.first().map(|c| c.name.as_str()));
        settings.shadows.cinematic = match name {
            Some(n) if on => scene.cinematic_shadows_for(n),
            _ if on => scene.cinematic_shadows,
            _ => None,
        };
        settings.shadows.validate()?;
        Ok(())
    }
}

impl RenderArgs {
    /// The `--gltf` model (read as glTF whatever its name ends with), else
    /// `--scene` ([`load_scene`]).
    pub fn load_scene(&self) -> Result<Scene> {
        if !self.at.is_finite() {
            bail!("--at {}: seconds, a finite number", self.at);
        }
        let mut scene = self.load_model()?;
        match self.animation.as_deref() {
            None => {}
            Some("none") => scene.set_animation(None)?,
            Some(name) => scene.set_animation(Some(name))?,
        }
        Ok(scene)
    }

    fn load_model(&self) -> Result<Scene> {
        let budget = crate::memory_budget()?;
        match (&self.gltf, &self.variant) {
            (Some(path), variant) => Ok(Scene::from_gltf_variant(
                Path::new(path),
                budget,
                variant.as_deref(),
            )?),
            (None, Some(_)) if is_gltf(&self.scene) => Ok(Scene::from_gltf_variant(
                Path::new(&self.scene),
                budget,
                self.variant.as_deref(),
            )?),
            (None, Some(v)) => bail!("--variant {v}: variants are a glTF model's (--gltf FILE)"),
            (None, None) => load_scene(&self.scene),
        }
    }

    /// The renderer for what [`Self::load_scene`] loaded: a `--gltf` model
    /// is never a world ([`open_renderer`] otherwise).
    pub fn open_renderer(&self, ctx: himal::gpu::GpuContext, scene: &Scene) -> Result<Renderer> {
        match &self.gltf {
            Some(_) => Ok(Renderer::new(ctx, scene)?),
            None => open_renderer(&self.scene, ctx, scene),
        }
    }
}

/// `--hero NAME` must name an object of the scene.
fn check_hero(scene: &Scene, hero: Option<&str>) -> Result<()> {
    let Some(name) = hero.filter(|h| *h != "off") else {
        return Ok(());
    };
    if scene.objects.iter().any(|o| o.name == name) {
        return Ok(());
    }
    let mut moving: Vec<&str> = scene
        .objects
        .iter()
        .filter(|o| o.motion.is_some())
        .map(|o| o.name.as_str())
        .collect();
    moving.dedup();
    bail!(
        "--hero {name}: the scene has no object of that name (moving objects: {})",
        if moving.is_empty() {
            "none".to_string()
        } else {
            moving.join(", ")
        }
    )
}

fn sequence_path(out: &Path, index: u32) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("frame");
    let ext = out.extension().and_then(|s| s.to_str()).unwrap_or("png");
    out.with_file_name(format!("{stem}_{index:04}.{ext}"))
}

/// The scene (with --gltf / --env applied), its camera and the frame settings
/// the options ask for (shared with `himal view`).
pub fn setup(
    args: &RenderArgs,
) -> Result<(himal::scene::Scene, himal::scene::Camera, FrameSettings)> {
    let (width, height) = parse_size(&args.size)?;
    let view: ViewBuffer = args
        .view
        .parse()
        .map_err(|e| anyhow::anyhow!("--view {}: {e}", args.view))?;
    let kind = ImageKind::from_path(&args.out)?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    // A dolly of more than a kilometre per frame leaves any world at once.
    if !(args.speed.is_finite() && args.speed.abs() <= 1000.0) {
        bail!(
            "--speed {}: must be a finite number of metres per frame in -1000..=1000",
            args.speed
        );
    }
    if !(args.env_intensity.is_finite() && args.env_intensity >= 0.0) {
        bail!(
            "--env-intensity {}: must be a finite scale >= 0",
            args.env_intensity
        );
    }
    let budget = crate::memory_budget()?;
    budget
        .check(
            format!("--size {}", args.size),
            u64::from(width) * u64::from(height) * himal::budget::FRAME_BYTES_PER_PIXEL,
        )
        .map_err(anyhow::Error::msg)?;
    check_output_space(&args.out, width, height, args.frames, kind)?;
    let mut scene = args.load_scene()?;
    check_hero(&scene, args.shadows.hero.as_deref())?;
    let model = args.gltf.is_some() || is_gltf(&args.scene);
    apply_environment(args, &mut scene, model);
    let camera = view_camera(args, &scene, model)?;
    let mut sun = scene.sun.clone();
    if let Some(t) = &args.time {
        sun.time_hours = himal::scene::parse_time(t).map_err(|e| anyhow::anyhow!("--time: {e}"))?;
    }
    let mut settings = FrameSettings::new(width, height, sun);
    settings.view = view;
    settings.raw = kind == ImageKind::Exr;
    args.post.apply(&mut settings)?;
    args.shadows.apply(&mut settings)?;
    args.shadows
        .apply_cinematic(&mut settings, &scene, args.camera.as_deref())?;
    settings.ao = args.ao.settings()?;
    Ok((scene, camera, settings))
}

/// A streamed world's haze in `settings` when `renderer` draws one
/// (after [`open_renderer`]).
pub fn world_haze(renderer: &Renderer, settings: &mut FrameSettings) {
    if renderer.world().is_some() {
        settings.aerial_extinction = himal::scene::world::HAZE_EXTINCTION;
    }
}

/// A sequence that cannot fit on the output's file system is refused
/// before the first frame: an error when even at 4:1 compression it would
/// not fit, a warning when uncompressed it would not.
fn check_output_space(
    out: &Path,
    width: u32,
    height: u32,
    frames: u32,
    kind: ImageKind,
) -> Result<()> {
    let per_pixel = match kind {
        ImageKind::Png => 4,
        ImageKind::Exr => 16,
    };
    let bytes = u64::from(width) * u64::from(height) * per_pixel * u64::from(frames);
    let mut dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    // The folder may not exist yet: ask the nearest one that does.
    while !dir.exists() {
        match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => dir = p,
            _ => {
                dir = Path::new(".");
                break;
            }
        }
    }
    let Some(free) = free_bytes(dir) else {
        return Ok(());
    };
    let size = himal::budget::Bytes(bytes);
    if bytes / 4 > free {
        bail!(
            "--frames {frames} at {width}x{height}: the sequence needs up to {size}, \
             and {} is left on the file system of {}",
            himal::budget::Bytes(free),
            dir.display()
        );
    }
    if bytes > free {
        log::warn!(
            "--frames {frames} at {width}x{height}: up to {size} of images, {} free on {}",
            himal::budget::Bytes(free),
            dir.display()
        );
    }
    Ok(())
}

/// Bytes free to this user on the file system holding `dir` (statvfs).
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st = std::mem::MaybeUninit::<libc::statvfs>::uninit();
    // SAFETY: `c` is a NUL-terminated path and `st` is written by statvfs
    // before it is read (checked by the return value).
    let r = unsafe { libc::statvfs(c.as_ptr(), st.as_mut_ptr()) };
    if r != 0 {
        return None;
    }
    // SAFETY: statvfs returned 0, so it filled `st`.
    let st = unsafe { st.assume_init() };
    // Pseudo file systems (/proc, /sys) report no blocks at all.
    if st.f_blocks == 0 {
        return None;
    }
    // The field types differ between platforms (u32 on some 32-bit ones).
    #[allow(clippy::unnecessary_cast)]
    Some(st.f_bavail as u64 * st.f_frsize as u64)
}

/// `--sky-tables` / `--tables`: default or reference.
pub fn parse_table_sizes(s: &str) -> Result<TableSizes> {
    match s {
        "default" => Ok(TableSizes::DEFAULT),
        "reference" => Ok(TableSizes::REFERENCE),
        other => bail!("{other}: expected default or reference"),
    }
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let (scene, camera, mut settings) = setup(args)?;
    let (width, height) = (settings.width, settings.height);
    let time_lapse = args
        .time_lapse
        .as_deref()
        .map(parse_time_lapse)
        .transpose()?;
    let mut renderer = args.open_renderer(args.gpu.context()?, &scene)?;
    world_haze(&renderer, &mut settings);
    args.post.configure(&mut renderer, &args.gpu, &scene)?;
    if args.graph {
        print!("{}", renderer.describe_graph(&settings)?);
        return Ok(());
    }
    let progress = (args.frames > 1).then(|| {
        let bar = indicatif::ProgressBar::new(args.frames as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{msg} [{bar:40}] {pos}/{len} frames, {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.set_message("rendering");
        bar
    });
    for i in 0..args.frames {
        let mut cam = camera.clone();
        if let Some((start, end)) = time_lapse {
            let f = i as f32 / (args.frames - 1).max(1) as f32;
            settings.sun.time_hours = start + (end - start) * f;
            // Hours pass between frames: no history, adaptation starts adapted.
            renderer.reset_history();
        } else {
            cam.position += cam.forward * (args.speed * i as f32);
        }
        // Animation (moving objects, sway) at 30 frames per second of sequence time.
        settings.time_s = args.at + i as f32 / 30.0;
        // Offline frames wait for every sector in range: the same image on every run.
        renderer.settle_world(&cam, std::time::Duration::from_secs(600))?;
        let frame = renderer.render(&cam, &settings)?;
        let path = if args.frames > 1 {
            sequence_path(&args.out, i)
        } else {
            args.out.clone()
        };
        himal::image_io::save(&path, &frame.image)?;
        if args.print_exposure {
            let (l_avg, l_a) = renderer.exposure_state()?;
            let line = format!("frame {i}: log-average {l_avg:.5}, adapted {l_a:.5}");
            match &progress {
                // println on a hidden bar (no terminal) would drop the line.
                Some(bar) => bar.suspend(|| println!("{line}")),
                None => println!("{line}"),
            }
        }
        match &progress {
            Some(bar) => bar.inc(1),
            None => println!(
                "wrote {} ({width}x{height}, {})",
                path.display(),
                renderer.context().info.name
            ),
        }
    }
    let stats = renderer.context().pipelines.stats();
    crate::save_cache(renderer.context());
    if let Some(bar) = progress {
        bar.finish_with_message(format!(
            "wrote {} frames next to {}",
            args.frames,
            args.out.display()
        ));
    }
    println!("pipelines: {stats}");
    Ok(())
}
