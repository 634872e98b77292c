//! Deferred lighting (TECHNIQUES M1, M2, L1 foundation): sun with the
//! anisotropic GGX BRDF, SH9 sky irradiance, split-sum ambient specular,
//! aerial perspective. CPU twin: [`reference::shade`]. Permutations (E1):
//! [`LightingKey`] (override constants `SHADOWS`, `FOG`, `SSAO`, `ENV_SPECULAR`,
//! `SKY_OCCLUSION`: L2 height-field sky visibility from `passes/skyocc`;
//! `SSDO`, `REFLECTION_OCCLUSION`: O4 directional occlusion).

pub mod ambient;
pub mod reference;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{Fallback, FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::target;
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::GBuffer;
use crate::passes::indirect::{IndirectFrame, IndirectPass};
use crate::passes::skyocc::{SkyOccFrame, SkyOccPass};

/// Format of the HDR scene-radiance targets (lighting, sky, forward, bloom):
/// linear radiance in kcd/m², before exposure and tone mapping.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The lighting permutation, Far Cry's "environment" axis: which light
/// terms the shader keeps (static branches on override constants).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightingKey {
    /// Sun shadow lookup.
    pub shadows: bool,
    /// Aerial perspective.
    pub fog: bool,
    /// Screen-space AO fetch.
    pub ssao: bool,
    /// Ambient specular from the filtered environment cube and the DFG
    /// table (L4, M4); off: SH along the reflection vector and the fitted DFG.
    pub env_specular: bool,
    /// L2 sky occlusion: SH2 visibility and bent normal from the sector pool.
    pub sky_occlusion: bool,
    /// O4: the directional term occludes the sun and local lights (needs `ssao`).
    pub ssdo: bool,
    /// O4 reflection occlusion of ambient specular: along the reflection
    /// vector with `ssdo`, Lagarde's AO formula without.
    pub reflection_occlusion: bool,
    /// O5 colour bleeding: ambient diffuse occlusion tinted per channel by
    /// the low-frequency albedo (`passes/ao/bleed`); only with `ssao`.
    pub ao_bleed: bool,
    /// L5: indirect light from the probes' clip map replaces the sky SH's
    /// flat ground bounce (passes/indirect).
    pub indirect: bool,
    /// `--view indirect`: the pass writes L5's irradiance alone (needs `indirect`).
    pub indirect_view: bool,
}

impl Default for LightingKey {
    fn default() -> Self {
        Self {
            shadows: true,
            fog: true,
            ssao: true,
            env_specular: true,
            sky_occlusion: false,
            ssdo: false,
            reflection_occlusion: false,
            ao_bleed: false,
            indirect: false,
            indirect_view: false,
        }
    }
}

impl LightingKey {
    /// Relighting environment probes (L3): sun unshadowed, sky SH, nothing else.
    pub const RELIGHT: LightingKey = LightingKey {
        shadows: false,
        fog: false,
        ssao: false,
        env_specular: false,
        sky_occlusion: false,
        ssdo: false,
        reflection_occlusion: false,
        ao_bleed: false,
        indirect: false,
        indirect_view: false,
    };

    /// Every shading permutation (for pre-warming; `ssdo` and bleeding only
    /// with `ssao`; not the `--view indirect` one).
    pub fn all() -> impl Iterator<Item = LightingKey> {
        (0..512u32)
            .map(|bits| LightingKey {
                shadows: bits & 1 != 0,
                fog: bits & 2 != 0,
                ssao: bits & 4 != 0,
                env_specular: bits & 8 != 0,
                sky_occlusion: bits & 16 != 0,
                ssdo: bits & 32 != 0,
                reflection_occlusion: bits & 64 != 0,
                ao_bleed: bits & 128 != 0,
                indirect: bits & 256 != 0,
                // The indirect view compiles on first use (a debug view).
                indirect_view: false,
            })
            .filter(|k| k.ssao || !(k.ssdo || k.ao_bleed))
    }

    fn constants(self) -> [(&'static str, f64); 10] {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        [
            ("SHADOWS", b(self.shadows)),
            ("FOG", b(self.fog)),
            ("SSAO", b(self.ssao)),
            ("ENV_SPECULAR", b(self.env_specular)),
            ("SKY_OCCLUSION", b(self.sky_occlusion)),
            ("SSDO", b(self.ssdo)),
            ("REFLECTION_OCCLUSION", b(self.reflection_occlusion)),
            ("AO_BLEED", b(self.ao_bleed)),
            ("INDIRECT", b(self.indirect)),
            ("INDIRECT_VIEW", b(self.indirect_view)),
        ]
    }
}

