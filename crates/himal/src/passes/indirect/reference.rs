//! CPU twins of the per-frame probe work: the lighting SH, radiance
//! transfer, injection into the camera-centred clip map and its sampling
//! in deferred lighting (docs/techniques/L5.md "Per frame").

use glam::{IVec2, Vec2, Vec3};

use super::cell::{CELL_PROBES, Cell, CellKey, MIPS, Transfer};
use crate::math::sh::{SH4_COUNT, SH9_COSINE_BAND_FACTORS, Sh9Rgb, sh4_basis, sh4_irradiance};

/// Second-order SH, rgb per coefficient.
pub type Sh4 = [Vec3; SH4_COUNT];

/// Clip-map texels per axis per cascade.
pub const CLIP_RES: i32 = 32;
/// Cascades (one per cell mip).
pub const CASCADES: usize = MIPS;
/// Sampling stays this many texels inside a cascade's edge (bilinear taps
/// and the blend band need a margin), measured against the cells the pool
/// guarantees (1.5 cells = 12 texels of each side of the camera).
const GUARANTEED_TEXELS: f32 = 12.0;
/// Width of the band (texels) over which cascade C fades into C + 1.
const BLEND_TEXELS: f32 = 3.0;

/// The lighting the probes transfer: sky radiance above the horizon (no
/// ground: the probes' geometry is the ground) plus the sun as a
/// directional light, in second-order SH.
pub fn lighting_sh(sky_radiance: &Sh9Rgb, sun_direction: Vec3, sun_illuminance: Vec3) -> Sh4 {
    let mut s = [
        sky_radiance.c[0],
        sky_radiance.c[1],
        sky_radiance.c[2],
        sky_radiance.c[3],
    ];
    if sun_direction.y > 0.0 {
        for (c, y) in s.iter_mut().zip(sh4_basis(sun_direction)) {
            *c += sun_illuminance * y;
        }
    }
    s
}

/// The flat ground bounce as SH2 radiance, what a clip-map texel with no
/// baked cell holds (so unbaked ground keeps the bounce it had without
/// L5): bands 0 and 1 of its irradiance SH over the cosine lobe's factors
/// (A0 = pi, A1 = 2 pi / 3). Band 2 of a uniformly lit plane below the
/// horizon is zero, so nothing is lost but the sky SH's own truncation.
pub fn ground_sh2(ground: &Sh9Rgb) -> Sh4 {
    let [a0, a1, _] = SH9_COSINE_BAND_FACTORS;
    [
        ground.c[0] / a0,
        ground.c[1] / a1,
        ground.c[2] / a1,
        ground.c[3] / a1,
    ]
}

/// The sky's radiance above the horizon in SH (zero below), from a radiance function.
pub fn sky_radiance_sh(radiance: impl Fn(Vec3) -> Vec3) -> Sh9Rgb {
    Sh9Rgb::project(|d| if d.y > 0.0 { radiance(d) } else { Vec3::ZERO }, 64)
}

/// `probes.transfer`: the probe's bounced radiance SH, L_i = sum_j T[i][j] S_j per channel.
pub fn transfer(t: &Transfer, lighting: &Sh4) -> Sh4 {
    let mut out = [Vec3::ZERO; SH4_COUNT];
    for c in 0..3 {
        for (i, o) in out.iter_mut().enumerate() {
            o[c] = (0..4)
                .map(|j| t.m[c * 16 + i * 4 + j] * lighting[j][c])
                .sum();
        }
    }
    out
}

/// A cell's SH probes for this frame's lighting.
pub fn transfer_cell(cell: &Cell, lighting: &Sh4) -> Vec<Sh4> {
    cell.probes.iter().map(|t| transfer(t, lighting)).collect()
}

/// The clip map: `CASCADES` layers of 32 x 32 SH probes around the camera.
/// Cascade c's texels are mip c's probes (8 m x 2^c apart), so injection is
/// a copy and the GPU's bilinear filter interpolates between probes.
#[derive(Clone, Debug)]
pub struct ClipMap {
    /// Grid origin (sector (0, 0)'s min corner).
    pub origin: Vec2,
    /// Per cascade, the global probe index of texel (0, 0).
    pub base: [IVec2; CASCADES],
    /// `texels[c][(v * 32 + u)]`: the probe, or the fallback where no cell
    /// was resident (`None` only where the fallback is).
    pub texels: Vec<Vec<Option<Sh4>>>,
}

/// Spacing of cascade `c`'s texels (m).
pub fn texel_size(c: usize) -> f32 {
    CellKey {
        mip: c as u8,
        x: 0,
        z: 0,
    }
    .spacing()
}

impl ClipMap {
    /// Global probe index of texel (0, 0) of each cascade, camera-centred.
    pub fn bases(origin: Vec2, camera: Vec2) -> [IVec2; CASCADES] {
        std::array::from_fn(|c| {
            ((camera - origin) / texel_size(c)).floor().as_ivec2() - CLIP_RES / 2
        })
    }

