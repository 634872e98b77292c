//! E1 pipeline cache (Wenzel, "Far Cry and DirectX", GDC 2005: "object has
//! shader handles? use those; otherwise find the shader in memory; if that
//! fails load it from disk; if that fails compile it and store a backup").
//!
//! A pipeline's key is its permutation: the program (composed WGSL, by
//! hash), entry points, WGSL `override` constants and fixed-function state.
//! Lookup: the pass's own handle (it keeps what it fetched) → this cache's
//! memory map → the on-disk cache (wgpu's `PipelineCache` blob, where the
//! adapter has `Features::PIPELINE_CACHE`, plus himal's index of keys that
//! blob holds) → compile and store. The counters say which level answered.
//!
//! On-disk file `<dir>/<adapter>.himal-pipelines`, little-endian:
//! magic `HIMALPC\0`, format version u32, adapter identity (u32 length +
//! UTF-8), key count u32 and keys (u32 length + UTF-8 each), blob length
//! u64 and wgpu's blob, FNV-1a 64 checksum of everything before it.
//! A short, corrupted, foreign or old file is ignored with a warning and
//! rewritten by the next save.

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use super::{GpuContext, GpuError};

const MAGIC: &[u8; 8] = b"HIMALPC\0";
/// Largest pipeline cache read (lavapipe's for every permutation: ~20 MB).
const MAX_CACHE_BYTES: u64 = 512 << 20;

/// Reads `path` when it is a regular file of at most `max` bytes (a
/// symlink to a device or an endless file is refused before reading).
fn read_bounded(path: &Path, max: u64) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() || meta.len() > max {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not a regular file of at most {} MiB", max >> 20),
        ));
    }
    std::fs::read(path)
}
/// Bumped whenever the file layout or the key format changes.
pub const FORMAT_VERSION: u32 = 1;

/// FNV-1a, 64 bit: the file checksum and the source/state hashes in keys.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// A permutation's canonical name (see [`crate::gpu::pipeline::Program`]).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PipelineKey(pub String);

impl std::fmt::Display for PipelineKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Which level answered, counted since the context was created.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CacheStats {
    /// Requests answered by a pipeline already created in this process.
    pub memory_hits: u64,
    /// Created from the on-disk cache (key in the index, driver blob loaded).
    pub disk_hits: u64,
    /// Pipelines compiled from scratch (not in memory nor in the disk index).
    pub compiles: u64,
    /// Milliseconds spent creating pipelines found on disk.
    pub disk_ms: f64,
    /// Milliseconds spent compiling pipelines not found anywhere.
    pub compile_ms: f64,
}

impl CacheStats {
    /// Counts since `earlier` (e.g. over a frame sequence).
    pub fn since(&self, earlier: &CacheStats) -> CacheStats {
        CacheStats {
            memory_hits: self.memory_hits - earlier.memory_hits,
            disk_hits: self.disk_hits - earlier.disk_hits,
            compiles: self.compiles - earlier.compiles,
            disk_ms: self.disk_ms - earlier.disk_ms,
            compile_ms: self.compile_ms - earlier.compile_ms,
        }
    }
}

impl std::fmt::Display for CacheStats {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} memory hits, {} disk hits ({:.1} ms), {} compiles ({:.1} ms)",
            self.memory_hits, self.disk_hits, self.disk_ms, self.compiles, self.compile_ms
        )
    }
}

/// What opening the on-disk cache found.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadStatus {
    /// No directory: memory only.
    MemoryOnly,
    /// No file yet (first run for this adapter).
    Missing(PathBuf),
    /// The file was read; its pipelines are created from the driver blob.
    Loaded {
        /// The cache file.
        path: PathBuf,
        /// Number of pipeline keys in its index.
        keys: usize,
        /// Size of the driver's pipeline-cache blob in bytes.
        blob_bytes: usize,
    },
    /// The file was unusable and is ignored; the next save rewrites it.
    Rejected {
        /// The cache file.
        path: PathBuf,
        /// Why: unreadable, bad magic or checksum, another format version or another adapter/driver.
        reason: String,
    },
}

