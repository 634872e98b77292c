//! L5 in the streamed world (docs/techniques/L5.md "The streamed world").
//! A 10 km world has 25,600 mip-0 cells: they are baked per *block* of
//! 4 x 4 sectors (one mip-2 cell) against that block's own geometry,
//! generated from the world's seed: the block's sectors and a ring of one
//! sector around them in full (terrain every 2 m, rocks, houses, roofs,
//! fences, fields, water; trees are foliage and left out, as in scenes),
//! and the terrain four sectors further at 8 m. A block therefore bakes to
//! the same bytes whenever and in whatever order it is baked, so cells are
//! baked on demand around the camera, ahead of time by `himal bake
//! --probes --scene world`, and cached either way.
//!
//! [`WorldProbes`] is the pool's [`CellSource`] there: blocks near the
//! camera (the mip-2 cells the pool wants: cascades 0..2 fully covered)
//! are read from the cache or baked, cached blocks as far as mip 4 wants
//! are read, and a mip-3/4 cell exists once its children all do. Where no
//! cell is, the clip map holds the flat ground's bounce. Synchronously
//! ([`WorldProbes::follow`] bakes before the frame: headless renders stay
//! deterministic) or on a background thread ([`WorldProbes::start`]: the
//! viewer never waits, and the far blocks under mips 3 and 4 are baked
//! too, nearest first). Cells farther than [`KEEP_RADIUS`] leave memory.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, RwLock};

use glam::{IVec2, Vec2, Vec3};

use super::bake::{BakeSettings, bake_cell};
use super::cell::{Cell, CellKey, GRID_SECTORS, MIPS};
use super::pool::{cell_distance, wanted_cells};
use super::store::{BakeReport, CellSource};
use crate::passes::terrain::TerrainLayerDesc;
use crate::scene::Mesh;
use crate::scene::raycast::RayScene;
use crate::scene::world::{InstanceKind, SECTOR_SIZE, SectorCoord, TILE_RES, World};

/// Sectors per block side: a block is one mip-2 cell, the unit of baking.
pub const BLOCK: i32 = 4;
/// Mip of a block's cell.
pub const BLOCK_MIP: u8 = 2;
/// Sectors of full geometry around a block.
const DETAIL_RING: i32 = 1;
/// Sectors of coarse terrain beyond the full ring.
const COARSE_RING: i32 = 4;
/// Terrain samples (1 m apart) per triangle edge in the full ring.
const DETAIL_STEP: usize = 2;
/// Coarse terrain spacing (m).
const COARSE_SPACING: f32 = 8.0;
/// Cells farther than this from the camera (m) leave memory (the cache keeps them).
pub const KEEP_RADIUS: f32 = 3000.0;

/// The world's bake settings: 128 x 16 rays, an eighth of a scene's cost
/// (measured in docs/techniques/L5.md), so a block bakes in about a second.
pub fn world_bake_settings() -> BakeSettings {
    BakeSettings {
        rays: 128,
        visibility_rays: 16,
        ..BakeSettings::default()
    }
}

