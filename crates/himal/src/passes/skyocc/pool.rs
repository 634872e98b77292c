//! The sector pool of the sky occlusion (L2): which 64x64 m sectors are
//! wanted this frame, and which pool layer holds each resident one, with
//! least-recently-used eviction. Pure CPU; the pass renders what `plan` returns.

use std::collections::{HashMap, HashSet};

use glam::{IVec2, Mat4, Vec2, Vec3, Vec4};

use super::reference::SECTOR_SIZE;
use crate::scene::Aabb;

/// Sector coordinates: sector (i, j) covers x in [64 i, 64 (i + 1)), z likewise.
pub type Sector = IVec2;

/// The sector holding world (x, z).
pub fn sector_of(x: f32, z: f32) -> Sector {
    IVec2::new(
        (x / SECTOR_SIZE).floor() as i32,
        (z / SECTOR_SIZE).floor() as i32,
    )
}

/// Sectors whose box (the scene's height range) is within `range` metres
/// of the camera (horizontally) and not entirely outside one plane of the
/// frustum `view_proj` (reverse-Z, infinite far: the near plane and the four
/// sides are tested). Nearest first, so a capped frame renders those first.
pub fn visible_sectors(
    camera: Vec3,
    view_proj: Mat4,
    range: f32,
    heights: (f32, f32),
) -> Vec<Sector> {
    let lo = sector_of(camera.x - range, camera.z - range);
    let hi = sector_of(camera.x + range, camera.z + range);
    let rows = view_proj.transpose();
    // Gribb-Hartmann planes for clip x, y in [-w, w] and z in [0, w]... reverse-Z:
    // near is z <= w, and z >= 0 is at infinity (skipped).
    let planes = [
        rows.w_axis + rows.x_axis,
        rows.w_axis - rows.x_axis,
        rows.w_axis + rows.y_axis,
        rows.w_axis - rows.y_axis,
        rows.w_axis - rows.z_axis,
    ];
    let mut out = Vec::new();
    for j in lo.y..=hi.y {
        for i in lo.x..=hi.x {
            let min = Vec2::new(i as f32, j as f32) * SECTOR_SIZE;
            let max = min + SECTOR_SIZE;
            let nearest = Vec2::new(camera.x, camera.z).clamp(min, max);
            if nearest.distance(Vec2::new(camera.x, camera.z)) > range {
                continue;
            }
            let b = Aabb::new(
                Vec3::new(min.x, heights.0, min.y),
                Vec3::new(max.x, heights.1, max.y),
            );
            let outside = planes
                .iter()
                .any(|p: &Vec4| b.corners().iter().all(|c| p.dot(c.extend(1.0)) < 0.0));
            if !outside {
                out.push(IVec2::new(i, j));
            }
        }
    }
    let centre = |s: &Sector| (s.as_vec2() + 0.5) * SECTOR_SIZE;
    let cam = Vec2::new(camera.x, camera.z);
    out.sort_by(|a, b| centre(a).distance(cam).total_cmp(&centre(b).distance(cam)));
    out
}

/// Fixed pool of `capacity` layers with LRU eviction.
#[derive(Clone, Debug)]
pub struct SectorPool {
    capacity: usize,
    /// Resident sector -> (layer, frame it was last wanted).
    resident: HashMap<Sector, (u32, u64)>,
    /// Resident sectors whose geometry changed since they were rendered
    /// (the world streamed in around them): rendered again into their own
    /// layer when next wanted, shown as they were until then.
    stale: HashSet<Sector>,
    frame: u64,
}