/// What the lighting pass reads besides the G-buffer and the frame
/// constants (view, lighting, sky).
pub struct LightingInputs<'a> {
    /// Shadow mask of `shadows.mask`, R = sun visibility; `None`: unshadowed.
    pub shadow_mask: Option<TextureHandle>,
    /// Screen-space AO (`.x`); `None`: unoccluded.
    pub ao: Option<TextureHandle>,
    /// O4 directional coefficients (c1, c2); `None`: none (read as 0).
    pub ao_dir: Option<TextureHandle>,
    /// `AoParams` (the O4 strength and penumbra widths).
    pub ao_params: &'a wgpu::Buffer,
    /// O5 bleed colour (`passes/ao/bleed`); `None`: black (plain occlusion).
    pub ao_bleed: Option<TextureHandle>,
    /// Point and spot lights (`LocalLights` in `shaders/shadow.wgsl`, S3).
    pub lights: &'a wgpu::Buffer,
    /// The environment-map pass, for its DFG table and cube sampler (L4).
    pub envmap: &'a EnvMapPass,
    /// Filtered environment cube (L4, `envmap.filtered` after this
    /// frame's filtering, if any), read as `env_specular`.
    pub env: TextureHandle,
    /// Sky occlusion pass (L2), for its sector table and sampler.
    pub skyocc: &'a SkyOccPass,
    /// The sky occlusion pool's visibility and height layers as graph
    /// handles, so lighting is ordered after this frame's sector updates.
    pub skyocc_frame: SkyOccFrame,
    /// L5: the probes' pass (its parameters and sampler) and this frame's
    /// clip map; `None`: no indirect light (the sky SH's flat ground).
    pub indirect: Option<(&'a IndirectPass, IndirectFrame)>,
    /// The permutation to draw with.
    pub key: LightingKey,
}

/// The deferred lighting pass (`lighting.deferred`): shades the G-buffer
/// into an [`HDR_FORMAT`] target, one pipeline per [`LightingKey`].
pub struct LightingPass {
    program: Program,
    /// The scene's `[[ambient_light]]`s (also bound by the forward passes).
    pub ambient_lights: ambient::AmbientLightBuffer,
}

impl LightingPass {
    /// Loads `deferred.wgsl`, uploads the scene's ambient lights and builds
    /// the default permutation (an error if the shader does not compile).
    pub fn new(ctx: &GpuContext, scene: &crate::scene::Scene) -> Result<Self, GpuError> {
        let pass = Self {
            program: Program::new(ctx, "passes/lighting/deferred.wgsl")?,
            ambient_lights: ambient::AmbientLightBuffer::new(&ctx.device, &scene.ambient_lights),
        };
        pass.pipeline(ctx, LightingKey::default())?;
        Ok(pass)
    }

    /// The pipeline of permutation `key` (memory, disk or compile).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        key: LightingKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("lighting.deferred", &targets);
        let constants = key.constants();
        spec.constants = &constants;
        self.program.render_pipeline(ctx, &spec)
    }

    /// Shades the G-buffer into a new HDR target (sky pixels stay black).
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        inputs: LightingInputs<'a>,
    ) -> TextureHandle {
        let hdr = graph.create_texture("hdr", TextureDesc::new_2d(size.0, size.1, HDR_FORMAT));
        let envmap = inputs.envmap;
        let sky = inputs.skyocc.bindings();
        graph
            .fullscreen("lighting.deferred", &self.program)
            .pipeline(self.pipeline(ctx, inputs.key))
            .read("gbuffer_albedo", gbuffer.albedo)
            .read("gbuffer_frame", gbuffer.frame)
            .read("gbuffer_material", gbuffer.material)
            .read("depth", gbuffer.depth)
            .optional("shadow_mask", inputs.shadow_mask, Fallback::White)
            .optional("ao", inputs.ao, Fallback::White)
            .optional("ao_dir", inputs.ao_dir, Fallback::Black)
            .uniform("ao_params", inputs.ao_params)
            .optional("ao_bleed", inputs.ao_bleed, Fallback::Black)
            .uniform("lights", inputs.lights)
            .uniform("ambient_lights", &self.ambient_lights.buffer)
            .read_cube("env_specular", inputs.env)
            .sampler("env_sampler", &envmap.sampler)
            .external("dfg_lut", &envmap.dfg_view)
            .external("skyocc_table", sky.table)
            .read_array("skyocc_vis", inputs.skyocc_frame.vis)
            .read_array("skyocc_heights_load", inputs.skyocc_frame.heights)
            .sampler("skyocc_sampler", sky.sampler)
            .optional_buffer("indirect_params", inputs.indirect.map(|i| &i.0.params))
            .optional_array(
                "indirect_r",
                inputs.indirect.map(|i| i.1.clip[0]),
                Fallback::BlackArray,
            )
            .optional_array(
                "indirect_g",
                inputs.indirect.map(|i| i.1.clip[1]),
                Fallback::BlackArray,
            )
            .optional_array(
                "indirect_b",
                inputs.indirect.map(|i| i.1.clip[2]),
                Fallback::BlackArray,
            )
            .sampler("indirect_sampler", &envmap.sampler)
            .color(hdr, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }
}
