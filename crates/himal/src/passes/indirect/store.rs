//! Every baked cell of a scene: mip 0 from the bake (or the cache), mips
//! 1..4 from their children, and the cache directory they live in
//! (docs/techniques/L5.md "Bake").

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use glam::Vec2;

use super::bake::{BakeSettings, bake_cell};
use super::cell::{Cell, CellKey, GRID_SECTORS, MIPS};
use crate::scene::Aabb;
use crate::scene::raycast::RayScene;
use crate::scene::world::SECTOR_SIZE;

/// The grid origin of plain scenes: the world's 160 x 160 sectors, centred on (0, 0).
pub const SCENE_ORIGIN: Vec2 = Vec2::splat(-(GRID_SECTORS as f32) * SECTOR_SIZE * 0.5);

/// Where the GPU pool's cells come from: a scene's finished bake
/// ([`ProbeStore`]) or the streamed world's cells, loaded and baked as the
/// camera moves ([`super::world::WorldProbes`]).
pub trait CellSource: Send + Sync {
    /// Min corner (x, z) of sector (0, 0).
    fn origin(&self) -> Vec2;
    /// Whether cell `key` can be streamed now.
    fn contains(&self, key: CellKey) -> bool;
    /// Cell `key` for an upload (cloned or shared; at most a few per frame).
    fn fetch(&self, key: CellKey) -> Option<std::sync::Arc<Cell>>;
    /// The camera is at (x, z) this frame: a source that loads or bakes as
    /// the camera moves starts on what is near it.
    fn follow(&self, _camera: Vec2) {}
    /// Cells of every mip held now.
    fn held(&self) -> usize;
}

impl CellSource for ProbeStore {
    fn origin(&self) -> Vec2 {
        self.origin
    }

    fn contains(&self, key: CellKey) -> bool {
        self.cells.contains_key(&key)
    }

    fn fetch(&self, key: CellKey) -> Option<std::sync::Arc<Cell>> {
        self.cells.get(&key).cloned().map(std::sync::Arc::new)
    }

    fn held(&self) -> usize {
        self.cells.len()
    }
}

/// Baked cells of every mip, by key.
#[derive(Clone, Debug, Default)]
pub struct ProbeStore {
    /// Min corner (x, z) of sector (0, 0).
    pub origin: Vec2,
    cells: BTreeMap<CellKey, Cell>,
}

/// How a bake went: cells baked now, cells read from the cache.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BakeReport {
    /// Cells baked by this call.
    pub baked: usize,
    /// Cells read from the cache.
    pub cached: usize,
}

/// The mip-0 cells whose square overlaps `bounds` (x, z), inside the grid.
pub fn cells_over(bounds: &Aabb, origin: Vec2) -> Vec<CellKey> {
    if bounds.is_empty() {
        return Vec::new();
    }
    let lo = ((Vec2::new(bounds.min.x, bounds.min.z) - origin) / SECTOR_SIZE)
        .floor()
        .as_ivec2();
    let hi = ((Vec2::new(bounds.max.x, bounds.max.z) - origin) / SECTOR_SIZE)
        .floor()
        .as_ivec2();
    let lo = lo.max(glam::IVec2::ZERO);
    let hi = hi.min(glam::IVec2::splat(GRID_SECTORS - 1));
    let mut out = Vec::new();
    for z in lo.y..=hi.y {
        for x in lo.x..=hi.x {
            out.push(CellKey { mip: 0, x, z });
        }
    }
    out
}

/// The cache folder of one scene's cells: its geometry and bake settings
/// hashed, so an edited scene bakes afresh.
pub fn cache_folder(cache: &Path, scene: &RayScene, settings: &BakeSettings) -> PathBuf {
    let mut h = crc32fast::Hasher::new();
    h.update(&scene.fingerprint().to_le_bytes());
    for v in [
        settings.rays,
        settings.visibility_rays,
        settings.probe_height.to_bits(),
    ] {
        h.update(&v.to_le_bytes());
    }
    h.update(&super::cell::VERSION.to_le_bytes());
    cache.join("probes").join(format!("{:08x}", h.finalize()))
}

impl ProbeStore {
    /// Bakes the mip-0 cells over `scene`'s bounds (reading those a previous
    /// bake left in `cache`, writing the new ones there: a bake stopped
    /// half-way resumes) and derives mips 1..4. `progress(done, total)`
    /// after each cell.
    pub fn bake(
        scene: &RayScene,
        settings: &BakeSettings,
        cache: Option<&Path>,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<(ProbeStore, BakeReport), String> {
        let origin = SCENE_ORIGIN;
        let keys = cells_over(&scene.bounds(), origin);
        let folder = cache.map(|c| cache_folder(c, scene, settings));
        if let Some(f) = &folder {
            std::fs::create_dir_all(f).map_err(|e| format!("{}: {e}", f.display()))?;
        }
        let mut store = ProbeStore {
            origin,
            cells: BTreeMap::new(),
        };
        let mut report = BakeReport::default();
        for (n, key) in keys.iter().enumerate() {
            let path = folder.as_ref().map(|f| f.join(key.file_name()));
            let cached = path.as_ref().and_then(|p| Cell::read(p, *key));
            let cell = match cached {
                Some(c) => {
                    report.cached += 1;
                    c
                }
                None => {
                    let c = bake_cell(scene, *key, origin, settings);
                    if let Some(p) = &path {
                        c.write(p)?;
                    }
                    report.baked += 1;
                    c
                }
            };
            store.cells.insert(*key, cell);
            progress(n + 1, keys.len());
        }
        store.build_mips();
        Ok((store, report))
    }

    /// A store of given mip-0 cells (tests, tools), with mips derived.
    pub fn from_cells(origin: Vec2, cells: Vec<Cell>) -> ProbeStore {
        let mut store = ProbeStore {
            origin,
            cells: cells
                .into_iter()
                .filter(|c| c.key.mip == 0)
                .map(|c| (c.key, c))
                .collect(),
        };
        store.build_mips();
        store
    }

    fn build_mips(&mut self) {
        for mip in 1..MIPS as u8 {
            let parents: BTreeSet<CellKey> = self
                .cells
                .keys()
                .filter(|k| k.mip == mip - 1)
                .map(|k| CellKey {
                    mip,
                    x: k.x >> 1,
                    z: k.z >> 1,
                })
                .collect();
            for p in parents {
                let kids = p.children().map(|k| self.cells.get(&k));
                if let Some(c) = Cell::downsample(p, kids) {
                    self.cells.insert(p, c);
                }
            }
        }
    }

    /// The cell `key`, if baked.
    pub fn cell(&self, key: CellKey) -> Option<&Cell> {
        self.cells.get(&key)
    }

    /// Cells of every mip.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// No cell at all.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }
}
