//! Deferred lighting (TECHNIQUES M1, M2, L1 foundation): sun with the
//! anisotropic GGX BRDF, SH9 sky irradiance, split-sum ambient specular,
//! aerial perspective. CPU twin: [`reference::shade`]. Permutations (E1):
//! [`LightingKey`] (override constants `SHADOWS`, `FOG`, `SSAO`, `ENV_SPECULAR`,
//! `SKY_OCCLUSION`: L2 height-field sky visibility from `passes/skyocc`).

pub mod reference;

use std::collections::HashMap;

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{draw_fullscreen, target};
use crate::passes::envmap::EnvMapPass;
use crate::passes::gbuffer::GBuffer;
use crate::passes::skyocc::{SkyOccFrame, SkyOccPass};

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
}

impl Default for LightingKey {
    fn default() -> Self {
        Self {
            shadows: true,
            fog: true,
            ssao: true,
            env_specular: true,
            sky_occlusion: false,
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
    };

    /// Every permutation (for pre-warming).
    pub fn all() -> impl Iterator<Item = LightingKey> {
        (0..32u32).map(|bits| LightingKey {
            shadows: bits & 1 != 0,
            fog: bits & 2 != 0,
            ssao: bits & 4 != 0,
            env_specular: bits & 8 != 0,
            sky_occlusion: bits & 16 != 0,
        })
    }

    fn constants(self) -> [(&'static str, f64); 5] {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        [
            ("SHADOWS", b(self.shadows)),
            ("FOG", b(self.fog)),
            ("SSAO", b(self.ssao)),
            ("ENV_SPECULAR", b(self.env_specular)),
            ("SKY_OCCLUSION", b(self.sky_occlusion)),
        ]
    }
}

/// Uniform buffers the lighting pass reads (owned by the renderer).
pub struct LightingInputs<'a> {
    pub view: &'a wgpu::Buffer,
    pub lighting: &'a wgpu::Buffer,
    pub sky: &'a wgpu::Buffer,
    /// Shadow mask of `shadows.mask`, R = sun visibility (1x1 white when off).
    pub shadow_mask: TextureHandle,
    /// Screen-space AO (`.x`); a 1x1 white placeholder when AO is off.
    pub ao: TextureHandle,
    /// Point and spot lights (`LocalLights` in `shaders/shadow.wgsl`, S3).
    pub lights: &'a wgpu::Buffer,
    /// Filtered environment cube and DFG table (L4); `env` orders the read
    /// after this frame's filtering, if any.
    pub envmap: &'a EnvMapPass,
    pub env: TextureHandle,
    /// Sky occlusion pool (L2): handles order the read after this frame's
    /// sector updates; bound whatever the permutation.
    pub skyocc: &'a SkyOccPass,
    pub skyocc_frame: SkyOccFrame,
    /// The permutation to draw with (prepared beforehand).
    pub key: LightingKey,
}

pub struct LightingPass {
    program: Program,
    pipelines: HashMap<LightingKey, wgpu::RenderPipeline>,
}

impl LightingPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let mut pass = Self {
            program: Program::new(ctx, "passes/lighting/deferred.wgsl")?,
            pipelines: HashMap::new(),
        };
        pass.prepare(ctx, LightingKey::default())?;
        Ok(pass)
    }

    /// Fetches the pipeline of permutation `key` (memory, disk or compile).
    pub fn prepare(&mut self, ctx: &GpuContext, key: LightingKey) -> Result<(), GpuError> {
        if self.pipelines.contains_key(&key) {
            return Ok(());
        }
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("lighting.deferred", &targets);
        let constants = key.constants();
        spec.constants = &constants;
        let pipeline = self.program.render_pipeline(ctx, &spec)?;
        self.pipelines.insert(key, pipeline);
        Ok(())
    }

    /// Shades the G-buffer into a new HDR target (sky pixels stay black).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        gbuffer: GBuffer,
        inputs: LightingInputs<'a>,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let hdr = graph.create_texture("hdr", TextureDesc::new_2d(size.0, size.1, HDR_FORMAT));
        let mut pass = graph.add_pass("lighting.deferred");
        for t in [
            gbuffer.albedo,
            gbuffer.frame,
            gbuffer.material,
            gbuffer.depth,
            inputs.shadow_mask,
            inputs.ao,
            inputs.env,
            inputs.skyocc_frame.vis,
            inputs.skyocc_frame.heights,
        ] {
            pass.read(t, TextureAccess::Sampled);
        }
        let hdr = pass.write(hdr, TextureAccess::ColorAttachment);
        let pipeline = self.pipelines.get(&inputs.key);
        pass.execute(move |ctx| {
            let Some(pipeline) = pipeline else {
                errors.record::<()>(Err(GpuError::Other(format!(
                    "lighting permutation {:?} was not prepared",
                    inputs.key
                ))));
                return;
            };
            let sky = inputs.skyocc.bindings();
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("view", inputs.view.as_entire_binding()),
                    ("lighting", inputs.lighting.as_entire_binding()),
                    ("sky", inputs.sky.as_entire_binding()),
                    (
                        "gbuffer_albedo",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.albedo)),
                    ),
                    (
                        "gbuffer_frame",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.frame)),
                    ),
                    (
                        "gbuffer_material",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.material)),
                    ),
                    (
                        "depth",
                        wgpu::BindingResource::TextureView(ctx.view(gbuffer.depth)),
                    ),
                    (
                        "shadow_mask",
                        wgpu::BindingResource::TextureView(ctx.view(inputs.shadow_mask)),
                    ),
                    (
                        "ao",
                        wgpu::BindingResource::TextureView(ctx.view(inputs.ao)),
                    ),
                    ("lights", inputs.lights.as_entire_binding()),
                    (
                        "env_specular",
                        wgpu::BindingResource::TextureView(&inputs.envmap.filtered_cube),
                    ),
                    (
                        "env_sampler",
                        wgpu::BindingResource::Sampler(&inputs.envmap.sampler),
                    ),
                    (
                        "dfg_lut",
                        wgpu::BindingResource::TextureView(&inputs.envmap.dfg_view),
                    ),
                    (
                        "skyocc_table",
                        wgpu::BindingResource::TextureView(sky.table),
                    ),
                    ("skyocc_vis", wgpu::BindingResource::TextureView(sky.vis)),
                    (
                        "skyocc_heights_load",
                        wgpu::BindingResource::TextureView(sky.heights),
                    ),
                    (
                        "skyocc_sampler",
                        wgpu::BindingResource::Sampler(sky.sampler),
                    ),
                ],
            );
            if let Some(bg) = errors.record(bind_group) {
                let target = ctx.view(hdr);
                draw_fullscreen(
                    ctx,
                    pipeline,
                    &bg,
                    target,
                    wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    None,
                );
            }
        });
        hdr
    }
}
