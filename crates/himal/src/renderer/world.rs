//! The streamed world in the renderer (`--scene world`): each frame the
//! streamer's changes become object records and culling bounds in the
//! scene's pool regions (one per instance kind, two per tree kind: its
//! trunk and its leaves), and the regions' live
//! counts become the culling chunks' counts. Sector generation runs on the
//! streamer's workers; this thread only copies what changed.

use std::sync::Arc;
use std::time::Duration;

use glam::{Vec2, Vec3};

use super::*;
use crate::clock::{Span, Stopwatch};
use crate::gpu_scene::{OBJECT_TINTED, ObjectBounds, ObjectGpu};
use crate::passes::cull::CullPass;
use crate::passes::terrain::{TerrainDesc, TerrainLayerDesc, TerrainPass};
use crate::scene::world::stream::{StreamStats, StreamUpdate, Streamer};
use crate::scene::world::{Instance, InstanceKind, World, forest};
use crate::scene::{Aabb, Foliage, lod};

/// L2's depth range below the lowest coarse height and above the highest
/// (m): tiles between coarse points, and the tallest house on a peak.
const SKYOCC_BELOW: f32 = 50.0;
const SKYOCC_ABOVE: f32 = 100.0;

/// One frame of the streamed world, as [`Renderer::draw`] reports it.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldFrame {
    /// The streamer's figures for this frame (sectors wanted, missing, resident...).
    pub stream: StreamStats,
    /// Render-thread milliseconds of streaming (inside `CpuTimes::plan_ms`).
    pub stream_ms: f64,
    /// The same by phase, on the wall clock and the thread's CPU clock.
    pub stream_times: StreamTimes,
    /// The terrain's CDLOD selection for the camera and the cascades.
    pub terrain: Option<crate::passes::terrain::TerrainStats>,
}

/// The render thread's streaming in one frame, by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamTimes {
    /// The streamer's update: releases, placement, requests.
    pub update: Span,
    /// Terrain tiles freed and written.
    pub tiles: Span,
    /// Object records and culling bounds of the changed pool slots.
    pub records: Span,
    /// L2 and S2 told which areas the new sectors cover.
    pub follow: Span,
    /// All of it (`WorldFrame::stream_ms` is its wall time).
    pub total: Span,
}

/// The world's streaming state between frames: the streamer and what the
/// pool records need of each kind's mesh.
pub struct WorldState {
    /// Streams the world's sectors around the camera (generation on its workers).
    pub streamer: Streamer,
    /// The last applied update's figures ...
    pub stats: StreamStats,
    /// ... and the render thread's time for it (update and pool writes, ms) ...
    pub stream_ms: f64,
    /// ... by phase.
    pub stream_times: StreamTimes,
    /// Per kind: its pool regions (a tree's trunk and leaves).
    regions: Vec<Vec<RegionRecords>>,
}

/// What the records of one pool region need: the region (its index in
/// `SceneGpu::pool`), its mesh's bounds and geometric-mean triangle area
/// (E2), and its foliage (leaves: vegetation parameters, bounds grown by
/// the sway).
struct RegionRecords {
    region: usize,
    bounds: Aabb,
    area: f32,
    foliage: Option<Foliage>,
}

impl WorldState {
    /// A streamer over `world` with nothing resident yet; `scene` is the
    /// world's scene (`World::scene`: its meshes as [`forest::regions`] lays them out).
    pub fn new(world: Arc<World>, scene: &Scene) -> Self {
        let mut regions: Vec<Vec<RegionRecords>> =
            InstanceKind::ALL.iter().map(|_| Vec::new()).collect();
        for (region, r) in forest::regions().into_iter().enumerate() {
            let Some(m) = scene.meshes.get(r.mesh) else {
                continue;
            };
            regions[r.kind as usize].push(RegionRecords {
                region,
                bounds: m.bounds,
                area: lod::geometric_mean_area(&m.vertices, &m.indices),
                foliage: r.leaves.then(|| forest::foliage(m)),
            });
        }
        WorldState {
            streamer: Streamer::new(world),
            stats: StreamStats::default(),
            stream_ms: 0.0,
            stream_times: StreamTimes::default(),
            regions,
        }
    }

    /// The GPU record and culling bounds of `instance` in region `r`.
    fn records(r: &RegionRecords, i: &Instance) -> (ObjectGpu, ObjectBounds) {
        let m = i.transform();
        let t = i.tint.map(|c| c as f32 / 255.0);
        let (params, margin) = match r.foliage {
            // Swaying cards reach up to their amplitude (scaled) beyond the mesh.
            Some(f) => (f.params(), f.sway * i.size.max_element()),
            None => ([OBJECT_TINTED, t[0], t[1], t[2]], 0.0),
        };
        let object = ObjectGpu::new(m, m, params);
        let b = r.bounds.transform(&m);
        let b = Aabb::new(b.min - Vec3::splat(margin), b.max + Vec3::splat(margin));
        let b = ObjectBounds::new(&b, lod::object_size(r.area, &m), lod::linear_scale(&m));
        (object, b)
    }

