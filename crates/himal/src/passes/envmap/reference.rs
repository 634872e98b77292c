//! CPU twins of the environment-map passes (TECHNIQUES L4, M4): cube-face
//! directions, box mips, GGX filtered importance sampling, a brute-force
//! Monte Carlo reference, the split-sum DFG table and the M4 reflection normal.

use glam::{Mat3, Vec2, Vec3};

use crate::math::brdf::{MIN_ALPHA, v_smith_ggx_correlated_aniso};
use crate::math::sampling::{hammersley, importance_sample_ggx_aniso};

/// Twin of `cube_face_direction` (envmap.wgsl): faces +X, -X, +Y, -Y, +Z, -Z.
pub fn cube_face_direction(face: usize, uv: Vec2) -> Vec3 {
    let (s, t) = (uv.x * 2.0 - 1.0, uv.y * 2.0 - 1.0);
    match face {
        0 => Vec3::new(1.0, -t, -s),
        1 => Vec3::new(-1.0, -t, s),
        2 => Vec3::new(s, 1.0, t),
        3 => Vec3::new(s, -1.0, -t),
        4 => Vec3::new(s, -t, 1.0),
        _ => Vec3::new(-s, -t, -1.0),
    }
    .normalize()
}

/// Inverse of [`cube_face_direction`]: the face and uv in \[0,1\]^2 that `d` goes through.
pub fn cube_face_uv(d: Vec3) -> (usize, Vec2) {
    let a = d.abs();
    let (face, s, t, m) = if a.x >= a.y && a.x >= a.z {
        if d.x > 0.0 {
            (0, -d.z, -d.y, a.x)
        } else {
            (1, d.z, -d.y, a.x)
        }
    } else if a.y >= a.z {
        if d.y > 0.0 {
            (2, d.x, d.z, a.y)
        } else {
            (3, d.x, -d.z, a.y)
        }
    } else if d.z > 0.0 {
        (4, d.x, -d.y, a.z)
    } else {
        (5, -d.x, -d.y, a.z)
    };
    (face, Vec2::new(s / m, t / m) * 0.5 + 0.5)
}

/// One mip of a cube: `size`² texels per face, row-major, rows top down.
#[derive(Clone, Debug)]
pub struct CubeMip {
    /// Face edge in texels.
    pub size: usize,
    /// Linear RGB texels of the faces +X, -X, +Y, -Y, +Z, -Z.
    pub faces: [Vec<Vec3>; 6],
}

impl CubeMip {
    /// A mip whose texel centres hold `f(direction)` (direction: unit vector through the texel centre).
    pub fn from_fn(size: usize, f: impl Fn(Vec3) -> Vec3) -> Self {
        let faces = std::array::from_fn(|face| {
            (0..size * size)
                .map(|i| {
                    let uv = (Vec2::new((i % size) as f32, (i / size) as f32) + 0.5) / size as f32;
                    f(cube_face_direction(face, uv))
                })
                .collect()
        });
        Self { size, faces }
    }

    /// Bilinear within the face `d` points into, clamped at its edges (the
    /// GPU filters across seams: the two differ on edge texels only).
    pub fn sample(&self, d: Vec3) -> Vec3 {
        let (face, uv) = cube_face_uv(d);
        let n = self.size as f32;
        let p = uv * n - 0.5;
        let p0 = p.floor();
        let f = p - p0;
        let at = |x: f32, y: f32| {
            let x = (x.max(0.0) as usize).min(self.size - 1);
            let y = (y.max(0.0) as usize).min(self.size - 1);
            self.faces[face][y * self.size + x]
        };
        let top = at(p0.x, p0.y).lerp(at(p0.x + 1.0, p0.y), f.x);
        let bottom = at(p0.x, p0.y + 1.0).lerp(at(p0.x + 1.0, p0.y + 1.0), f.x);
        top.lerp(bottom, f.y)
    }
}

/// Box-filtered chain down to 1x1 (twin of `mips.wgsl`).
pub fn box_mips(level0: CubeMip) -> Vec<CubeMip> {
    let mut chain = vec![level0];
    while let Some(parent) = chain.last().filter(|m| m.size > 1) {
        let size = parent.size / 2;
        let faces = std::array::from_fn(|face| {
            let src = &parent.faces[face];
            (0..size * size)
                .map(|i| {
                    let (x, y) = (2 * (i % size), 2 * (i / size));
                    let at = |dx: usize, dy: usize| src[(y + dy) * parent.size + x + dx];
                    (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) * 0.25
                })
                .collect()
        });
        chain.push(CubeMip { size, faces });
    }
    chain
}