    /// `probes.inject` through the combined page table `table` (one byte
    /// per sector, [`super::pool::CellPool::combined_table`]): the finest
    /// resident cell over the texel centre's sector and its probe nearest
    /// the centre; `probes(slot)` gives that slot's SH probes. Texels
    /// without a cell take `fallback` ([`ground_sh2`] in the frame).
    pub fn inject<'a>(
        origin: Vec2,
        camera: Vec2,
        table: &[u8],
        probes: impl Fn(u32) -> Option<&'a [Sh4]>,
        fallback: Option<Sh4>,
    ) -> ClipMap {
        let base = Self::bases(origin, camera);
        let n = CELL_PROBES as i32;
        let sectors = super::cell::GRID_SECTORS;
        let texels = (0..CASCADES)
            .map(|c| {
                (0..CLIP_RES * CLIP_RES)
                    .map(|t| {
                        let g = base[c] + IVec2::new(t % CLIP_RES, t / CLIP_RES);
                        let x = (g.as_vec2() + 0.5) * texel_size(c);
                        let s = (x / texel_size(0) / n as f32).floor().as_ivec2();
                        if s.min_element() < 0 || s.max_element() >= sectors {
                            return fallback;
                        }
                        let slot = table[(s.y * sectors + s.x) as usize];
                        if slot == super::pool::NO_CELL {
                            return fallback;
                        }
                        // Slots are per mip, 16 each: the slot names the cell's mip.
                        let m = slot as usize / super::pool::CELLS_PER_MIP;
                        let local = (x / texel_size(m))
                            .floor()
                            .as_ivec2()
                            .rem_euclid(IVec2::splat(n));
                        probes(slot as u32).map(|p| p[(local.y * n + local.x) as usize])
                    })
                    .collect()
            })
            .collect();
        ClipMap {
            origin,
            base,
            texels,
        }
    }

    /// [`ClipMap::inject`] for the cells resident in `pool`, their SH
    /// probes from `probes(key)`, `fallback` elsewhere.
    pub fn inject_resident<'a>(
        origin: Vec2,
        camera: Vec2,
        pool: &super::pool::CellPool,
        probes: impl Fn(CellKey) -> Option<&'a [Sh4]>,
        fallback: Option<Sh4>,
    ) -> ClipMap {
        let table = pool.combined_table();
        Self::inject(
            origin,
            camera,
            &table,
            |slot| pool.cell(slot).and_then(&probes),
            fallback,
        )
    }

    fn texel(&self, c: usize, t: IVec2) -> Option<Sh4> {
        let t = t.clamp(IVec2::ZERO, IVec2::splat(CLIP_RES - 1));
        self.texels[c][(t.y * CLIP_RES + t.x) as usize]
    }

    /// Bilinear SH at `p` (x, z) in cascade `c` (texel centres at probes).
    pub fn sample_cascade(&self, c: usize, p: Vec2) -> Option<Sh4> {
        let f = (p - self.origin) / texel_size(c) - 0.5 - self.base[c].as_vec2();
        let i = f.floor();
        let w = f - i;
        let i = i.as_ivec2();
        let mut out = [Vec3::ZERO; SH4_COUNT];
        for (d, wt) in [
            (IVec2::new(0, 0), (1.0 - w.x) * (1.0 - w.y)),
            (IVec2::new(1, 0), w.x * (1.0 - w.y)),
            (IVec2::new(0, 1), (1.0 - w.x) * w.y),
            (IVec2::new(1, 1), w.x * w.y),
        ] {
            let s = self.texel(c, i + d)?;
            for (o, v) in out.iter_mut().zip(s) {
                *o += v * wt;
            }
        }
        Some(out)
    }

    /// The cascade `p` falls in and the weight of the next one: C is the
    /// finest whose guaranteed square holds `p`; within the last
    /// `BLEND_TEXELS` of it, C + 1 fades in. `None` beyond every cascade.
    pub fn cascade(camera: Vec2, p: Vec2) -> Option<(usize, f32)> {
        let d = (p - camera).abs().max_element();
        (0..CASCADES).find_map(|c| {
            let edge = (GUARANTEED_TEXELS - 1.0) * texel_size(c);
            (d < edge).then(|| {
                let band = BLEND_TEXELS * texel_size(c);
                let w = ((d - (edge - band)) / band).clamp(0.0, 1.0);
                (c, if c + 1 < CASCADES { w } else { 0.0 })
            })
        })
    }

    /// Indirect irradiance at `p` (x, y, z) for normal `n`: cascades C and
    /// C + 1 blended by distance, then the SH irradiance for `n`.
    pub fn irradiance(&self, camera: Vec2, p: Vec3, n: Vec3) -> Option<Vec3> {
        let xz = Vec2::new(p.x, p.z);
        let (c, w) = Self::cascade(camera, xz)?;
        let a = self.sample_cascade(c, xz)?;
        let sh = if w > 0.0 {
            let b = self.sample_cascade(c + 1, xz)?;
            std::array::from_fn(|i| a[i] * (1.0 - w) + b[i] * w)
        } else {
            a
        };
        Some(sh4_irradiance(&sh, n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::indirect::cell::PROBES_PER_CELL;

    const O: Vec2 = Vec2::new(-5120.0, -5120.0);

    #[test]
    fn transfer_is_the_matrix_product_per_channel() {
        let mut t = Transfer::default();
        // Red: identity; green: coefficient 0 from 2; blue: nothing.
        for i in 0..4 {
            t.m[i * 4 + i] = 1.0;
        }
        t.m[16] = 2.0;
        t.m[16 + 2] = 3.0;
        let l = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.0, 5.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
        ];
        let out = transfer(&t, &l);
        assert_eq!(out[0], Vec3::new(1.0, 2.0 + 15.0, 0.0));
        assert_eq!(out[3], Vec3::new(4.0, 0.0, 0.0));
    }

    #[test]
    fn the_clip_map_reproduces_a_probe_at_its_position_and_interpolates_between() {
        // One resident mip-0 cell whose probe k has band-0 value k.
        let key = CellKey {
            mip: 0,
            x: 80,
            z: 80,
        };
        let sh: Vec<Sh4> = (0..PROBES_PER_CELL)
            .map(|k| [Vec3::splat(k as f32), Vec3::ZERO, Vec3::ZERO, Vec3::ZERO])
            .collect();
        let camera = key.corner(O) + 32.0;
        let mut pool = crate::passes::indirect::pool::CellPool::default();
        pool.admit(key, O, camera);
        let ground = [Vec3::splat(0.5), Vec3::ZERO, Vec3::splat(-0.25), Vec3::ZERO];
        let map = ClipMap::inject_resident(
            O,
            camera,
            &pool,
            |k| (k == key).then_some(sh.as_slice()),
            Some(ground),
        );
        let at = |i: usize, j: usize| Cell::probe_xz(key, O, i, j);
        let s = map.sample_cascade(0, at(3, 4)).unwrap();
        assert!((s[0].x - 35.0).abs() < 1e-4, "{}", s[0].x);
        let mid = (at(3, 4) + at(4, 5)) * 0.5;
        let s = map.sample_cascade(0, mid).unwrap();
        assert!((s[0].x - (35.0 + 36.0 + 43.0 + 44.0) / 4.0).abs() < 1e-4);
        // Outside the resident cell the texels hold the flat ground's SH2.
        assert_eq!(map.sample_cascade(0, key.corner(O) - 20.0), Some(ground));
    }

    #[test]
    fn the_ground_fallback_gives_the_flat_ground_bounce() {
        // A plane of albedo 0.3 under 10 klux: radiance 0.3 * 10 / pi below the horizon.
        let l = 0.3 * 10.0 / std::f32::consts::PI;
        let radiance = Sh9Rgb::project(|d| Vec3::splat(if d.y < 0.0 { l } else { 0.0 }), 64);
        let ground = radiance.radiance_to_irradiance_coeffs();
        let sh2 = ground_sh2(&ground);
        for n in [
            Vec3::Y,
            -Vec3::Y,
            Vec3::X,
            Vec3::new(0.6, 0.8, 0.0),
            Vec3::new(0.0, -0.6, 0.8),
        ] {
            let exact = l * std::f32::consts::PI * (1.0 - n.y) * 0.5;
            let got = sh4_irradiance(&sh2, n).x;
            // Measured: 0.020 of pi * l at worst (the SH9 projection's ringing).
            assert!(
                (got - exact).abs() < 0.03 * l * std::f32::consts::PI,
                "{n}: {got} vs {exact}"
            );
        }
    }

    #[test]
    fn cascades_grow_outward_and_blend_near_their_edge() {
        let cam = Vec2::new(100.0, -40.0);
        assert_eq!(ClipMap::cascade(cam, cam), Some((0, 0.0)));
        let (c, w) = ClipMap::cascade(cam, cam + Vec2::new(85.0, 0.0)).unwrap();
        assert_eq!(c, 0);
        assert!(w > 0.5 && w < 1.0, "{w}");
        assert_eq!(
            ClipMap::cascade(cam, cam + Vec2::new(100.0, 0.0))
                .unwrap()
                .0,
            1
        );
        assert_eq!(
            ClipMap::cascade(cam, cam + Vec2::new(1400.0, 0.0))
                .unwrap()
                .0,
            4
        );
        assert!(ClipMap::cascade(cam, cam + Vec2::new(1500.0, 0.0)).is_none());
    }
}