/// The opaque geometry block `block` (in blocks) is baked against.
pub fn block_geometry(
    world: &World,
    meshes: &[Option<Mesh>],
    layers: &[TerrainLayerDesc],
    block: IVec2,
) -> RayScene {
    let n = world.desc.sectors as i32;
    let lo = block * BLOCK;
    let (d_lo, d_hi) = (
        (lo - DETAIL_RING).max(IVec2::ZERO),
        (lo + BLOCK + DETAIL_RING).min(IVec2::splat(n)),
    );
    let mut tris: Vec<([Vec3; 3], Vec3, bool)> = Vec::new();
    let mut terrain = |v: [Vec3; 3], tris: &mut Vec<_>| {
        let normal = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or(Vec3::Y);
        let slope = normal.y.clamp(-1.0, 1.0).acos().to_degrees();
        let height = (v[0].y + v[1].y + v[2].y) / 3.0;
        tris.push((
            v,
            TerrainLayerDesc::mean_albedo(layers, height, slope),
            true,
        ));
    };
    // Counter-clockwise seen from above: (p00, p01, p10), (p10, p01, p11).
    let quad =
        |p: [[Vec3; 2]; 2], tris: &mut Vec<_>, terrain: &mut dyn FnMut([Vec3; 3], &mut Vec<_>)| {
            terrain([p[0][0], p[0][1], p[1][0]], tris);
            terrain([p[1][0], p[0][1], p[1][1]], tris);
        };
    for sz in d_lo.y..d_hi.y {
        for sx in d_lo.x..d_hi.x {
            let sector = world.sector(SectorCoord {
                x: sx as u16,
                z: sz as u16,
            });
            let corner = world.origin + IVec2::new(sx, sz).as_vec2() * SECTOR_SIZE;
            let s = SECTOR_SIZE / (TILE_RES - 1) as f32;
            let at = |i: usize, j: usize| {
                Vec3::new(
                    corner.x + i as f32 * s,
                    sector.heights[j * TILE_RES + i],
                    corner.y + j as f32 * s,
                )
            };
            for j in (0..TILE_RES - 1).step_by(DETAIL_STEP) {
                for i in (0..TILE_RES - 1).step_by(DETAIL_STEP) {
                    let (i1, j1) = (i + DETAIL_STEP, j + DETAIL_STEP);
                    quad(
                        [[at(i, j), at(i, j1)], [at(i1, j), at(i1, j1)]],
                        &mut tris,
                        &mut terrain,
                    );
                }
            }
            // Trees have no mesh here: the bake skips them.
            for inst in &sector.instances {
                let Some(mesh) = InstanceKind::ALL
                    .iter()
                    .position(|k| *k == inst.kind)
                    .and_then(|k| meshes.get(k)?.as_ref())
                else {
                    continue;
                };
                let m = inst.transform();
                let tint = Vec3::new(
                    inst.tint[0] as f32,
                    inst.tint[1] as f32,
                    inst.tint[2] as f32,
                ) / 255.0;
                let ground = matches!(inst.kind, InstanceKind::Water | InstanceKind::Field);
                let world_of =
                    |i: u32| m.transform_point3(Vec3::from(mesh.vertices[i as usize].position));
                for t in mesh.indices.chunks_exact(3) {
                    let colour = t
                        .iter()
                        .map(|&i| Vec3::from_slice(&mesh.vertices[i as usize].color[..3]))
                        .sum::<Vec3>()
                        / 3.0;
                    tris.push((
                        [world_of(t[0]), world_of(t[1]), world_of(t[2])],
                        colour * tint,
                        ground,
                    ));
                }
            }
        }
    }
    // Coarse terrain around the full ring, skipping what the ring covers.
    let c_lo = (d_lo - COARSE_RING).max(IVec2::ZERO).as_vec2() * SECTOR_SIZE;
    let c_hi = (d_hi + COARSE_RING).min(IVec2::splat(n)).as_vec2() * SECTOR_SIZE;
    let (f_lo, f_hi) = (d_lo.as_vec2() * SECTOR_SIZE, d_hi.as_vec2() * SECTOR_SIZE);
    let steps = ((c_hi - c_lo) / COARSE_SPACING).round().as_ivec2();
    let h = |x: f32, z: f32| world.terrain.height(world.origin.x + x, world.origin.y + z);
    let p = |x: f32, z: f32| Vec3::new(world.origin.x + x, h(x, z), world.origin.y + z);
    for j in 0..steps.y {
        for i in 0..steps.x {
            let a = c_lo + IVec2::new(i, j).as_vec2() * COARSE_SPACING;
            let b = a + COARSE_SPACING;
            let mid = (a + b) * 0.5;
            if mid.cmpge(f_lo).all() && mid.cmplt(f_hi).all() {
                continue;
            }
            quad(
                [[p(a.x, a.y), p(a.x, b.y)], [p(b.x, a.y), p(b.x, b.y)]],
                &mut tris,
                &mut terrain,
            );
        }
    }
    RayScene::from_triangles(&tris)
}

/// The mip-0 cells of block `block`.
pub fn block_cells(block: IVec2) -> impl Iterator<Item = CellKey> {
    (0..BLOCK * BLOCK).map(move |k| CellKey {
        mip: 0,
        x: block.x * BLOCK + k % BLOCK,
        z: block.y * BLOCK + k / BLOCK,
    })
}

