//! CPU twins of `shaders/shadow.wgsl`: the disk rotation and the rotated
//! Poisson-disk filter of hardware-compared bilinear taps, for the
//! GPU-versus-CPU test on a tiny depth map (`tests/shadows_filter.rs`).
//! The whole chain is checked against CPU ray casting in `tests/shadows.rs`.

use glam::{Mat4, Vec2, Vec3};

use super::local::{LocalLightGpu, ShadowTileGpu};

/// `SHADOW_POISSON_16` of shadow.wgsl.
#[allow(clippy::excessive_precision)] // digits as in shadow.wgsl
pub const POISSON_16: [[f32; 2]; 16] = [
    [-0.942_016_24, -0.399_062_16],
    [0.945_586_09, -0.768_907_25],
    [0.974_843_98, 0.756_483_79],
    [-0.814_099_55, 0.914_375_9],
    [-0.094_184_1, -0.929_388_7],
    [0.344_959_38, 0.293_877_6],
    [-0.915_885_81, 0.457_714_32],
    [-0.815_442_32, -0.879_124_64],
    [-0.382_775_43, 0.276_768_45],
    [0.443_233_25, -0.975_115_54],
    [0.537_429_81, -0.473_734_2],
    [-0.264_969_11, -0.418_930_23],
    [0.791_975_14, 0.190_901_88],
    [-0.241_888_4, 0.997_065_07],
    [0.199_841_26, 0.786_413_67],
    [0.143_831_61, -0.141_007_9],
];

/// `shadow_rotation_angle`: interleaved gradient noise of a map cell.
pub fn rotation_angle(cell: Vec2) -> f32 {
    let f = |x: f32| x - x.floor();
    std::f32::consts::TAU * f(52.982_918 * f(cell.dot(Vec2::new(0.067_110_56, 0.005_837_15))))
}

/// `shadow_cube_face`: the cube face of direction `d` (light to point),
/// 0..5 = +X, -X, +Y, -Y, +Z, -Z.
pub fn cube_face(d: Vec3) -> u32 {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        return if d.x > 0.0 { 0 } else { 1 };
    }
    if a.y >= a.z {
        return if d.y > 0.0 { 2 } else { 3 };
    }
    if d.z > 0.0 { 4 } else { 5 }
}

/// `shadow_local_tile`: the atlas tile local light `l` reads at `p` (its
/// cube face's for a point light), `None` beyond its range.
pub fn local_tile(l: &LocalLightGpu, p: Vec3) -> Option<u32> {
    let to_p = p - Vec3::from_slice(&l.position_range[..3]);
    if to_p.length() >= l.position_range[3] {
        return None;
    }
    let first = l.params[2] as u32;
    Some(if l.color_kind[3] < 0.5 {
        first + cube_face(to_p)
    } else {
        first
    })
}

/// `shadow_local_lookup` without the disk rotation: where `p` (normal `n`)
/// reads tile `t`: (atlas uv, compare depth), `None` off the tile.
pub fn local_lookup(l: &LocalLightGpu, t: &ShadowTileGpu, p: Vec3, n: Vec3) -> Option<(Vec2, f32)> {
    let to_p = p - Vec3::from_slice(&l.position_range[..3]);
    let d = to_p.length();
    let texel = t.info[0] * d;
    let q = p + n * (1.5 * texel) - (to_p / d) * (2.0 * texel);
    let c = Mat4::from_cols_array_2d(&t.view_proj) * q.extend(1.0);
    if c.w <= 0.0 {
        return None;
    }
    let ndc = c.truncate() / c.w;
    let uv_tile = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    let inside = uv_tile.cmpge(Vec2::ZERO).all() && uv_tile.cmple(Vec2::ONE).all() && ndc.z <= 1.0;
    inside.then(|| {
        (
            Vec2::new(t.rect[0], t.rect[1]) + uv_tile * Vec2::new(t.rect[2], t.rect[3]),
            ndc.z,
        )
    })
}

/// `shadow_local_point_visibility`: a particle at `p` seen by local light
/// `l` through tile `t` of `atlas`, the 4 x 4 gather; 1 off the tile.
pub fn local_point_visibility(
    l: &LocalLightGpu,
    t: &ShadowTileGpu,
    p: Vec3,
    atlas: &DepthMap,
) -> f32 {
    match local_lookup(l, t, p, Vec3::ZERO) {
        Some((uv, depth_ref)) => atlas.gather_4x4(uv, depth_ref),
        None => 1.0,
    }
}

/// A depth map on the CPU (row-major, texel (x, y) at `depth[y * width + x]`).
pub struct DepthMap<'a> {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` depths as the map stores them (0 nearest the light .. 1).
    pub depth: &'a [f32],
}

