//! LDR-FLIP: a per-pixel perceptual error map between a reference and a test
//! image, after Andersson et al., "FLIP: A Difference Evaluator for
//! Alternating Images", HPG 2020 (constants checked against NVIDIA's
//! reference implementation, github.com/NVlabs/flip; the code is written anew).
//!
//! Pipeline, per image (inputs sRGB-encoded, clamped to [0, 1]):
//!
//! - Colour: sRGB -> linear RGB -> YCxCz; each opponent channel is filtered
//!   with its contrast sensitivity function (a sum of Gaussians); back to linear RGB, clamped to the unit cube; CIELab; Hunt
//!   adjustment; then the HyAB distance between the images, raised to `qc`
//!   and mapped to [0, 1] with the `pc`/`pt` knee against `cmax`, the
//!   distance between green and blue.
//! - Features: on the unfiltered achromatic channel, normalised to [0, 1],
//!   edges (first Gaussian derivative) and points (second derivative) with
//!   `sigma = gw * ppd / 2`; `feature_err = (max(|dEdge|, |dPoint|) / sqrt 2)^qf`.
//! - `error = color_err^(1 - feature_err)`.
//!
//! All filters are separable (the blue-yellow CSF as a sum of two separable
//! Gaussians, jointly normalised, which equals the 2D kernel exactly) and
//! sample with clamp-to-edge. Arithmetic is f32, like the reference.
//!
//! The metric is symmetric: HyAB and the feature differences are absolute
//! differences, so swapping reference and test gives the same map bit for bit
//! (the paper does not ask for this; it falls out of the formulas, and
//! nothing here relies on it).

use glam::{Mat3, Vec3};

/// Pixels per degree of visual angle for a 0.7 m wide 4K monitor seen from
/// 0.7 m, the paper's default: `distance * (pixels / monitor width) * pi / 180`
/// `= 0.7 * 3840 / 0.7 * pi / 180 = 67.02`, rounded.
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = 67.0;

/// Exponent on the HyAB distance (paper: q_c).
const QC: f32 = 0.7;
/// Fraction of `cmax` where the error knee sits (p_c) ...
const PC: f32 = 0.4;
/// ... and the error value it maps to (p_t).
const PT: f32 = 0.95;
/// Peak-to-trough width of the edge detector in degrees, two standard deviations (w).
const GW: f32 = 0.082;
/// Exponent on the feature difference (q_f).
const QF: f32 = 0.5;

/// One CSF as `a1 sqrt(pi/b1) exp(-pi^2 r^2 / b1) + a2 sqrt(pi/b2) exp(-pi^2 r^2 / b2)`,
/// r in degrees, with the paper's constants.
struct Csf {
    a1: f32,
    b1: f32,
    a2: f32,
    b2: f32,
}

/// Achromatic (Y).
const CSF_A: Csf = Csf {
    a1: 1.0,
    b1: 0.0047,
    a2: 0.0,
    b2: 1e-5,
};
/// Red-green (Cx).
const CSF_RG: Csf = Csf {
    a1: 1.0,
    b1: 0.0053,
    a2: 0.0,
    b2: 1e-5,
};
/// Blue-yellow (Cz).
const CSF_BY: Csf = Csf {
    a1: 34.1,
    b1: 0.04,
    a2: 13.5,
    b2: 0.025,
};
/// Largest b over all channels: it sets the common filter radius.
const CSF_MAX_B: f32 = 0.04;

