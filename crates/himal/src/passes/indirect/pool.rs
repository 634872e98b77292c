//! The GPU's fixed pool of probe cells (16 per mip, 80 in all), which cells
//! the camera wants, and the page tables that find a sector's cell
//! (docs/techniques/L5.md "Streaming").

use glam::Vec2;

use super::cell::{CellKey, GRID_SECTORS, MIPS};

/// Cells per mip in the pool (the talk's 16).
pub const CELLS_PER_MIP: usize = 16;
/// Slots in all.
pub const POOL_CELLS: usize = CELLS_PER_MIP * MIPS;
/// Page-table entry of a sector with no resident cell.
pub const NO_CELL: u8 = u8::MAX;

/// Half-width of the square around the camera whose cells are wanted, in
/// cells of the mip: 1.5 cells always fit in 4 x 4 = 16 cells, wherever
/// the camera is within its cell.
pub const WANTED_HALF_CELLS: f32 = 1.5;

/// What [`CellPool::admit`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Admit {
    /// Already resident in this slot.
    Resident(u32),
    /// Took a free slot.
    Stored(u32),
    /// Took the slot of a more distant cell, which is no longer resident.
    Evicted {
        /// The slot now holding the new cell.
        slot: u32,
        /// The cell that lost it.
        evicted: CellKey,
    },
    /// The pool is full of cells nearer than this one.
    Refused,
}

/// Distance (x, z) from `p` to a cell's square; 0 inside.
pub fn cell_distance(key: CellKey, origin: Vec2, p: Vec2) -> f32 {
    let lo = key.corner(origin);
    let hi = lo + Vec2::splat(key.size());
    (lo - p).max(p - hi).max(Vec2::ZERO).length()
}

/// Fixed slots per mip; slot `mip * 16 + i`.
#[derive(Clone, Debug)]
pub struct CellPool {
    slots: Vec<Option<CellKey>>,
}

impl Default for CellPool {
    fn default() -> Self {
        CellPool {
            slots: vec![None; POOL_CELLS],
        }
    }
}

impl CellPool {
    /// Slots in use.
    pub fn used(&self) -> usize {
        self.slots.iter().flatten().count()
    }

    /// The cell in `slot`.
    pub fn cell(&self, slot: u32) -> Option<CellKey> {
        self.slots.get(slot as usize).copied().flatten()
    }

    /// The slot holding `key`.
    pub fn slot_of(&self, key: CellKey) -> Option<u32> {
        let base = key.mip as usize * CELLS_PER_MIP;
        (base..base + CELLS_PER_MIP)
            .find(|&s| self.slots[s] == Some(key))
            .map(|s| s as u32)
    }

    /// Make `key` resident: a free slot of its mip, else the slot of the
    /// most distant resident cell of that mip if it is farther from `camera`
    /// than `key` (the talk: "if no cell is available, discard a more
    /// distant cell").
    pub fn admit(&mut self, key: CellKey, origin: Vec2, camera: Vec2) -> Admit {
        if let Some(s) = self.slot_of(key) {
            return Admit::Resident(s);
        }
        let base = key.mip as usize * CELLS_PER_MIP;
        let range = base..base + CELLS_PER_MIP;
        if let Some(s) = range.clone().find(|&s| self.slots[s].is_none()) {
            self.slots[s] = Some(key);
            return Admit::Stored(s as u32);
        }
        let distance = |k: CellKey| cell_distance(k, origin, camera);
        let (far, far_d) = range
            .map(|s| (s, distance(self.slots[s].expect("full"))))
            .fold((base, f32::MIN), |a, b| if b.1 > a.1 { b } else { a });
        if far_d <= distance(key) {
            return Admit::Refused;
        }
        let evicted = self.slots[far].replace(key).expect("full");
        Admit::Evicted {
            slot: far as u32,
            evicted,
        }
    }

    /// Free `key`'s slot (streamed out); its slot, if it was resident.
    pub fn release(&mut self, key: CellKey) -> Option<u32> {
        let s = self.slot_of(key)?;
        self.slots[s as usize] = None;
        Some(s)
    }