/// The cache folder of a world's cells: its description and the bake
/// settings hashed, so another seed or shape bakes afresh.
pub fn world_cache_folder(cache: &Path, world: &World, settings: &BakeSettings) -> PathBuf {
    let mut h = crc32fast::Hasher::new();
    let d = &world.desc;
    h.update(
        format!(
            "{:?}{:?}{:?}{}",
            d.sectors, d.shape, d.rules, d.coarse_spacing
        )
        .as_bytes(),
    );
    if let crate::scene::world::HeightSource::Image(g) = &d.source {
        h.update(bytemuck::cast_slice(&g.heights));
    }
    for v in [
        settings.rays,
        settings.visibility_rays,
        settings.probe_height.to_bits(),
        super::cell::VERSION,
    ] {
        h.update(&v.to_le_bytes());
    }
    cache
        .join("probes")
        .join(format!("world-{:08x}", h.finalize()))
}

/// Progress of a synchronous bake: (blocks done, blocks to do).
pub type Progress = Box<dyn Fn(usize, usize) + Send + Sync>;

struct Shared {
    world: Arc<World>,
    meshes: Vec<Option<Mesh>>,
    layers: Vec<TerrainLayerDesc>,
    settings: BakeSettings,
    folder: Option<PathBuf>,
    cells: RwLock<BTreeMap<CellKey, Arc<Cell>>>,
    /// The camera the background thread serves (`None`: not yet known).
    camera: Mutex<Option<Vec2>>,
    wake: Condvar,
    stop: AtomicBool,
    /// The first cache write that failed (reported once, baking goes on).
    error: Mutex<Option<String>>,
    progress: Option<Progress>,
}

/// The streamed world's probe cells, read and baked around the camera.
pub struct WorldProbes {
    shared: Arc<Shared>,
    background: Mutex<Option<std::thread::JoinHandle<()>>>,
}

impl Drop for WorldProbes {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.shared.wake.notify_all();
        if let Some(t) = self.background.lock().ok().and_then(|mut t| t.take()) {
            let _ = t.join();
        }
    }
}

impl WorldProbes {
    /// `world`'s cells, cached under `cache` (`None`: baked again each run).
    /// `progress` hears of synchronous bakes ([`Self::follow`], [`Self::bake_around`]).
    pub fn new(
        world: Arc<World>,
        settings: BakeSettings,
        cache: Option<&Path>,
        progress: Option<Progress>,
    ) -> Result<Self, String> {
        let folder = cache.map(|c| world_cache_folder(c, &world, &settings));
        if let Some(f) = &folder {
            std::fs::create_dir_all(f).map_err(|e| format!("{}: {e}", f.display()))?;
        }
        Ok(WorldProbes {
            shared: Arc::new(Shared {
                meshes: crate::scene::world::meshes::solid_meshes(),
                layers: TerrainLayerDesc::for_world(&world),
                world,
                settings,
                folder,
                cells: RwLock::new(BTreeMap::new()),
                camera: Mutex::new(None),
                wake: Condvar::new(),
                stop: AtomicBool::new(false),
                error: Mutex::new(None),
                progress,
            }),
            background: Mutex::new(None),
        })
    }

    /// The cache folder, if any.
    pub fn folder(&self) -> Option<&Path> {
        self.shared.folder.as_deref()
    }

    /// Bakes on a background thread from now on: [`Self::follow`] only
    /// tells it where the camera is, and cells appear as they are baked.
    pub fn start(&self) {
        let Ok(mut slot) = self.background.lock() else {
            return;
        };
        if slot.is_some() {
            return;
        }
        let shared = self.shared.clone();
        *slot = std::thread::Builder::new()
            .name("himal-probe-bake".into())
            .spawn(move || shared.serve())
            .ok();
    }

