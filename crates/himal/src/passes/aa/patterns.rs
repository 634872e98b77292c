//! A5: the sampling-pattern study (Laine & Aila 2006, as quoted in the Far
//! Cry 4 talk). Pure CPU; `himal aa-patterns` prints it.
//!
//! Every pattern estimates the coverage of one pixel (the unit square, y down)
//! by an ideal half-plane edge as `c_est = Σ w_i · inside(s_i)`. The reference
//! `c_ref` is the coverage of a box filter `W` pixels wide around the pixel
//! centre, measured with 1024 samples (a 32x32 grid). The error over edges is
//!
//! ```text
//! E_rms² = Σ_θ w(θ) Σ_d (c_est(θ, d) − c_ref(θ, d))²  /  Σ_θ w(θ) Σ_d 1
//! w(θ)   = cos(2θ)^p                    (p = orientation_exponent, 16)
//! E      = √2 · E_rms / E_rms(1x centre)
//! ```
//!
//! θ is the edge normal's angle over [0, π) (the complement edge has the same
//! error) and d its signed offset from the pixel centre over [−0.75 W, 0.75 W]
//! (every line that crosses the filter). Choices, documented in
//! docs/techniques/A5.md with a sensitivity table:
//! - `w(θ)`: Laine & Aila weight edge orientations by how visible their
//!   aliasing is; nearly horizontal and nearly vertical edges (long
//!   stair-steps that crawl under motion) dominate. `cos(2θ)^16` keeps the
//!   weight above one half within ±8° of the axes.
//! - `W = 1.25`: Laine & Aila judge patterns with reconstruction kernels wider
//!   than a pixel; a 1-pixel box counts the shared boundary samples of
//!   quincunx and FLIPQUAD as pure error (FLIPQUAD then ties or loses to 4x
//!   RG). 1.25 lies between the pixel (1) and the FLIPQUAD footprint (4/3).
//! - The scale √2 / E_rms(1x) is ours (1x then reads 1.41, the talk's
//!   ">1.0"); ranking and ratios are the claim.

use std::f64::consts::PI;

/// One sample: position in the pixel (x right, y down, 0..1 edges included;
/// samples on an edge or a corner are shared with the neighbours) and weight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternSample {
    /// Horizontal position in the pixel (0: left edge, 1: right edge).
    pub x: f64,
    /// Vertical position in the pixel (0: top edge, 1: bottom edge).
    pub y: f64,
    /// Weight in the pixel's value (a pattern's weights sum to 1).
    pub weight: f64,
}

const fn s(x: f64, y: f64, weight: f64) -> PatternSample {
    PatternSample { x, y, weight }
}

/// A sampling pattern and the talk's error estimate for it (where given).
#[derive(Clone, Debug)]
pub struct SamplePattern {
    /// Name in the study's table (`quincunx`, `FLIPQUAD`, ...).
    pub name: &'static str,
    /// Samples rendered per pixel (shared samples count once).
    pub cost: f64,
    /// The samples of one pixel.
    pub samples: Vec<PatternSample>,
    /// The talk's E (slide "TEMPORAL SUPERSAMPLING", after [Laine 06]); 1x says ">1.0".
    pub talk: Option<f64>,
}

/// The six patterns of the talk, in its order, then himal's temporal FLIPQUAD.
pub fn patterns() -> Vec<SamplePattern> {
    let q = 0.25;
    vec![
        SamplePattern {
            name: "1x centre",
            cost: 1.0,
            samples: vec![s(0.5, 0.5, 1.0)],
            talk: Some(1.0),
        },
        SamplePattern {
            // D3D standard 2x MSAA: (±4/16, ±4/16) around the centre.
            name: "2x rotated grid",
            cost: 2.0,
            samples: vec![s(0.75, 0.75, 0.5), s(0.25, 0.25, 0.5)],
            talk: None,
        },
        SamplePattern {
            // Centre 1/2, four shared corners 1/8 each.
            name: "quincunx",
            cost: 2.0,
            samples: vec![
                s(0.5, 0.5, 0.5),
                s(0.0, 0.0, 0.125),
                s(1.0, 0.0, 0.125),
                s(0.0, 1.0, 0.125),
                s(1.0, 1.0, 0.125),
            ],
            talk: Some(0.518),
        },
        SamplePattern {
            name: "4x uniform",
            cost: 4.0,
            samples: vec![s(q, q, q), s(0.75, q, q), s(q, 0.75, q), s(0.75, 0.75, q)],
            talk: Some(0.698),
        },
        SamplePattern {
            // D3D standard 4x MSAA: (-2,-6), (6,-2), (-6,2), (2,6) / 16.
            name: "4x rotated grid",
            cost: 4.0,
            samples: vec![
                s(0.375, 0.125, q),
                s(0.875, 0.375, q),
                s(0.125, 0.625, q),
                s(0.625, 0.875, q),
            ],
            talk: Some(0.439),
        },
        SamplePattern {
            // Akenine-Möller 2003: one sample on each edge at 1/3 and 2/3,
            // mirrored in every other pixel so that edge samples are shared.
            name: "FLIPQUAD",
            cost: 2.0,
            samples: vec![
                s(1.0 / 3.0, 0.0, q),
                s(1.0, 1.0 / 3.0, q),
                s(2.0 / 3.0, 1.0, q),
                s(0.0, 2.0 / 3.0, q),
            ],
            talk: Some(0.364),
        },
        SamplePattern {
            // himal's temporal FLIPQUAD (A2): a projection jitter is the same
            // for every pixel, so the mirrored pixels of FLIPQUAD cannot be
            // had; frame A samples the middle of the left edge, frame B of
            // the top edge, and the resolve averages the own and the right
            // (A) / lower (B) neighbour's samples.
            name: "TFQ (himal)",
            cost: 2.0,
            samples: vec![
                s(0.0, 0.5, q),
                s(1.0, 0.5, q),
                s(0.5, 0.0, q),
                s(0.5, 1.0, q),
            ],
            talk: None,
        },
    ]
}

