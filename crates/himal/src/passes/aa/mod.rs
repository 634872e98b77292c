//! Hybrid reconstruction anti-aliasing (TECHNIQUES A1–A5): SMAA, temporal
//! FLIPQUAD, TAA, unsharp recovery, and the sampling-pattern study.
//! Runs after tone mapping, on the display-referred image.

pub mod patterns;
pub mod settings;
pub mod smaa;
pub mod temporal;

pub use settings::{AaBuffers, AaMode};
pub use smaa::{SmaaInputs, SmaaPass};
pub use temporal::buffers::BufferTaaPass;
pub use temporal::{AaParams, TemporalPass, TemporalTuning};

use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, History, TextureDesc, TextureHandle};
use temporal::{RESOLVED_FORMAT, ResolveMode};

/// What the anti-aliasing chain of one frame needs.
pub struct AaFrame<'a> {
    /// Anti-aliasing mode of this frame: which passes the chain runs.
    pub mode: AaMode,
    /// SMAA area-table subsample index of this frame.
    pub subsample: u32,
    /// SMAA blending weights only on edge pixels ([`smaa::MASK_FORMAT`]).
    pub edge_mask: bool,
    /// Holds the temporal modes' rings ([`temporal::declare_history`]).
    pub history: &'a History,
    /// SMAA pipelines (the `smaa`, `smaa-t2x` and `hraa` modes).
    pub smaa: &'a SmaaPass,
    /// Resolve, TAA and unsharp pipelines (the temporal modes).
    pub temporal: &'a TemporalPass,
    /// G-buffer depth (depth predication of SMAA).
    pub depth: TextureHandle,
    /// G-buffer tangent frame (normal predication of SMAA).
    pub normals: TextureHandle,
    /// Motion vectors the resolve and the TAA reproject with: the G-buffer's, or `aa.taa_motion`'s
    /// (`motion_jitter_free`).
    pub motion: TextureHandle,
    /// `motion` is `aa.taa_motion`'s stabilised jitter-free motion.
    pub motion_jitter_free: bool,
    /// The particles' coverage this frame (E4): the TAA drops its history
    /// there and where it recorded coverage last frame.
    pub reactive: Option<TextureHandle>,
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
    ctx: &GpuContext,
    g: &mut FrameGraph<'a>,
    aa: AaFrame<'a>,
    output: TextureHandle,
    tonemap: impl FnOnce(&mut FrameGraph<'a>, TextureHandle) -> TextureHandle,
) -> Result<TextureHandle, GpuError> {
    let Some(desc) = g.texture_desc(output).cloned() else {
        return Ok(tonemap(g, output));
    };
    let size = (desc.width, desc.height);
    if aa.mode == AaMode::None {
        return Ok(tonemap(g, output));
    }
    let ring = |g: &mut FrameGraph<'a>, name: &str| {
        aa.history
            .import(g, name)
            .ok_or_else(|| GpuError::Other(format!("temporal anti-aliasing without {name}")))
    };
    let raw = match aa.mode.temporal() {
        true => Some(ring(g, temporal::RAW_HISTORY)?),
        false => None,
    };
    // Where this frame's (SMAA-filtered) samples go: the output, or the
    // history ring that the resolve reads.
    let stage = raw.map_or(output, |r| r.next);
    let stage = if aa.mode.smaa() {
        let ldr = g.create_texture("ldr", TextureDesc::new_2d(size.0, size.1, desc.format));
        let ldr = tonemap(g, ldr);
        let inputs = SmaaInputs {
            color: ldr,
            depth: aa.depth,
            normals: aa.normals,
        };
        aa.smaa
            .add(g, inputs, size, aa.subsample, aa.edge_mask, stage)
    } else {
        tonemap(g, stage)
    };
    let Some(raw) = raw else {
        return Ok(stage);
    };
    let motion_ring = ring(g, temporal::MOTION_HISTORY)?;
    let motion_prev = motion_ring.previous[0];
    let mode = match aa.mode {
        AaMode::Taa => ResolveMode::PassThrough,
        AaMode::SmaaT2x => ResolveMode::TwoTap,
        _ => ResolveMode::FlipQuad,
    };
    let t = aa.temporal;
    // The TAA ring, when a TAA follows: its alpha is last frame's particle
    // coverage, which the resolve reads too (E4).
    let taa = match aa.mode {
        AaMode::Tfq => None,
        _ => Some(ring(g, temporal::TAA_HISTORY)?),
    };
    let reactive = match (aa.reactive, &taa) {
        (Some(r), Some(h)) if mode != ResolveMode::PassThrough => Some((r, h.previous[0])),
        _ => None,
    };
    let (resolved, motion) = t.add_resolve(
        ctx,
        g,
        (mode, aa.motion_jitter_free),
        stage,
        (raw.previous[0], raw.previous[1]),
        aa.motion,
        motion_prev,
        motion_ring.next,
        reactive,
    );
    if aa.mode == AaMode::Tfq {
        return Ok(t.add_unsharp(ctx, g, resolved, output));
    }
    let taa = taa.ok_or_else(|| GpuError::Other("aa.taa without its history".into()))?;
    let color = if aa.mode == AaMode::Hraa {
        g.create_texture(
            "aa.taa.out",
            TextureDesc::new_2d(size.0, size.1, RESOLVED_FORMAT),
        )
    } else {
        output
    };
    let (_, color) = t.add_taa(
        ctx,
        g,
        resolved,
        (taa.previous[0], taa.next),
        motion,
        motion_prev,
        aa.reactive,
        color,
    );
    Ok(if aa.mode == AaMode::Hraa {
        t.add_unsharp(ctx, g, color, output)
    } else {
        color
    })
}
