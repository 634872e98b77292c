//! The frame options `render`, `bench`, `view` and `soak` share: HDR post
//! and the techniques' switches (`PostArgs`), shadows (`ShadowArgs`).
//! Moved from render.rs as they are.

use anyhow::{Context, Result, bail};
use clap::Args;
use himal::FrameSettings;
use himal::Renderer;
use himal::passes::post::Tonemapper;
use himal::passes::sky::bruneton::TableSizes;
use himal::scene::Scene;

use crate::render::parse_table_sizes;

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
    /// SMAA blending weights only on edge pixels (#23: a depth mask from
    /// the edge pass, as the reference's stencil; the same image).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub smaa_edge_mask: String,
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
    /// Motion vectors of skinned glTF vertices from their previous frame's
    /// pose (off: from the object's transform only, as before issue #22).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub deform_motion: String,
    /// V1 vegetation: trees, bushes and grass drawn (off: skipped in every
    /// pass; the frame then culls on the CPU).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub vegetation: String,
    /// V3 depth impostors: trees' leaves past LOD2 draw as impostors
    /// (off: LOD2 stays to the end).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub impostors: String,
    /// V4 tree occlusion volumes: the sky light of the trees and of the
    /// ground under them darkened by each species' baked volume.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub tree_ao: String,
    /// V2: trees bent by the wind, simulated on the GPU, with V5's branch
    /// waves and leaf flutter (bones: V2 alone; off: at rest).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|bones|off",
        allow_hyphen_values = true
    )]
    pub vegetation_motion: String,
    /// V5: leaves lit through from behind (translucency of the sun and
    /// local lights) with a low, broad specular (off: like any dielectric).
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub leaf_shading: String,
    /// V2: the global wind, SPEED (m/s, 0..100) toward DIR degrees about +Y
    /// from +X (90: toward -z), in place of the scene's `[wind]`.
    #[arg(long, value_name = "SPEED,DIR", allow_hyphen_values = true)]
    pub wind: Option<String>,
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
    /// E4 particle lighting: at the corners of each particle's quad,
    /// interpolated across it (vertex, Ryse's), once at its centre
    /// (particle), or at every pixel (pixel, the reference both are
    /// measured against).
    #[arg(
        long,
        default_value = "vertex",
        value_name = "vertex|particle|pixel",
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
        self.configure_for(renderer, gpu, scene, false)
    }

    /// [`Self::configure`] for the viewer: the world's probe cells bake on
    /// a background thread (frames never wait; unbaked ground keeps the
    /// flat bounce until its cells arrive).
    pub fn configure_live(
        &self,
        renderer: &mut Renderer,
        gpu: &crate::GpuArgs,
        scene: &Scene,
    ) -> Result<()> {
        self.configure_for(renderer, gpu, scene, true)
    }

    fn configure_for(
        &self,
        renderer: &mut Renderer,
        gpu: &crate::GpuArgs,
        scene: &Scene,
        background: bool,
    ) -> Result<()> {
        if on_off("--indirect", &self.indirect)? {
            let cache = gpu.cache_dir();
            crate::scene_source::attach_probes(renderer, scene, cache.as_deref(), background)?;
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
        settings.smaa_edge_mask = on_off("--smaa-edge-mask", &self.smaa_edge_mask)?;
        settings.deform_motion = on_off("--deform-motion", &self.deform_motion)?;
        settings.vegetation = on_off("--vegetation", &self.vegetation)?;
        settings.impostors = on_off("--impostors", &self.impostors)?;
        settings.tree_ao = on_off("--tree-ao", &self.tree_ao)?;
        settings.vegetation_motion = (self.vegetation_motion.parse())
            .map_err(|e| anyhow::anyhow!("--vegetation-motion {e}"))?;
        settings.leaf_shading = on_off("--leaf-shading", &self.leaf_shading)?;
        settings.wind = self.wind.as_deref().map(parse_wind).transpose()?;
        settings.visibility_remap = on_off("--visibility-remap", &self.visibility_remap)?;
        settings.ambient_lights = on_off("--ambient-lights", &self.ambient_lights)?;
        if !(0.0..=1.0).contains(&self.wetness) {
            bail!("--wetness {}: must be in [0, 1]", self.wetness);
        }
        settings.wetness = self.wetness;
        settings.particles = on_off("--particles", &self.particles)?;
        (
            settings.particles_light_corners,
            settings.particles_per_pixel,
        ) = match self.particle_lighting.as_str() {
            "vertex" => (true, false),
            "particle" => (false, false),
            "pixel" => (true, true),
            other => bail!("--particle-lighting {other}: expected vertex, particle or pixel"),
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
pub(crate) fn on_off(name: &str, value: &str) -> Result<bool> {
    match value {
        "on" => Ok(true),
        "off" => Ok(false),
        other => bail!("{name} {other}: expected on or off"),
    }
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
    /// glTF MASK and BLEND shadow casters alpha-tested (a leaf card casts
    /// its holes; BLEND as a mask at 0.5), or cast as opaque cards.
    #[arg(
        long,
        default_value = "on",
        value_name = "on|off",
        allow_hyphen_values = true
    )]
    pub shadow_alpha_test: String,
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
        s.alpha_test = match self.shadow_alpha_test.as_str() {
            "on" => true,
            "off" => false,
            other => bail!("--shadow-alpha-test {other}: expected on or off"),
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

/// `--wind SPEED,DIR`: the velocity (the scene file's `[wind]` convention:
/// toward (cos DIR, 0, -sin DIR)).
fn parse_wind(s: &str) -> Result<glam::Vec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [speed, dir] = parts.as_slice() else {
        bail!("--wind {s}: give SPEED,DIR (m/s, degrees), e.g. 8,90");
    };
    let speed: f32 = speed
        .parse()
        .map_err(|_| anyhow::anyhow!("--wind {s}: speed \"{speed}\" is not a number"))?;
    let dir: f32 = dir
        .parse()
        .map_err(|_| anyhow::anyhow!("--wind {s}: direction \"{dir}\" is not a number"))?;
    if !(0.0..=himal::scene::MAX_WIND).contains(&speed) {
        bail!(
            "--wind {s}: speed must lie in [0, {}] m/s",
            himal::scene::MAX_WIND
        );
    }
    if !(-360.0..=360.0).contains(&dir) {
        bail!("--wind {s}: direction must lie in [-360, 360] degrees");
    }
    let a = dir.to_radians();
    Ok(glam::Vec3::new(a.cos(), 0.0, -a.sin()) * speed)
}