/// Linear sRGB -> XYZ (D65), the exact rationals of the sRGB primaries, as rows.
const RGB_TO_XYZ: Mat3 = rows([
    [
        10135552.0 / 24577794.0,
        8788810.0 / 24577794.0,
        4435075.0 / 24577794.0,
    ],
    [
        2613072.0 / 12288897.0,
        8788810.0 / 12288897.0,
        887015.0 / 12288897.0,
    ],
    [
        1425312.0 / 73733382.0,
        8788810.0 / 73733382.0,
        70074185.0 / 73733382.0,
    ],
]);
/// Its inverse, with the reference's 9 digits (more than f32 keeps) so the
/// numbers can be checked against it.
#[allow(clippy::excessive_precision)]
const XYZ_TO_RGB: Mat3 = rows([
    [3.241003275, -1.537398934, -0.498615861],
    [-0.969224334, 1.875930071, 0.041554224],
    [0.055639423, -0.204011202, 1.057148933],
]);
/// D65 white in XYZ: the row sums of `RGB_TO_XYZ` (0.950428545, 1, 1.088900371),
/// so linear white maps to Lab (100, 0, 0).
const WHITE: Vec3 = Vec3::new(23359437.0 / 24577794.0, 1.0, 80288307.0 / 73733382.0);

const fn rows(m: [[f32; 3]; 3]) -> Mat3 {
    Mat3::from_cols(
        Vec3::new(m[0][0], m[1][0], m[2][0]),
        Vec3::new(m[0][1], m[1][1], m[2][1]),
        Vec3::new(m[0][2], m[1][2], m[2][2]),
    )
}

/// Per-pixel LDR-FLIP error map in [0, 1] between two sRGB-encoded images
/// (values in [0, 1], row-major, `width * height` RGB triples), viewed at
/// `pixels_per_degree` ([`DEFAULT_PIXELS_PER_DEGREE`] as in the paper).
///
/// Values outside [0, 1] are clamped, as the reference implementation does.
/// Errors (instead of panics): a slice whose length is not `width * height`,
/// a non-finite input value (a NaN in a rendered image is a bug to report,
/// not to clamp away), or `pixels_per_degree` not finite and positive.
/// A 0-pixel image gives an empty map.
pub fn flip_map(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    pixels_per_degree: f32,
) -> Result<Vec<f32>, String> {
    check_inputs(reference, test, width, height, pixels_per_degree)?;
    if width == 0 || height == 0 {
        return Ok(Vec::new());
    }
    let ppd = pixels_per_degree;
    let csf = CsfKernels::new(ppd);
    let feat = FeatureKernels::new(ppd);

    let ycxcz_ref: Vec<Vec3> = reference.iter().map(|&c| srgb_to_ycxcz(c)).collect();
    let ycxcz_test: Vec<Vec3> = test.iter().map(|&c| srgb_to_ycxcz(c)).collect();

    let lab_ref = filtered_hunt_lab(&ycxcz_ref, width, height, &csf);
    let lab_test = filtered_hunt_lab(&ycxcz_test, width, height, &csf);
    let feat_ref = features(&ycxcz_ref, width, height, &feat);
    let feat_test = features(&ycxcz_test, width, height, &feat);

    let cmax = cmax();
    let map = (0..width * height)
        .map(|i| {
            let color_err = compress(hyab(lab_ref[i], lab_test[i]).powf(QC), cmax);
            let d_edge = (feat_ref.edge[i] - feat_test.edge[i]).abs();
            let d_point = (feat_ref.point[i] - feat_test.point[i]).abs();
            // At most 1 in exact arithmetic; the min keeps rounding from making the
            // exponent below negative (0^negative would be infinite).
            let feature_err = (d_edge.max(d_point) * std::f32::consts::FRAC_1_SQRT_2)
                .powf(QF)
                .min(1.0);
            color_err.powf(1.0 - feature_err)
        })
        .collect();
    Ok(map)
}

/// Mean of [`flip_map`]; the same errors, plus one for a 0-pixel image,
/// which has no mean.
pub fn flip_mean(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    pixels_per_degree: f32,
) -> Result<f32, String> {
    let map = flip_map(reference, test, width, height, pixels_per_degree)?;
    if map.is_empty() {
        return Err("flip_mean: the image has no pixels".into());
    }
    // f64 sum: a large map's f32 sum would lose the small errors.
    Ok((map.iter().map(|&e| f64::from(e)).sum::<f64>() / map.len() as f64) as f32)
}