#[derive(Clone)]
enum Cached {
    Render(wgpu::RenderPipeline),
    Compute(wgpu::ComputePipeline),
}

struct Inner {
    dir: Option<PathBuf>,
    status: LoadStatus,
    memory: HashMap<PipelineKey, Cached>,
    /// Keys of the loaded index (their pipelines are in the wgpu blob).
    on_disk: HashSet<PipelineKey>,
    /// Keys created in this process (written by `save`).
    created: HashSet<PipelineKey>,
    wgpu_cache: Option<wgpu::PipelineCache>,
    stats: CacheStats,
}

/// himal's pipeline cache; one per [`GpuContext`] (`ctx.pipelines`).
pub struct ShaderCache {
    inner: Mutex<Inner>,
}

impl Default for ShaderCache {
    fn default() -> Self {
        Self {
            inner: Mutex::new(Inner {
                dir: None,
                status: LoadStatus::MemoryOnly,
                memory: HashMap::new(),
                on_disk: HashSet::new(),
                created: HashSet::new(),
                wgpu_cache: None,
                stats: CacheStats::default(),
            }),
        }
    }
}

/// Adapter and driver identity written in the header; a file from another
/// adapter, driver, wgpu or himal version is not used.
pub fn adapter_identity(info: &wgpu::AdapterInfo) -> String {
    format!(
        "{:?}|{}|{:04x}:{:04x}|{}|{}|wgpu 30|himal {}",
        info.backend,
        info.name,
        info.vendor,
        info.device,
        info.driver,
        info.driver_info,
        env!("CARGO_PKG_VERSION")
    )
}

/// The cache file for this adapter in `dir`.
pub fn cache_file(dir: &Path, info: &wgpu::AdapterInfo) -> PathBuf {
    let slug = format!(
        "{}-{:04x}-{:04x}",
        format!("{:?}", info.backend).to_lowercase(),
        info.vendor,
        info.device
    );
    dir.join(format!("{slug}.himal-pipelines"))
}

/// Index and blob of a valid file.
#[derive(Debug)]
struct FileContents {
    keys: Vec<PipelineKey>,
    blob: Vec<u8>,
}

struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl<'b> Reader<'b> {
    fn take(&mut self, n: usize) -> Result<&'b [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("truncated at byte {}", self.at))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn u64(&mut self) -> Result<u64, String> {
        let b = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(b);
        Ok(u64::from_le_bytes(a))
    }
    fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        let b = self.take(n)?;
        String::from_utf8(b.to_vec()).map_err(|_| format!("text at byte {} is not UTF-8", self.at))
    }
}