impl DepthMap<'_> {
    /// Comparison LessEqual of texel (x, y), clamped to the edge: 1 = lit.
    fn compare(&self, x: i64, y: i64, depth_ref: f32) -> f32 {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        let stored = self.depth[y * self.width as usize + x];
        if depth_ref <= stored { 1.0 } else { 0.0 }
    }

    /// One linear-filtered comparison at `uv` (Vulkan: compare the four
    /// nearest texels, then weight the results bilinearly).
    pub fn sample_compare(&self, uv: Vec2, depth_ref: f32) -> f32 {
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let (x0, y0) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - x0, p.y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top =
            self.compare(x0, y0, depth_ref) * (1.0 - fx) + self.compare(x0 + 1, y0, depth_ref) * fx;
        let bottom = self.compare(x0, y0 + 1, depth_ref) * (1.0 - fx)
            + self.compare(x0 + 1, y0 + 1, depth_ref) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// `shadow_poisson_visibility`: mean of 16 rotated, scaled disk taps, or
    /// of the outer four when they agree.
    pub fn poisson_visibility(
        &self,
        uv: Vec2,
        depth_ref: f32,
        radius_texels: f32,
        angle: f32,
    ) -> f32 {
        let texel = Vec2::new(1.0 / self.width as f32, 1.0 / self.height as f32);
        let (s, c) = angle.sin_cos();
        let tap = |&[ox, oy]: &[f32; 2]| {
            let r = Vec2::new(ox * c - oy * s, ox * s + oy * c);
            self.sample_compare(uv + r * radius_texels * texel, depth_ref)
        };
        let ring: f32 = POISSON_16[..4].iter().map(tap).sum();
        if ring == 0.0 || ring == 4.0 {
            return ring / 4.0;
        }
        (ring + POISSON_16[4..].iter().map(tap).sum::<f32>()) / 16.0
    }

    /// `shadow_gather_4x4` (R2): the 4 x 4 texels around `uv` compared and
    /// weighted per axis by (1 - f, 2 - f, 1 + f, f) / 4.
    pub fn gather_4x4(&self, uv: Vec2, depth_ref: f32) -> f32 {
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let (bx, by) = (p.x.floor(), p.y.floor());
        let (fx, fy) = (p.x - bx, p.y - by);
        let w = |f: f32| [1.0 - f, 2.0 - f, 1.0 + f, f].map(|x| x * 0.25);
        let (wx, wy) = (w(fx), w(fy));
        let mut v = 0.0;
        for (j, wy) in wy.iter().enumerate() {
            for (i, wx) in wx.iter().enumerate() {
                let (x, y) = (bx as i64 + i as i64 - 1, by as i64 + j as i64 - 1);
                v += wx * wy * self.compare(x, y, depth_ref);
            }
        }
        v
    }
}

impl DepthMap<'_> {
    /// Depth of texel (x, y), clamped to the edge (the sampler's addressing).
    pub fn texel(&self, x: i64, y: i64) -> f32 {
        let x = x.clamp(0, self.width as i64 - 1) as usize;
        let y = y.clamp(0, self.height as i64 - 1) as usize;
        self.depth[y * self.width as usize + x]
    }
}

/// `SHADOW_TILE_FILTER`, `_LIT`, `_SHADOWED` (#23, `shadows.mask_tiles`).
pub const TILE_FILTER: u32 = 0;
/// Every tap of every pixel of the tile passes.
pub const TILE_LIT: u32 = 1;
/// Every tap of every pixel of the tile fails.
pub const TILE_SHADOWED: u32 = 2;

/// `shadow_tile_reach`: texels from a lookup's own to the farthest a tap reads.
pub fn tile_reach(radius_texels: f32) -> i32 {
    (1.03 * radius_texels + 0.5).ceil() as i32
}

/// `shadow_texel_verdict`: bit 0 every comparison with [ref_min, ref_max]
/// passes, bit 1 every one fails.
pub fn texel_verdict(z: f32, ref_min: f32, ref_max: f32) -> u32 {
    let eps = 3e-5;
    u32::from(z >= ref_max + eps) | (u32::from(z + eps < ref_min) << 1)
}

/// `shadow_tile_state`.
pub fn tile_state(inside: u32, valid: u32, read: bool, lit: bool, shadowed: bool) -> u32 {
    if inside == 0 {
        TILE_LIT
    } else if !read {
        TILE_FILTER
    } else if lit {
        TILE_LIT
    } else if shadowed && inside == valid {
        TILE_SHADOWED
    } else {
        TILE_FILTER
    }
}

/// One map's state over one tile as `shadows.mask_tiles` finds it: the
/// pixels' lookups inside the map (`lookups`: uv, compare depth) of `valid`
/// pixels not sky, binned by texel, each bin's compare depths spread over
/// the taps' reach, every texel of the footprint given its verdict;
/// `max_texels`: the grid's edge (`SHADOW_TILE_MAX_TEXELS`).
pub fn classify_tile(
    map: &DepthMap,
    lookups: &[(Vec2, f32)],
    valid: u32,
    radius_texels: f32,
    max_texels: i32,
) -> u32 {
    let size = Vec2::new(map.width as f32, map.height as f32);
    let cells: Vec<(i64, i64, f32)> = lookups
        .iter()
        .map(|(uv, r)| {
            let c = (*uv * size).floor();
            (c.x as i64, c.y as i64, *r)
        })
        .collect();
    let inside = cells.len() as u32;
    if inside == 0 {
        return tile_state(0, valid, false, false, false);
    }
    let reach = tile_reach(radius_texels) as i64;
    let x0 = cells.iter().map(|c| c.0).min().unwrap_or(0) - reach;
    let y0 = cells.iter().map(|c| c.1).min().unwrap_or(0) - reach;
    let x1 = cells.iter().map(|c| c.0).max().unwrap_or(0) + reach;
    let y1 = cells.iter().map(|c| c.1).max().unwrap_or(0) + reach;
    let read = x1 - x0 < max_texels as i64 && y1 - y0 < max_texels as i64;
    let (mut lit, mut shadowed) = (true, true);
    if read {
        for y in y0..=y1 {
            for x in x0..=x1 {
                let near = cells
                    .iter()
                    .filter(|c| (c.0 - x).abs() <= reach && (c.1 - y).abs() <= reach);
                let (lo, hi) = near.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(c.2), hi.max(c.2))
                });
                if hi == f32::NEG_INFINITY {
                    continue;
                }
                let v = texel_verdict(map.texel(x, y), lo, hi);
                lit &= v & 1 != 0;
                shadowed &= v & 2 != 0;
            }
        }
    }
    tile_state(inside, valid, read, lit, shadowed)
}
