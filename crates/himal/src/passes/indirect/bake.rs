//! The offline bake of radiance-transfer probes (L5): ray casting the
//! scene's triangles on the CPU. One bounce: the probe sees surfaces lit
//! by the sky and the sun (both given as second-order SH at run time),
//! with their visibility, and nothing of the light those surfaces receive
//! from other surfaces. docs/techniques/L5.md "Bake".
//!
//! Transfer of probe p, channel c (N primary rays w_k, hit x_k with albedo
//! rho and normal n_k; M cosine-distributed rays w'_m about n_k):
//!   t_j(x)     = pi / M * sum_m V(x, w'_m) Y_j(w'_m)
//!   T_c[i][j]  = 4 pi / N * sum_k Y_i(w_k) rho_c(x_k) / pi * t_j(x_k)
//! so that the probe's bounced radiance is L_i = sum_j T[i][j] S_j for
//! the lighting SH S (sky + sun).

use glam::{Vec2, Vec3};

use super::cell::{CELL_PROBES, Cell, CellKey, PROBES_PER_CELL, Transfer};
use crate::math::sampling::{Pcg32, cosine_sample_hemisphere, hammersley, uniform_sample_sphere};
use crate::math::sh::sh4_basis;
use crate::scene::raycast::{RayScene, frame_about};

/// Bake quality and probe placement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeSettings {
    /// Primary rays per probe (uniform over the sphere).
    pub rays: u32,
    /// Sky-visibility rays per primary hit (cosine over its hemisphere).
    pub visibility_rays: u32,
    /// Probe height above the terrain (m).
    pub probe_height: f32,
    /// Worker threads (0: the machine's cores).
    pub threads: usize,
}

impl Default for BakeSettings {
    /// 256 x 64 rays: the transfer's Monte Carlo noise is below 3 % of its
    /// band-0 term on the test scenes. Probes 3 m up: of 2, 2.5, 3 and
    /// 3.5 m, the least mean error against the path tracer on open ground
    /// (docs/techniques/L5.md "Probe height").
    fn default() -> Self {
        BakeSettings {
            rays: 256,
            visibility_rays: 64,
            probe_height: 3.0,
            threads: 0,
        }
    }
}

/// Offset along the normal before tracing from a surface (m).
const SURFACE_BIAS: f32 = 2e-3;

/// The terrain height under (x, z): the first ground triangle from above,
/// else the first triangle of any kind, else zero.
pub fn ground_height(scene: &RayScene, xz: Vec2) -> f32 {
    let top = scene.bounds().max.y + 1.0;
    let from = Vec3::new(xz.x, top, xz.y);
    let reach = top - scene.bounds().min.y + 1.0;
    scene
        .trace_ground(from, -Vec3::Y, reach)
        .or_else(|| scene.trace(from, -Vec3::Y, 0.0, reach))
        .map_or(0.0, |h| top - h.t)
}

/// A probe whose rays meet this fraction of back faces stands inside a
/// closed object (a house on its grid point): its transfer is taken from
/// its neighbours instead.
pub const INSIDE_FRACTION: f32 = 0.2;

/// One probe's transfer at `p` and the fraction of its rays that hit a
/// back face; `seed` decorrelates the sample patterns of neighbours.
pub fn bake_probe(
    scene: &RayScene,
    p: Vec3,
    settings: &BakeSettings,
    seed: u64,
) -> (Transfer, f32) {
    let mut rng = Pcg32::new(seed);
    let shift = rng.next_vec2();
    let n = settings.rays.max(1);
    let m = settings.visibility_rays.max(1);
    let mut t = Transfer::default();
    let mut back = 0u32;
    for k in 0..n {
        let u = (hammersley(k, n) + shift).fract();
        let w = uniform_sample_sphere(u);
        let Some(hit) = scene.trace(p, w, 0.0, f32::INFINITY) else {
            continue;
        };
        if hit.backface {
            back += 1;
            continue;
        }
        let x = p + w * hit.t + hit.normal * SURFACE_BIAS;
        let frame = frame_about(hit.normal);
        let spin = rng.next_vec2();
        let mut t_j = [0.0f32; 4];
        for s in 0..m {
            let d = frame * cosine_sample_hemisphere((hammersley(s, m) + spin).fract());
            if scene.unoccluded(x, d, 0.0, f32::INFINITY) {
                for (tj, y) in t_j.iter_mut().zip(sh4_basis(d)) {
                    *tj += y;
                }
            }
        }
        let y_i = sh4_basis(w);
        // 4 pi / N (sphere estimator) * rho / pi * pi / M (cosine estimator).
        let scale = 4.0 * std::f32::consts::PI / (n as f32 * m as f32);
        for (c, rows) in t.m.chunks_exact_mut(16).enumerate() {
            let rho = hit.albedo[c];
            for (row, yi) in rows.chunks_exact_mut(4).zip(y_i) {
                for (v, tj) in row.iter_mut().zip(t_j) {
                    *v += scale * rho * yi * tj;
                }
            }
        }
    }
    (t, back as f32 / n as f32)
}

