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

use super::pool::SlotPool;
use super::{SECTOR_SIZE, SectorCoord, SectorData, World};

/// Where a resident sector lives in the GPU pools.
#[derive(Clone, Debug)]
pub struct Residency {
    pub data: Arc<SectorData>,
    /// Layer of the terrain tile array.
    pub tile: u32,
    /// Instance blocks (each `PoolSizes::block` records), in instance order.
    pub blocks: Vec<u32>,
}

/// A sector to write into the pools.
#[derive(Clone, Debug)]
pub struct Upload {
    pub data: Arc<SectorData>,
    pub tile: u32,
    pub blocks: Vec<u32>,
}

/// A sector whose pool entries are free again.
#[derive(Clone, Debug, PartialEq)]
pub struct Eviction {
    pub coord: SectorCoord,
    pub tile: u32,
    pub blocks: Vec<u32>,
}

/// This frame's streaming figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamStats {
    pub wanted: u32,
    /// Wanted sectors not yet resident.
    pub missing: u32,
    pub resident: u32,
    /// Requested from the workers, not yet applied.
    pub in_flight: u32,
    pub tiles_used: u32,
    pub tiles_total: u32,
    pub blocks_used: u32,
    pub blocks_total: u32,
    pub instances: u32,
    pub uploaded: u32,
    pub upload_bytes: u64,
    pub evicted: u32,
    /// Wanted sectors beyond the pools' capacity (the radius is too large for them).
    pub over_capacity: u32,
    /// Time `update` itself took on the calling thread (seconds).
    pub cpu_s: f64,
}

/// The frame's work for the renderer.
#[derive(Clone, Debug, Default)]
pub struct StreamUpdate {
    pub evictions: Vec<Eviction>,
    pub uploads: Vec<Upload>,
    pub stats: StreamStats,
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
    blocks: SlotPool,
    block: u32,
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
        let block = pools.block.max(1);
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
        let max_in_flight = 4 * workers.len().max(1);
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
            blocks: SlotPool::new(pools.instances / block),
            block,
        }
    }

    pub fn world(&self) -> &World {
        &self.world
    }

    /// Resident sectors and where they live.
    pub fn resident(&self) -> &HashMap<SectorCoord, Residency> {
        &self.resident
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
        if let Some(r) = self.resident.remove(&c) {
            self.tiles.free(r.tile);
            for &b in &r.blocks {
                self.blocks.free(b);
            }
            u.evictions.push(Eviction {
                coord: c,
                tile: r.tile,
                blocks: r.blocks,
            });
        }
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
            let blocks_needed = (data.instances.len() as u32).div_ceil(self.block);
            let placed = loop {
                if self.tiles.available() > 0 && self.blocks.available() >= blocks_needed {
                    let tile = self.tiles.alloc();
                    let blocks = self.blocks.alloc_n(blocks_needed);
                    break tile.zip(blocks);
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
            let Some((tile, blocks)) = placed else {
                continue;
            };
            spent += bytes;
            let data = Arc::new(data);
            self.resident.insert(
                data.coord,
                Residency {
                    data: data.clone(),
                    tile,
                    blocks: blocks.clone(),
                },
            );
            u.uploads.push(Upload { data, tile, blocks });
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
        let st = &mut u.stats;
        st.wanted = wanted.len() as u32;
        st.missing = wanted
            .iter()
            .filter(|(_, c)| !self.resident.contains_key(c))
            .count() as u32;
        st.resident = self.resident.len() as u32;
        st.in_flight = self.in_flight.len() as u32;
        st.tiles_used = self.tiles.used();
        st.tiles_total = self.tiles.capacity();
        st.blocks_used = self.blocks.used();
        st.blocks_total = self.blocks.capacity();
        st.instances = self
            .resident
            .values()
            .map(|r| r.data.instances.len() as u32)
            .sum();
        st.uploaded = u.uploads.len() as u32;
        st.evicted = u.evictions.len() as u32;
        st.over_capacity = over;
    }
}
