//! Anti-aliasing mode of a frame (`--aa`) and its projection jitter.

/// Which anti-aliasing runs after tone mapping.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum AaMode {
    /// Tone mapping writes the output directly.
    #[default]
    None,
    /// A1 SMAA 1x: edges, blending weights, neighbourhood blending.
    Smaa,
    /// A1 SMAA T2x/1TX: SMAA with the frame's subsample areas, two-frame
    /// resolve, accumulation whose sample count follows signal frequency.
    SmaaT2x,
    /// A2 temporal FLIPQUAD (two jittered frames, shared samples) + A4 unsharp.
    Tfq,
    /// A3 TAA alone: exponential history over an 8-phase Halton jitter.
    Taa,
    /// SMAA + TFQ + TAA + unsharp (Far Cry 4's HRAA).
    Hraa,
}

/// TFQ frame A sample: middle of the pixel's left edge (pixels, y down).
/// A projection jitter is global, so FLIPQUAD's mirrored pixels cannot be
/// had; among global layouts (own + right/lower neighbour's sample) the
/// edge midpoints score best in the A5 study (E 0.485; FLIPQUAD 0.407,
/// quincunx 0.538; left edge 1/6 above the centre scores 0.670).
pub const TFQ_JITTER_A: [f32; 2] = [-0.5, 0.0];
/// TFQ frame B sample: middle of the pixel's top edge.
pub const TFQ_JITTER_B: [f32; 2] = [0.0, -0.5];
/// SMAA T2x jitters (Jimenez et al. 2012: ±0.25 on the diagonal).
pub const T2X_JITTER: [[f32; 2]; 2] = [[0.25, -0.25], [-0.25, 0.25]];

/// Radical inverse of `i` in `base` (Halton sequence).
fn halton(mut i: u32, base: u32) -> f32 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= base as f32;
        r += f * (i % base) as f32;
        i /= base;
    }
    r
}

impl AaMode {
    /// Every name `--aa` knows.
    pub const NAMES: [&'static str; 6] = ["none", "smaa", "smaa-t2x", "tfq", "taa", "hraa"];

    /// The mode of an `--aa` name (one of [`AaMode::NAMES`]); an error names the known ones.
    pub fn parse(name: &str) -> Result<Self, String> {
        match name {
            "none" => Ok(Self::None),
            "smaa" => Ok(Self::Smaa),
            "smaa-t2x" => Ok(Self::SmaaT2x),
            "tfq" => Ok(Self::Tfq),
            "taa" => Ok(Self::Taa),
            "hraa" => Ok(Self::Hraa),
            other => Err(format!(
                "unknown anti-aliasing mode \"{other}\" (known: {})",
                Self::NAMES.join(", ")
            )),
        }
    }

    /// The mode's `--aa` name (inverse of [`AaMode::parse`]).
    pub fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Smaa => "smaa",
            Self::SmaaT2x => "smaa-t2x",
            Self::Tfq => "tfq",
            Self::Taa => "taa",
            Self::Hraa => "hraa",
        }
    }

    /// Whether the mode keeps history between frames.
    pub fn temporal(self) -> bool {
        !matches!(self, Self::None | Self::Smaa)
    }

    /// Whether SMAA runs on each frame.
    pub fn smaa(self) -> bool {
        matches!(self, Self::Smaa | Self::SmaaT2x | Self::Hraa)
    }

    /// Sub-pixel sample offset of frame `frame_index` in pixels (x right,
    /// y down, from the pixel centre); zero for `none` and `smaa`.
    pub fn jitter(self, frame_index: u64) -> [f32; 2] {
        let phase = (frame_index % 2) as usize;
        match self {
            Self::None | Self::Smaa => [0.0, 0.0],
            Self::Tfq | Self::Hraa => [TFQ_JITTER_A, TFQ_JITTER_B][phase],
            Self::SmaaT2x => T2X_JITTER[phase],
            Self::Taa => {
                let i = (frame_index % 8) as u32 + 1;
                [halton(i, 2) - 0.5, halton(i, 3) - 0.5]
            }
        }
    }

    /// SMAA area-table subsample index of frame `frame_index`: T2x uses the
    /// tables of its jitter (1: −0.25, 2: +0.25), every other mode 0.
    pub fn smaa_subsample(self, frame_index: u64) -> u32 {
        match self {
            Self::SmaaT2x => 1 + (frame_index % 2) as u32,
            _ => 0,
        }
    }
}

/// Buffers other than the final colour that get their own TAA (A3,
/// `--aa-buffers`): the AO result and the motion vectors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct AaBuffers {
    /// `aa.taa_ao`: exponential history of the AO after the STF.
    pub ao: bool,
    /// `aa.taa_motion`: stabilised jitter-free motion, read by the AO TAA
    /// and the resolve instead of the G-buffer motion.
    pub motion: bool,
}

impl AaBuffers {
    /// `none`, or a comma-separated list of `ao` and `motion`.
    pub fn parse(list: &str) -> Result<Self, String> {
        let mut b = Self::default();
        for name in list.split(',').map(str::trim) {
            match name {
                "none" | "" => {}
                "ao" => b.ao = true,
                "motion" => b.motion = true,
                other => {
                    return Err(format!(
                        "unknown buffer \"{other}\" (known: none, ao, motion)"
                    ));
                }
            }
        }
        Ok(b)
    }

    /// Whether any buffer gets its own TAA.
    pub fn any(self) -> bool {
        self.ao || self.motion
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jitter_is_zero_without_temporal_modes_and_deterministic() {
        for f in 0..4 {
            assert_eq!(AaMode::None.jitter(f), [0.0, 0.0]);
            assert_eq!(AaMode::Smaa.jitter(f), [0.0, 0.0]);
            assert_eq!(AaMode::Hraa.jitter(f), AaMode::Hraa.jitter(f + 2));
        }
        assert_ne!(AaMode::Tfq.jitter(0), AaMode::Tfq.jitter(1));
        let j = AaMode::Taa.jitter(0);
        assert!((j[0] - 0.0).abs() < 1e-6 && (j[1] - (1.0 / 3.0 - 0.5)).abs() < 1e-6);
    }

    #[test]
    fn buffers_parse() {
        assert_eq!(AaBuffers::parse("none"), Ok(AaBuffers::default()));
        let both = AaBuffers::parse("ao,motion").expect("list");
        assert!(both.ao && both.motion);
        assert!(AaBuffers::parse("bloom").is_err());
    }
}
