//! What a frame is asked for: [`FrameSettings`], the buffer it shows
//! ([`ViewBuffer`]) and the output formats.

use crate::Error;
use crate::passes::ao::{AoSettings, AoView};
use crate::passes::debug::DebugView;
use crate::passes::envmap::EnvView;
use crate::passes::post::{AdaptationSettings, BloomSettings};
use crate::passes::shadows::{ShadowSettings, ShadowView};
use crate::passes::skyocc::SkyOccView;
use crate::scene::SunDesc;

/// Format of the displayable output (PNG).
pub const DISPLAY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Format of raw float output (EXR of a debug view).
pub const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Sun cascade edge (S1): four 2048² cascades hold as many texels as the
/// single 4096² map they replaced (docs/techniques/S1.md).
pub const DEFAULT_SHADOW_RESOLUTION: u32 = 2048;

/// The buffer a frame shows (`--view`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ViewBuffer {
    /// The tonemapped, post-processed image.
    #[default]
    Final,
    /// A G-buffer channel or other debug visualisation (`albedo`, `normal`, `depth`, `motion`, `sectors`, `lod`...).
    Debug(DebugView),
    /// AO buffers (`ao`, `ao-raw`, `stability-mask`).
    Ao(AoView),
    /// Shadow buffers (`shadow-mask`, `cascades`).
    Shadow(ShadowView),
    /// What the ambient specular reads from the environment cube (`env-probe`, `env-mirror`).
    Env(EnvView),
    /// Sky occlusion (L2: `sky-visibility`, `bent-normal`).
    SkyOcc(SkyOccView),
    /// The final image with white particles: their lighting alone (E4,
    /// `particle-lighting`).
    ParticleLighting,
    /// L5's probes (the lighting view's display): `indirect` (irradiance,
    /// klux raw), `probe-cells` (the grid of the cascade each pixel reads),
    /// `clipmap` (the cascade as a hue).
    Indirect(IndirectView),
    /// V4: the tree occlusion volumes' factor on the sky light
    /// (`tree-ao`; white outside every tree's box).
    TreeAo,
}

/// What `--view indirect|probe-cells|clipmap` shows (L5); the number is
/// the mode the lighting pass reads (`IndirectParams::counts.y`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IndirectView {
    /// The probes' indirect irradiance.
    Irradiance = 0,
    /// The irradiance with the probes of the sampled cascade as dots and
    /// the cells' borders as lines.
    ProbeCells = 1,
    /// The cascade each pixel samples as a hue (C + 1 blended in), shaded
    /// by the irradiance.
    ClipMap = 2,
}

impl ViewBuffer {
    /// Every name `--view` accepts (what [`str::parse`] reads), in the order the viewer lists them.
    pub const NAMES: [&'static str; 33] = [
        "final",
        "albedo",
        "normal",
        "tangent",
        "glossiness",
        "reflectance",
        "metallic",
        "anisotropy",
        "depth",
        "motion",
        "lighting",
        "ao",
        "ao-raw",
        "stability-mask",
        "luminance",
        "bloom",
        "shadow-mask",
        "cascades",
        "env-probe",
        "env-mirror",
        "sky-visibility",
        "bent-normal",
        "sectors",
        "lod",
        "ssdo",
        "ao-bleed",
        "particle-lighting",
        "indirect",
        "probe-cells",
        "clipmap",
        "impostor",
        "foliage",
        "tree-ao",
    ];

    /// The tone-mapped image (the final one, or the particles' lighting in it).
    pub fn is_final(self) -> bool {
        matches!(self, ViewBuffer::Final | ViewBuffer::ParticleLighting)
    }
}