    /// Resident cells.
    pub fn resident(&self) -> impl Iterator<Item = (u32, CellKey)> + '_ {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(s, k)| k.map(|k| (s as u32, k)))
    }

    /// Mip `mip`'s page table: one entry per cell of that mip over the
    /// grid ((160 >> mip) rounded up, squared), the slot or [`NO_CELL`].
    pub fn page_table(&self, mip: u8) -> Vec<u8> {
        let n = cells_per_axis(mip);
        let mut t = vec![NO_CELL; (n * n) as usize];
        for (s, k) in self.resident().filter(|(_, k)| k.mip == mip) {
            if (0..n).contains(&k.x) && (0..n).contains(&k.z) {
                t[(k.z * n + k.x) as usize] = s as u8;
            }
        }
        t
    }

    /// The per-mip tables combined at sector resolution (160 x 160, one
    /// byte per sector: 25 KB, the talk's figure): each sector points at
    /// the finest resident cell that covers it.
    pub fn combined_table(&self) -> Vec<u8> {
        let n = GRID_SECTORS;
        let mut t = vec![NO_CELL; (n * n) as usize];
        for mip in (0..MIPS as u8).rev() {
            let table = self.page_table(mip);
            let m = cells_per_axis(mip);
            for sz in 0..n {
                for sx in 0..n {
                    let e = table[((sz >> mip) * m + (sx >> mip)) as usize];
                    if e != NO_CELL {
                        t[(sz * n + sx) as usize] = e;
                    }
                }
            }
        }
        t
    }
}

/// What one streaming step did: cells to upload into their slots, and
/// how many were freed or evicted.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StreamStep {
    /// (slot, cell) to copy to the GPU.
    pub uploads: Vec<(u32, CellKey)>,
    /// Cells streamed out (no longer wanted) or evicted.
    pub released: u32,
}

impl CellPool {
    /// One frame of streaming for a camera at (x, z): cells no longer
    /// wanted are freed first, then the wanted ones that `available` says
    /// are baked are admitted nearest first (so farthest-first eviction can
    /// only strike cells nobody wants).
    pub fn stream(
        &mut self,
        origin: Vec2,
        camera: Vec2,
        available: impl Fn(CellKey) -> bool,
    ) -> StreamStep {
        let mut step = StreamStep::default();
        let mut wanted: Vec<CellKey> = wanted_cells(origin, camera)
            .into_iter()
            .filter(|k| available(*k))
            .collect();
        let gone: Vec<CellKey> = self
            .resident()
            .map(|(_, k)| k)
            .filter(|k| !wanted.contains(k))
            .collect();
        for k in gone {
            self.release(k);
            step.released += 1;
        }
        let distance = |k: &CellKey| cell_distance(*k, origin, camera);
        wanted.sort_by(|a, b| distance(a).total_cmp(&distance(b)).then(a.cmp(b)));
        for k in wanted {
            match self.admit(k, origin, camera) {
                Admit::Resident(_) | Admit::Refused => {}
                Admit::Stored(s) => step.uploads.push((s, k)),
                Admit::Evicted { slot, .. } => {
                    step.released += 1;
                    step.uploads.push((slot, k));
                }
            }
        }
        step
    }
}

/// Cells per axis of mip `mip` over the 160-sector grid.
pub fn cells_per_axis(mip: u8) -> i32 {
    (GRID_SECTORS + (1 << mip) - 1) >> mip
}

