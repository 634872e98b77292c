//! CPU twins of `luminance.wgsl`, `adapt.wgsl`, `bloom.wgsl` and `tonemap.wgsl`.

use glam::Vec3;

/// Offset inside the logarithm (Reinhard 2002's delta), as in the shader.
pub const DELTA: f64 = 1e-4;

/// Relative luminance of linear Rec.709 RGB (weights 0.2126, 0.7152, 0.0722), as `color.wgsl`.
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// exp(mean(log(delta + L))) over all pixels, accumulated in f64.
pub fn log_average_luminance(pixels: &[Vec3]) -> f64 {
    if pixels.is_empty() {
        return DELTA;
    }
    let sum: f64 = pixels
        .iter()
        .map(|&c| (DELTA + luminance(c).clamp(0.0, 65504.0) as f64).ln())
        .sum();
    (sum / pixels.len() as f64).exp()
}

/// Reinhard's global operator with hue preserved: the colour is scaled by
/// L_d / L_w where L = key / L_avg * L_w and L_d = L / (1 + L).
pub fn reinhard(c: Vec3, key: f32, log_average: f32) -> Vec3 {
    let scale = key / log_average.max(1e-6);
    let l_w = luminance(c) * scale;
    if l_w <= 0.0 {
        return Vec3::ZERO;
    }
    let l_d = l_w / (1.0 + l_w);
    c * scale * (l_d / l_w)
}

/// Reinhard 2002 eq. 4 with white point `l_white` (scaled luminance that maps to 1):
/// L_d = L (1 + L / L_white^2) / (1 + L).
pub fn reinhard_white(c: Vec3, key: f32, log_average: f32, l_white: f32) -> Vec3 {
    let scale = key / log_average.max(1e-6);
    let l_w = luminance(c) * scale;
    if l_w <= 0.0 {
        return Vec3::ZERO;
    }
    let l_white = l_white.max(1e-3);
    let l_d = l_w * (1.0 + l_w / (l_white * l_white)) / (1.0 + l_w);
    c * scale * (l_d / l_w)
}

/// The tone-map stage of `tonemap.wgsl` on HDR colour `c` exposed by
/// `scale` (key / L_exposure * 2^EV): display-linear, not yet clamped.
pub fn tonemap(c: Vec3, scale: f32, mapper: super::Tonemapper, white: Option<f32>) -> Vec3 {
    use super::Tonemapper;
    let c = c.max(Vec3::ZERO);
    match mapper {
        // reinhard() takes the key and log-average; scale = key / average.
        Tonemapper::Reinhard => match white {
            Some(w) => reinhard_white(c, 1.0, 1.0 / scale, w),
            None => reinhard(c, 1.0, 1.0 / scale),
        },
        Tonemapper::Neutral => pbr_neutral(c * scale),
        Tonemapper::Aces => aces_hill(c * scale),
        Tonemapper::Agx => agx(c * scale),
    }
}

/// Khronos PBR Neutral, as its specification states it
/// (KhronosGroup/ToneMapping, PBR_Neutral/README.md): F90 = 0.04,
/// K_s = 0.8 - F90, K_d = 0.15.
pub fn pbr_neutral(c: Vec3) -> Vec3 {
    const F90: f32 = 0.04;
    const K_S: f32 = 0.8 - F90;
    const K_D: f32 = 0.15;
    let x = c.min_element();
    let f = if x <= 2.0 * F90 {
        x - x * x / (4.0 * F90)
    } else {
        F90
    };
    let c = c - Vec3::splat(f);
    let p = c.max_element();
    if p <= K_S {
        return c;
    }
    let p_n = 1.0 - (1.0 - K_S) * (1.0 - K_S) / (p + 1.0 - 2.0 * K_S);
    let g = 1.0 / (K_D * (p - p_n) + 1.0);
    c * (p_n / p) * g + Vec3::splat(p_n) * (1.0 - g)
}

/// ACES input matrix of Hill's fit (sRGB to ACES AP1 with the RRT's
/// saturation), rows as published.
const ACES_IN: [[f32; 3]; 3] = [
    [0.59719, 0.35458, 0.04823],
    [0.07600, 0.90834, 0.01566],
    [0.02840, 0.13383, 0.83777],
];
/// ODT output matrix of Hill's fit (AP1 to sRGB), rows.
const ACES_OUT: [[f32; 3]; 3] = [
    [1.60475, -0.53108, -0.07367],
    [-0.10208, 1.10813, -0.00605],
    [-0.00327, -0.07276, 1.07602],
];

