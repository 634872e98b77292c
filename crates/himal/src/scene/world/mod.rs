//! The open world (`--scene world`): a 10.24 km square of 160 x 160
//! sectors of 64 m (Far Cry 4's sector grid and page table), generated
//! deterministically per sector from a seed and streamed around the camera.
//!
//! - [`terrain`]: the height function (mountains, river, levelled villages)
//!   or a user's 16-bit height map.
//! - [`sector`]: one sector's terrain tile and instances, on its own.
//! - [`stream`]: residency around the camera, worker threads, fixed pools,
//!   farthest-first eviction, a per-frame upload budget.
//! - [`path`]: named cameras and the flight path across the world.
//! - [`mod@file`]: a world from a scene file's `[world]` table.
//! - [`forest`]: the trees' meshes (V1) and the pool regions they fill.
//!
//! Nothing here touches the GPU; the renderer applies the uploads that
//! [`stream::Streamer::update`] hands it. See `docs/world.md`.

pub mod file;
pub mod forest;
pub mod meshes;
pub mod path;
pub mod pool;
pub mod sector;
pub mod stream;
pub mod terrain;

use std::sync::Arc;

use glam::{Vec2, Vec3};

pub use file::WorldFile;
pub use path::FlightPath;
pub use sector::{
    Instance, InstanceKind, PlacementRules, SECTOR_SIZE, SectorCoord, SectorData, TILE_RES,
};
pub use terrain::{HeightSource, Village, WorldShape, WorldTerrain};

use crate::scene::{Aabb, NamedCamera, Scene, SunDesc};

/// Aerial-perspective extinction (1/m) for a 10 km world: a third of the
/// light left at 14 km (the valley's default leaves a third at 4 km).
pub const HAZE_EXTINCTION: f32 = 8e-5;

/// Bytes of one instance as the GPU pool stores it: its object record
/// (model, normal and previous matrices, parameters) and its culling
/// bounds (checked against `gpu_scene`'s types there).
pub const GPU_INSTANCE_BYTES: usize = 208 + 32;

/// Sizes of the fixed GPU pools (set by the scene file).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PoolSizes {
    /// Terrain tiles (`TILE_RES`^2 heights each).
    pub tiles: u32,
    /// Instance slots per kind, in [`InstanceKind::ALL`] order (a tree
    /// kind's slots twice: its trunk and leaves regions).
    pub instances: [u32; InstanceKind::ALL.len()],
}

impl Default for PoolSizes {
    /// Room for the default 1 km radius (about 800 sectors) where forests
    /// and villages are densest, measured over the flight (docs/world.md).
    fn default() -> Self {
        PoolSizes {
            tiles: 1024,
            // rock0..2, house, roof, field, fence, larch, rosewood, water
            instances: [
                16384, 16384, 16384, 4096, 4096, 1024, 16384, 65536, 65536, 1024,
            ],
        }
    }
}

/// How sectors stream (set by the scene file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamSettings {
    /// Sectors whose rectangle lies within this distance of the camera (x, z) are wanted.
    pub radius: f32,
    /// Resident sectors are released beyond `radius + unload_margin` (hysteresis).
    pub unload_margin: f32,
    /// Worker threads generating sectors (0: the machine's cores, at most 8).
    pub workers: usize,
    /// Bytes handed to the GPU per frame at most (one sector always passes).
    pub upload_budget: u64,
}

impl Default for StreamSettings {
    fn default() -> Self {
        StreamSettings {
            radius: 1000.0,
            unload_margin: 128.0,
            workers: 0,
            upload_budget: 4 << 20,
        }
    }
}

/// Everything that defines a world.
#[derive(Clone, Debug)]
pub struct WorldDesc {
    /// Sectors per side (160: 10.24 km).
    pub sectors: u16,
    /// Parameters of the procedural height function (also the snow and tree lines for an image).
    pub shape: WorldShape,
    /// Procedural heights or a user's height map.
    pub source: HeightSource,
    /// What sectors place (rocks, trees, village parts).
    pub rules: PlacementRules,
    /// Streaming radius, workers and upload budget.
    pub stream: StreamSettings,
    /// Capacities of the fixed GPU pools.
    pub pools: PoolSizes,
    /// Spacing of the whole-world coarse height grid (a multiple of 1 m
    /// dividing the sector size), what terrain beyond the streamed tiles reads.
    pub coarse_spacing: f32,
}

impl Default for WorldDesc {
    fn default() -> Self {
        WorldDesc {
            sectors: 160,
            shape: WorldShape::default(),
            source: HeightSource::Procedural,
            rules: PlacementRules::default(),
            stream: StreamSettings::default(),
            pools: PoolSizes::default(),
            coarse_spacing: 16.0,
        }
    }
}

/// A world ready to generate sectors: its description and height function.
#[derive(Clone, Debug)]
pub struct World {
    /// The description it was made from.
    pub desc: WorldDesc,
    /// The height function, shared with the streaming workers.
    pub terrain: Arc<WorldTerrain>,
    /// Min corner (x, z); the world is centred on the origin.
    pub origin: Vec2,
    /// Cameras placed from the terrain ([`path::cameras`]), after any the
    /// scene file names ([`World::with_cameras`]).
    pub cameras: Vec<NamedCamera>,
    /// Camera flight paths; [`World::new`] adds one across the world.
    pub paths: Vec<FlightPath>,
    /// The sun [`World::scene`] gives the frame (the scene file's `[sun]`).
    pub sun: SunDesc,
}