impl SectorPool {
    /// An empty pool of `capacity` layers (at least 1).
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.max(1),
            resident: HashMap::new(),
            stale: HashSet::new(),
            frame: 0,
        }
    }

    /// Number of layers.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Layer of `sector` if resident.
    pub fn layer(&self, sector: Sector) -> Option<u32> {
        self.resident.get(&sector).map(|&(l, _)| l)
    }

    /// Resident sectors and their layers (any order).
    pub fn resident(&self) -> impl Iterator<Item = (Sector, u32)> + '_ {
        self.resident.iter().map(|(s, &(l, _))| (*s, l))
    }

    /// Forgets every sector (scene change).
    pub fn clear(&mut self) {
        self.resident.clear();
        self.stale.clear();
    }

    /// Marks `sector` for rendering again (no effect unless resident).
    pub fn mark_stale(&mut self, sector: Sector) {
        if self.resident.contains_key(&sector) {
            self.stale.insert(sector);
        }
    }

    /// Resident sectors waiting to be rendered again.
    pub fn stale(&self) -> usize {
        self.stale.len()
    }

    /// One frame: marks the `wanted` sectors used, then gives up to `cap`
    /// missing ones a layer (a free one, else the least recently used
    /// sector's; never one wanted this frame) and takes stale ones again
    /// in their own layer, in `wanted` order. Returns (sector, layer) to
    /// render. Sectors left without a layer (pool over-committed or cap
    /// reached) count as fully visible in lighting.
    pub fn plan(&mut self, wanted: &[Sector], cap: usize) -> Vec<(Sector, u32)> {
        self.frame += 1;
        let frame = self.frame;
        for s in wanted {
            if let Some(e) = self.resident.get_mut(s) {
                e.1 = frame;
            }
        }
        let mut out = Vec::new();
        for s in wanted {
            if out.len() >= cap {
                break;
            }
            if let Some(&(layer, _)) = self.resident.get(s) {
                if self.stale.remove(s) {
                    out.push((*s, layer));
                }
                continue;
            }
            let layer = if self.resident.len() < self.capacity {
                // The lowest layer no sector holds.
                let used: Vec<u32> = self.resident.values().map(|&(l, _)| l).collect();
                (0..self.capacity as u32).find(|l| !used.contains(l))
            } else {
                let victim = self
                    .resident
                    .iter()
                    .filter(|(_, (_, f))| *f != frame)
                    .min_by_key(|(v, (_, f))| (*f, v.x, v.y))
                    .map(|(v, &(l, _))| (*v, l));
                victim.map(|(v, l)| {
                    self.resident.remove(&v);
                    self.stale.remove(&v);
                    l
                })
            };
            let Some(layer) = layer else { break };
            self.resident.insert(*s, (layer, frame));
            out.push((*s, layer));
        }
        out
    }
}

/// Edge of the sector table (entries indexed by sector coordinates modulo
/// this): 32 sectors = 2 km, far more than the occlusion range, so two
/// wanted sectors never share an entry.
pub const TABLE_SIZE: usize = 32;

