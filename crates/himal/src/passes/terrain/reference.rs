//! CPU twin of the terrain pass (`shaders/terrain.wgsl`): height sampling,
//! LOD ranges, the CDLOD quadtree selection and the vertex morph, with the
//! same f32 expressions in the same order as the WGSL, so a test can rebuild
//! the GPU's mesh vertex by vertex. The selection itself runs only here (the
//! pass uploads its result), and the min/max pyramid it culls with is built
//! and updated here from the coarse grid and the resident tiles.
//!
//! Notation (docs/techniques/terrain.md): `s_0` the fine sample spacing,
//! `s_l = s_0 2^l` the vertex spacing of level `l`, `size_l = 32 s_l` a
//! node's side, `r_l` the range of level `l`, `m` the morph fraction.

use glam::{Vec2, Vec3};

use super::{TerrainDesc, TerrainSettings};
use crate::passes::cull::CullView;

/// Page-table entry of a sector without a resident tile.
pub const NONE: u32 = u32::MAX;
/// Quads per side of the drawn patch (a quadrant of a node).
pub const PATCH_QUADS: u32 = 16;
/// Quads per side of a node: 2 x 2 patches.
pub const NODE_QUADS: u32 = 2 * PATCH_QUADS;
/// Vertices per side of a patch.
pub const PATCH_VERTICES: u32 = PATCH_QUADS + 1;
/// LOD levels at most (level 15 nodes are 2^20 fine samples wide).
pub const MAX_LEVELS: usize = 16;
/// Morph reaches 1 at this fraction of the range, so a vertex on the range
/// sphere is fully morphed despite rounding (`end_l = MORPH_END r_l`).
pub const MORPH_END: f32 = 0.99;

/// The world's layout derived from a [`TerrainDesc`] (validated).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// World x, z of the world's min corner.
    pub origin: Vec2,
    /// Sectors per side.
    pub sectors: u32,
    /// Side of a sector (metres).
    pub sector_size: f32,
    /// Fine samples per tile side, including the shared edge.
    pub tile_res: u32,
    /// Spacing of the coarse grid (metres).
    pub coarse_spacing: f32,
    /// `s_0 = sector_size / (tile_res - 1)`.
    pub fine_spacing: f32,
    /// Coarse samples per side: `sectors sector_size / coarse_spacing + 1`.
    pub coarse_n: u32,
    /// `c` with `coarse_spacing = s_0 2^c`: levels `l >= c` read only the
    /// coarse grid (their vertices lie on its points).
    pub coarse_level: u32,
    /// Side of the world's square, `sectors sector_size` (metres).
    pub world_size: f32,
    /// Fine tiles resident at most (the pool's slots).
    pub fine_slots: u32,
}

impl Geometry {
    /// Checks `desc`'s numbers (not its arrays' contents) and derives the layout.
    pub fn new(desc: &TerrainDesc) -> Result<Self, String> {
        let finite = desc.origin.is_finite()
            && desc.sector_size.is_finite()
            && desc.coarse_spacing.is_finite();
        if !finite || desc.sector_size <= 0.0 || desc.coarse_spacing <= 0.0 {
            return Err(format!(
                "terrain: origin {}, sector size {} and coarse spacing {} must be finite, sizes positive",
                desc.origin, desc.sector_size, desc.coarse_spacing
            ));
        }
        if desc.sectors == 0 || desc.sectors > 4096 {
            return Err(format!(
                "terrain: {} sectors per side (1..=4096)",
                desc.sectors
            ));
        }
        if !(2..=1025).contains(&desc.tile_res) {
            return Err(format!(
                "terrain: tile resolution {} (2..=1025 samples per side)",
                desc.tile_res
            ));
        }
        if desc.fine_slots == 0 {
            return Err("terrain: the fine tile pool has no slots".into());
        }
        let fine_spacing = desc.sector_size / (desc.tile_res - 1) as f32;
        // The coarse lattice must be the fine lattice thinned by a power of
        // two, and fit whole sectors, so vertices of coarse levels land on
        // coarse points and tiles' samples on both.
        let ratio = desc.coarse_spacing / fine_spacing;
        let coarse_level = ratio.log2().round();
        let per_sector = desc.sector_size / desc.coarse_spacing;
        if !(0.0..=15.0).contains(&coarse_level)
            || (ratio - coarse_level.exp2()).abs() > 1e-4 * ratio
            || (per_sector - per_sector.round()).abs() > 1e-4
            || per_sector.round() < 1.0
        {
            return Err(format!(
                "terrain: coarse spacing {} must be the fine spacing {fine_spacing} times a power of two and divide the sector size {}",
                desc.coarse_spacing, desc.sector_size
            ));
        }
        let coarse_n = desc.sectors * per_sector.round() as u32 + 1;
        Ok(Self {
            origin: desc.origin,
            sectors: desc.sectors,
            sector_size: desc.sector_size,
            tile_res: desc.tile_res,
            coarse_spacing: desc.coarse_spacing,
            fine_spacing,
            coarse_n,
            coarse_level: coarse_level as u32,
            world_size: desc.sectors as f32 * desc.sector_size,
            fine_slots: desc.fine_slots,
        })
    }