fn rows(m: &[[f32; 3]; 3], v: Vec3) -> Vec3 {
    Vec3::new(
        Vec3::from(m[0]).dot(v),
        Vec3::from(m[1]).dot(v),
        Vec3::from(m[2]).dot(v),
    )
}

/// ACES RRT + ODT (sRGB, 100 nits) as fitted by Stephen Hill (BakingLab):
/// v = M_in c, then (v (v + 0.0245786) - 0.000090537) /
/// (v (0.983729 v + 0.432951) + 0.238081), then M_out; the input divided by
/// 0.6 as three.js and the Khronos sample viewer do.
pub fn aces_hill(c: Vec3) -> Vec3 {
    let v = rows(&ACES_IN, c / 0.6);
    let rrt = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.432951) + 0.238081);
    rows(&ACES_OUT, rrt).clamp(Vec3::ZERO, Vec3::ONE)
}

/// AgX's inset (linear sRGB -> Rec.2020 -> AgX inset) and outset (inverse
/// outset -> Rec.2020 -> linear sRGB) matrices, columns (Blender's AgX
/// via EaryChow's AgX_LUT_Gen, combined with the Rec.2020 conversion).
const AGX_INSET: [[f32; 3]; 3] = [
    [0.544_908_1, 0.140_440_06, 0.088_827_41],
    [0.373_779_46, 0.754_109_6, 0.178_877_12],
    [0.081_384_98, 0.105_433_58, 0.732_25],
];
const AGX_OUTSET: [[f32; 3]; 3] = [
    [1.964_551, -0.299_322_43, -0.164_368_34],
    [-0.855_858_45, 1.326_451_1, -0.238_224_64],
    [-0.108_867_11, -0.027_084_02, 1.402_665_3],
];

/// AgX's tone curve, from its defining parameters: log2 encoding over
/// [log2 0.18 - 10, log2 0.18 + 6.5] EV, a power sigmoid of slope 2.4 and
/// power 1.5 through (0, 0), the pivot (10 / 16.5, 0.18^(1/2.4)) and (1, 1),
/// then the 2.4 power back to display-linear.
#[derive(Clone, Copy, Debug)]
pub struct AgxCurve {
    /// Lowest encoded exposure: log2(0.18) - 10 (EV, maps to x = 0).
    pub min_ev: f32,
    /// EV span of the log2 encoding: 16.5 (x = 1 at log2(0.18) + 6.5).
    pub range_ev: f32,
    /// Normalised log2 position of middle grey 0.18: 10 / 16.5.
    pub x_pivot: f32,
    /// Sigmoid output at the pivot: 0.18^(1/2.4), so middle grey stays 0.18 after the 2.4 power.
    pub y_pivot: f32,
    /// Sigmoid scale below the pivot (solved for y(0) = 0).
    pub k_bottom: f32,
    /// Sigmoid scale above the pivot (solved for y(1) = 1).
    pub k_top: f32,
}

impl AgxCurve {
    /// Slope of the sigmoid at the pivot.
    pub const SLOPE: f32 = 2.4;
    /// Power of the sigmoid's shoulder and toe (higher = sharper).
    pub const POWER: f32 = 1.5;

    /// Solves the curve for its defining parameters (see the type's docs).
    pub fn new() -> AgxCurve {
        let (below, above) = (10.0f32, 6.5f32);
        let x_p = below / (below + above);
        let y_p = 0.18f32.powf(1.0 / 2.4);
        // y(x) = y_p + s d / (1 + (k |d|)^p)^(1/p), d = x - x_p, through the end points.
        let k = |dx: f32, dy: f32| {
            ((Self::SLOPE * dx / dy).powf(Self::POWER) - 1.0).powf(1.0 / Self::POWER) / dx
        };
        AgxCurve {
            min_ev: 0.18f32.log2() - below,
            range_ev: below + above,
            x_pivot: x_p,
            y_pivot: y_p,
            k_bottom: k(x_p, y_p),
            k_top: k(1.0 - x_p, 1.0 - y_p),
        }
    }

    /// Display-encoded value of normalised log2 `x`.
    pub fn sigmoid(&self, x: f32) -> f32 {
        let d = x - self.x_pivot;
        let k = if d >= 0.0 { self.k_top } else { self.k_bottom };
        self.y_pivot
            + Self::SLOPE * d / (1.0 + (k * d.abs()).powf(Self::POWER)).powf(1.0 / Self::POWER)
    }
}

