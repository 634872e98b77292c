//! Procedural detail textures for the terrain layers, made on the CPU when
//! the pass is created: per layer an albedo + glossiness variation map
//! (RGBA8, mean 0.5) and a tangent-space normal map (xy * 0.5 + 0.5) from
//! a height field, both tileable (periodic lattice noise), with box-filtered
//! mips; the normal maps' alpha holds E3's normal variance of each level
//! ([`normal_mips`]). A pure function of (kind, seed): the same bytes every run.

use glam::Vec3;

use super::DetailKind;
use crate::math::brdf::{next_normal_variance_level, normal_variance_encode};

/// Texels per side of a detail map (level 0).
pub const DETAIL_SIZE: u32 = 256;

/// Mip levels of a [`DETAIL_SIZE`] map (down to 1 x 1).
pub fn mip_count() -> u32 {
    DETAIL_SIZE.ilog2() + 1
}

fn hash(seed: u32, i: u32, j: u32) -> f32 {
    let mut h = seed
        .wrapping_mul(0x9e37_79b9)
        .wrapping_add(i.wrapping_mul(0x85eb_ca6b))
        ^ j.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2c1b_3c6d);
    h ^= h >> 12;
    h = h.wrapping_mul(0x297a_2d39);
    h ^= h >> 15;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Value noise in [0, 1] at texel (x, y) with `period` cells across the
/// map (so it tiles), smoothstep-interpolated.
fn noise(seed: u32, x: f32, y: f32, period: u32) -> f32 {
    let cell = DETAIL_SIZE as f32 / period as f32;
    let (u, v) = (x / cell, y / cell);
    let (i, j) = (u.floor(), v.floor());
    let (fu, fv) = (u - i, v - j);
    let (su, sv) = (fu * fu * (3.0 - 2.0 * fu), fv * fv * (3.0 - 2.0 * fv));
    let (i, j) = (i as i64, j as i64);
    let p = period as i64;
    let at = |a: i64, b: i64| hash(seed, (a.rem_euclid(p)) as u32, (b.rem_euclid(p)) as u32);
    let top = at(i, j) * (1.0 - su) + at(i + 1, j) * su;
    let bottom = at(i, j + 1) * (1.0 - su) + at(i + 1, j + 1) * su;
    top * (1.0 - sv) + bottom * sv
}

/// Fractal sum of `octaves`, period doubling, gain 1/2; in [0, 1].
fn fbm(seed: u32, x: f32, y: f32, period: u32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut norm, mut p) = (0.0, 1.0, 0.0, period);
    for o in 0..octaves {
        sum += amp * noise(seed.wrapping_add(o * 7919), x, y, p.min(DETAIL_SIZE));
        norm += amp;
        amp *= 0.5;
        p *= 2;
    }
    sum / norm
}

/// Height (0..1), albedo variation (rgb, mean ~0.5), glossiness variation
/// and normal strength of `kind` at texel (x, y).
fn texel(kind: DetailKind, seed: u32, x: f32, y: f32) -> (f32, [f32; 3], f32) {
    match kind {
        DetailKind::Grass => {
            let clumps = fbm(seed, x, y, 8, 4);
            let blades = noise(seed ^ 0x51ed, x, y, 128);
            let hue = fbm(seed ^ 0x2f1c, x, y, 4, 3) - 0.5;
            let v = 0.5 + 0.35 * (clumps - 0.5) + 0.15 * (blades - 0.5);
            let h = 0.6 * clumps + 0.4 * blades;
            (
                h,
                [v + 0.18 * hue, v + 0.05 * hue, v - 0.15 * hue],
                0.5 + 0.2 * (blades - 0.5),
            )
        }
        DetailKind::Rock => {
            let r = fbm(seed, x, y, 4, 6);
            let ridged = 1.0 - (2.0 * r - 1.0).abs();
            let strata = (std::f32::consts::TAU
                * (y / DETAIL_SIZE as f32 * 6.0 + 0.6 * fbm(seed ^ 0x1b87, x, y, 4, 2)))
            .sin();
            let grain = noise(seed ^ 0x6a09, x, y, 64);
            let h = 0.7 * ridged + 0.15 * strata + 0.15 * grain;
            let v = 0.5 + 0.45 * (h - 0.5) + 0.1 * (grain - 0.5);
            (h, [v * 1.02, v, v * 0.96], 0.5 + 0.3 * (ridged - 0.5))
        }
        DetailKind::Snow => {
            let drift = fbm(seed, x, y, 4, 4);
            let sparkle = noise(seed ^ 0x3c6e, x, y, 128);
            let v = 0.5 + 0.06 * (drift - 0.5);
            (
                0.5 * drift,
                [v * 0.98, v, v * 1.02],
                0.5 + 0.3 * (sparkle - 0.5),
            )
        }
        DetailKind::Soil => {
            let base = fbm(seed, x, y, 8, 3);
            let stones = noise(seed ^ 0x7f4a, x, y, 32);
            let pebble = ((stones - 0.62) * 6.0).clamp(0.0, 1.0);
            let fine = noise(seed ^ 0x0b3d, x, y, 128);
            let h = 0.5 * base + 0.4 * pebble + 0.1 * fine;
            let v = 0.5 + 0.25 * (base - 0.5) + 0.22 * (pebble - 0.3) + 0.08 * (fine - 0.5);
            (h, [v * 1.04, v, v * 0.94], 0.5 - 0.15 + 0.3 * pebble)
        }
    }
}

/// Normal strength (height units per texel slope) of each kind.
fn bumpiness(kind: DetailKind) -> f32 {
    match kind {
        DetailKind::Grass => 6.0,
        DetailKind::Rock => 10.0,
        DetailKind::Snow => 3.0,
        DetailKind::Soil => 8.0,
    }
}