fn check_inputs(
    reference: &[[f32; 3]],
    test: &[[f32; 3]],
    width: usize,
    height: usize,
    ppd: f32,
) -> Result<(), String> {
    let n = width
        .checked_mul(height)
        .ok_or_else(|| format!("flip: {width} x {height} pixels overflows usize"))?;
    for (name, img) in [("reference", reference), ("test", test)] {
        if img.len() != n {
            return Err(format!(
                "flip: {name} has {} pixels, {width} x {height} needs {n}",
                img.len()
            ));
        }
        if let Some(i) = img.iter().position(|c| c.iter().any(|v| !v.is_finite())) {
            return Err(format!(
                "flip: {name} pixel ({}, {}) is not finite: {:?}",
                i % width,
                i / width,
                img[i]
            ));
        }
    }
    if !(ppd.is_finite() && ppd > 0.0) {
        return Err(format!(
            "flip: pixels_per_degree must be finite and > 0, got {ppd}"
        ));
    }
    Ok(())
}

fn srgb_to_linear(c: f32) -> f32 {
    if c > 0.04045 {
        ((c + 0.055) / 1.055).powf(2.4)
    } else {
        c / 12.92
    }
}

fn srgb_to_ycxcz(c: [f32; 3]) -> Vec3 {
    let rgb = Vec3::from(c.map(|v| srgb_to_linear(v.clamp(0.0, 1.0))));
    let xyz = RGB_TO_XYZ * rgb / WHITE;
    // YCxCz is Lab without the cube root: linear in XYZ, so filtering in it is meaningful.
    Vec3::new(
        116.0 * xyz.y - 16.0,
        500.0 * (xyz.x - xyz.y),
        200.0 * (xyz.y - xyz.z),
    )
}

fn ycxcz_to_linear_rgb(c: Vec3) -> Vec3 {
    let y = (c.x + 16.0) / 116.0;
    XYZ_TO_RGB * (Vec3::new(y + c.y / 500.0, y, y - c.z / 200.0) * WHITE)
}