    /// `s_l = s_0 2^l`.
    pub fn spacing(&self, level: u32) -> f32 {
        self.fine_spacing * (level as f32).exp2()
    }

    /// `size_l = 32 s_l`.
    pub fn node_size(&self, level: u32) -> f32 {
        NODE_QUADS as f32 * self.spacing(level)
    }

    /// Whether level `l` reads only the coarse grid (`s_l >= coarse_spacing`).
    pub fn coarse_only(&self, level: u32) -> bool {
        level >= self.coarse_level
    }

    /// `xz` clamped to the world's square (vertices past the edge fold onto it).
    pub fn clamp(&self, xz: Vec2) -> Vec2 {
        xz.clamp(self.origin, self.origin + Vec2::splat(self.world_size))
    }

    /// Samples per fine tile.
    pub fn tile_samples(&self) -> usize {
        (self.tile_res * self.tile_res) as usize
    }
}

/// The height data on the CPU: coarse grid, page table and the tile pool
/// (a mirror of the GPU's textures, for bounds and the twin).
#[derive(Clone, Debug)]
pub struct Heights {
    /// The world's layout.
    pub geometry: Geometry,
    /// Row-major coarse heights (`coarse_n^2`, row = z; metres).
    pub coarse: Vec<f32>,
    /// `sectors^2`, row = z: the slot holding the sector's tile, or [`NONE`].
    pub pages: Vec<u32>,
    /// Per slot: the sector it holds.
    pub slots: Vec<Option<(u32, u32)>>,
    /// `fine_slots` tiles of `tile_res^2` samples, row = z.
    pub tiles: Vec<f32>,
}

/// Bilinear weights as the WGSL writes them: `a (1 - t) + b t`.
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// Lower sample index and fraction of `u` on a lattice of `n` samples
/// (clamped to the lattice), as `terrain_cell` in WGSL.
fn cell(u: Vec2, n: u32) -> (Vec2, Vec2) {
    let last = (n - 1) as f32;
    let uc = u.clamp(Vec2::ZERO, Vec2::splat(last));
    let i0 = uc.floor().min(Vec2::splat(last - 1.0));
    (i0, uc - i0)
}

impl Heights {
    /// The coarse grid of `desc` (checked), no tiles resident.
    pub fn new(desc: &TerrainDesc) -> Result<Self, String> {
        let g = Geometry::new(desc)?;
        let n = g.coarse_n as usize;
        if desc.coarse.len() != n * n {
            return Err(format!(
                "terrain: the coarse grid has {} heights; {n} x {n} expected",
                desc.coarse.len()
            ));
        }
        if let Some(i) = desc.coarse.iter().position(|h| !h.is_finite()) {
            return Err(format!("terrain: coarse height {i} is not finite"));
        }
        let sectors = (g.sectors * g.sectors) as usize;
        Ok(Self {
            geometry: g,
            coarse: desc.coarse.clone(),
            pages: vec![NONE; sectors],
            slots: vec![None; g.fine_slots as usize],
            tiles: vec![0.0; g.fine_slots as usize * g.tile_samples()],
        })
    }

    fn coarse_at(&self, i: u32, j: u32) -> f32 {
        self.coarse[(j * self.geometry.coarse_n + i) as usize]
    }