impl Default for AgxCurve {
    fn default() -> Self {
        Self::new()
    }
}

fn columns(m: &[[f32; 3]; 3], v: Vec3) -> Vec3 {
    Vec3::from(m[0]) * v.x + Vec3::from(m[1]) * v.y + Vec3::from(m[2]) * v.z
}

/// AgX base: inset, log2 encoding, sigmoid, 2.4 power, outset (Blender's
/// low-side compensation left out: negatives are clamped at display).
pub fn agx(c: Vec3) -> Vec3 {
    let curve = AgxCurve::new();
    let v = columns(&AGX_INSET, c.max(Vec3::splat(2e-10)));
    let x = ((v.to_array()).map(|v| ((v.log2() - curve.min_ev) / curve.range_ev).max(0.0)))
        .map(|x| curve.sigmoid(x).powf(2.4));
    columns(&AGX_OUTSET, Vec3::from(x))
}

/// sRGB encoding (IEC 61966-2-1) of a display-linear value, clamped.
pub fn srgb_encode(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// One step of light adaptation (`adapt.wgsl`):
/// L_a' = L_avg + (L_a - L_avg) exp(-dt / tau), tau by direction of change.
pub fn adapt(l_a: f64, l_avg: f64, dt: f64, tau_brighten: f64, tau_darken: f64) -> f64 {
    let tau = if l_avg > l_a {
        tau_brighten
    } else {
        tau_darken
    };
    l_avg + (l_a - l_avg) * (-dt / tau).exp()
}

/// An RGB image, row-major, for the bloom twins.
#[derive(Clone, Debug)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height` linear RGB values, row by row.
    pub pixels: Vec<Vec3>,
}

impl Image {
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = x.clamp(0, self.width as i64 - 1) as u32;
        let y = y.clamp(0, self.height as i64 - 1) as u32;
        self.pixels[(y * self.width + x) as usize]
    }

    /// Bilinear sample at continuous pixel coordinates (texel centres at +0.5),
    /// clamp to edge, as a linear sampler does.
    pub fn bilinear(&self, x: f32, y: f32) -> Vec3 {
        let (fx, fy) = (x - 0.5, y - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), tx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), tx);
        top.lerp(bottom, ty)
    }

    /// Sum of all pixels (energy checks).
    pub fn sum(&self) -> Vec3 {
        self.pixels.iter().fold(Vec3::ZERO, |a, &b| a + b)
    }
}

/// One Kawase pass at offset `k`: the mean of 4 bilinear taps at
/// (+-(k + 1/2), +-(k + 1/2)) texels around each pixel centre.
pub fn kawase_pass(src: &Image, k: u32) -> Image {
    let d = k as f32 + 0.5;
    let mut pixels = Vec::with_capacity(src.pixels.len());
    for y in 0..src.height {
        for x in 0..src.width {
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let sum = src.bilinear(cx - d, cy - d)
                + src.bilinear(cx + d, cy - d)
                + src.bilinear(cx - d, cy + d)
                + src.bilinear(cx + d, cy + d);
            pixels.push(sum * 0.25);
        }
    }
    Image {
        width: src.width,
        height: src.height,
        pixels,
    }
}

/// The bright pass at quarter resolution: 4 bilinear taps per 4x4 block,
/// each keeping `c * max(L_s - T, 0) / L_s` with `L_s = scale * L(c)`.
pub fn bright_pass(src: &Image, scale: f32, threshold: f32) -> Image {
    let (w, h) = (src.width.div_ceil(4).max(1), src.height.div_ceil(4).max(1));
    let bright = |c: Vec3| {
        let l_s = luminance(c) * scale;
        if l_s > 0.0 {
            c * ((l_s - threshold).max(0.0) / l_s)
        } else {
            Vec3::ZERO
        }
    };
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let (cx, cy) = (x as f32 * 4.0 + 2.0, y as f32 * 4.0 + 2.0);
            let sum = bright(src.bilinear(cx - 1.0, cy - 1.0))
                + bright(src.bilinear(cx + 1.0, cy - 1.0))
                + bright(src.bilinear(cx - 1.0, cy + 1.0))
                + bright(src.bilinear(cx + 1.0, cy + 1.0));
            pixels.push(sum * 0.25);
        }
    }
    Image {
        width: w,
        height: h,
        pixels,
    }
}
