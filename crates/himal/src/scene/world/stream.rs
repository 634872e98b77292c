//! Sector streaming: which sectors the camera wants, generated on worker
//! threads (never on the caller's thread), placed into fixed pools under a
//! per-frame upload budget, farthest first out when a pool is full.
//!
//! [`Streamer::update`] is called once per frame with the camera's (x, z);
//! it returns the uploads and evictions for the renderer to apply to the
//! GPU pools and the figures `bench --path` prints. Work per call is
//! bounded by the wanted disc (about (2 r / 64)^2 sectors), never the world.

use std::collections::{HashMap, HashSet};
use std::sync::mpsc::{Receiver, RecvTimeoutError, Sender, channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use glam::Vec2;

use super::pool::{DensePool, SlotPool};
use super::{Instance, InstanceKind, SECTOR_SIZE, SectorCoord, SectorData, World};

/// Runs the calling thread at the lowest scheduling priority (Linux: a
/// thread's nice value is its own), so sector generation never takes the
/// render thread's core; elsewhere a no-op.
pub(crate) fn lower_priority() {
    #[cfg(target_os = "linux")]
    // SAFETY: setpriority with PRIO_PROCESS and who = 0 changes only the
    // calling thread's nice value; a failure leaves it unchanged.
    unsafe {
        libc::setpriority(libc::PRIO_PROCESS, 0, 19);
    }
}

/// Requests outstanding per worker at most: deep enough that slow frames
/// (software adapters, benches) do not starve the workers, short enough
/// that requests stay nearest-first as the camera moves.
pub const MAX_IN_FLIGHT_PER_WORKER: usize = 16;

/// Instance kinds (one dense pool region each).
pub const KINDS: usize = InstanceKind::ALL.len();

/// Where a resident sector lives in the GPU pools.
#[derive(Clone, Debug)]
pub struct Residency {
    /// The generated sector: heights and instances.
    pub data: Arc<SectorData>,
    /// Layer of the terrain tile array.
    pub tile: u32,
    /// Per kind: the indices into `data.instances` of that kind, in order ...
    pub by_kind: Vec<Vec<u32>>,
    /// ... and the slot of each in the kind's pool region (moves as other
    /// sectors leave).
    pub slots: Vec<Vec<u32>>,
}

/// A sector whose terrain tile to write (its instances are in `dirty`).
#[derive(Clone, Debug)]
pub struct Upload {
    /// The sector to write.
    pub data: Arc<SectorData>,
    /// Layer of the terrain tile array to write its heights into.
    pub tile: u32,
}

/// A sector whose tile is free again.
#[derive(Clone, Debug, PartialEq)]
pub struct Eviction {
    /// The sector released.
    pub coord: SectorCoord,
    /// The tile array layer it held.
    pub tile: u32,
}

/// This frame's streaming figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamStats {
    /// Sectors within the streaming radius of the camera.
    pub wanted: u32,
    /// Wanted sectors not yet resident.
    pub missing: u32,
    /// Sectors in the pools after this update.
    pub resident: u32,
    /// Requested from the workers, not yet applied.
    pub in_flight: u32,
    /// Terrain tile layers in use.
    pub tiles_used: u32,
    /// Terrain tile layers in the pool (its capacity).
    pub tiles_total: u32,
    /// Live instances in all kinds' regions.
    pub instances: u32,
    /// Of those, trees (the kinds with a species: V1's forests).
    pub trees: u32,
    /// Instance slots in all kinds' regions (the pools' capacity).
    pub instances_total: u32,
    /// Instance slots rewritten this frame (new, moved or emptied).
    pub instance_writes: u32,
    /// Sectors placed in the pools this frame.
    pub uploaded: u32,
    /// Bytes those sectors upload (heights and instance records): at most the
    /// per-frame budget, except that one sector always passes.
    pub upload_bytes: u64,
    /// Sectors released this frame.
    pub evicted: u32,
    /// Wanted sectors beyond the pools' capacity (the radius is too large for them).
    pub over_capacity: u32,
    /// Time `update` itself took on the calling thread (seconds).
    pub cpu_s: f64,
}

/// The frame's work for the renderer.
#[derive(Clone, Debug, Default)]
pub struct StreamUpdate {
    /// Sectors released this frame; apply them before the uploads, which may reuse their tiles.
    pub evictions: Vec<Eviction>,
    /// Sectors placed this frame: their terrain tiles to write.
    pub uploads: Vec<Upload>,
    /// Per kind: slots whose content changed, sorted, once each; a slot at
    /// or beyond `live[kind]` is empty now ([`Streamer::instance`]).
    pub dirty: Vec<Vec<u32>>,
    /// Per kind: live instances (packed at the front of the region).
    pub live: Vec<u32>,
    /// This frame's figures.
    pub stats: StreamStats,
}