    /// Bakes (or reads) every block within `radius` of any of `centres`
    /// (x, z), nearest first; what `himal bake --probes` does for a world.
    pub fn bake_around(&self, centres: &[Vec2], radius: f32) -> Result<BakeReport, String> {
        let s = &self.shared;
        let size = BLOCK as f32 * SECTOR_SIZE;
        let n = s.blocks_per_axis();
        let mut blocks: Vec<(f32, IVec2)> = Vec::new();
        for z in 0..n {
            for x in 0..n {
                let key = CellKey {
                    mip: BLOCK_MIP,
                    x,
                    z,
                };
                let d = centres
                    .iter()
                    .map(|c| cell_distance(key, s.world.origin, *c))
                    .fold(f32::INFINITY, f32::min);
                if d <= radius {
                    blocks.push((d, IVec2::new(x, z)));
                }
            }
        }
        debug_assert!(size > 0.0);
        blocks.sort_by(|a, b| {
            a.0.total_cmp(&b.0)
                .then(a.1.to_array().cmp(&b.1.to_array()))
        });
        s.run(blocks.into_iter().map(|b| b.1).collect())
    }

    /// A cache write that failed, if any (the cells stay in memory).
    pub fn error(&self) -> Option<String> {
        self.shared.error.lock().ok().and_then(|e| e.clone())
    }
}

impl Shared {
    fn blocks_per_axis(&self) -> i32 {
        (self.world.desc.sectors as i32).min(GRID_SECTORS) / BLOCK
    }

    /// Blocks the pool wants near `camera` (baked if missing), and farther
    /// blocks under the wanted mip-3/4 cells (read if cached), nearest first.
    fn wanted_blocks(&self, camera: Vec2) -> (Vec<IVec2>, Vec<IVec2>) {
        let origin = self.world.origin;
        let n = self.blocks_per_axis();
        let inside = |b: &IVec2| b.min_element() >= 0 && b.max_element() < n;
        let mut near = Vec::new();
        let mut far = Vec::new();
        for k in wanted_cells(origin, camera) {
            if k.mip == BLOCK_MIP {
                near.push(IVec2::new(k.x, k.z));
            } else if k.mip > BLOCK_MIP {
                let per = 1 << (k.mip - BLOCK_MIP);
                for dz in 0..per {
                    for dx in 0..per {
                        far.push(IVec2::new(k.x * per + dx, k.z * per + dz));
                    }
                }
            }
        }
        let d = |b: &IVec2| {
            let key = CellKey {
                mip: BLOCK_MIP,
                x: b.x,
                z: b.y,
            };
            cell_distance(key, origin, camera)
        };
        for list in [&mut near, &mut far] {
            list.retain(inside);
            list.sort_by(|a, b| d(a).total_cmp(&d(b)).then(a.to_array().cmp(&b.to_array())));
            list.dedup();
        }
        far.retain(|b| !near.contains(b));
        (near, far)
    }

    fn has_block(&self, block: IVec2) -> bool {
        self.cells.read().is_ok_and(|c| {
            c.contains_key(&CellKey {
                mip: BLOCK_MIP,
                x: block.x,
                z: block.y,
            })
        })
    }

    fn file(&self, key: CellKey) -> Option<PathBuf> {
        self.folder.as_ref().map(|f| f.join(key.file_name()))
    }

    fn read(&self, key: CellKey) -> Option<Cell> {
        Cell::read(&self.file(key)?, key)
    }

    /// Reads block `block`'s cells from the cache, baking the missing ones
    /// when `bake`; false when it is not complete afterwards.
    fn load_block(&self, block: IVec2, bake: bool, report: &mut BakeReport) -> bool {
        let mut cells: Vec<Cell> = Vec::new();
        let mut missing = Vec::new();
        for key in block_cells(block) {
            match self.read(key) {
                Some(c) => cells.push(c),
                None if !bake => return false,
                None => missing.push(key),
            }
        }
        report.cached += cells.len();
        if !missing.is_empty() {
            let geometry = block_geometry(&self.world, &self.meshes, &self.layers, block);
            for key in missing {
                let c = bake_cell(&geometry, key, self.world.origin, &self.settings);
                if let (Some(Err(e)), Ok(mut first)) =
                    (self.file(key).map(|p| c.write(&p)), self.error.lock())
                    && first.is_none()
                {
                    *first = Some(e);
                }
                report.baked += 1;
                cells.push(c);
            }
        }
        self.insert(cells);
        true
    }