    /// Writes `u`'s dirty slots into `scene`'s pool regions (runs of consecutive slots, one write each)
    /// and the regions' live counts.
    pub fn apply(
        &mut self,
        u: &StreamUpdate,
        scene: &SceneGpu,
        cull: &mut CullPass,
        terrain: Option<&TerrainPass>,
        queue: &wgpu::Queue,
    ) -> Result<(), GpuError> {
        let tiles = Stopwatch::start();
        // Freed tiles first: an upload this frame may reuse the slot.
        if let Some(t) = terrain {
            for e in &u.evictions {
                t.evict(queue, e.tile)?;
            }
            for up in &u.uploads {
                let c = up.data.coord;
                t.upload_tile(queue, up.tile, c.x.into(), c.z.into(), &up.data.heights)?;
            }
        }
        self.stream_times.tiles = tiles.span();
        let records = Stopwatch::start();
        for (k, dirty) in u.dirty.iter().enumerate() {
            let Some(&kind) = InstanceKind::ALL.get(k) else {
                continue;
            };
            let live = u.live.get(k).copied().unwrap_or(0);
            // Slot s of the kind is slot s of each of its regions.
            for r in &self.regions[k] {
                let Some(region) = scene.pool.get(r.region) else {
                    continue;
                };
                let mut run: Vec<(ObjectGpu, ObjectBounds)> = Vec::new();
                let mut start = 0u32;
                let flush =
                    |start: u32, run: &mut Vec<(ObjectGpu, ObjectBounds)>, cull: &mut CullPass| {
                        if run.is_empty() {
                            return;
                        }
                        let first = region.first_object + start;
                        let (objects, bounds): (Vec<ObjectGpu>, Vec<ObjectBounds>) =
                            run.drain(..).unzip();
                        scene.write_objects(queue, first, &objects);
                        cull.write_bounds(queue, first, &bounds);
                    };
                for &slot in dirty.iter().filter(|&&s| s < region.capacity) {
                    if !run.is_empty() && slot != start + run.len() as u32 {
                        flush(start, &mut run, cull);
                    }
                    if run.is_empty() {
                        start = slot;
                    }
                    let record = match self.streamer.instance(kind, slot).filter(|_| slot < live) {
                        Some(i) => Self::records(r, i),
                        None => (bytemuck::Zeroable::zeroed(), ObjectBounds::NONE),
                    };
                    run.push(record);
                }
                flush(start, &mut run, cull);
                cull.set_live(queue, r.region, live.min(region.capacity));
            }
        }
        self.stream_times.records = records.span();
        self.stats = u.stats;
        Ok(())
    }
}

/// The CDLOD terrain of `world`: its whole coarse grid (computed here on
/// the machine's cores), an empty tile pool of the scene file's size.
fn terrain_desc(world: &World) -> TerrainDesc {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    TerrainDesc {
        origin: world.origin,
        sectors: world.desc.sectors.into(),
        sector_size: crate::scene::world::SECTOR_SIZE,
        tile_res: crate::scene::world::TILE_RES as u32,
        coarse_spacing: world.desc.coarse_spacing,
        coarse: world.coarse_grid(threads, &|_| {}),
        fine_slots: world.desc.pools.tiles,
        layers: TerrainLayerDesc::for_world(world),
    }
}

/// The pool regions of `world`'s scene ([`forest::regions`]): one per kind
/// (its mesh is the kind's; a tree kind's trunk, opaque) and per tree kind
/// its leaves (vegetation, with the leaves' foliage parameters), each of the
/// kind's size in the scene file, culled at the kind's draw distance.
/// `scene`: [`World::scene`].
pub fn world_pools(world: &World, scene: &Scene) -> Vec<crate::gpu_scene::PoolSpec> {
    forest::regions()
        .into_iter()
        .map(|r| crate::gpu_scene::PoolSpec {
            mesh: r.mesh,
            capacity: world.desc.pools.instances[r.kind as usize],
            max_distance: r.kind.draw_distance(),
            foliage: (r.leaves)
                .then(|| scene.meshes.get(r.mesh).map(forest::foliage))
                .flatten(),
            vegetation: r.kind.species().is_some(),
        })
        .collect()
}