    /// Bilinear coarse height at world `xz` (`terrain_coarse_height`).
    pub fn coarse_height(&self, xz: Vec2) -> f32 {
        let g = &self.geometry;
        let u = (xz - g.origin) / g.coarse_spacing;
        let (i0, t) = cell(u, g.coarse_n);
        let (i, j) = (i0.x as u32, i0.y as u32);
        let h0 = lerp(self.coarse_at(i, j), self.coarse_at(i + 1, j), t.x);
        let h1 = lerp(self.coarse_at(i, j + 1), self.coarse_at(i + 1, j + 1), t.x);
        lerp(h0, h1, t.y)
    }

    /// The sector holding `xz` (clamped to the world).
    pub fn sector_of(&self, xz: Vec2) -> (u32, u32) {
        let g = &self.geometry;
        let s = ((xz - g.origin) / g.sector_size).floor();
        let last = (g.sectors - 1) as f32;
        let s = s.clamp(Vec2::ZERO, Vec2::splat(last));
        (s.x as u32, s.y as u32)
    }

    /// Height at `xz` (`terrain_height`): the resident tile's bilinear
    /// sample, else the coarse grid; `coarse_only` for levels that read
    /// only the coarse grid.
    pub fn height(&self, xz: Vec2, coarse_only: bool) -> f32 {
        if !coarse_only {
            let g = &self.geometry;
            let (sx, sz) = self.sector_of(xz);
            let slot = self.pages[(sz * g.sectors + sx) as usize];
            if slot != NONE {
                let corner = g.origin + Vec2::new(sx as f32, sz as f32) * g.sector_size;
                let local = (xz - corner) / g.fine_spacing;
                let (i0, t) = cell(local, g.tile_res);
                let n = g.tile_res as usize;
                let base = slot as usize * g.tile_samples();
                let at = |i: usize, j: usize| self.tiles[base + j * n + i];
                let (i, j) = (i0.x as usize, i0.y as usize);
                let h0 = lerp(at(i, j), at(i + 1, j), t.x);
                let h1 = lerp(at(i, j + 1), at(i + 1, j + 1), t.x);
                return lerp(h0, h1, t.y);
            }
        }
        self.coarse_height(xz)
    }

    /// Checks an upload: slot and sector in range, `tile_res^2` finite heights.
    pub fn check_tile(&self, slot: u32, sx: u32, sz: u32, heights: &[f32]) -> Result<(), String> {
        let g = &self.geometry;
        if slot >= g.fine_slots {
            return Err(format!(
                "terrain: slot {slot} is outside the pool of {}",
                g.fine_slots
            ));
        }
        if sx >= g.sectors || sz >= g.sectors {
            return Err(format!(
                "terrain: sector ({sx}, {sz}) is outside the {0} x {0} world",
                g.sectors
            ));
        }
        if heights.len() != g.tile_samples() {
            return Err(format!(
                "terrain: a tile has {} heights; {} x {} expected",
                heights.len(),
                g.tile_res,
                g.tile_res
            ));
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(format!("terrain: tile height {i} is not finite"));
        }
        Ok(())
    }

    /// Makes `heights` the tile of sector (`sx`, `sz`) in `slot` (checked
    /// first), evicting whatever the slot or the sector held. The coarse
    /// points inside the sector take the tile's values there, so coarse
    /// and fine levels agree exactly where they meet. Returns the coarse
    /// block written: (first i, first j, side).
    pub fn upload(
        &mut self,
        slot: u32,
        sx: u32,
        sz: u32,
        heights: &[f32],
    ) -> Result<(u32, u32, u32), String> {
        self.check_tile(slot, sx, sz, heights)?;
        let g = self.geometry;
        self.evict(slot);
        let page = (sz * g.sectors + sx) as usize;
        if self.pages[page] != NONE {
            let old = self.pages[page];
            self.evict(old);
        }
        let n = g.tile_samples();
        self.tiles[slot as usize * n..][..n].copy_from_slice(heights);
        self.pages[page] = slot;
        self.slots[slot as usize] = Some((sx, sz));
        let per = (g.sector_size / g.coarse_spacing).round() as u32;
        let step = (g.tile_res - 1) / per;
        let (i0, j0) = (sx * per, sz * per);
        for b in 0..=per {
            for a in 0..=per {
                let h = heights[(b * step * g.tile_res + a * step) as usize];
                self.coarse[((j0 + b) * g.coarse_n + i0 + a) as usize] = h;
            }
        }
        Ok((i0, j0, per + 1))
    }