/// What follows the streaming, sector by sector (L5 probes, L2 sky
/// occlusion, S2 static shadows): told of every sector placed in the
/// pools and every one released, in the order the renderer applies them
/// (releases of an update first). No GPU here: a listener queues its own
/// work for its pass's planning.
pub trait SectorListener: Send {
    /// A sector was placed in the pools (called after this update's evictions).
    fn loaded(&mut self, sector: &Arc<SectorData>);
    /// A sector was released from the pools.
    fn evicted(&mut self, sector: SectorCoord);
}

/// Streams `world`'s sectors around a moving camera.
pub struct Streamer {
    world: Arc<World>,
    requests: Option<Sender<SectorCoord>>,
    results: Receiver<SectorData>,
    workers: Vec<JoinHandle<()>>,
    resident: HashMap<SectorCoord, Residency>,
    in_flight: HashSet<SectorCoord>,
    ready: Vec<SectorData>,
    max_in_flight: usize,
    tiles: SlotPool,
    kinds: Vec<DensePool<SectorCoord>>,
    listeners: Vec<Box<dyn SectorListener>>,
}

impl Drop for Streamer {
    fn drop(&mut self) {
        // Closing the request channel ends every worker's loop.
        self.requests = None;
        for w in self.workers.drain(..) {
            let _ = w.join();
        }
    }
}

impl Streamer {
    /// Starts the worker threads; nothing is resident yet.
    pub fn new(world: Arc<World>) -> Streamer {
        let pools = world.desc.pools;
        let workers = super::worker_count(world.desc.stream.workers);
        let (request_tx, request_rx) = channel::<SectorCoord>();
        let (result_tx, results) = channel::<SectorData>();
        let request_rx = Arc::new(Mutex::new(request_rx));
        let workers: Vec<JoinHandle<()>> = (0..workers)
            .map(|i| {
                let (world, rx, tx) = (world.clone(), request_rx.clone(), result_tx.clone());
                std::thread::Builder::new()
                    .name(format!("himal-sector-{i}"))
                    .spawn(move || {
                        lower_priority();
                        loop {
                            // The lock is held only to take one request.
                            let next = rx.lock().map(|r| r.recv());
                            let Ok(Ok(c)) = next else { break };
                            if tx.send(world.sector(c)).is_err() {
                                break;
                            }
                        }
                    })
                    .ok()
            })
            .collect::<Option<Vec<_>>>()
            .unwrap_or_default();
        let max_in_flight = MAX_IN_FLIGHT_PER_WORKER * workers.len().max(1);
        Streamer {
            world,
            requests: Some(request_tx),
            results,
            workers,
            resident: HashMap::new(),
            in_flight: HashSet::new(),
            ready: Vec::new(),
            max_in_flight,
            tiles: SlotPool::new(pools.tiles),
            kinds: pools.instances.iter().map(|&n| DensePool::new(n)).collect(),
            listeners: Vec::new(),
        }
    }

    /// Adds `listener`, first told of every sector resident now (in
    /// sector order), then of each update's changes.
    pub fn add_listener(&mut self, mut listener: Box<dyn SectorListener>) {
        let mut now: Vec<&Residency> = self.resident.values().collect();
        now.sort_by_key(|r| r.data.coord);
        for r in now {
            listener.loaded(&r.data);
        }
        self.listeners.push(listener);
    }

    fn notify(&mut self, u: &StreamUpdate) {
        for l in &mut self.listeners {
            for e in &u.evictions {
                l.evicted(e.coord);
            }
            for up in &u.uploads {
                l.loaded(&up.data);
            }
        }
    }

    /// The world being streamed, shared (L5's bake generates its sectors too).
    pub fn shared_world(&self) -> Arc<World> {
        self.world.clone()
    }

    /// The world being streamed.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Resident sectors and where they live.
    pub fn resident(&self) -> &HashMap<SectorCoord, Residency> {
        &self.resident
    }

    /// The instance in `kind`'s region at `slot`; `None` past the live ones.
    pub fn instance(&self, kind: InstanceKind, slot: u32) -> Option<&Instance> {
        let (c, i) = self.kinds.get(kind as usize)?.owner(slot)?;
        let r = self.resident.get(&c)?;
        let at = *r.by_kind.get(kind as usize)?.get(i as usize)?;
        r.data.instances.get(at as usize)
    }

    /// Capacity of each kind's region.
    pub fn capacities(&self) -> Vec<u32> {
        self.kinds.iter().map(|k| k.capacity()).collect()
    }

