//! CPU twins of `luminance.wgsl`, `adapt.wgsl`, `bloom.wgsl` and `tonemap.wgsl`.

use glam::Vec3;

/// Offset inside the logarithm (Reinhard 2002's delta), as in the shader.
pub const DELTA: f64 = 1e-4;

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
    pub width: u32,
    pub height: u32,
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