impl Renderer {
    /// A renderer for the streamed `world` (`--scene world`): its meshes and
    /// fixed pools uploaded, nothing resident until the first frame (or
    /// [`Renderer::settle_world`]).
    pub fn with_world(ctx: GpuContext, world: Arc<World>) -> Result<Self, Error> {
        let scene = world.scene();
        let scene_gpu = SceneGpu::upload_with_pool(&ctx, &scene, &world_pools(&world, &scene))?;
        let desc = terrain_desc(&world);
        let terrain = TerrainPass::new(&ctx, &desc)?;
        let mut r = Self::from_upload(ctx, &scene, scene_gpu)?;
        r.res.passes.terrain = Some(terrain);
        // L2 samples the terrain; its depth range holds the ground (the
        // coarse grid, with room for tiles between its points) and what
        // stands on it.
        let (lo, hi) = (desc.coarse.iter())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            });
        let skyocc = &mut r.res.passes.skyocc;
        skyocc.attach_terrain(&r.ctx, (lo - SKYOCC_BELOW, hi + SKYOCC_ABOVE))?;
        // S2 holds the same casters in a camera-centred map.
        (r.res.passes.shadows).attach_world((lo - SKYOCC_BELOW, hi + SKYOCC_ABOVE));
        r.world = Some(WorldState::new(world, &scene));
        Ok(r)
    }

    /// Streams every sector around `camera` in (blocking, up to
    /// `timeout`) so the next frame is complete and the same on every run.
    pub fn settle_world(
        &mut self,
        camera: &Camera,
        timeout: Duration,
    ) -> Result<Option<StreamStats>, Error> {
        let eye = Vec2::new(camera.position.x, camera.position.z);
        let stats = self.stream_with(|s| s.settle(eye, timeout))?;
        // The static map completes in the next frame too.
        self.res.passes.shadows.settle();
        Ok(stats)
    }

    /// One frame of streaming for `camera` (inside `plan_frame`).
    pub(super) fn stream_world(&mut self, camera: &Camera) -> Result<(), Error> {
        let eye = Vec2::new(camera.position.x, camera.position.z);
        self.stream_with(|s| s.update(eye)).map(drop)
    }

    /// Runs `step` on the streamer and applies its update to the pools.
    fn stream_with(
        &mut self,
        step: impl FnOnce(&mut Streamer) -> StreamUpdate,
    ) -> Result<Option<StreamStats>, Error> {
        let Some(w) = self.world.as_mut() else {
            return Ok(None);
        };
        let total = Stopwatch::start();
        let u = step(&mut w.streamer);
        w.stream_times.update = total.span();
        let p = &mut self.res.passes;
        let terrain = p.terrain.as_ref();
        w.apply(&u, &self.res.scene, &mut p.cull, terrain, &self.ctx.queue)?;
        // L2 follows the streaming: sky-occlusion sectors rendered before a
        // neighbouring world sector arrived are rendered again.
        let world = w.streamer.world();
        let follow = Stopwatch::start();
        // So does S2: the static-map tiles under a sector's ground and what
        // stands on it.
        for up in &u.uploads {
            let d = &up.data;
            let min = crate::scene::world::sector::sector_origin(world.origin, d.coord);
            let max = min + crate::scene::world::SECTOR_SIZE;
            p.skyocc.refresh(min, max);
            let top = d.max_height + crate::passes::shadows::world_map::OBJECT_HEADROOM;
            p.shadows.refresh(&Aabb::new(
                Vec3::new(min.x, d.min_height, min.y),
                Vec3::new(max.x, top, max.y),
            ));
        }
        w.stream_times.follow = follow.span();
        w.stream_times.total = total.span();
        w.stream_ms = w.stream_times.total.wall_ms;
        Ok(Some(w.stats))
    }

    /// Subscribes `listener` to the world's streaming (the hook sector-based
    /// techniques follow it by, e.g. L5 probes); `false`: not a world.
    pub fn add_sector_listener(
        &mut self,
        listener: Box<dyn crate::scene::world::stream::SectorListener>,
    ) -> bool {
        match self.world.as_mut() {
            Some(w) => {
                w.streamer.add_listener(listener);
                true
            }
            None => false,
        }
    }

    /// The last frame's streaming figures (`None`: not a world).
    pub fn world_stats(&self) -> Option<StreamStats> {
        self.world.as_ref().map(|w| w.stats)
    }

    /// The streamed world, shared (`None`: a plain scene).
    pub fn shared_world(&self) -> Option<Arc<World>> {
        self.world.as_ref().map(|w| w.streamer.shared_world())
    }

    /// The streamed world (`None`: a plain scene).
    pub fn world(&self) -> Option<&World> {
        self.world.as_ref().map(|w| w.streamer.world())
    }
}