    /// Whether the worker threads started (none where the platform has no threads).
    pub fn has_workers(&self) -> bool {
        !self.workers.is_empty()
    }

    /// Sectors within the stream radius of `eye`, nearest first (ties by
    /// coordinate), at most as many as the tile pool holds; and how many
    /// more there were.
    pub fn wanted(&self, eye: Vec2) -> (Vec<(f32, SectorCoord)>, u32) {
        self.disc(eye, self.world.desc.stream.radius)
    }

    fn disc(&self, eye: Vec2, radius: f32) -> (Vec<(f32, SectorCoord)>, u32) {
        let w = &self.world;
        let n = w.desc.sectors as i64;
        let cell = |v: f32| ((v / SECTOR_SIZE).floor() as i64).clamp(0, n - 1);
        let lo = (eye - w.origin - radius).to_array().map(cell);
        let hi = (eye - w.origin + radius).to_array().map(cell);
        let mut out = Vec::new();
        for z in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                let c = SectorCoord {
                    x: x as u16,
                    z: z as u16,
                };
                let d = w.sector_distance(c, eye);
                if d <= radius {
                    out.push((d, c));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let cap = self.tiles.capacity() as usize;
        let over = out.len().saturating_sub(cap) as u32;
        out.truncate(cap);
        (out, over)
    }

    /// One frame of streaming for a camera at (x, z) = `eye`.
    pub fn update(&mut self, eye: Vec2) -> StreamUpdate {
        let t0 = Instant::now();
        let mut u = StreamUpdate::default();
        self.release_far(eye, &mut u);
        self.collect();
        self.apply_ready(eye, self.world.desc.stream.upload_budget, &mut u);
        let (wanted, over) = self.wanted(eye);
        self.request(&wanted);
        self.finish_stats(&wanted, over, &mut u);
        self.notify(&u);
        u.stats.cpu_s = t0.elapsed().as_secs_f64();
        u
    }

    /// Blocks until every wanted sector around `eye` is resident (or
    /// `timeout` passes), ignoring the upload budget; results are applied
    /// nearest first, so a settled frame is the same on every run.
    pub fn settle(&mut self, eye: Vec2, timeout: Duration) -> StreamUpdate {
        let t0 = Instant::now();
        let mut u = StreamUpdate::default();
        self.release_far(eye, &mut u);
        let (wanted, over) = self.wanted(eye);
        // Waves: request the nearest missing, wait for every outstanding
        // request, apply them sorted; the same on every run from a fresh start.
        'waves: loop {
            let missing: Vec<(f32, SectorCoord)> = wanted
                .iter()
                .copied()
                .filter(|(_, c)| !self.resident.contains_key(c))
                .collect();
            if missing.is_empty() || !self.has_workers() {
                break;
            }
            self.request(&missing);
            while self.ready.len() < self.in_flight.len() {
                if t0.elapsed() > timeout {
                    break 'waves;
                }
                match self.results.recv_timeout(Duration::from_millis(50)) {
                    Ok(d) => self.ready.push(d),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => break 'waves,
                }
            }
            self.apply_ready(eye, u64::MAX, &mut u);
        }
        self.finish_stats(&wanted, over, &mut u);
        self.notify(&u);
        u.stats.cpu_s = t0.elapsed().as_secs_f64();
        u
    }

    fn release_far(&mut self, eye: Vec2, u: &mut StreamUpdate) {
        let s = self.world.desc.stream;
        let keep = s.radius + s.unload_margin;
        let mut far: Vec<(f32, SectorCoord)> = self
            .resident
            .keys()
            .map(|&c| (self.world.sector_distance(c, eye), c))
            .filter(|(d, _)| *d > keep)
            .collect();
        far.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        for (_, c) in far {
            self.evict(c, u);
        }
    }

    fn evict(&mut self, c: SectorCoord, u: &mut StreamUpdate) {
        let Some(r) = self.resident.remove(&c) else {
            return;
        };
        self.tiles.free(r.tile);
        u.dirty.resize(KINDS, Vec::new());
        for (k, slots) in r.slots.iter().enumerate() {
            let resident = &mut self.resident;
            self.kinds[k].remove(slots, &mut u.dirty[k], |owner, i, slot| {
                if let Some(o) = resident.get_mut(&owner) {
                    o.slots[k][i as usize] = slot;
                }
            });
        }
        u.evictions.push(Eviction {
            coord: c,
            tile: r.tile,
        });
    }

    /// Takes finished sectors from the workers without waiting.
    fn collect(&mut self) {
        while let Ok(d) = self.results.try_recv() {
            self.ready.push(d);
        }
    }