fn linear_rgb_to_lab(rgb: Vec3) -> Vec3 {
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA * DELTA * DELTA {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let t = RGB_TO_XYZ * rgb / WHITE;
    let (fx, fy, fz) = (f(t.x), f(t.y), f(t.z));
    Vec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

/// Hunt effect: chroma is less visible in the dark, so scale a, b by L/100.
fn hunt(lab: Vec3) -> Vec3 {
    Vec3::new(lab.x, 0.01 * lab.x * lab.y, 0.01 * lab.x * lab.z)
}

/// HyAB: city-block in L, Euclidean in (a, b); better than Euclidean Lab for large differences.
fn hyab(p: Vec3, q: Vec3) -> f32 {
    (p.x - q.x).abs() + (p.y - q.y).hypot(p.z - q.z)
}

/// The largest colour difference, `HyAB(green, blue)^qc` in Hunt-adjusted Lab (about 41.3).
fn cmax() -> f32 {
    let lab = |rgb: Vec3| hunt(linear_rgb_to_lab(rgb));
    hyab(lab(Vec3::Y), lab(Vec3::Z)).powf(QC)
}

/// Map `hyab^qc` to [0, 1]: linear up to `pc * cmax` (reaching `pt`), then
/// the rest up to `cmax` into (pt, 1], so small differences get most of the range.
fn compress(e: f32, cmax: f32) -> f32 {
    let knee = PC * cmax;
    if e < knee {
        PT / knee * e
    } else {
        PT + (e - knee) / (cmax - knee) * (1.0 - PT)
    }
}

/// 1D factors of the CSF filters at one ppd. The 2D kernel of a channel is
/// `sum_k term_k(x) term_k(y)`.
struct CsfKernels {
    y: Vec<Vec<f32>>,
    cx: Vec<Vec<f32>>,
    cz: Vec<Vec<f32>>,
}

impl CsfKernels {
    fn new(ppd: f32) -> Self {
        use std::f32::consts::PI;
        // Three standard deviations of the widest Gaussian: exp(-pi^2 r^2 / b) has sigma^2 = b / (2 pi^2).
        let radius = (3.0 * (CSF_MAX_B / (2.0 * PI * PI)).sqrt() * ppd).ceil() as i32;
        let dx = 1.0 / ppd;
        let channel = |c: &Csf| {
            // Each Gaussian term c * e(x) e(y), c = a sqrt(pi / b), splits into
            // sqrt(c) e(x) times sqrt(c) e(y); the 2D kernel's sum is the sum of
            // the squared 1D sums, so dividing every factor by its square root
            // normalises the 2D kernel to 1.
            let mut terms: Vec<Vec<f32>> = [(c.a1, c.b1), (c.a2, c.b2)]
                .into_iter()
                .filter(|&(a, _)| a > 0.0)
                .map(|(a, b)| {
                    let scale = (a * (PI / b).sqrt()).sqrt();
                    (-radius..=radius)
                        .map(|i| {
                            let x = i as f32 * dx;
                            scale * (-PI * PI * x * x / b).exp()
                        })
                        .collect()
                })
                .collect();
            let total: f32 = terms.iter().map(|t| t.iter().sum::<f32>().powi(2)).sum();
            let norm = total.sqrt().recip();
            terms.iter_mut().flatten().for_each(|w| *w *= norm);
            terms
        };
        Self {
            y: channel(&CSF_A),
            cx: channel(&CSF_RG),
            cz: channel(&CSF_BY),
        }
    }
}

/// CSF-filter an image in YCxCz, return it as Hunt-adjusted Lab.
fn filtered_hunt_lab(ycxcz: &[Vec3], width: usize, height: usize, k: &CsfKernels) -> Vec<Vec3> {
    let filter = |channel: usize, terms: &[Vec<f32>]| {
        let plane: Vec<f32> = ycxcz.iter().map(|c| c[channel]).collect();
        let mut sum = vec![0.0f32; plane.len()];
        for t in terms {
            let f = separable(&plane, width, height, Taps::smooth(t), Taps::smooth(t));
            sum.iter_mut().zip(f).for_each(|(s, v)| *s += v);
        }
        sum
    };
    let (y, cx, cz) = (filter(0, &k.y), filter(1, &k.cx), filter(2, &k.cz));
    (0..ycxcz.len())
        .map(|i| {
            // Clamp in linear RGB: filtering can leave the displayable gamut.
            let rgb =
                ycxcz_to_linear_rgb(Vec3::new(y[i], cx[i], cz[i])).clamp(Vec3::ZERO, Vec3::ONE);
            hunt(linear_rgb_to_lab(rgb))
        })
        .collect()
}

/// 1D Gaussian and its first and second derivatives for feature detection.
struct FeatureKernels {
    g: Vec<f32>,
    dg: Vec<f32>,
    ddg: Vec<f32>,
}

impl FeatureKernels {
    fn new(ppd: f32) -> Self {
        let sigma = 0.5 * GW * ppd;
        let radius = (3.0 * sigma).ceil() as i32;
        let xs = || (-radius..=radius).map(|i| i as f32);
        let gauss = |x: f32| (-x * x / (2.0 * sigma * sigma)).exp();
        let mut g: Vec<f32> = xs().map(gauss).collect();
        let mut dg: Vec<f32> = xs().map(|x| -x * gauss(x)).collect();
        let mut ddg: Vec<f32> = xs()
            .map(|x| (x * x / (sigma * sigma) - 1.0) * gauss(x))
            .collect();
        let sum: f32 = g.iter().sum();
        g.iter_mut().for_each(|w| *w /= sum);
        normalise_lobes(&mut dg);
        normalise_lobes(&mut ddg);
        Self { g, dg, ddg }
    }
}

/// Scale positive weights to sum to 1 and negative ones to -1, as the paper
/// does, so a unit step gives a response of at most 1 whatever the ppd.
fn normalise_lobes(k: &mut [f32]) {
    let pos: f32 = k.iter().filter(|&&w| w > 0.0).sum();
    let neg: f32 = -k.iter().filter(|&&w| w < 0.0).sum::<f32>();
    for w in k {
        // A lobe can be empty only at a degenerate ppd (radius 0); leave it at 0.
        if *w > 0.0 {
            *w /= pos;
        } else if *w < 0.0 {
            *w /= neg;
        }
    }
}

struct Features {
    edge: Vec<f32>,
    point: Vec<f32>,
}

/// Edge and point magnitudes (each at most sqrt 2) of the achromatic channel.
fn features(ycxcz: &[Vec3], width: usize, height: usize, k: &FeatureKernels) -> Features {
    // (Y + 16) / 116 undoes YCxCz's offset: it is relative luminance, in [0, 1].
    let y: Vec<f32> = ycxcz.iter().map(|c| (c.x + 16.0) / 116.0).collect();
    let conv = |kx, ky| separable(&y, width, height, kx, ky);
    let (g, dg, ddg) = (
        Taps::smooth(&k.g),
        Taps::derivative(&k.dg),
        Taps::derivative(&k.ddg),
    );
    let (dx, dy) = (conv(dg, g), conv(g, dg));
    let (ddx, ddy) = (conv(ddg, g), conv(g, ddg));
    Features {
        edge: dx.iter().zip(&dy).map(|(a, b)| a.hypot(*b)).collect(),
        point: ddx.iter().zip(&ddy).map(|(a, b)| a.hypot(*b)).collect(),
    }
}

/// A centred 1D kernel of odd length.
#[derive(Clone, Copy)]
struct Taps<'a> {
    w: &'a [f32],
    /// A derivative: the weights sum to 0 in exact arithmetic. Such kernels are
    /// applied to differences from the centre sample, so a flat region gives
    /// exactly 0 rather than rounding noise, which the feature term's `^qf`
    /// (a square root) would amplify to ~1e-4.
    zero_sum: bool,
}

impl Taps<'_> {
    fn smooth(w: &[f32]) -> Taps<'_> {
        Taps { w, zero_sum: false }
    }

    fn derivative(w: &[f32]) -> Taps<'_> {
        Taps { w, zero_sum: true }
    }

    /// `sum_j w_j sample(i + j - r)`, samples clamped to `[0, n)`.
    fn apply(self, i: usize, n: usize, sample: impl Fn(usize) -> f32) -> f32 {
        let r = self.w.len() / 2;
        let centre = if self.zero_sum { sample(i) } else { 0.0 };
        self.w
            .iter()
            .enumerate()
            .map(|(j, w)| w * (sample((i + j).saturating_sub(r).min(n - 1)) - centre))
            .sum()
    }
}