    /// Frees `slot`; returns the sector it held.
    pub fn evict(&mut self, slot: u32) -> Option<(u32, u32)> {
        let held = self.slots.get_mut(slot as usize)?.take()?;
        self.pages[(held.1 * self.geometry.sectors + held.0) as usize] = NONE;
        Some(held)
    }
}

/// Min/max heights per square of the coarse lattice and its parents, from
/// the coarse grid and the resident tiles (conservative for every level).
#[derive(Clone, Debug)]
pub struct Pyramid {
    /// Level `p`: cells `coarse_spacing 2^p` wide, (side, [min, max] row = z).
    pub levels: Vec<(u32, Vec<[f32; 2]>)>,
}

impl Pyramid {
    /// The pyramid of `h`'s coarse grid and resident tiles.
    pub fn new(h: &Heights) -> Self {
        let n0 = h.geometry.coarse_n - 1;
        let mut base = vec![[0.0; 2]; (n0 * n0) as usize];
        for j in 0..n0 {
            for i in 0..n0 {
                base[(j * n0 + i) as usize] = Self::base_cell(h, i, j);
            }
        }
        let mut p = Self {
            levels: vec![(n0, base)],
        };
        while p.levels.last().is_some_and(|(n, _)| *n > 1) {
            let (n, _) = p.levels[p.levels.len() - 1];
            let m = n.div_ceil(2);
            p.levels.push((
                m,
                vec![[f32::INFINITY, f32::NEG_INFINITY]; (m * m) as usize],
            ));
            let l = p.levels.len() - 1;
            for j in 0..m {
                for i in 0..m {
                    p.refresh(l, i, j);
                }
            }
        }
        p
    }

    /// Coarse cell (i, j): its four coarse corners and, when resident, the
    /// tile's samples inside it (edges included).
    fn base_cell(h: &Heights, i: u32, j: u32) -> [f32; 2] {
        let g = &h.geometry;
        let mut b = [f32::INFINITY, f32::NEG_INFINITY];
        let mut add = |v: f32| {
            b[0] = b[0].min(v);
            b[1] = b[1].max(v);
        };
        for (a, c) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            add(h.coarse_at(i + a, j + c));
        }
        let per = (g.sector_size / g.coarse_spacing).round() as u32;
        let (sx, sz) = (i / per, j / per);
        let slot = h.pages[(sz * g.sectors + sx) as usize];
        if slot != NONE {
            let step = (g.tile_res - 1) / per;
            let (u0, v0) = ((i % per) * step, (j % per) * step);
            let base = slot as usize * g.tile_samples();
            for v in v0..=v0 + step {
                for u in u0..=u0 + step {
                    add(h.tiles[base + (v * g.tile_res + u) as usize]);
                }
            }
        }
        b
    }

    fn refresh(&mut self, l: usize, i: u32, j: u32) {
        let (n, below) = (&self.levels[l - 1].0, &self.levels[l - 1].1);
        let mut b = [f32::INFINITY, f32::NEG_INFINITY];
        for (a, c) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (x, z) = (2 * i + a, 2 * j + c);
            if x < *n && z < *n {
                let v = below[(z * n + x) as usize];
                b = [b[0].min(v[0]), b[1].max(v[1])];
            }
        }
        let m = self.levels[l].0;
        self.levels[l].1[(j * m + i) as usize] = b;
    }

    /// Recomputes the cells of sector (`sx`, `sz`) and their ancestors
    /// (after an upload or eviction): O(cells of a sector + log world).
    pub fn update_sector(&mut self, h: &Heights, sx: u32, sz: u32) {
        let g = &h.geometry;
        let per = (g.sector_size / g.coarse_spacing).round() as u32;
        let (i0, j0, n0) = (sx * per, sz * per, self.levels[0].0);
        // A tile's edge samples touch the neighbours' corner cells too: their
        // coarse corners were patched.
        let lo = (i0.saturating_sub(1), j0.saturating_sub(1));
        let hi = ((i0 + per + 1).min(n0), (j0 + per + 1).min(n0));
        for j in lo.1..hi.1 {
            for i in lo.0..hi.0 {
                self.levels[0].1[(j * n0 + i) as usize] = Self::base_cell(h, i, j);
            }
        }
        let (mut lo, mut hi) = (lo, hi);
        for l in 1..self.levels.len() {
            lo = (lo.0 / 2, lo.1 / 2);
            hi = (hi.0.div_ceil(2), hi.1.div_ceil(2));
            for j in lo.1..hi.1 {
                for i in lo.0..hi.0 {
                    self.refresh(l, i, j);
                }
            }
        }
    }

    /// [min, max] height over the square of pyramid level `p`, index (i, j);
    /// `None` when it lies outside the world. Levels above the top are the
    /// whole world (index 0 only).
    pub fn bounds(&self, p: u32, i: u32, j: u32) -> Option<[f32; 2]> {
        let top = self.levels.len() as u32 - 1;
        if p > top {
            let k = p - top;
            return (k >= 32 || (i >> k == 0 && j >> k == 0))
                .then(|| self.levels[top as usize].1[0]);
        }
        let (n, cells) = &self.levels[p as usize];
        (i < *n && j < *n).then(|| cells[(j * n + i) as usize])
    }
}

