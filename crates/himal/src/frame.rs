//! The whole frame, top to bottom, in one place to read.
//!
//! ```text
//! envmap.capture | envmap.probeN.* ─> envmap.mips ─> envmap.filter ──────────────┐ (when the sky changed)
//! shadows.cascade0..3, shadows.static, shadows.hero ─┐
//! gbuffer ─┬─────────────────────────────────────────┴─> shadows.mask ─┐
//!          ├─> ao.hbao ─> … ─> ao.blur_y_stf ──────────────────────────┴─> lighting.deferred ─> sky ─> [forward.emissive ─> forward.blend] ─┬─> post.luminance ─> post.adapt ─┐
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

use std::cell::RefCell;

use crate::gpu::GpuError;
use crate::graph::FrameGraph;
use crate::passes::aa::{
    AaBuffers, AaFrame, AaHistory, AaMode, BufferHistory, BufferTaaPass, SmaaPass, TemporalPass,
};
use crate::passes::ao::{AoHistory, AoInputs, AoPass, AoSettings, AoTargets};
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
use crate::passes::shadows::ShadowPass;
use crate::passes::sky::SkyPass;
use crate::passes::skyocc::SkyOccPass;
use crate::renderer::ViewBuffer;
use crate::renderer::scene_gpu::SceneGpu;

/// Errors raised while a pass records (closures cannot return them).
#[derive(Default)]
pub struct FrameErrors(RefCell<Vec<GpuError>>);

impl FrameErrors {
    /// Keeps the error, if any, and returns the value.
    pub fn record<T>(&self, r: Result<T, GpuError>) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.0.borrow_mut().push(e);
                None
            }
        }
    }

    pub fn take_first(&self) -> Option<GpuError> {
        let mut v = self.0.borrow_mut();
        if v.is_empty() {
            None
        } else {
            Some(v.remove(0))
        }
    }
}

/// Every pass's pipelines, created once.
pub struct Passes {
    pub shadows: ShadowPass,
    pub gbuffer: GBufferPass,
    pub ao: AoPass,
    pub envmap: EnvMapPass,
    pub env_view: EnvViewPass,
    pub probes: ProbeSet,
    pub lighting: LightingPass,
    pub sky: SkyPass,
    pub skyocc: SkyOccPass,
    pub forward: ForwardPass,
    pub luminance: LuminancePass,
    pub adapt: AdaptPass,
    pub bloom: BloomPass,
    pub tonemap: TonemapPass,
    pub smaa: SmaaPass,
    pub temporal: TemporalPass,
    /// A3 TAA on the AO and the motion vectors (`--aa-buffers`).
    pub aa_buffers: BufferTaaPass,
    pub debug: DebugPass,
}

/// What the frame reads that outlives it.
pub struct FrameInputs<'a> {
    pub passes: &'a Passes,
    pub scene: &'a SceneGpu,
    pub view: &'a wgpu::Buffer,
    pub lighting: &'a wgpu::Buffer,
    pub sky: &'a wgpu::Buffer,
    /// Sky parameters without the sun disk (environment maps: the sun is lit analytically).
    pub sky_no_disk: &'a wgpu::Buffer,
    /// The probe whose relit cube feeds ambient specular (L3), and whether
    /// its G-buffer cube must be captured this frame; `None`: the sky alone.
    pub probe: Option<(usize, bool)>,
    pub luminance: &'a LuminanceBuffers,
    pub post: PostFrame<'a>,
    pub output: &'a wgpu::Texture,
    /// 1x1 white mask bound when shadows are off (the pass planned nothing).
    pub shadow_placeholder: &'a wgpu::Texture,
    /// AO settings and history; `None` = AO off.
    pub ao: Option<(&'a AoSettings, &'a AoHistory)>,
    /// 1x1 white texture bound in place of AO when it is off.
    pub ao_placeholder: &'a wgpu::Texture,
    /// Lighting permutation (prepared by the renderer).
    pub lighting_key: LightingKey,
    /// Anti-aliasing after tone mapping.
    pub aa: FrameAa<'a>,
    pub errors: &'a FrameErrors,
}