impl std::str::FromStr for ViewBuffer {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        use DebugView as D;
        Ok(match s {
            "final" => ViewBuffer::Final,
            "albedo" => ViewBuffer::Debug(D::Albedo),
            "normal" => ViewBuffer::Debug(D::Normal),
            "tangent" => ViewBuffer::Debug(D::Tangent),
            "glossiness" => ViewBuffer::Debug(D::Glossiness),
            "reflectance" => ViewBuffer::Debug(D::Reflectance),
            "metallic" => ViewBuffer::Debug(D::Metallic),
            "anisotropy" => ViewBuffer::Debug(D::Anisotropy),
            "depth" => ViewBuffer::Debug(D::Depth),
            "motion" => ViewBuffer::Debug(D::Motion),
            "lighting" => ViewBuffer::Debug(D::Lighting),
            "ao" => ViewBuffer::Ao(AoView::Ao),
            "ao-raw" => ViewBuffer::Ao(AoView::Raw),
            "stability-mask" => ViewBuffer::Ao(AoView::Stability),
            "ssdo" => ViewBuffer::Ao(AoView::Directional),
            "ao-bleed" => ViewBuffer::Ao(AoView::Bleed),
            "luminance" => ViewBuffer::Debug(D::Luminance),
            "bloom" => ViewBuffer::Debug(D::Bloom),
            "shadow-mask" => ViewBuffer::Shadow(ShadowView::Mask),
            "cascades" => ViewBuffer::Shadow(ShadowView::Cascades),
            "env-probe" => ViewBuffer::Env(EnvView::Probe),
            "env-mirror" => ViewBuffer::Env(EnvView::Mirror),
            "sky-visibility" => ViewBuffer::SkyOcc(SkyOccView::Visibility),
            "bent-normal" => ViewBuffer::SkyOcc(SkyOccView::BentNormal),
            "sectors" => ViewBuffer::Debug(D::Sectors),
            "lod" => ViewBuffer::Debug(D::Lod),
            "impostor" => ViewBuffer::Debug(D::Impostor),
            "foliage" => ViewBuffer::Debug(D::Foliage),
            "particle-lighting" => ViewBuffer::ParticleLighting,
            "indirect" => ViewBuffer::Indirect(IndirectView::Irradiance),
            "probe-cells" => ViewBuffer::Indirect(IndirectView::ProbeCells),
            "clipmap" => ViewBuffer::Indirect(IndirectView::ClipMap),
            "tree-ao" => ViewBuffer::TreeAo,
            other => {
                return Err(Error::InvalidSettings(format!(
                    "unknown view \"{other}\" (known: {})",
                    ViewBuffer::NAMES.join(", ")
                )));
            }
        })
    }
}