    /// Adds mip-0 cells and every coarser cell whose children are now all present.
    fn insert(&self, cells: Vec<Cell>) {
        let Ok(mut map) = self.cells.write() else {
            return;
        };
        let mut parents: Vec<CellKey> = Vec::new();
        for c in cells {
            parents.push(c.key);
            map.insert(c.key, Arc::new(c));
        }
        for mip in 1..MIPS as u8 {
            let mut next: Vec<CellKey> = parents
                .iter()
                .map(|k| CellKey {
                    mip,
                    x: k.x >> 1,
                    z: k.z >> 1,
                })
                .collect();
            next.sort();
            next.dedup();
            next.retain(|p| !map.contains_key(p));
            let mut built = Vec::new();
            for p in next {
                let kids = p.children().map(|k| map.get(&k).cloned());
                if kids.iter().all(Option::is_some) {
                    let refs = std::array::from_fn(|i| kids[i].as_deref());
                    if let Some(c) = Cell::downsample(p, refs) {
                        built.push(p);
                        map.insert(p, Arc::new(c));
                    }
                }
            }
            parents = built;
        }
    }

    /// Loads or bakes `blocks` in order, telling the progress callback.
    fn run(&self, blocks: Vec<IVec2>) -> Result<BakeReport, String> {
        let mut report = BakeReport::default();
        let total = blocks.len();
        for (i, b) in blocks.into_iter().enumerate() {
            if self.stop.load(Ordering::Relaxed) {
                break;
            }
            if !self.has_block(b) {
                self.load_block(b, true, &mut report);
            }
            if let Some(p) = &self.progress {
                p(i + 1, total);
            }
        }
        match self.error.lock().ok().and_then(|e| e.clone()) {
            Some(e) => Err(e),
            None => Ok(report),
        }
    }

    /// Makes everything `camera` wants present: near blocks baked, far
    /// cached blocks read. Returns whether anything changed.
    fn prepare(&self, camera: Vec2, bake_near: bool) -> bool {
        let (near, far) = self.wanted_blocks(camera);
        let mut report = BakeReport::default();
        let todo: Vec<IVec2> = near.into_iter().filter(|b| !self.has_block(*b)).collect();
        let total = todo.len();
        for (i, b) in todo.into_iter().enumerate() {
            if self.stop.load(Ordering::Relaxed) {
                return true;
            }
            self.load_block(b, bake_near, &mut report);
            if bake_near && let Some(p) = &self.progress {
                p(i + 1, total);
            }
        }
        for b in far {
            if self.stop.load(Ordering::Relaxed) {
                break;
            }
            if !self.has_block(b) {
                self.load_block(b, false, &mut report);
            }
        }
        self.trim(camera);
        report.baked + report.cached > 0
    }

    /// Drops cells farther than [`KEEP_RADIUS`] from memory.
    fn trim(&self, camera: Vec2) {
        if let Ok(mut map) = self.cells.write() {
            let origin = self.world.origin;
            map.retain(|k, _| cell_distance(*k, origin, camera) <= KEEP_RADIUS);
        }
    }

    /// Whether `camera` needs a [`Self::prepare`]: a block it wants near is
    /// missing, or it left `done_for`'s block (far cached blocks to read).
    fn needs(&self, camera: Vec2, done_for: Option<IVec2>) -> bool {
        done_for != Some(self.block_of(camera))
            || self
                .wanted_blocks(camera)
                .0
                .iter()
                .any(|b| !self.has_block(*b))
    }

    /// The nearest block under the wanted mip-3/4 cells that is not held.
    fn next_far(&self, camera: Vec2) -> Option<IVec2> {
        self.wanted_blocks(camera)
            .1
            .into_iter()
            .find(|b| !self.has_block(*b))
    }