/// Trilinear lookup in a chain.
pub fn sample_lod(chain: &[CubeMip], d: Vec3, lod: f32) -> Vec3 {
    let lod = lod.clamp(0.0, (chain.len() - 1) as f32);
    let m0 = lod.floor() as usize;
    let m1 = (m0 + 1).min(chain.len() - 1);
    chain[m0]
        .sample(d)
        .lerp(chain[m1].sample(d), lod - m0 as f32)
}

/// Twin of `envmap_basis`: a rotation taking +z to `n`.
fn basis(n: Vec3) -> Mat3 {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    Mat3::from_cols(
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
        n,
    )
}

fn d_ggx(n_o_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_o_h * n_o_h * (a2 - 1.0) + 1.0;
    a2 / (std::f32::consts::PI * d * d)
}

/// GGX-lobe estimate around `n` (n = v = r) with `samples` Hammersley points,
/// weighted by n.l; `lod(pdf)` picks the source level per sample.
fn ggx_lobe(
    chain: &[CubeMip],
    n: Vec3,
    alpha: f32,
    samples: u32,
    lod: impl Fn(f32) -> f32,
) -> Vec3 {
    let m = basis(n);
    let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
    for i in 0..samples {
        let h_local = importance_sample_ggx_aniso(hammersley(i, samples), alpha, alpha);
        let h = m * h_local;
        let l = 2.0 * n.dot(h) * h - n;
        let n_o_l = n.dot(l);
        if n_o_l > 0.0 {
            let pdf = d_ggx(h_local.z, alpha) * 0.25;
            sum += sample_lod(chain, l, lod(pdf)) * n_o_l;
            weight += n_o_l;
        }
    }
    sum / weight.max(1e-6)
}

/// Twin of `cs_filter`: filtered importance sampling, the lod from the
/// sample's solid angle against the source texel's.
pub fn filter_fis(chain: &[CubeMip], n: Vec3, alpha: f32, samples: u32) -> Vec3 {
    let w = chain[0].size as f32;
    let omega_p = 4.0 * std::f32::consts::PI / (6.0 * w * w);
    ggx_lobe(chain, n, alpha, samples, |pdf| {
        let omega_s = 1.0 / (samples as f32 * pdf + 1e-6);
        0.5 * (omega_s / omega_p).log2()
    })
}

/// Brute-force reference: the same n.l-weighted GGX lobe, all samples from
/// level 0 (no prefiltering), e.g. 16384 samples.
pub fn filter_reference(level0: &CubeMip, n: Vec3, alpha: f32, samples: u32) -> Vec3 {
    ggx_lobe(std::slice::from_ref(level0), n, alpha, samples, |_| 0.0)
}

/// Alpha of filtered mip `mip` of `levels` (perceptual roughness mip / (levels - 1)).
pub fn mip_alpha(mip: u32, levels: u32) -> f32 {
    let r = mip as f32 / (levels - 1) as f32;
    (r * r).max(MIN_ALPHA)
}

/// Twin of `cs_dfg`: split-sum (A, B) at `n_o_v` and perceptual roughness.
pub fn dfg(n_o_v: f32, roughness: f32, samples: u32) -> Vec2 {
    let alpha = (roughness * roughness).max(MIN_ALPHA);
    let v = Vec3::new((1.0 - n_o_v * n_o_v).max(0.0).sqrt(), 0.0, n_o_v);
    let mut ab = Vec2::ZERO;
    for i in 0..samples {
        let h = importance_sample_ggx_aniso(hammersley(i, samples), alpha, alpha);
        let v_o_h = v.dot(h);
        let l = 2.0 * v_o_h * h - v;
        if l.z > 0.0 && v_o_h > 0.0 {
            let vis = v_smith_ggx_correlated_aniso(n_o_v, l.z, v.x, 0.0, l.x, l.y, alpha, alpha);
            let g_vis = 4.0 * vis * l.z * v_o_h / h.z;
            let fc = (1.0 - v_o_h).powi(5);
            ab += Vec2::new(1.0 - fc, fc) * g_vis;
        }
    }
    ab / samples as f32
}

/// Twin of `m4_reflection_normal` (M4); `v` points to the camera.
pub fn m4_reflection_normal(n: Vec3, b: Vec3, v: Vec3, anisotropy: f32) -> Vec3 {
    let aniso_tangent = (-v).cross(b);
    let aniso_normal = aniso_tangent.cross(b);
    n.lerp(aniso_normal, anisotropy)
        .try_normalize()
        .unwrap_or(n)
}