/// The cells of every mip within [`WANTED_HALF_CELLS`] of `camera` (x, z),
/// inside the grid; at most 16 per mip.
pub fn wanted_cells(origin: Vec2, camera: Vec2) -> Vec<CellKey> {
    let mut out = Vec::new();
    for mip in 0..MIPS as u8 {
        let size = CellKey { mip, x: 0, z: 0 }.size();
        let l = (camera - origin) / size;
        let lo = (l - WANTED_HALF_CELLS)
            .floor()
            .as_ivec2()
            .max(glam::IVec2::ZERO);
        let n = cells_per_axis(mip);
        // A cell whose far edge is exactly at the square's edge is not wanted.
        let hi = ((l + WANTED_HALF_CELLS).ceil().as_ivec2() - 1).min(glam::IVec2::splat(n - 1));
        for z in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                out.push(CellKey { mip, x, z });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const O: Vec2 = Vec2::new(-5120.0, -5120.0);

    fn key(mip: u8, x: i32, z: i32) -> CellKey {
        CellKey { mip, x, z }
    }

    #[test]
    fn a_full_mip_evicts_its_most_distant_cell_and_refuses_a_farther_one() {
        let mut pool = CellPool::default();
        let camera = key(0, 80, 80).corner(O) + 32.0;
        for i in 0..CELLS_PER_MIP as i32 {
            // Cells 80..96 along x: distances 0, 32, 96, ...
            assert!(matches!(
                pool.admit(key(0, 80 + i, 80), O, camera),
                Admit::Stored(_)
            ));
        }
        assert_eq!(pool.used(), 16);
        // Mip 1 has its own slots.
        assert!(matches!(
            pool.admit(key(1, 40, 40), O, camera),
            Admit::Stored(16)
        ));
        // A nearer cell takes the farthest one's slot.
        let far = key(0, 95, 80);
        let s = pool.slot_of(far).unwrap();
        assert_eq!(
            pool.admit(key(0, 79, 80), O, camera),
            Admit::Evicted {
                slot: s,
                evicted: far
            }
        );
        assert_eq!(pool.slot_of(far), None);
        // A cell farther than everything resident is refused, the pool unchanged.
        assert_eq!(pool.admit(key(0, 120, 80), O, camera), Admit::Refused);
        assert_eq!(pool.admit(key(0, 79, 80), O, camera), Admit::Resident(s));
        assert_eq!(pool.release(key(0, 79, 80)), Some(s));
        assert!(matches!(pool.admit(key(0, 120, 80), O, camera), Admit::Stored(x) if x == s));
        assert_eq!(pool.used(), 17);
    }

    #[test]
    fn the_wanted_set_fits_the_pool_anywhere_and_covers_the_camera_square() {
        for (i, p) in [
            Vec2::ZERO,
            Vec2::new(31.9, -0.1),
            Vec2::new(-5100.0, 5000.0),
            Vec2::new(1234.5, 987.6),
        ]
        .into_iter()
        .enumerate()
        {
            let wanted = wanted_cells(O, p);
            for mip in 0..MIPS as u8 {
                let cells: Vec<_> = wanted.iter().filter(|k| k.mip == mip).collect();
                assert!(
                    cells.len() <= CELLS_PER_MIP,
                    "case {i} mip {mip}: {}",
                    cells.len()
                );
                let half = WANTED_HALF_CELLS * key(mip, 0, 0).size() - 1.0;
                for c in [p + half, p - half, p + Vec2::new(half, -half)] {
                    let l = ((c - O) / key(mip, 0, 0).size()).floor().as_ivec2();
                    let inside = (0..cells_per_axis(mip)).contains(&l.x)
                        && (0..cells_per_axis(mip)).contains(&l.y);
                    assert!(
                        !inside || cells.iter().any(|k| k.x == l.x && k.z == l.y),
                        "case {i} mip {mip} misses {c}"
                    );
                }
            }
        }
    }

    #[test]
    fn page_tables_point_at_the_finest_resident_cell_in_25_kb() {
        let mut pool = CellPool::default();
        let camera = Vec2::ZERO;
        let fine = key(0, 80, 80);
        let coarse = key(2, 20, 20);
        let sf = match pool.admit(fine, O, camera) {
            Admit::Stored(s) => s,
            a => panic!("{a:?}"),
        };
        let sc = match pool.admit(coarse, O, camera) {
            Admit::Stored(s) => s,
            a => panic!("{a:?}"),
        };
        assert_eq!(pool.page_table(2).len(), 40 * 40);
        let t = pool.combined_table();
        assert_eq!(t.len(), 25_600, "160 x 160 bytes, the talk's 25 KB");
        assert_eq!(t[80 * 160 + 80], sf as u8);
        assert_eq!(t[81 * 160 + 83], sc as u8, "covered by the mip-2 cell only");
        assert_eq!(t[84 * 160 + 80], NO_CELL);
    }
}