    /// The background thread: waits for a camera, prepares around it
    /// whenever [`Self::needs`] says so, and in between bakes the far
    /// blocks one at a time (nearest first), so mips 3 and 4 fill in.
    fn serve(&self) {
        crate::scene::world::stream::lower_priority();
        let mut done_for: Option<IVec2> = None;
        loop {
            let camera = {
                let Ok(mut cam) = self.camera.lock() else {
                    return;
                };
                loop {
                    if self.stop.load(Ordering::Relaxed) {
                        return;
                    }
                    if let Some(c) = *cam
                        && (self.needs(c, done_for) || self.next_far(c).is_some())
                    {
                        break c;
                    }
                    cam = match self.wake.wait(cam) {
                        Ok(c) => c,
                        Err(_) => return,
                    };
                }
            };
            if self.needs(camera, done_for) {
                done_for = Some(self.block_of(camera));
                self.prepare(camera, true);
            } else if let Some(b) = self.next_far(camera) {
                self.load_block(b, true, &mut BakeReport::default());
            }
        }
    }

    fn block_of(&self, camera: Vec2) -> IVec2 {
        ((camera - self.world.origin) / (BLOCK as f32 * SECTOR_SIZE))
            .floor()
            .as_ivec2()
    }
}

impl CellSource for WorldProbes {
    fn origin(&self) -> Vec2 {
        self.shared.world.origin
    }

    fn contains(&self, key: CellKey) -> bool {
        self.shared.cells.read().is_ok_and(|c| c.contains_key(&key))
    }

    fn fetch(&self, key: CellKey) -> Option<Arc<Cell>> {
        self.shared.cells.read().ok()?.get(&key).cloned()
    }

    /// Without a background thread, bakes what the camera wants before
    /// returning (a frame that needs nothing new costs 16 lookups).
    fn follow(&self, camera: Vec2) {
        let s = &self.shared;
        let running = self.background.lock().is_ok_and(|t| t.is_some());
        let Ok(mut cam) = s.camera.lock() else {
            return;
        };
        let before = cam.map(|c| s.block_of(c));
        *cam = Some(camera);
        drop(cam);
        if running {
            s.wake.notify_all();
        } else if s.needs(camera, before) {
            s.prepare(camera, true);
        }
    }

    fn held(&self) -> usize {
        self.shared.cells.read().map_or(0, |c| c.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::passes::indirect::Transfer;
    use crate::passes::indirect::cell::PROBES_PER_CELL;

    fn empty(key: CellKey) -> Cell {
        Cell {
            key,
            heights: [0.0; PROBES_PER_CELL],
            probes: vec![Transfer::default(); PROBES_PER_CELL],
        }
    }

    #[test]
    fn coarser_cells_appear_when_all_their_children_do_and_far_cells_leave_memory() {
        let world = Arc::new(World::new(Default::default()));
        let probes = WorldProbes::new(world.clone(), world_bake_settings(), None, None).unwrap();
        let s = &probes.shared;
        // Three of a mip-1 cell's four children: no parent yet.
        let parent = CellKey {
            mip: 1,
            x: 40,
            z: 40,
        };
        let kids = parent.children();
        s.insert(kids[..3].iter().map(|k| empty(*k)).collect());
        assert!(!probes.contains(parent));
        s.insert(vec![empty(kids[3])]);
        assert!(probes.contains(parent));
        // A whole 64 x 64-sector corner (4 km), then the camera at the far corner.
        let corner: Vec<Cell> = (0..64 * 64)
            .map(|k| {
                empty(CellKey {
                    mip: 0,
                    x: k % 64,
                    z: k / 64,
                })
            })
            .collect();
        s.insert(corner);
        assert!(probes.contains(CellKey { mip: 4, x: 3, z: 3 }));
        let before = probes.held();
        s.trim(world.origin + Vec2::splat(10_000.0));
        assert_eq!(probes.held(), 0, "all {before} cells are over 3 km away");
        // Near the corner, only cells within KEEP_RADIUS stay.
        s.insert(
            (0..64 * 64)
                .map(|k| {
                    empty(CellKey {
                        mip: 0,
                        x: k % 64,
                        z: k / 64,
                    })
                })
                .collect(),
        );
        let camera = world.origin + Vec2::splat(100.0);
        s.trim(camera);
        let kept = s.cells.read().unwrap();
        assert!(kept.len() < before);
        assert!(
            kept.keys()
                .all(|k| cell_distance(*k, world.origin, camera) <= KEEP_RADIUS)
        );
    }
}