impl World {
    /// A world from `desc`, centred on the origin, with terrain-placed cameras,
    /// the flight path and the default sun.
    pub fn new(desc: WorldDesc) -> World {
        let extent = desc.sectors as f32 * SECTOR_SIZE;
        let origin = Vec2::splat(-extent * 0.5);
        let terrain = Arc::new(WorldTerrain::new(
            desc.shape.clone(),
            desc.source.clone(),
            origin,
            extent,
        ));
        let mut w = World {
            desc,
            terrain,
            origin,
            cameras: Vec::new(),
            paths: Vec::new(),
            sun: SunDesc::default(),
        };
        w.cameras = path::cameras(&w);
        w.paths = vec![path::flight(&w)];
        w
    }

    /// `cameras` first (so the first is the default view), then the
    /// terrain-placed ones whose names they do not take.
    pub fn with_cameras(mut self, cameras: Vec<NamedCamera>) -> World {
        self.cameras
            .retain(|c| cameras.iter().all(|f| f.name != c.name));
        self.cameras.splice(0..0, cameras);
        self
    }

    /// Edge length in metres.
    pub fn extent(&self) -> f32 {
        self.desc.sectors as f32 * SECTOR_SIZE
    }

    /// Sector `c`, generated on its own.
    pub fn sector(&self, c: SectorCoord) -> SectorData {
        sector::generate(&self.terrain, &self.desc.rules, self.origin, c)
    }

    /// The sector under world (x, z), if inside the world.
    pub fn sector_at(&self, p: Vec2) -> Option<SectorCoord> {
        let l = (p - self.origin) / SECTOR_SIZE;
        let n = self.desc.sectors as f32;
        (l.x >= 0.0 && l.y >= 0.0 && l.x < n && l.y < n).then_some(SectorCoord {
            x: l.x as u16,
            z: l.y as u16,
        })
    }

    /// Distance in (x, z) from `p` to sector `c`'s rectangle (0 inside).
    pub fn sector_distance(&self, c: SectorCoord, p: Vec2) -> f32 {
        let lo = sector::sector_origin(self.origin, c);
        let hi = lo + Vec2::splat(SECTOR_SIZE);
        (p.clamp(lo, hi) - p).length()
    }

    /// Samples per side of the coarse grid.
    pub fn coarse_res(&self) -> usize {
        (self.extent() / self.desc.coarse_spacing).round() as usize + 1
    }

    /// The whole world's heights every `coarse_spacing` metres (row-major, z
    /// outer), computed on `threads` threads; `progress` gets rows done.
    pub fn coarse_grid(&self, threads: usize, progress: &(dyn Fn(usize) + Sync)) -> Vec<f32> {
        let n = self.coarse_res();
        let s = self.desc.coarse_spacing;
        let mut out = vec![0.0f32; n * n];
        let threads = threads.clamp(1, 16);
        let done = std::sync::atomic::AtomicUsize::new(0);
        let rows_per = n.div_ceil(threads);
        std::thread::scope(|scope| {
            for (t, chunk) in out.chunks_mut(rows_per * n).enumerate() {
                let (terrain, origin, done) = (&self.terrain, self.origin, &done);
                scope.spawn(move || {
                    for (r, row) in chunk.chunks_mut(n).enumerate() {
                        let z = origin.y + (t * rows_per + r) as f32 * s;
                        for (i, h) in row.iter_mut().enumerate() {
                            *h = terrain.height(origin.x + i as f32 * s, z);
                        }
                        let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                        progress(d);
                    }
                });
            }
        });
        out
    }
}

impl World {
    /// The world as a [`Scene`] for the renderer: its shared meshes (one per
    /// [`InstanceKind`], a tree kind's trunk, then the tree kinds' leaves:
    /// [`forest::regions`]), the trees' impostors, its cameras, its sun and
    /// its bounds; no objects of its own (instances stream).
    pub fn scene(&self) -> Scene {
        let (meshes, impostors) = meshes::world_meshes();
        let half = self.extent() * 0.5;
        let (bottom, top) = match &self.desc.source {
            HeightSource::Procedural => (
                0.0,
                self.desc.shape.mountain_height + self.desc.shape.hill_height + 200.0,
            ),
            HeightSource::Image(g) => g.heights.iter().fold((0.0f32, 200.0f32), |(lo, hi), &h| {
                (lo.min(h), hi.max(h + 200.0))
            }),
        };
        Scene {
            path: None,
            meshes,
            objects: Vec::new(),
            materials: Vec::new(),
            cameras: self.cameras.clone(),
            cinematic_shadows: None,
            sun: self.sun.clone(),
            lights: Vec::new(),
            ambient_lights: Vec::new(),
            emitters: Vec::new(),
            wind: crate::scene::DEFAULT_WIND,
            wind_sources: Vec::new(),
            tree_rigs: Vec::new(),
            bounds: Aabb::new(Vec3::new(-half, bottom, -half), Vec3::new(half, top, half)),
            pbr: Default::default(),
            probes: Vec::new(),
            environment: None,
            impostors,
            ao_volumes: Vec::new(),
        }
    }
}

/// Worker threads to use for `requested` (0: the machine's cores, at most 8).
pub fn worker_count(requested: usize) -> usize {
    if requested > 0 {
        return requested.min(64);
    }
    std::thread::available_parallelism().map_or(2, |n| n.get().min(8))
}
