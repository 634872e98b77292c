//! `post.tonemap`: bloom composite and a tone mapper (Reinhard, Khronos
//! PBR Neutral, ACES, AgX), one pipeline per [`TonemapKey`] (override
//! constants `BLOOM`, `WHITE_POINT`, `TONEMAP`). Curves:
//! `docs/techniques/H3.md`; CPU twin: `reference.rs`.

use std::str::FromStr;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, Fallback, FrameGraph, TextureHandle};
use crate::passes::common::target;

/// The curve from exposed scene-referred colour to display-linear [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Tonemapper {
    /// Reinhard et al. 2002 on luminance, hue kept (the talk's, H3; the default).
    #[default]
    Reinhard,
    /// Khronos PBR Neutral (glTF viewers: base colours kept up to 0.76).
    Neutral,
    /// ACES RRT + sRGB ODT, Hill's fit, with three.js's 1/0.6 exposure.
    Aces,
    /// AgX (Blender's base look), the analytic sigmoid of its LUT script.
    Agx,
}

impl Tonemapper {
    /// Every curve, in the order the viewer cycles them (and the shader's `TONEMAP` ids).
    pub const ALL: [Tonemapper; 4] = [
        Tonemapper::Reinhard,
        Tonemapper::Neutral,
        Tonemapper::Aces,
        Tonemapper::Agx,
    ];

    /// The `--tonemap` name (`reinhard`, `neutral`, `aces`, `agx`).
    pub fn name(self) -> &'static str {
        match self {
            Tonemapper::Reinhard => "reinhard",
            Tonemapper::Neutral => "neutral",
            Tonemapper::Aces => "aces",
            Tonemapper::Agx => "agx",
        }
    }

    /// The shader's `TONEMAP` constant.
    fn id(self) -> f64 {
        Self::ALL.iter().position(|&m| m == self).unwrap_or(0) as f64
    }

    /// The next one (the viewer cycles them).
    pub fn next(self) -> Tonemapper {
        Self::ALL[(self.id() as usize + 1) % Self::ALL.len()]
    }
}

impl FromStr for Tonemapper {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = Self::ALL.iter().map(|m| m.name()).collect();
                format!("tone mapper \"{s}\": expected {}", names.join(", "))
            })
    }
}

/// The tone-map permutation: which code the shader keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct TonemapKey {
    /// Add the bloom chain's output before the curve.
    pub bloom: bool,
    /// Reinhard's white point (eq. 4); only with [`Tonemapper::Reinhard`].
    pub white_point: bool,
    /// The tone curve.
    pub mapper: Tonemapper,
}

impl TonemapKey {
    /// Every permutation (for pre-warming).
    pub fn all() -> Vec<TonemapKey> {
        let mut keys = Vec::new();
        for mapper in Tonemapper::ALL {
            for bloom in [false, true] {
                for white_point in [false, true] {
                    if white_point && mapper != Tonemapper::Reinhard {
                        continue;
                    }
                    keys.push(TonemapKey {
                        bloom,
                        white_point,
                        mapper,
                    });
                }
            }
        }
        keys
    }

    fn constants(self) -> [(&'static str, f64); 3] {
        let b = |v: bool| if v { 1.0 } else { 0.0 };
        [
            ("BLOOM", b(self.bloom)),
            ("WHITE_POINT", b(self.white_point)),
            ("TONEMAP", self.mapper.id()),
        ]
    }
}

/// What `post.tonemap` and the debug views read besides the HDR image.
#[derive(Clone, Copy)]
pub struct PostInputs<'a> {
    /// The frame's [`super::PostUniform`] (key, white point, exposure bias, bloom strength).
    pub post: &'a wgpu::Buffer,
    /// Adapted luminance or this frame's log-average.
    pub exposure: BufferHandle,
    /// Bloom chain output; `None`: no bloom (the shader skips it).
    pub bloom: Option<TextureHandle>,
    /// Linear clamp sampler for upsampling the bloom.
    pub sampler: &'a wgpu::Sampler,
}

/// `post.tonemap`: exposes the HDR image, adds bloom, applies the tone curve and writes the display target.
pub struct TonemapPass {
    program: Program,
    format: wgpu::TextureFormat,
}

impl TonemapPass {
    /// Compiles the tonemap shader for targets of `output_format` and makes the default permutation.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let pass = Self {
            program: Program::new(ctx, "passes/post/tonemap.wgsl")?,
            format: output_format,
        };
        pass.pipeline(ctx, TonemapKey::default())?;
        Ok(pass)
    }

    /// The pipeline of permutation `key` (memory, disk or compile).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        key: TonemapKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [target(self.format)];
        let mut spec = RenderSpec::fullscreen("post.tonemap", &targets);
        let constants = key.constants();
        spec.constants = &constants;
        self.program.render_pipeline(ctx, &spec)
    }

    /// Tone-maps `hdr` (plus bloom) into `output` (imported LDR target); returns its new version.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        key: TonemapKey,
        hdr: TextureHandle,
        inputs: PostInputs<'a>,
        output: TextureHandle,
    ) -> TextureHandle {
        graph
            .fullscreen("post.tonemap", &self.program)
            .pipeline(self.pipeline(ctx, key))
            .uniform("post", inputs.post)
            .read("hdr", hdr)
            .read_buffer("exposure", inputs.exposure, BufferAccess::StorageRead)
            .optional("bloom", inputs.bloom, Fallback::Black)
            .sampler("bloom_sampler", inputs.sampler)
            .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }
}