/// Everything one frame needs besides the camera.
#[derive(Clone, Debug)]
pub struct FrameSettings {
    /// Output width in pixels (at least 1).
    pub width: u32,
    /// Output height in pixels (at least 1).
    pub height: u32,
    /// The buffer the frame shows (`--view`).
    pub view: ViewBuffer,
    /// Raw float values (for EXR) instead of a displayable image.
    pub raw: bool,
    /// Sun position and sky inputs: time of day, latitude, day of year, turbidity.
    pub sun: SunDesc,
    /// Exposure bias in EV on top of the auto exposure.
    pub exposure_ev: f32,
    /// H3 light adaptation; off = expose each frame for its own log-average.
    pub adaptation: AdaptationSettings,
    /// Reinhard white point (scaled luminance mapped to white); `None` = L/(1+L).
    pub white_point: Option<f32>,
    /// The tone-map curve (Reinhard, the talk's, by default).
    pub tonemapper: crate::passes::post::Tonemapper,
    /// H2 Kawase bloom.
    pub bloom: BloomSettings,
    /// Aerial perspective extinction per metre (0 = off).
    pub aerial_extinction: f32,
    /// Sun cascade edge in texels; 0 = shadows off.
    pub shadow_resolution: u32,
    /// Shadow mode, split, static map, hero (S1-S4).
    pub shadows: ShadowSettings,
    /// Screen-space AO (TECHNIQUES O1-O3).
    pub ao: AoSettings,
    /// Ambient specular from the GGX-filtered sky cube (L4, M4); off: SH
    /// along the reflection vector.
    pub environment_specular: bool,
    /// L2 height-field sky occlusion (sky light and ambient specular times
    /// the SH2 visibility along the bent normal). Off by default in the
    /// library (the L3 relighting test compares against unoccluded lighting);
    /// the CLI turns it on.
    pub sky_occlusion: bool,
    /// L5: indirect light from the baked radiance-transfer probes (needs
    /// [`crate::Renderer::set_probe_cells`]; `--indirect`).
    pub indirect: bool,
    /// L2: evaluate the sky light along the bent normal (on by default);
    /// off keeps the visibility but uses the surface normal (comparisons).
    pub bent_normals: bool,
    /// V6: draw runs of consecutive objects of one mesh as one instanced
    /// draw (on by default); off: one draw per object (comparisons).
    pub instancing: bool,
    /// Which objects the G-buffer and the sun cascades draw (V6): those
    /// whose bounds may be inside the view, culled on the GPU (default)
    /// or the CPU, or every object (`Off`: the G-buffer; cascades still
    /// cull on the CPU).
    pub culling: Culling,
    /// V6 Hi-Z occlusion culling of the camera's objects against the
    /// previous frame's depth (GPU culling path only; off by default).
    pub occlusion: Occlusion,
    /// E2 LOD by triangle size: an object draws its next level once its
    /// mean triangle would cover fewer than this many pixels; 0 = LOD0
    /// everywhere (the library's default, so references stay exact; the
    /// CLI turns it on).
    pub lod_threshold_px: f32,
    /// E2 transitions: over this fraction of the first transition distance
    /// before each switch, the GPU path draws both levels with
    /// complementary screen-door masks (0: levels pop).
    pub lod_band: f32,
    /// E2 guard (himal's, beside the talk's triangle size): no level whose
    /// simplification error would show more than this many pixels (0: none).
    pub lod_error_px: f32,
    /// E2 comparison metric: when > 0, levels by object size instead of
    /// triangle size, the first switch where the object's bounding radius
    /// projects to this many pixels (later ones at multiples of it).
    pub lod_object_px: f32,
    /// Forget the sky occlusion sectors each frame so the wanted ones are
    /// re-rendered (bench rows `skyocc.*`).
    pub sky_occlusion_every_frame: bool,
    /// L3: ambient specular from the relit G-buffer cube of the probe
    /// nearest the camera (scenes with `[[probe]]`); off: the sky cube.
    pub environment_probes: bool,
    /// Re-capture and re-filter the environment cube every frame (bench rows;
    /// otherwise only when the sky changes).
    pub envmap_every_frame: bool,
    /// Anti-aliasing after tone mapping (TECHNIQUES A1-A4).
    pub aa: crate::passes::aa::AaMode,
    /// Tuning of the temporal anti-aliasing passes.
    pub aa_tuning: crate::passes::aa::TemporalTuning,
    /// A3 TAA on the AO and the motion vectors (`--aa-buffers`).
    pub aa_buffers: crate::passes::aa::AaBuffers,
    /// L1 sky: Preetham (default, the goldens' sky) or Bruneton tables.
    pub sky_model: crate::passes::sky::SkyModel,
    /// E3 specular anti-aliasing: glTF roughness widened by the normal
    /// variance baked into normal-map mips (Toksvig; on by default).
    pub specular_aa: bool,
    /// SMAA blending weights only on edge pixels (#23; the reference's
    /// stencil as a depth mask written by the edge pass; the same image;
    /// on by default).
    pub smaa_edge_mask: bool,
    /// Motion vectors of skinned vertices from their previous frame's pose
    /// (`passes/skin`, `shaders/deform.wgsl`); off: from the object's
    /// transform only (TAA then smears moving limbs).
    pub deform_motion: bool,
    /// R4: Burley's remapped roughness ((1 + r) / 2)^2 in the visibility
    /// term of the sun and local lights, less specular gain on rough
    /// surfaces at grazing light (off by default; docs/techniques/R4.md).
    pub visibility_remap: bool,
    /// The scene's `[[ambient_light]]` volumes scale the ambient light (on
    /// by default; docs/ambient-lights.md).
    pub ambient_lights: bool,
    /// Wetness of up-facing surfaces in [0, 1] (`gbuffer.wet`, E3's
    /// screen-space filter example); 0: the pass does not run.
    pub wetness: f32,
    /// E4 particles: the scene's `[[emitter]]`s simulated, lit and drawn
    /// (on by default; scenes without emitters draw nothing either way).
    pub particles: bool,
    /// E4: light the particles at each pixel instead of once per particle
    /// (the reference of the per-particle light; off by default).
    pub particles_per_pixel: bool,
    /// E4: light the centre and the corners of a particle's quad and
    /// interpolate across it (Ryse's per-vertex light; on by default)
    /// instead of once at its centre.
    pub particles_light_corners: bool,
    /// E4: light the particles at each pixel with the world's sun shadow
    /// (cascades, S1 filter) instead of the static map's 4 x 4 gather per
    /// particle (the reference of Ryse's particle shadows; off by default).
    pub particles_cascaded_shadows: bool,
    /// E4: particles mark a reactive mask that shortens the TAA history
    /// where they drew this frame or the last (no trails behind moving
    /// smoke; on by default).
    pub particles_reactive: bool,
    /// E4: each emitter's particles drawn far to near (a GPU sort per
    /// emitter, rings up to 1024 slots; off: ring order).
    pub particles_sort: bool,
    /// E4: particles' ambient from the environment cube's lowest specular
    /// mip (Ryse) instead of the sky irradiance the world's surfaces get
    /// (off by default: the world's own term keeps particles consistent).
    pub particles_probe_ambient: bool,
    /// V1 vegetation drawn: trees (trunks and leaves), bushes and grass
    /// (off: their draws are skipped in every pass; the frame culls on the
    /// CPU then, as the GPU culling's lists hold every object).
    pub vegetation: bool,
    /// V3 depth impostors as the trees' leaves' level after LOD2 (off:
    /// LOD2 stays to the end).
    pub impostors: bool,
    /// V4: the trees' occlusion volumes darken the sky light of everything
    /// inside their boxes (the trees and the ground under them).
    pub tree_ao: bool,
    /// V2 wind on the trees (`vegetation.simulate`) and V5's branch waves
    /// and leaf flutter; `Bones`: V2 alone; `Off`: at rest.
    pub vegetation_motion: crate::passes::vegetation::VegetationMotion,
    /// V5 leaf shading: foliage pixels (the G-buffer's leaf amount) get
    /// light through the leaf from behind and a low, broad specular (off:
    /// shaded like any dielectric).
    pub leaf_shading: bool,
    /// V2: the global wind (m/s) in place of the scene's `[wind]`
    /// (`--wind SPEED,DIR`); `None`: the scene's.
    pub wind: Option<glam::Vec3>,
    /// Animation clock in seconds (moving objects, vegetation sway); set by
    /// the caller, e.g. frame / 30 in sequences, so frames are deterministic.
    pub time_s: f32,
}