    /// Places ready sectors nearest first while `budget` bytes last (the
    /// first always goes); a full pool evicts the farthest resident that
    /// is farther than the newcomer.
    fn apply_ready(&mut self, eye: Vec2, budget: u64, u: &mut StreamUpdate) {
        let s = self.world.desc.stream;
        let keep = s.radius + s.unload_margin;
        let world = self.world.clone();
        let mut ready: Vec<(f32, SectorData)> = self
            .ready
            .drain(..)
            .map(|d| (world.sector_distance(d.coord, eye), d))
            .collect();
        ready.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.coord.cmp(&b.1.coord)));
        let mut spent = 0u64;
        let mut waiting = Vec::new();
        for (d, data) in ready {
            if d > keep || self.resident.contains_key(&data.coord) {
                // Flown past before it arrived: dropped, may be asked for again.
                self.in_flight.remove(&data.coord);
                continue;
            }
            let bytes = data.upload_bytes();
            if u.uploads.len() as u64 > 0 && spent + bytes > budget {
                waiting.push(data);
                continue;
            }
            let mut by_kind = vec![Vec::new(); KINDS];
            for (i, inst) in data.instances.iter().enumerate() {
                by_kind[inst.kind as usize].push(i as u32);
            }
            let fits = |s: &Self| {
                s.tiles.available() > 0
                    && by_kind
                        .iter()
                        .zip(&s.kinds)
                        .all(|(v, k)| v.len() as u32 <= k.available())
            };
            let placed = loop {
                if fits(self) {
                    break self.tiles.alloc();
                }
                // Farthest resident first, only if it is farther than this one.
                let victim = self
                    .resident
                    .keys()
                    .map(|&c| (world.sector_distance(c, eye), c))
                    .filter(|(vd, _)| *vd > d)
                    .max_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
                match victim {
                    Some((_, c)) => self.evict(c, u),
                    None => break None,
                }
            };
            self.in_flight.remove(&data.coord);
            let Some(tile) = placed else {
                continue;
            };
            spent += bytes;
            u.dirty.resize(KINDS, Vec::new());
            let slots: Vec<Vec<u32>> = by_kind
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    let s = self.kinds[k]
                        .push(data.coord, v.len() as u32)
                        .unwrap_or_default();
                    u.dirty[k].extend_from_slice(&s);
                    s
                })
                .collect();
            let data = Arc::new(data);
            self.resident.insert(
                data.coord,
                Residency {
                    data: data.clone(),
                    tile,
                    by_kind,
                    slots,
                },
            );
            u.uploads.push(Upload { data, tile });
        }
        u.stats.upload_bytes += spent;
        self.ready = waiting;
    }

    /// Asks the workers for wanted sectors nearest first, keeping at most
    /// `max_in_flight` outstanding.
    fn request(&mut self, wanted: &[(f32, SectorCoord)]) {
        let Some(tx) = &self.requests else { return };
        for &(_, c) in wanted {
            if self.in_flight.len() >= self.max_in_flight {
                break;
            }
            if self.resident.contains_key(&c) || self.in_flight.contains(&c) {
                continue;
            }
            if tx.send(c).is_ok() {
                self.in_flight.insert(c);
            }
        }
    }

    fn finish_stats(&self, wanted: &[(f32, SectorCoord)], over: u32, u: &mut StreamUpdate) {
        u.dirty.resize(KINDS, Vec::new());
        for d in &mut u.dirty {
            d.sort_unstable();
            d.dedup();
        }
        u.live = self.kinds.iter().map(|k| k.live()).collect();
        let st = &mut u.stats;
        st.instance_writes = u.dirty.iter().map(|d| d.len() as u32).sum();
        st.wanted = wanted.len() as u32;
        st.missing = wanted
            .iter()
            .filter(|(_, c)| !self.resident.contains_key(c))
            .count() as u32;
        st.resident = self.resident.len() as u32;
        st.in_flight = self.in_flight.len() as u32;
        st.tiles_used = self.tiles.used();
        st.tiles_total = self.tiles.capacity();
        st.instances = self.kinds.iter().map(|k| k.live()).sum();
        st.trees = (InstanceKind::ALL.iter().zip(&self.kinds))
            .filter(|(kind, _)| kind.species().is_some())
            .map(|(_, k)| k.live())
            .sum();
        st.instances_total = self.kinds.iter().map(|k| k.capacity()).sum();
        st.uploaded = u.uploads.len() as u32;
        st.evicted = u.evictions.len() as u32;
        st.over_capacity = over;
    }
}