/// A mip-0 cell: probes at their grid positions, `probe_height` above the
/// ground, baked on `settings.threads` threads (same bytes for any count).
pub fn bake_cell(scene: &RayScene, key: CellKey, origin: Vec2, settings: &BakeSettings) -> Cell {
    debug_assert_eq!(key.mip, 0, "mips come from Cell::downsample");
    let positions: Vec<Vec3> = (0..PROBES_PER_CELL)
        .map(|k| {
            let xz = Cell::probe_xz(key, origin, k % CELL_PROBES, k / CELL_PROBES);
            Vec3::new(xz.x, ground_height(scene, xz) + settings.probe_height, xz.y)
        })
        .collect();
    let seed_of = |k: usize| {
        let g = |v: i32| v as u32 as u64;
        (g(key.x) << 40) ^ (g(key.z) << 16) ^ k as u64
    };
    let threads = crate::scene::world::worker_count(settings.threads).max(1);
    let mut probes = vec![(Transfer::default(), 0.0); PROBES_PER_CELL];
    let chunk = PROBES_PER_CELL.div_ceil(threads);
    std::thread::scope(|s| {
        for (n, out) in probes.chunks_mut(chunk).enumerate() {
            let positions = &positions;
            s.spawn(move || {
                for (i, t) in out.iter_mut().enumerate() {
                    let k = n * chunk + i;
                    *t = bake_probe(scene, positions[k], settings, seed_of(k));
                }
            });
        }
    });
    let mut heights = [0.0; PROBES_PER_CELL];
    for (h, p) in heights.iter_mut().zip(&positions) {
        *h = p.y;
    }
    let inside: Vec<bool> = probes.iter().map(|p| p.1 > INSIDE_FRACTION).collect();
    Cell {
        key,
        heights,
        probes: fill_inside(probes.into_iter().map(|p| p.0).collect(), &inside),
    }
}

/// Probes inside objects take the mean of their nearest outside neighbours
/// in the cell (ring by ring); a cell all inside keeps zero light.
fn fill_inside(mut probes: Vec<Transfer>, inside: &[bool]) -> Vec<Transfer> {
    let n = CELL_PROBES as i32;
    let source = probes.clone();
    for k in (0..PROBES_PER_CELL).filter(|&k| inside[k]) {
        let (i, j) = ((k % CELL_PROBES) as i32, (k / CELL_PROBES) as i32);
        for ring in 1..n {
            let mut sum = Transfer::default();
            let mut count = 0.0;
            for dj in -ring..=ring {
                for di in -ring..=ring {
                    let (x, z) = (i + di, j + dj);
                    if di.abs().max(dj.abs()) != ring
                        || !(0..n).contains(&x)
                        || !(0..n).contains(&z)
                    {
                        continue;
                    }
                    let q = (z * n + x) as usize;
                    if !inside[q] {
                        sum.m.iter_mut().zip(source[q].m).for_each(|(a, b)| *a += b);
                        count += 1.0;
                    }
                }
            }
            if count > 0.0 {
                sum.m.iter_mut().for_each(|a| *a /= count);
                probes[k] = sum;
                break;
            }
        }
    }
    probes
}