/// Per-level ranges and morph constants for one camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ranges {
    /// Levels drawn: 0 ..= levels - 1 (roots at the top level).
    pub levels: u32,
    /// `r_l = 2^l r_0`.
    pub range: [f32; MAX_LEVELS],
    /// Morph start per level (`r_l - m (r_l - r_{l-1})`) ...
    pub morph_start: [f32; MAX_LEVELS],
    /// ... and `1 / (end_l - start_l)`, `end_l = MORPH_END r_l` (0 at the
    /// top level: no coarser level to morph to).
    pub morph_scale: [f32; MAX_LEVELS],
    /// Continuous morph (off: vertices snap, [`TerrainSettings::morph`]).
    pub morph: bool,
}

impl Ranges {
    /// `r_0 = max(s_0 f / t 2^bias, sqrt(3) size_0 / (1 - m))` (f the focal
    /// length in pixels, t the target on-screen vertex spacing); levels
    /// added until `r_top >= view_distance`.
    ///
    /// The floor keeps the morph area of level `l` outside the whole of any
    /// level `l - 1` node (diagonal at most `sqrt(3) size_{l-1}` while a
    /// node's relief is at most its side), which is what makes the level
    /// boundaries crack-free.
    pub fn new(g: &Geometry, s: &TerrainSettings, focal_px: f32) -> Self {
        let m = s.morph_fraction.clamp(0.05, 0.9);
        let target = if s.target_px.is_finite() && s.target_px > 0.0 {
            s.target_px
        } else {
            TerrainSettings::default().target_px
        };
        let bias = if s.lod_bias.is_finite() {
            s.lod_bias.clamp(-8.0, 8.0)
        } else {
            0.0
        };
        let focal = if focal_px.is_finite() && focal_px > 0.0 {
            focal_px
        } else {
            1.0
        };
        let r_pixels = g.fine_spacing * focal / target * bias.exp2();
        let r_floor = 3f32.sqrt() * g.node_size(0) / (1.0 - m);
        let r0 = r_pixels.max(r_floor);
        let view = if s.view_distance.is_finite() {
            s.view_distance.max(r0)
        } else {
            r0
        };
        let mut levels = 1;
        while levels < MAX_LEVELS as u32 && r0 * ((levels - 1) as f32).exp2() < view {
            levels += 1;
        }
        let mut r = Self {
            levels,
            range: [0.0; MAX_LEVELS],
            morph_start: [0.0; MAX_LEVELS],
            morph_scale: [0.0; MAX_LEVELS],
            morph: s.morph,
        };
        for l in 0..levels as usize {
            r.range[l] = r0 * (l as f32).exp2();
            let below = if l == 0 { 0.0 } else { r.range[l - 1] };
            let start = r.range[l] - m * (r.range[l] - below);
            if l + 1 < levels as usize {
                r.morph_start[l] = start;
                r.morph_scale[l] = 1.0 / (MORPH_END * r.range[l] - start);
            }
        }
        r
    }

    /// The farthest distance drawn.
    pub fn view_distance(&self) -> f32 {
        self.range[self.levels as usize - 1]
    }

    /// Fine tiles matter only where level `c - 1` is not fully morphed:
    /// within `MORPH_END r_{c-1}` (vertices farther lie on coarse points).
    pub fn fine_radius(&self, g: &Geometry) -> f32 {
        match g.coarse_level {
            0 => 0.0,
            c => MORPH_END * self.range[(c as usize - 1).min(self.levels as usize - 1)],
        }
    }
}