fn unorm(v: f32) -> u8 {
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Level 0 of the albedo and normal maps of `kind` (row-major RGBA8).
pub fn detail_maps(kind: DetailKind, seed: u32) -> (Vec<[u8; 4]>, Vec<[u8; 4]>) {
    let n = DETAIL_SIZE as usize;
    let mut height = vec![0.0f32; n * n];
    let mut albedo = vec![[0u8; 4]; n * n];
    for y in 0..n {
        for x in 0..n {
            let (h, rgb, gloss) = texel(kind, seed, x as f32, y as f32);
            height[y * n + x] = h;
            albedo[y * n + x] = [unorm(rgb[0]), unorm(rgb[1]), unorm(rgb[2]), unorm(gloss)];
        }
    }
    let k = bumpiness(kind);
    let at = |x: usize, y: usize| height[(y % n) * n + (x % n)];
    let normal = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            // Central differences with wrap-around: the map tiles.
            let du = (at(x + 1, y) - at(x + n - 1, y)) * 0.5 * k;
            let dv = (at(x, y + 1) - at(x, y + n - 1)) * 0.5 * k;
            let len = (du * du + dv * dv + 1.0).sqrt();
            [
                unorm(-du / len * 0.5 + 0.5),
                unorm(-dv / len * 0.5 + 0.5),
                unorm(1.0 / len),
                // E3: level 0 has no variance.
                0,
            ]
        })
        .collect();
    (albedo, normal)
}

/// `level0` (DETAIL_SIZE^2) and its box-filtered mips down to 1 x 1.
pub fn mips(level0: Vec<[u8; 4]>) -> Vec<Vec<[u8; 4]>> {
    let mut out = vec![level0];
    let mut n = DETAIL_SIZE as usize;
    while n > 1 {
        let m = n / 2;
        let src = &out[out.len() - 1];
        let next = (0..m * m)
            .map(|i| {
                let (x, y) = (2 * (i % m), 2 * (i / m));
                std::array::from_fn(|c| {
                    let s: u32 = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)]
                        .iter()
                        .map(|&(a, b)| u32::from(src[b * n + a][c]))
                        .sum();
                    ((s + 2) / 4) as u8
                })
            })
            .collect();
        out.push(next);
        n = m;
    }
    out
}

/// The mips of a normal map's `level0` (DETAIL_SIZE^2, alpha 0): RGB
/// box-filtered as [`mips`] (the shader's UDN offsets average), alpha E3's
/// normal variance of each level, encoded (`math::brdf`
/// [`next_normal_variance_level`]: level 1 from level 0's bilinear field,
/// wrapping around as the tiling sampler does; computed in f32 down the
/// chain, rounded once per level).
pub fn normal_mips(level0: Vec<[u8; 4]>) -> Vec<Vec<[u8; 4]>> {
    let n = DETAIL_SIZE as i32;
    let decode = |t: [u8; 4]| Vec3::new(t[0] as f32, t[1] as f32, t[2] as f32) / 255.0;
    let mut chain: Vec<(Vec3, f32)> = level0.iter().map(|&t| (decode(t), 0.0)).collect();
    let mut out = mips(level0);
    let mut side = n;
    for (level, data) in out.iter_mut().enumerate().skip(1) {
        let prev = &chain;
        let texel =
            |x: i32, y: i32| prev[(y.rem_euclid(side) * side + x.rem_euclid(side)) as usize];
        let next = next_normal_variance_level(side as u32, side as u32, texel, level == 1);
        for (t, &(_, variance)) in data.iter_mut().zip(&next) {
            t[3] = unorm(normal_variance_encode(variance));
        }
        chain = next.into_iter().map(|(m, v)| (m * 0.5 + 0.5, v)).collect();
        side /= 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::brdf::normal_variance_decode;

    #[test]
    fn normal_mips_keep_the_box_rgb_and_add_growing_variance() {
        let (_, normal) = detail_maps(DetailKind::Rock, 5);
        let plain = mips(normal.clone());
        let baked = normal_mips(normal);
        assert_eq!(baked.len(), plain.len());
        let mut last = 0.0;
        for (level, (b, p)) in baked.iter().zip(&plain).enumerate() {
            // The shader's offsets (RGB) are the plain box mips': E3 off
            // draws what it drew before.
            assert!(
                b.iter().zip(p).all(|(x, y)| x[..3] == y[..3]),
                "level {level}"
            );
            let mean = b
                .iter()
                .map(|t| normal_variance_decode(t[3] as f32 / 255.0))
                .sum::<f32>()
                / b.len() as f32;
            if level == 0 {
                assert!(b.iter().all(|t| t[3] == 0), "level 0 has no variance");
            } else {
                // A mixture's variance never shrinks down the chain (8-bit
                // rounding of the encoding aside).
                assert!(
                    mean > 0.0 && mean >= last * 0.98,
                    "level {level}: {mean} after {last}"
                );
            }
            last = mean;
        }
    }

    #[test]
    fn level_one_wraps_around_as_the_tiling_sampler_does() {
        // A map that is flat but for one column of tilted normals at x = 0:
        // level 1's texels at both edges see it (bilinear field wraps), the
        // middle does not.
        let n = DETAIL_SIZE as usize;
        let tilted = [200u8, 128, 230, 0];
        let level0: Vec<[u8; 4]> = (0..n * n)
            .map(|i| {
                if i % n == 0 {
                    tilted
                } else {
                    [128, 128, 255, 0]
                }
            })
            .collect();
        let level1 = &normal_mips(level0)[1];
        let m = n / 2;
        let (first, last, middle) = (level1[0][3], level1[m - 1][3], level1[m / 2][3]);
        assert!(first > 0 && last > 0, "edges {first} {last}");
        assert_eq!(middle, 0);
    }
}
