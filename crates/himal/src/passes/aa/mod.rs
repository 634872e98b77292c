//! Hybrid reconstruction anti-aliasing (TECHNIQUES A1–A5): SMAA, temporal
//! FLIPQUAD, TAA, unsharp recovery, and the sampling-pattern study.
//! Runs after tone mapping, on the display-referred image.

pub mod patterns;
pub mod settings;
pub mod smaa;
pub mod temporal;

pub use settings::{AaBuffers, AaMode};
pub use smaa::{SmaaInputs, SmaaPass};
pub use temporal::buffers::{BufferHistory, BufferTaaPass};
pub use temporal::{AaHistory, AaParams, TemporalPass, TemporalTuning};

use crate::frame::FrameErrors;
use crate::gpu::GpuError;
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use temporal::{RESOLVED_FORMAT, ResolveMode};

/// What the anti-aliasing chain of one frame needs.
pub struct AaFrame<'a> {
    pub mode: AaMode,
    /// SMAA area-table subsample index of this frame.
    pub subsample: u32,
    /// History of the temporal modes (`None` for none/smaa).
    pub history: Option<&'a AaHistory>,
    pub smaa: &'a SmaaPass,
    pub temporal: &'a TemporalPass,
    pub depth: TextureHandle,
    /// G-buffer tangent frame (normal predication of SMAA).
    pub normals: TextureHandle,
    pub motion: TextureHandle,
    /// `motion` is `aa.taa_motion`'s stabilised jitter-free motion.
    pub motion_jitter_free: bool,
}

/// Adds tone mapping (`tonemap` writes into the target it is given) and the
/// anti-aliasing chain of `aa.mode` ending in `output`; returns the output's
/// new version.
///
/// none: tonemap → output. smaa: tonemap → ldr → SMAA → output.
/// tfq: tonemap → raw → resolve (FLIPQUAD) → unsharp → output.
/// taa: tonemap → raw → resolve (pass-through) → TAA → output.
/// smaa-t2x: tonemap → ldr → SMAA (T2x areas) → raw → resolve (2 taps) → TAA → output.
/// hraa: tonemap → ldr → SMAA → raw → resolve (FLIPQUAD) → TAA → unsharp → output.
pub fn add_chain<'a>(
    g: &mut FrameGraph<'a>,
    aa: AaFrame<'a>,
    output: TextureHandle,
    tonemap: impl FnOnce(&mut FrameGraph<'a>, TextureHandle) -> TextureHandle,
    errors: &'a FrameErrors,
) -> TextureHandle {
    let Some(desc) = g.texture_desc(output).cloned() else {
        return tonemap(g, output);
    };
    let size = (desc.width, desc.height);
    if aa.mode == AaMode::None {
        return tonemap(g, output);
    }
    let history = match (aa.mode.temporal(), aa.history) {
        (false, _) => None,
        (true, Some(h)) => Some(h.frame()),
        (true, None) => {
            errors.record::<()>(Err(GpuError::Other(
                "temporal anti-aliasing without its history".into(),
            )));
            return tonemap(g, output);
        }
    };
    // Where this frame's (SMAA-filtered) samples go: the output, or the
    // history ring that the resolve reads.
    let stage = match &history {
        Some(h) => g.import_texture("aa.raw", h.raw),
        None => output,
    };
    let stage = if aa.mode.smaa() {
        let ldr = g.create_texture("ldr", TextureDesc::new_2d(size.0, size.1, desc.format));
        let ldr = tonemap(g, ldr);
        let inputs = SmaaInputs {
            color: ldr,
            depth: aa.depth,
            normals: aa.normals,
        };
        aa.smaa.add(g, inputs, size, aa.subsample, stage, errors)
    } else {
        tonemap(g, stage)
    };
    let Some(history) = history else {
        return stage;
    };
    let raw = stage;
    let previous = (
        g.import_texture("aa.raw.prev", history.raw_prev),
        g.import_texture("aa.raw.prev2", history.raw_prev2),
    );
    let motion_prev = g.import_texture("aa.motion.prev", history.motion_prev);
    let motion_next = g.import_texture("aa.motion", history.motion);
    let mode = match aa.mode {
        AaMode::Taa => ResolveMode::PassThrough,
        AaMode::SmaaT2x => ResolveMode::TwoTap,
        _ => ResolveMode::FlipQuad,
    };
    let t = aa.temporal;
    let (resolved, motion) = t.add_resolve(
        g,
        (mode, aa.motion_jitter_free),
        raw,
        previous,
        aa.motion,
        motion_prev,
        motion_next,
        errors,
    );
    if aa.mode == AaMode::Tfq {
        return t.add_unsharp(g, resolved, output, errors);
    }
    let taa_prev = g.import_texture("aa.taa.prev", history.taa_prev);
    let taa_next = g.import_texture("aa.taa", history.taa);
    let color = if aa.mode == AaMode::Hraa {
        g.create_texture(
            "aa.taa.out",
            TextureDesc::new_2d(size.0, size.1, RESOLVED_FORMAT),
        )
    } else {
        output
    };
    let (_, color) = t.add_taa(
        g,
        resolved,
        taa_prev,
        taa_next,
        motion,
        motion_prev,
        color,
        errors,
    );
    if aa.mode == AaMode::Hraa {
        t.add_unsharp(g, color, output, errors)
    } else {
        color
    }
}