/// Convolve a plane with `kx` along rows, then `ky` along columns, clamping
/// samples to the edge.
fn separable(plane: &[f32], width: usize, height: usize, kx: Taps, ky: Taps) -> Vec<f32> {
    let mut rows = vec![0.0f32; plane.len()];
    for y in 0..height {
        let row = &plane[y * width..(y + 1) * width];
        for x in 0..width {
            rows[y * width + x] = kx.apply(x, width, |i| row[i]);
        }
    }
    let mut out = vec![0.0f32; plane.len()];
    for y in 0..height {
        for x in 0..width {
            out[y * width + x] = ky.apply(y, height, |i| rows[i * width + x]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const PPD: f32 = DEFAULT_PIXELS_PER_DEGREE;

    fn uniform(c: [f32; 3], w: usize, h: usize) -> Vec<[f32; 3]> {
        vec![c; w * h]
    }

    /// A deterministic textured image: an integer hash per pixel and channel,
    /// quantised to 1/16, scaled into [0, scale] (no transcendental functions,
    /// so the C++ reference run below generated exactly the same values).
    fn pattern(w: usize, h: usize, scale: f32) -> Vec<[f32; 3]> {
        (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                [0, 1, 2]
                    .map(|c| ((x * 7 + y * 13 + c * 5 + (x * y) % 5) % 17) as f32 / 16.0 * scale)
            })
            .collect()
    }

    #[test]
    fn identical_images_give_exactly_zero() {
        let (w, h) = (37, 23);
        let img = pattern(w, h, 1.0);
        let map = flip_map(&img, &img, w, h, PPD).unwrap();
        assert_eq!(map.len(), w * h);
        assert!(map.iter().all(|&e| e == 0.0), "{map:?}");
    }

    #[test]
    fn black_versus_white_is_near_one() {
        // Uniform images have no features (`flat_regions_have_no_features`), so
        // error = color_err. Black is Lab (0, 0, 0) and white (100, 0, 0)
        // (WHITE is the white point), so HyAB = 100 and 100^0.7 = 25.119, above the
        // knee pc * cmax = 16.510; hence 0.95 + (25.119 - 16.510) / (41.276 - 16.510) * 0.05
        // with cmax = 41.276 (see `cmax_is_green_versus_blue`): 0.96738. (NVIDIA's C++
        // FLIP.h gives 0.9673918, see `matches_the_reference_implementation` for why.)
        let (w, h) = (16, 16);
        let map = flip_map(
            &uniform([0.0; 3], w, h),
            &uniform([1.0; 3], w, h),
            w,
            h,
            PPD,
        )
        .unwrap();
        let c = cmax();
        let expected = PT + (100f32.powf(QC) - PC * c) / (c - PC * c) * (1.0 - PT);
        for &e in &map {
            assert!((e - expected).abs() < 1e-5, "{e} vs {expected}");
            assert!(e > 0.96 && e <= 1.0);
        }
    }

    #[test]
    fn cmax_is_green_versus_blue() {
        // Hunt-adjusted Lab of linear green: L = 87.736, (a, b) * L/100 = (-75.610, 72.981);
        // of blue: L = 32.298, (a, b) * L/100 = (25.578, -34.836). HyAB = 55.438 + 147.864
        // = 203.302, and 203.302^0.7 = 41.2761 (computed in f64; NVIDIA's C++ FLIP.h
        // computeMaxDistance(0.7) gives 41.2760963).
        assert!((cmax() - 41.2761).abs() < 1e-3, "{}", cmax());
    }

    #[test]
    fn matches_the_reference_implementation() {
        // Numbers from NVIDIA's C++ FLIP.h (github.com/NVlabs/flip, src/cpp, v1.6),
        // run once outside this repository on the same images at PPD 67 (its input
        // is linear RGB, so the harness decoded them with FLIP's own sRGBToLinearRGB).
        struct Case {
            name: &'static str,
            reference: Vec<[f32; 3]>,
            test: Vec<[f32; 3]>,
            size: (usize, usize),
            mean: f32,
            /// (pixel index, map value)
            probes: Vec<(usize, f32)>,
            tolerance: f32,
        }
        let mut pixel = uniform([0.5; 3], 64, 48);
        pixel[30 * 64 + 20] = [1.0, 0.8, 0.2];
        let rotated: Vec<[f32; 3]> = pattern(19, 17, 0.7)
            .iter()
            .map(|c| [c[2], c[0], c[1]])
            .collect();
        // Both are f32 with different summation orders: 1e-5 is ~170 ulps at 0.5.
        let cases = [
            Case {
                name: "pattern",
                reference: pattern(19, 17, 1.0),
                test: rotated,
                size: (19, 17),
                mean: 0.6066842,
                probes: vec![(0, 0.5612628), (102, 0.5022005), (322, 0.8060886)],
                tolerance: 1e-5,
            },
            Case {
                name: "pixel",
                reference: uniform([0.5; 3], 64, 48),
                test: pixel,
                size: (64, 48),
                mean: 0.0024552,
                probes: vec![
                    (1940, 0.2887104),
                    (1941, 0.2262252),
                    (2071, 0.0474110),
                    (1950, 0.0009768),
                    (1951, 0.0),
                ],
                tolerance: 1e-5,
            },
            // On uniform images the reference's derivative filters leave ~1e-8 of
            // rounding, which the feature term's square root turns into a relative
            // error of up to ~1e-4 in the result (black-white: 0.9673919 against
            // the closed form's 0.9673797; grey: 0.2850555 against 0.2850130, see
            // `uniform_greys_match_the_closed_form`). Here flat regions give an
            // exact 0, hence the wider tolerance for these two.
            Case {
                name: "black-white",
                reference: uniform([0.0; 3], 16, 16),
                test: uniform([1.0; 3], 16, 16),
                size: (16, 16),
                mean: 0.9673919,
                probes: vec![(0, 0.9673918)],
                tolerance: 1e-4,
            },
            Case {
                name: "grey",
                reference: uniform([0.5; 3], 8, 5),
                test: uniform([0.6; 3], 8, 5),
                size: (8, 5),
                mean: 0.2850555,
                probes: vec![(0, 0.2850556), (17, 0.2850556)],
                tolerance: 1e-4,
            },
        ];
        for c in cases {
            let (w, h) = c.size;
            let map = flip_map(&c.reference, &c.test, w, h, PPD).unwrap();
            let mean = flip_mean(&c.reference, &c.test, w, h, PPD).unwrap();
            assert!(
                (mean - c.mean).abs() < c.tolerance,
                "{}: mean {mean} vs {}",
                c.name,
                c.mean
            );
            for (i, expected) in c.probes {
                let got = map[i];
                assert!(
                    (got - expected).abs() < c.tolerance,
                    "{}: map[{i}] = {got} vs {expected}",
                    c.name
                );
            }
        }
    }

    #[test]
    fn flat_regions_have_no_features() {
        // What lets the uniform-image tests treat error as color_err exactly.
        let (w, h) = (23, 11);
        for grey in [0.0, 0.37, 1.0] {
            let ycxcz: Vec<Vec3> = uniform([grey; 3], w, h)
                .iter()
                .map(|&c| srgb_to_ycxcz(c))
                .collect();
            let f = features(&ycxcz, w, h, &FeatureKernels::new(PPD));
            assert!(
                f.edge.iter().chain(&f.point).all(|&v| v == 0.0),
                "grey {grey}"
            );
        }
    }

    #[test]
    fn uniform_greys_match_the_closed_form() {
        // Greys have a = b = 0 (up to rounding), so HyAB is |L1 - L2| with
        // L = 116 Y^(1/3) - 16 of the linear luminance Y, and the feature term is 0:
        // error = compress(|L1 - L2|^qc). Computed here in f64 from the formulas alone.
        let lightness = |s: f64| {
            let y = ((s + 0.055) / 1.055).powf(2.4);
            116.0 * y.cbrt() - 16.0
        };
        let cmax = f64::from(cmax());
        for (a, b) in [(0.5f32, 0.6f32), (0.2, 0.25), (0.9, 0.3), (0.45, 0.46)] {
            let e = (lightness(a.into()) - lightness(b.into())).abs().powf(0.7);
            let knee = 0.4 * cmax;
            let expected = if e < knee {
                0.95 / knee * e
            } else {
                0.95 + (e - knee) / (cmax - knee) * 0.05
            };
            let (w, h) = (8, 5);
            let map = flip_map(&uniform([a; 3], w, h), &uniform([b; 3], w, h), w, h, PPD).unwrap();
            for &got in &map {
                assert!(
                    (f64::from(got) - expected).abs() < 1e-5,
                    "{a} vs {b}: {got} vs {expected}"
                );
            }
        }
    }

    #[test]
    fn error_grows_with_a_uniform_offset() {
        let (w, h) = (24, 20);
        for reference in [uniform([0.3, 0.2, 0.25], w, h), pattern(w, h, 0.5)] {
            let mut last = -1.0;
            for k in 0..=10 {
                let offset = k as f32 * 0.05;
                let test: Vec<[f32; 3]> = reference.iter().map(|c| c.map(|v| v + offset)).collect();
                let mean = flip_mean(&reference, &test, w, h, PPD).unwrap();
                assert!(mean > last, "offset {offset}: {mean} <= {last}");
                last = mean;
            }
            assert!(last > 0.3, "{last}");
        }
    }

    #[test]
    fn a_single_pixel_difference_stays_local() {
        let (w, h) = (64, 48);
        let (px, py) = (20, 30);
        let reference = uniform([0.5; 3], w, h);
        let mut test = reference.clone();
        test[py * w + px] = [1.0, 0.8, 0.2];
        let map = flip_map(&reference, &test, w, h, PPD).unwrap();
        // At 67 ppd the CSF radius is ceil(3 sqrt(0.04 / (2 pi^2)) 67) = 10 and the
        // feature radius ceil(3 * 0.041 * 67) = 9; the kernels are separable, so
        // their support is a square.
        let support = 10;
        let peak = map[py * w + px];
        assert!(peak > 0.1, "{peak}");
        for y in 0..h {
            for x in 0..w {
                let e = map[y * w + x];
                let d = x.abs_diff(px).max(y.abs_diff(py));
                if d > support {
                    assert_eq!(e, 0.0, "({x}, {y})");
                } else if d <= 2 {
                    assert!(e > 0.0, "({x}, {y})");
                }
                assert!(e <= peak, "({x}, {y}): {e} > {peak}");
            }
        }
    }

    #[test]
    fn swapping_reference_and_test_changes_nothing() {
        let (w, h) = (19, 17);
        let a = pattern(w, h, 1.0);
        let b: Vec<[f32; 3]> = pattern(w, h, 0.7)
            .iter()
            .map(|c| [c[2], c[0], c[1]])
            .collect();
        assert_eq!(flip_map(&a, &b, w, h, PPD), flip_map(&b, &a, w, h, PPD));
    }

    #[test]
    fn colour_error_stays_in_unit_range_over_the_cube() {
        // cmax is the green-blue distance; check no pair of colours on a grid exceeds it.
        // 11 levels per channel, linear RGB: 1331 colours, all pairs.
        let level = |i: usize| i as f32 / 10.0;
        let lab: Vec<Vec3> = (0..11 * 11 * 11)
            .map(|i| Vec3::new(level(i % 11), level(i / 11 % 11), level(i / 121)))
            .map(|c| hunt(linear_rgb_to_lab(c)))
            .collect();
        let c = cmax();
        for p in &lab {
            for q in &lab {
                let e = compress(hyab(*p, *q).powf(QC), c);
                assert!((0.0..=1.0 + 1e-6).contains(&e), "{p} {q}: {e}");
            }
        }
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        let img = uniform([0.5; 3], 4, 4);
        let short = uniform([0.5; 3], 4, 3);
        let err = flip_map(&img, &short, 4, 4, PPD).unwrap_err();
        assert!(err.contains("test has 12 pixels"), "{err}");
        let err = flip_mean(&short, &img, 4, 4, PPD).unwrap_err();
        assert!(err.contains("reference has 12 pixels"), "{err}");
        assert!(flip_map(&img, &img, usize::MAX, 2, PPD).is_err());
        let mut nan = img.clone();
        nan[5][1] = f32::NAN;
        let err = flip_map(&img, &nan, 4, 4, PPD).unwrap_err();
        assert!(err.contains("(1, 1)"), "{err}");
        assert!(flip_map(&img, &img, 4, 4, 0.0).is_err());
        assert!(flip_map(&img, &img, 4, 4, f32::NAN).is_err());
        assert_eq!(flip_map(&[], &[], 0, 7, PPD), Ok(Vec::new()));
        assert!(flip_mean(&[], &[], 0, 7, PPD).is_err());
    }
}