/// Frustum culling of the G-buffer and the cascades (V6).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Culling {
    /// Every object in the G-buffer.
    Off,
    /// Per object on the render thread (the path of adapters without
    /// indirect draws).
    Cpu,
    /// Per instance on the GPU, drawn with multi-draw-indirect; the CPU
    /// path where the adapter lacks indirect draws with a first instance,
    /// or with instancing off.
    #[default]
    Gpu,
}

/// Occlusion culling of the camera's view (V6, issue #17 item 5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Occlusion {
    /// Frustum and distance culling only.
    #[default]
    Off,
    /// Each object's box reprojected with the previous frame's
    /// view-projection and tested against a min-depth pyramid of that
    /// frame's depth (`cull.hiz`); objects hidden last frame that this
    /// camera sees appear one frame late. Needs the GPU culling path (the
    /// CPU path has no previous depth) and `--culling gpu`.
    Hiz,
}

impl FrameSettings {
    /// Defaults for a `width` x `height` frame under `sun`: the final image,
    /// every technique at its default setting.
    pub fn new(width: u32, height: u32, sun: SunDesc) -> Self {
        Self {
            width,
            height,
            view: ViewBuffer::Final,
            raw: false,
            sun,
            exposure_ev: 0.0,
            adaptation: AdaptationSettings::default(),
            white_point: None,
            tonemapper: Default::default(),
            bloom: BloomSettings::default(),
            aerial_extinction: 2.5e-4,
            shadow_resolution: DEFAULT_SHADOW_RESOLUTION,
            shadows: ShadowSettings::default(),
            ao: AoSettings::default(),
            aa: crate::passes::aa::AaMode::None,
            aa_tuning: Default::default(),
            aa_buffers: Default::default(),
            time_s: 0.0,
            environment_specular: true,
            sky_occlusion: false,
            indirect: false,
            bent_normals: true,
            instancing: true,
            culling: Culling::Gpu,
            occlusion: Occlusion::Off,
            lod_threshold_px: 0.0,
            lod_band: 0.2,
            lod_error_px: 1.0,
            lod_object_px: 0.0,
            sky_occlusion_every_frame: false,
            environment_probes: true,
            envmap_every_frame: false,
            sky_model: Default::default(),
            specular_aa: true,
            smaa_edge_mask: true,
            deform_motion: true,
            visibility_remap: false,
            ambient_lights: true,
            wetness: 0.0,
            particles: true,
            particles_per_pixel: false,
            particles_light_corners: true,
            particles_cascaded_shadows: false,
            particles_reactive: true,
            particles_sort: true,
            particles_probe_ambient: false,
            vegetation: true,
            impostors: true,
            tree_ao: true,
            vegetation_motion: Default::default(),
            leaf_shading: true,
            wind: None,
        }
    }
}