/// One drawn patch: a quadrant of a node at `level`, `origin` its min
/// corner (twin of the instance in `terrain.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Patch {
    /// World x, z of the patch's min corner.
    pub origin: [f32; 2],
    /// LOD level of the patch's node.
    pub level: u32,
    /// Padding to 16 bytes.
    pub _pad: u32,
}

/// What one selection did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SelectStats {
    /// Nodes whose bounds were tested.
    pub visited: u32,
    /// Patches per level.
    pub per_level: [u32; MAX_LEVELS],
    /// Patches dropped because the list was full.
    pub dropped: u32,
}

impl SelectStats {
    /// Patches selected over all levels (dropped ones excluded).
    pub fn patches(&self) -> u32 {
        self.per_level.iter().sum()
    }
}

/// An axis-aligned box.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    min: Vec3,
    max: Vec3,
}

impl Bounds {
    fn distance_sq(&self, p: Vec3) -> f32 {
        let d = (self.min - p).max(p - self.max).max(Vec3::ZERO);
        d.length_squared()
    }

    /// Wholly behind one plane (`n . p + w < 0`), as `passes/cull`.
    fn outside(&self, view: &CullView) -> bool {
        let c = (self.min + self.max) * 0.5;
        let e = (self.max - self.min) * 0.5;
        view.planes.iter().any(|p| {
            let n = Vec3::from_slice(&p[..3]);
            n.dot(c) + p[3] + n.abs().dot(e) < 0.0
        })
    }
}

/// The quadtree selection (Strugar 2009, `LODSelect`) for one view.
pub struct Selector<'s> {
    /// The world's layout.
    pub geometry: &'s Geometry,
    /// Height bounds of the nodes.
    pub pyramid: &'s Pyramid,
    /// The view's per-level ranges.
    pub ranges: &'s Ranges,
    /// The LOD eye (the camera, also for shadow views, so they match).
    pub eye: Vec3,
    /// The view's culling volume (the camera's or a shadow view's).
    pub frustum: &'s CullView,
    /// Patches `out` may hold; the rest are counted in [`SelectStats::dropped`].
    pub capacity: usize,
}

impl Selector<'_> {
    /// Appends the patches to draw to `out`: O(nodes near the ranges'
    /// spheres and inside the frustum), never O(world).
    pub fn select(&self, out: &mut Vec<Patch>) -> SelectStats {
        let mut stats = SelectStats::default();
        let top = self.ranges.levels - 1;
        let roots = (self.geometry.world_size / self.geometry.node_size(top)).ceil() as u32;
        for j in 0..roots {
            for i in 0..roots {
                self.node(top, i, j, out, &mut stats);
            }
        }
        stats
    }

    /// Bounds of node (i, j) at `level` (or, with `quadrant`, of its patch).
    fn bounds(&self, level: u32, i: u32, j: u32) -> Option<Bounds> {
        let g = self.geometry;
        let size = g.node_size(level);
        // Node side = coarse_spacing 2^(level + 5 - c).
        let p = level as i32 + (NODE_QUADS.trailing_zeros() as i32) - g.coarse_level as i32;
        let y = if p >= 0 {
            self.pyramid.bounds(p as u32, i, j)?
        } else {
            // Nodes smaller than a coarse cell take the cell's bounds.
            self.pyramid.bounds(0, i >> (-p), j >> (-p))?
        };
        let lo = g.origin + Vec2::new(i as f32, j as f32) * size;
        let hi = g.clamp(lo + Vec2::splat(size));
        Some(Bounds {
            min: Vec3::new(lo.x, y[0], lo.y),
            max: Vec3::new(hi.x, y[1], hi.y),
        })
    }

    /// `LODSelect`: false when the node is beyond its level's range (the
    /// parent then draws its area); true when handled (drawn, culled or
    /// outside the world).
    fn node(
        &self,
        level: u32,
        i: u32,
        j: u32,
        out: &mut Vec<Patch>,
        stats: &mut SelectStats,
    ) -> bool {
        stats.visited += 1;
        let Some(b) = self.bounds(level, i, j) else {
            return true;
        };
        let r = self.ranges.range[level as usize];
        if b.distance_sq(self.eye) > r * r {
            return false;
        }
        if b.outside(self.frustum) {
            return true;
        }
        let finer = level.checked_sub(1);
        let r_finer = finer.map(|f| self.ranges.range[f as usize]);
        match (finer, r_finer) {
            (Some(f), Some(rf)) if b.distance_sq(self.eye) <= rf * rf => {
                for q in 0..4 {
                    let (ci, cj) = (2 * i + (q & 1), 2 * j + (q >> 1));
                    if !self.node(f, ci, cj, out, stats) {
                        self.patch(level, ci, cj, out, stats);
                    }
                }
            }
            _ => {
                for q in 0..4 {
                    self.patch(level, 2 * i + (q & 1), 2 * j + (q >> 1), out, stats);
                }
            }
        }
        true
    }

    /// Adds the patch of a `level` node covering the area of child (ci, cj)
    /// at level - 1, unless outside the world or the frustum.
    fn patch(&self, level: u32, ci: u32, cj: u32, out: &mut Vec<Patch>, stats: &mut SelectStats) {
        let g = self.geometry;
        let half = g.node_size(level) * 0.5;
        // The patch is a level - 1 node's square: its pyramid cell is one
        // level down (a level-0 patch takes half its node's p).
        let b = if level > 0 {
            self.bounds(level - 1, ci, cj)
        } else {
            self.bounds(0, ci / 2, cj / 2).map(|mut b| {
                let lo = g.origin + Vec2::new(ci as f32, cj as f32) * half;
                let hi = g.clamp(lo + Vec2::splat(half));
                (b.min.x, b.min.z, b.max.x, b.max.z) = (lo.x, lo.y, hi.x, hi.y);
                b
            })
        };
        let Some(b) = b else { return };
        if b.min.x >= b.max.x || b.min.z >= b.max.z || b.outside(self.frustum) {
            return;
        }
        if out.len() >= self.capacity {
            stats.dropped += 1;
            return;
        }
        let origin = g.origin + Vec2::new(ci as f32, cj as f32) * half;
        out.push(Patch {
            origin: origin.to_array(),
            level,
            _pad: 0,
        });
        stats.per_level[level as usize] += 1;
    }
}