/// The table lighting reads (`Rgba32Sint`, `TABLE_SIZE`² texels): at
/// (i mod 32, j mod 32) the sector (i, j, layer, 1) resident there, or
/// w = 0. `first` sectors win collisions (this frame's wanted ones).
pub fn sector_table(pool: &SectorPool, first: &[Sector]) -> Vec<[i32; 4]> {
    let mut table = vec![[0, 0, 0, 0]; TABLE_SIZE * TABLE_SIZE];
    let n = TABLE_SIZE as i32;
    let slot = |s: Sector| (s.y.rem_euclid(n) * n + s.x.rem_euclid(n)) as usize;
    for (s, l) in pool.resident() {
        table[slot(s)] = [s.x, s.y, l as i32, 1];
    }
    for s in first {
        if let Some(l) = pool.layer(*s) {
            table[slot(*s)] = [s.x, s.y, l as i32, 1];
        }
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_sector_stays_resident_and_lru_is_evicted() {
        let mut pool = SectorPool::new(4);
        let s = |i, j| IVec2::new(i, j);
        // Frame 1: a, b; frame 2: c, d (pool full); a wanted again in frame 3.
        assert_eq!(pool.plan(&[s(0, 0), s(1, 0)], 8).len(), 2);
        assert_eq!(pool.plan(&[s(2, 0), s(3, 0)], 8).len(), 2);
        assert_eq!(pool.plan(&[s(0, 0)], 8).len(), 0);
        // Frame 4: e needs a layer: (1, 0) was used least recently.
        let got = pool.plan(&[s(4, 0), s(0, 0)], 8);
        let freed = pool.layer(s(1, 0));
        assert_eq!(got.len(), 1);
        assert!(freed.is_none(), "the LRU sector (1, 0) must be evicted");
        assert!(pool.layer(s(0, 0)).is_some());
        // Property: while the wanted set fits the pool, every wanted sector
        // is resident after the frame, each in its own layer.
        let mut seed = 7u32;
        for _ in 0..500 {
            let mut wanted = Vec::new();
            for _ in 0..4 {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let w = s((seed >> 8) as i32 % 6, (seed >> 20) as i32 % 3);
                if !wanted.contains(&w) {
                    wanted.push(w);
                }
            }
            pool.plan(&wanted, 8);
            let mut layers: Vec<u32> = wanted.iter().filter_map(|w| pool.layer(*w)).collect();
            assert_eq!(layers.len(), wanted.len(), "{wanted:?}");
            layers.sort();
            layers.dedup();
            assert_eq!(layers.len(), wanted.len());
            assert!(pool.resident().count() <= 4);
        }
    }

    #[test]
    fn stale_sectors_render_again_in_their_own_layer_when_wanted() {
        let mut pool = SectorPool::new(4);
        let s = |i, j| IVec2::new(i, j);
        pool.plan(&[s(0, 0), s(1, 0)], 8);
        let layer = pool.layer(s(1, 0));
        pool.mark_stale(s(1, 0));
        pool.mark_stale(s(5, 5)); // not resident: ignored
        assert_eq!(pool.stale(), 1);
        // Not wanted: stays stale and keeps its layer.
        assert!(pool.plan(&[s(0, 0)], 8).is_empty());
        assert_eq!(pool.stale(), 1);
        // The cap counts re-renders too; nearest (first) wanted go first.
        pool.mark_stale(s(0, 0));
        let got = pool.plan(&[s(1, 0), s(0, 0)], 1);
        assert_eq!(got, vec![(s(1, 0), layer.unwrap_or(99))]);
        assert_eq!(pool.stale(), 1);
        assert_eq!(pool.plan(&[s(1, 0), s(0, 0)], 8).len(), 1);
        assert_eq!(pool.stale(), 0);
        assert!(pool.plan(&[s(1, 0), s(0, 0)], 8).is_empty());
    }

    #[test]
    fn over_committed_pool_keeps_this_frames_sectors() {
        let mut pool = SectorPool::new(2);
        let wanted: Vec<Sector> = (0..3).map(|i| IVec2::new(i, 0)).collect();
        let got = pool.plan(&wanted, 8);
        assert_eq!(got.len(), 2, "only two layers");
        assert!(pool.layer(wanted[2]).is_none());
        let table = sector_table(&pool, &wanted);
        assert_eq!(
            table[1],
            [1, 0, pool.layer(wanted[1]).unwrap_or(9) as i32, 1]
        );
        assert_eq!(table[2][3], 0);
    }

    #[test]
    fn sectors_in_front_of_the_camera_are_visible() {
        let cam = crate::scene::Camera::look_at(
            Vec3::new(1.0, 2.0, 1.0),
            Vec3::new(1.0, 2.0, -50.0),
            60.0,
        );
        let vp = cam.view_projection(1.0);
        let got = visible_sectors(cam.position, vp, 100.0, (-10.0, 50.0));
        assert_eq!(got[0], IVec2::new(0, 0));
        assert!(got.contains(&IVec2::new(0, -1)));
        assert!(
            !got.contains(&IVec2::new(0, 1)),
            "behind the camera: {got:?}"
        );
    }
}
