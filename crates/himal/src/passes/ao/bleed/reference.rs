//! CPU twin of `bleed.wgsl` and `shaders/ao_bleed.wgsl` (O5).

use glam::{Vec3, Vec4};

use super::SCALE;

/// The blur's weights, exp(−k²/8) normalised (`BLEED_WEIGHTS` in bleed.wgsl).
pub const BLUR_WEIGHTS: [f32; 5] = [0.20416, 0.18017, 0.12383, 0.06628, 0.02763];

/// `ao_bleed_occlusion`: occl^(1 − min(3 bleed, 0.7)) per channel.
pub fn bleed_occlusion(occl: f32, bleed: Vec3) -> Vec3 {
    let e = Vec3::ONE - (bleed * 3.0).min(Vec3::splat(0.7));
    let o = occl.max(0.0);
    Vec3::new(o.powf(e.x), o.powf(e.y), o.powf(e.z))
}

/// `ao_bleed_colour`: the coverage-weighted mean albedo of a bleed texel.
pub fn bleed_colour(texel: Vec4) -> Vec3 {
    texel.truncate() / texel.w.max(1e-4)
}

/// A row-major image of `w` x `h` texels.
#[derive(Clone, Debug)]
pub struct Texels {
    /// Width in texels (bleed resolution: full width / [`SCALE`], rounded up).
    pub w: usize,
    /// Height in texels.
    pub h: usize,
    /// `w * h` texels, top row first: rgb = albedo sum / 16, a = coverage.
    pub data: Vec<Vec4>,
}

impl Texels {
    fn at(&self, x: i64, y: i64) -> Vec4 {
        let x = x.clamp(0, self.w as i64 - 1) as usize;
        let y = y.clamp(0, self.h as i64 - 1) as usize;
        self.data[y * self.w + x]
    }
}

/// STEP 0: the sum of the albedo of pixels with geometry (`depth > 0`)
/// over each 4x4 block, and their count, over 16 (rgb, a).
pub fn downsample(albedo: &[Vec3], depth: &[f32], w: usize, h: usize) -> Texels {
    let s = SCALE as usize;
    let (bw, bh) = (w.div_ceil(s), h.div_ceil(s));
    let mut data = Vec::with_capacity(bw * bh);
    for qy in 0..bh {
        for qx in 0..bw {
            let mut sum = Vec4::ZERO;
            for j in 0..s {
                for i in 0..s {
                    let x = (qx * s + i).min(w - 1);
                    let y = (qy * s + j).min(h - 1);
                    if depth[y * w + x] > 0.0 {
                        sum += albedo[y * w + x].extend(1.0);
                    }
                }
            }
            data.push(sum / 16.0);
        }
    }
    Texels { w: bw, h: bh, data }
}

/// STEP 1 (x) or 2 (y): the 9-tap Gaussian with clamped edges.
pub fn blur(img: &Texels, along_x: bool) -> Texels {
    let (ax, ay) = if along_x { (1, 0) } else { (0, 1) };
    let mut data = Vec::with_capacity(img.data.len());
    for y in 0..img.h as i64 {
        for x in 0..img.w as i64 {
            let mut sum = img.at(x, y) * BLUR_WEIGHTS[0];
            for (k, w) in BLUR_WEIGHTS.iter().enumerate().skip(1) {
                let k = k as i64;
                sum += img.at(x + ax * k, y + ay * k) * *w;
                sum += img.at(x - ax * k, y - ay * k) * *w;
            }
            data.push(sum);
        }
    }
    Texels {
        w: img.w,
        h: img.h,
        data,
    }
}

/// The whole chain: downsample, blur x, blur y.
pub fn bleed_texture(albedo: &[Vec3], depth: &[f32], w: usize, h: usize) -> Texels {
    blur(&blur(&downsample(albedo, depth, w, h), true), false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one() {
        let s = BLUR_WEIGHTS[0] + 2.0 * BLUR_WEIGHTS[1..].iter().sum::<f32>();
        assert!((s - 1.0).abs() < 1e-4, "{s}");
    }

    #[test]
    fn white_and_black_bleed_keep_the_ends() {
        // Black: the plain occlusion; bright: occl^0.3 (the 0.7 cap).
        let o = bleed_occlusion(0.5, Vec3::new(0.0, 0.2, 1.0));
        assert!((o.x - 0.5).abs() < 1e-6);
        assert!((o.y - 0.5f32.powf(0.4)).abs() < 1e-6);
        assert!((o.z - 0.5f32.powf(0.3)).abs() < 1e-6);
        assert_eq!(bleed_occlusion(1.0, Vec3::ONE), Vec3::ONE);
    }
}