/// The morph factor of a vertex at distance `d` (`terrain_morph_k`):
/// `k = clamp((d - start_l) / (end_l - start_l), 0, 1)`; without morphing
/// it snaps at 1/2 (the level switches at once, halfway through the area).
pub fn morph_k(r: &Ranges, level: u32, d: f32) -> f32 {
    let l = level as usize;
    let k = ((d - r.morph_start[l]) * r.morph_scale[l]).clamp(0.0, 1.0);
    if r.morph {
        k
    } else if k >= 0.5 {
        1.0
    } else {
        0.0
    }
}

/// World position of vertex `grid` (0..=16 each) of `patch`
/// (`terrain_vertex`): odd grid lines slide onto the even ones by `k`
/// (Strugar's `morphVertex`), then the height is sampled there.
pub fn vertex(h: &Heights, r: &Ranges, eye: Vec3, patch: &Patch, grid: [u32; 2]) -> Vec3 {
    let g = &h.geometry;
    let s = g.spacing(patch.level);
    let coarse_only = g.coarse_only(patch.level);
    let origin = Vec2::from_array(patch.origin);
    let gf = Vec2::new(grid[0] as f32, grid[1] as f32);
    let xz0 = g.clamp(origin + gf * s);
    let h0 = h.height(xz0, coarse_only);
    let d = (eye - Vec3::new(xz0.x, h0, xz0.y)).length();
    let k = morph_k(r, patch.level, d);
    let odd = gf - 2.0 * (gf * 0.5).floor();
    let xz = g.clamp(origin + (gf - odd * k) * s);
    Vec3::new(xz.x, h.height(xz, coarse_only), xz.y)
}

/// The patch's triangles as vertex index triples into its
/// `PATCH_VERTICES^2` grid (row = z), one diagonal direction throughout so
/// a fully morphed 2 x 2 block is exactly the parent's quad.
pub fn patch_indices() -> Vec<u16> {
    let n = PATCH_VERTICES as u16;
    let mut out = Vec::with_capacity((PATCH_QUADS * PATCH_QUADS * 6) as usize);
    for j in 0..PATCH_QUADS as u16 {
        for i in 0..PATCH_QUADS as u16 {
            let a = j * n + i;
            let (b, c, d) = (a + 1, a + n, a + n + 1);
            // Counter-clockwise seen from +y (front faces).
            out.extend_from_slice(&[a, d, b, a, c, d]);
        }
    }
    out
}