/// Checks and parses a cache file; `Err` says why it is unusable.
fn parse(bytes: &[u8], identity: &str) -> Result<FileContents, String> {
    if bytes.len() < MAGIC.len() + 4 + 8 {
        return Err(format!("too short ({} bytes)", bytes.len()));
    }
    if &bytes[..8] != MAGIC {
        return Err("not a himal pipeline cache (bad magic)".into());
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    let mut r = Reader { bytes: body, at: 8 };
    let version = r.u32()?;
    if version != FORMAT_VERSION {
        return Err(format!(
            "incompatible format version {version} (this build reads {FORMAT_VERSION})"
        ));
    }
    let mut s = [0u8; 8];
    s.copy_from_slice(sum);
    let (stored, actual) = (u64::from_le_bytes(s), fnv1a(body));
    if stored != actual {
        return Err(format!(
            "checksum mismatch (stored {stored:016x}, computed {actual:016x}): corrupted"
        ));
    }
    let file_identity = r.string()?;
    if file_identity != identity {
        return Err(format!(
            "written for another adapter or driver (\"{file_identity}\", this is \"{identity}\")"
        ));
    }
    let count = r.u32()? as usize;
    let mut keys = Vec::with_capacity(count.min(1 << 16));
    for _ in 0..count {
        keys.push(PipelineKey(r.string()?));
    }
    let blob_len = r.u64()? as usize;
    let blob = r.take(blob_len)?.to_vec();
    if r.at != body.len() {
        return Err(format!("{} unexpected bytes at the end", body.len() - r.at));
    }
    Ok(FileContents { keys, blob })
}

fn serialize(identity: &str, keys: &[&PipelineKey], blob: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + blob.len() + keys.len() * 96);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    let string = |out: &mut Vec<u8>, s: &str| {
        out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        out.extend_from_slice(s.as_bytes());
    };
    string(&mut out, identity);
    out.extend_from_slice(&(keys.len() as u32).to_le_bytes());
    for k in keys {
        string(&mut out, &k.0);
    }
    out.extend_from_slice(&(blob.len() as u64).to_le_bytes());
    out.extend_from_slice(blob);
    let sum = fnv1a(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

impl ShaderCache {
    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic while holding the lock leaves plain data; keep using it.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Counts and times of each cache level since the context was created.
    pub fn stats(&self) -> CacheStats {
        self.lock().stats
    }

    /// What opening the on-disk cache found.
    pub fn status(&self) -> LoadStatus {
        self.lock().status.clone()
    }

    /// Number of distinct pipelines held in memory.
    pub fn len(&self) -> usize {
        self.lock().memory.len()
    }

    /// Whether no pipeline is held in memory yet.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Looks `key` up in memory, else creates it with `create` (given the
    /// wgpu cache when one is open) and counts a disk hit or a compile.
    fn get_or_create(
        &self,
        key: PipelineKey,
        create: impl FnOnce(Option<&wgpu::PipelineCache>) -> Result<Cached, GpuError>,
    ) -> Result<Cached, GpuError> {
        let (wgpu_cache, from_disk) = {
            let mut inner = self.lock();
            if let Some(p) = inner.memory.get(&key).cloned() {
                inner.stats.memory_hits += 1;
                return Ok(p);
            }
            let cache = inner.wgpu_cache.clone();
            let from_disk = cache.is_some() && inner.on_disk.contains(&key);
            (cache, from_disk)
        };
        let start = Instant::now();
        let pipeline = create(wgpu_cache.as_ref())?;
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let mut inner = self.lock();
        if from_disk {
            inner.stats.disk_hits += 1;
            inner.stats.disk_ms += ms;
        } else {
            inner.stats.compiles += 1;
            inner.stats.compile_ms += ms;
            log::debug!("pipeline compiled: {key} ({ms:.1} ms)");
        }
        inner.created.insert(key.clone());
        inner.memory.insert(key, pipeline.clone());
        Ok(pipeline)
    }

    /// The render pipeline for `key`: from memory, else made by `create` (which
    /// gets the wgpu cache when one is open). Fails if `key` names a compute pipeline.
    pub fn render(
        &self,
        key: PipelineKey,
        create: impl FnOnce(Option<&wgpu::PipelineCache>) -> Result<wgpu::RenderPipeline, GpuError>,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        match self.get_or_create(key.clone(), |c| create(c).map(Cached::Render))? {
            Cached::Render(p) => Ok(p),
            Cached::Compute(_) => Err(GpuError::Other(format!(
                "pipeline cache: {key} is a compute pipeline"
            ))),
        }
    }

    /// The compute pipeline for `key`: from memory, else made by `create` (which
    /// gets the wgpu cache when one is open). Fails if `key` names a render pipeline.
    pub fn compute(
        &self,
        key: PipelineKey,
        create: impl FnOnce(Option<&wgpu::PipelineCache>) -> Result<wgpu::ComputePipeline, GpuError>,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        match self.get_or_create(key.clone(), |c| create(c).map(Cached::Compute))? {
            Cached::Compute(p) => Ok(p),
            Cached::Render(_) => Err(GpuError::Other(format!(
                "pipeline cache: {key} is a render pipeline"
            ))),
        }
    }
}

impl GpuContext {
    /// Opens the on-disk pipeline cache in `dir` (created if needed) before
    /// pipelines are created; an unusable file is ignored with a warning.
    pub fn open_pipeline_cache(&self, dir: &Path) -> LoadStatus {
        let info = self.adapter.get_info();
        let path = cache_file(dir, &info);
        let identity = adapter_identity(&info);
        let mut contents = None;
        let status = match read_bounded(&path, MAX_CACHE_BYTES) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => LoadStatus::Missing(path.clone()),
            Err(e) => LoadStatus::Rejected {
                path: path.clone(),
                reason: format!("cannot read: {e}"),
            },
            Ok(bytes) => match parse(&bytes, &identity) {
                Ok(c) => {
                    let s = LoadStatus::Loaded {
                        path: path.clone(),
                        keys: c.keys.len(),
                        blob_bytes: c.blob.len(),
                    };
                    contents = Some(c);
                    s
                }
                Err(reason) => LoadStatus::Rejected {
                    path: path.clone(),
                    reason,
                },
            },
        };
        if let LoadStatus::Rejected { path, reason } = &status {
            log::warn!(
                "{}: {reason}; ignoring it, the pipeline cache will be rebuilt",
                path.display()
            );
        }
        let wgpu_cache = self
            .device
            .features()
            .contains(wgpu::Features::PIPELINE_CACHE)
            .then(|| {
                let data = contents.as_ref().map(|c| c.blob.as_slice());
                // SAFETY: `data` is a blob `PipelineCache::get_data` returned
                // on an adapter with this identity (checked above, checksum
                // included); `fallback` lets the driver drop data it rejects.
                unsafe {
                    self.device
                        .create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                            label: Some("himal.pipelines"),
                            data: data.filter(|d| !d.is_empty()),
                            fallback: true,
                        })
                }
            });
        let mut inner = self.pipelines.lock();
        inner.dir = Some(dir.to_path_buf());
        inner.status = status.clone();
        // Without wgpu's blob, the index alone saves nothing: every key compiles.
        inner.on_disk = match (&wgpu_cache, contents) {
            (Some(_), Some(c)) => c.keys.into_iter().collect(),
            _ => HashSet::new(),
        };
        inner.wgpu_cache = wgpu_cache;
        status
    }

    /// Writes the index (keys loaded and created) and wgpu's blob to the
    /// cache directory (temporary file, then rename); `None` when memory-only.
    pub fn save_pipeline_cache(&self) -> Result<Option<PathBuf>, GpuError> {
        let info = self.adapter.get_info();
        let inner = self.pipelines.lock();
        let Some(dir) = inner.dir.clone() else {
            return Ok(None);
        };
        let mut keys: Vec<&PipelineKey> = inner.on_disk.union(&inner.created).collect();
        keys.sort();
        let blob = inner
            .wgpu_cache
            .as_ref()
            .and_then(|c| c.get_data())
            .unwrap_or_default();
        let bytes = serialize(&adapter_identity(&info), &keys, &blob);
        drop(inner);
        let path = cache_file(&dir, &info);
        let io = |e: std::io::Error, what: &Path| {
            GpuError::Other(format!("pipeline cache {}: {e}", what.display()))
        };
        std::fs::create_dir_all(&dir).map_err(|e| io(e, &dir))?;
        let tmp = path.with_extension(format!("tmp{}", std::process::id()));
        std::fs::write(&tmp, &bytes).map_err(|e| io(e, &tmp))?;
        std::fs::rename(&tmp, &path).map_err(|e| io(e, &path))?;
        Ok(Some(path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_round_trips_and_rejects_damage() {
        let keys = [PipelineKey("a|x".into()), PipelineKey("b|y".into())];
        let refs: Vec<&PipelineKey> = keys.iter().collect();
        let bytes = serialize("id", &refs, &[1, 2, 3]);
        let c = parse(&bytes, "id").expect("valid");
        assert_eq!(c.keys, keys);
        assert_eq!(c.blob, vec![1, 2, 3]);
        let mut flipped = bytes.clone();
        flipped[20] ^= 0x40;
        assert!(parse(&flipped, "id").unwrap_err().contains("checksum"));
        assert!(
            parse(&bytes, "other")
                .unwrap_err()
                .contains("another adapter")
        );
        assert!(parse(&bytes[..10], "id").unwrap_err().contains("too short"));
        let mut old = bytes.clone();
        old[8] = 0;
        assert!(parse(&old, "id").unwrap_err().contains("version"));
    }
}