/// Resolution of the study.
#[derive(Clone, Copy, Debug)]
pub struct StudySettings {
    /// Edge normal angles over [0, π).
    pub angles: u32,
    /// Offsets per angle over [−0.75 W, 0.75 W].
    pub offsets: u32,
    /// Reference samples per axis (32 → 1024 per pixel).
    pub reference_grid: u32,
    /// Width W of the reference box filter in pixels.
    pub reference_width: f64,
    /// Exponent p of the orientation weight `cos(2θ)^p` (even).
    pub orientation_exponent: i32,
}

impl Default for StudySettings {
    fn default() -> Self {
        Self {
            angles: 720,
            offsets: 400,
            reference_grid: 32,
            reference_width: 1.25,
            orientation_exponent: 16,
        }
    }
}

/// Orientation weight `w(θ) = cos(2θ)^p` (θ: the edge normal's angle).
pub fn orientation_weight(theta: f64, p: i32) -> f64 {
    (2.0 * theta).cos().abs().powi(p)
}

/// One line of the study.
#[derive(Clone, Debug)]
pub struct PatternResult {
    /// The pattern's [`SamplePattern::name`].
    pub name: &'static str,
    /// Samples rendered per pixel ([`SamplePattern::cost`]).
    pub cost: f64,
    /// Weighted RMS coverage error (fraction of a pixel).
    pub rms: f64,
    /// √2 · `rms` / rms(1x centre) (the reported E).
    pub e: f64,
    /// The talk's E for comparison ([`SamplePattern::talk`]).
    pub talk: Option<f64>,
}

/// Weighted RMS coverage error of `pattern` against the `reference_grid`² reference.
pub fn weighted_rms(pattern: &SamplePattern, settings: StudySettings) -> f64 {
    let n = settings.reference_grid.max(1);
    let width = settings.reference_width;
    // Reference samples relative to the pixel centre, spread over the W-wide box.
    let reference: Vec<(f64, f64)> = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let u = |k: u32| ((k as f64 + 0.5) / n as f64 - 0.5) * width;
            (u(x), u(y))
        })
        .collect();
    let half = 0.75 * width;
    let (mut sum, mut weight_sum) = (0.0, 0.0);
    for a in 0..settings.angles {
        // Half-step offset keeps the angles off the exact axes, where
        // reference rows and edges coincide.
        let theta = (a as f64 + 0.5) / settings.angles as f64 * PI;
        let (nx, ny) = (theta.cos(), theta.sin());
        let w = orientation_weight(theta, settings.orientation_exponent);
        let inside = |x: f64, y: f64, d: f64| x * nx + y * ny < d;
        for o in 0..settings.offsets {
            let d = -half + (o as f64 + 0.5) / settings.offsets as f64 * 2.0 * half;
            let c_ref = reference.iter().filter(|&&(x, y)| inside(x, y, d)).count() as f64
                / reference.len() as f64;
            let c_est: f64 = pattern
                .samples
                .iter()
                .filter(|p| inside(p.x - 0.5, p.y - 0.5, d))
                .map(|p| p.weight)
                .sum();
            sum += w * (c_est - c_ref) * (c_est - c_ref);
            weight_sum += w;
        }
    }
    (sum / weight_sum).sqrt()
}

/// Runs the study over [`patterns`].
pub fn study(settings: StudySettings) -> Vec<PatternResult> {
    let all = patterns();
    let rms: Vec<f64> = all.iter().map(|p| weighted_rms(p, settings)).collect();
    let one = rms[0].max(f64::MIN_POSITIVE);
    all.iter()
        .zip(rms)
        .map(|(p, rms)| PatternResult {
            name: p.name,
            cost: p.cost,
            rms,
            e: rms / one * std::f64::consts::SQRT_2,
            talk: p.talk,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one() {
        for p in patterns() {
            let sum: f64 = p.samples.iter().map(|s| s.weight).sum();
            assert!((sum - 1.0).abs() < 1e-12, "{}: {sum}", p.name);
        }
    }
}