/// The anti-aliasing of one frame (mode, SMAA subsample, temporal history).
#[derive(Clone, Copy)]
pub struct FrameAa<'a> {
    pub mode: AaMode,
    pub subsample: u32,
    pub history: Option<&'a AaHistory>,
    /// Buffers with their own TAA and its history (`None`: none).
    pub buffers: Option<(AaBuffers, &'a BufferHistory)>,
}

/// Builds the frame graph; a debug `shown` view replaces tone mapping.
pub fn build<'a>(inputs: FrameInputs<'a>, size: (u32, u32), shown: ViewBuffer) -> FrameGraph<'a> {
    let FrameInputs {
        passes,
        scene,
        view,
        lighting,
        sky,
        luminance,
        post,
        output,
        shadow_placeholder,
        ao,
        ao_placeholder,
        lighting_key,
        sky_no_disk,
        probe,
        aa,
        errors,
    } = inputs;
    let mut g = FrameGraph::new();
    let mip_bias = aa.mode.temporal();
    let gbuffer = passes
        .gbuffer
        .add(&mut g, size, view, scene, mip_bias, errors);
    let shadow_mask = passes
        .shadows
        .add(&mut g, size, gbuffer, view, scene, errors);
    // A3 on other buffers: the stabilised motion replaces the G-buffer's for
    // every later reader (AO TAA, resolve, `--view motion`).
    let stable_motion = match aa.buffers {
        Some((b, h)) if b.motion => Some(passes.aa_buffers.add_motion(
            &mut g,
            gbuffer.motion,
            h,
            errors,
        )),
        _ => None,
    };
    let gbuffer = GBuffer {
        motion: stable_motion.unwrap_or(gbuffer.motion),
        ..gbuffer
    };
    let ao_targets = ao.map(|(settings, history)| {
        let inputs = AoInputs {
            settings,
            view,
            depth: gbuffer.depth,
            history,
        };
        let t = passes.ao.add(&mut g, size, inputs, errors);
        match aa.buffers {
            Some((b, h)) if b.ao => {
                let jitter_free = stable_motion.is_some();
                let ao =
                    passes
                        .aa_buffers
                        .add_ao(&mut g, t.ao, gbuffer.motion, jitter_free, h, errors);
                AoTargets { ao, ..t }
            }
            _ => t,
        }
    });
    // L2: new sectors' height fields and SH2 visibility (side effect: the pool).
    let skyocc = passes.skyocc.add(&mut g, scene, errors);
    let env = match probe {
        Some((index, capture)) if passes.envmap.dirty => {
            // L3: relight the probe's G-buffer cube face by face with the
            // lighting and sky passes (sun unshadowed, sky unoccluded).
            let probes = &passes.probes;
            let size = (probes.size, probes.size);
            let mut source = passes.envmap.import_source(&mut g);
            let env_before = g.import_texture("envmap.filtered.before", passes.envmap.filtered());
            for face in 0..6 {
                g.set_pass_prefix(Some(format!("envmap.probe{index}.face{face}")));
                let view = &probes.probes[index].faces[face].view;
                let stored = if capture {
                    let fresh = passes.gbuffer.add(&mut g, size, view, scene, false, errors);
                    probes.add_store(&mut g, index, face, fresh)
                } else {
                    probes.import_face(&mut g, index, face)
                };
                let relight = LightingInputs {
                    view,
                    lighting,
                    sky,
                    shadow_mask: g.import_texture("shadow.off", shadow_placeholder),
                    ao: g.import_texture("ao.off", ao_placeholder),
                    lights: &passes.shadows.local_lights,
                    envmap: &passes.envmap,
                    env: env_before,
                    skyocc: &passes.skyocc,
                    skyocc_frame: skyocc,
                    key: LightingKey::RELIGHT,
                };
                let hdr = passes.lighting.add(&mut g, size, stored, relight, errors);
                let hdr = passes
                    .sky
                    .add(&mut g, hdr, stored.depth, view, sky_no_disk, errors);
                source = probes.add_mirror(
                    &mut g,
                    face,
                    hdr,
                    source,
                    passes.envmap.source_level0(),
                    errors,
                );
            }
            g.set_pass_prefix(None);
            passes.envmap.add_mips_and_filter(&mut g, source, errors)
        }
        // L1: the Bruneton sky is captured by the sky pass from its tables.
        _ if passes.envmap.dirty && !passes.envmap.fixed_source && passes.sky.draws_bruneton() => {
            let source = passes.envmap.import_source(&mut g);
            let target = passes.envmap.source_level0();
            let source = passes
                .sky
                .add_capture(&mut g, source, target, sky_no_disk, errors);
            passes.envmap.add_mips_and_filter(&mut g, source, errors)
        }
        _ => passes.envmap.add(&mut g, sky_no_disk, errors),
    };
    let lighting_inputs = LightingInputs {
        view,
        lighting,
        sky,
        shadow_mask: match shadow_mask {
            Some(m) => m,
            None => g.import_texture("shadow.off", shadow_placeholder),
        },
        ao: match ao_targets {
            Some(t) => t.ao,
            None => g.import_texture("ao.off", ao_placeholder),
        },
        lights: &passes.shadows.local_lights,
        envmap: &passes.envmap,
        env,
        skyocc: &passes.skyocc,
        skyocc_frame: skyocc,
        key: lighting_key,
    };
    let hdr = passes
        .lighting
        .add(&mut g, size, gbuffer, lighting_inputs, errors);
    let hdr = passes
        .sky
        .add(&mut g, hdr, gbuffer.depth, view, sky, errors);
    // glTF emission and alpha BLEND surfaces (passes/forward).
    let forward = ForwardInputs {
        view,
        lighting,
        scene,
        envmap: &passes.envmap,
        env,
    };
    let hdr = passes
        .forward
        .add(&mut g, hdr, gbuffer.depth, forward, errors);
    let measured = passes.luminance.add(&mut g, hdr, size, luminance, errors);
    let exposure = if post.adaptation {
        let adapted = passes.adapt.add(
            &mut g,
            measured,
            &luminance.result,
            post.adapted,
            post.uniform,
            errors,
        );
        (adapted, post.adapted)
    } else {
        (measured, &luminance.result)
    };
    let bloom_inputs = BloomInputs {
        post: post.uniform,
        exposure: exposure.1,
    };
    let bloom = post.bloom_passes.map(|n| {
        passes
            .bloom
            .add(&mut g, hdr, exposure.0, bloom_inputs, n, errors)
    });
    let post_inputs = PostInputs {
        post: post.uniform,
        exposure,
        bloom,
        placeholder: post.bloom_placeholder,
        sampler: &passes.bloom.sampler,
    };
    let out = g.import_texture("output", output);
    let out = match shown {
        ViewBuffer::Final => {
            let chain = AaFrame {
                mode: aa.mode,
                subsample: aa.subsample,
                history: aa.history,
                smaa: &passes.smaa,
                temporal: &passes.temporal,
                depth: gbuffer.depth,
                normals: gbuffer.frame,
                motion: gbuffer.motion,
                motion_jitter_free: stable_motion.is_some(),
            };
            let tonemap = |g: &mut FrameGraph<'a>, target| {
                passes
                    .tonemap
                    .add(g, post.tonemap, hdr, post_inputs, target, errors)
            };
            crate::passes::aa::add_chain(&mut g, chain, out, tonemap, errors)
        }
        ViewBuffer::Ao(v) => match ao_targets {
            Some(t) => passes.ao.add_view(&mut g, v, t, out, errors),
            None => {
                errors.record::<()>(Err(GpuError::Other(
                    "AO views need AO on (--ao hbao or hbao+stf)".into(),
                )));
                out
            }
        },
        ViewBuffer::Shadow(v) => match shadow_mask {
            Some(m) => passes
                .shadows
                .add_view(&mut g, v, m, gbuffer.depth, view, out, errors),
            None => {
                errors.record::<()>(Err(GpuError::Other(
                    "shadow views need shadows on (--shadows csm or csm+static)".into(),
                )));
                out
            }
        },
        ViewBuffer::Env(v) => passes.env_view.add(
            &mut g,
            v,
            gbuffer,
            env,
            &passes.envmap,
            post_inputs,
            out,
            view,
            errors,
        ),
        ViewBuffer::SkyOcc(v) => passes
            .skyocc
            .add_view(&mut g, v, skyocc, gbuffer, view, out, errors),
        ViewBuffer::Debug(v) => {
            passes
                .debug
                .add(&mut g, v, gbuffer, hdr, post_inputs, out, view, errors)
        }
    };
    g.mark_output(out);
    g
}
