//! GPU timestamps around each pass: encoder timestamps around every pass,
//! and pass-level timestamp writes inside compute passes (lavapipe's
//! encoder timestamps do not bracket compute work: they read ~0.03 ms).

use std::sync::mpsc;

use super::GraphError;

/// How a [`PassTiming`] was measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingMethod {
    /// Encoder timestamps written before and after the pass's commands.
    EncoderTs,
    /// The compute pass's own timestamp writes (`ComputePassTimestampWrites`).
    PassTs,
    /// Wall clock of the pass submitted alone and waited for, less an empty
    /// submission's ([`crate::graph::CompiledGraph::execute_isolated`]).
    IsolatedWall,
}

impl TimingMethod {
    /// Short name for tables: `encoder-ts`, `pass-ts`, `isolated-wall`.
    pub fn name(self) -> &'static str {
        match self {
            TimingMethod::EncoderTs => "encoder-ts",
            TimingMethod::PassTs => "pass-ts",
            TimingMethod::IsolatedWall => "isolated-wall",
        }
    }
}

/// GPU time of one pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Id of the pass.
    pub id: String,
    /// The pass's time in milliseconds, by `method`.
    pub gpu_ms: f64,
    /// Time between the encoder timestamps around the pass (equal to
    /// `gpu_ms` for `EncoderTs`; 0 for `IsolatedWall`).
    pub encoder_ms: f64,
    /// How `gpu_ms` was measured.
    pub method: TimingMethod,
}

/// Two timestamps per pass in a query set, its resolve buffer and a
/// mappable read-back buffer.
struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl Queries {
    fn new(device: &wgpu::Device, label: &str, count: u32) -> Queries {
        let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
        let buffer = |suffix: &str, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label}.{suffix}")),
                size: bytes,
                usage,
                mapped_at_creation: false,
            })
        };
        Queries {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some(label),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: buffer(
                "resolve",
                wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            ),
            readback: buffer(
                "readback",
                wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }

    fn record_resolve(&self, encoder: &mut wgpu::CommandEncoder, count: u32) {
        if count > 0 {
            encoder.resolve_query_set(&self.set, 0..count, &self.resolve, 0);
            let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
            encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, bytes);
        }
    }

    /// Maps the first `count` resolved ticks; the caller waits for the GPU.
    fn map(&self, count: u32) -> Option<mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>> {
        if count == 0 {
            return None;
        }
        let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
        let (tx, rx) = mpsc::channel();
        self.readback
            .slice(0..bytes)
            .map_async(wgpu::MapMode::Read, move |r| {
                let _ = tx.send(r);
            });
        Some(rx)
    }

    fn ticks(
        &self,
        count: u32,
        rx: Option<mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>>,
    ) -> Result<Vec<u64>, GraphError> {
        let Some(rx) = rx else {
            return Ok(Vec::new());
        };
        rx.recv()
            .map_err(|_| GraphError::Device("timestamp map callback never ran".into()))?
            .map_err(|e| GraphError::Device(format!("mapping timestamps: {e}")))?;
        let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
        let ticks: Vec<u64> = {
            let view = self
                .readback
                .slice(0..bytes)
                .get_mapped_range()
                .map_err(|e| GraphError::Device(format!("reading timestamps: {e}")))?;
            view.chunks_exact(8)
                .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
                .collect()
        };
        self.readback.unmap();
        Ok(ticks)
    }
}

/// Encoder timestamps around every pass, and a second query set for the
/// compute passes' own timestamp writes. One `execute` per `read_timings`.
pub struct PassTimer {
    encoder: Queries,
    /// Pass-level pairs, handed out in order to the compute passes that ask.
    pass: Queries,
    capacity: u32,
    /// Nanoseconds per tick.
    period_ns: f64,
    /// Pass ids recorded by the last execute, with their pass-level pair
    /// (index into `pass`), awaiting read-back.
    pending: Vec<(String, Option<u32>)>,
}

impl PassTimer {
    /// `None` when the device lacks `TIMESTAMP_QUERY` or
    /// `TIMESTAMP_QUERY_INSIDE_ENCODERS` (timings are then simply absent).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, max_passes: u32) -> Option<PassTimer> {
        let needed =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        if !device.features().contains(needed) {
            return None;
        }
        let capacity = max_passes.clamp(1, wgpu::QUERY_SET_MAX_QUERIES / 2);
        Some(PassTimer {
            encoder: Queries::new(device, "himal.pass_timer", 2 * capacity),
            pass: Queries::new(device, "himal.pass_timer.pass", 2 * capacity),
            capacity,
            period_ns: queue.get_timestamp_period() as f64,
            pending: Vec::new(),
        })
    }

    /// Most passes one execute can time.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    pub(crate) fn query_set(&self) -> &wgpu::QuerySet {
        &self.encoder.set
    }

    /// The query set of the compute passes' own timestamp writes: pair `k`
    /// is queries `2k`, `2k + 1`.
    pub(crate) fn pass_query_set(&self) -> &wgpu::QuerySet {
        &self.pass.set
    }

    /// Resolves the pass pairs and copies them to the read-back buffers.
    /// `ids`: each pass in execution order with its pass-level pair.
    pub(crate) fn record_resolve(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        ids: Vec<(String, Option<u32>)>,
    ) {
        let pass_pairs = ids.iter().filter(|(_, k)| k.is_some()).count() as u32;
        self.encoder.record_resolve(encoder, 2 * ids.len() as u32);
        self.pass.record_resolve(encoder, 2 * pass_pairs);
        self.pending = ids;
    }

    /// After the command buffer from `execute` was submitted: waits for it,
    /// returns each pass's GPU milliseconds in execution order: the
    /// pass-level pair where the pass wrote one, the encoder pair otherwise.
    /// Empty when nothing is pending.
    pub fn read_timings(&mut self, device: &wgpu::Device) -> Result<Vec<PassTiming>, GraphError> {
        let ids = std::mem::take(&mut self.pending);
        if ids.is_empty() {
            return Ok(Vec::new());
        }
        let n_enc = 2 * ids.len() as u32;
        let n_pass = 2 * ids.iter().filter(|(_, k)| k.is_some()).count() as u32;
        let (rx_enc, rx_pass) = (self.encoder.map(n_enc), self.pass.map(n_pass));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GraphError::Device(format!("waiting for timestamps: {e}")))?;
        let enc = self.encoder.ticks(n_enc, rx_enc)?;
        let pass = self.pass.ticks(n_pass, rx_pass)?;
        // Some drivers reorder or reset counters: clamp to zero.
        let ms = |a: u64, b: u64| b.saturating_sub(a) as f64 * self.period_ns / 1.0e6;
        Ok(ids
            .into_iter()
            .zip(enc.chunks_exact(2))
            .map(|((id, k), pair)| {
                let encoder_ms = ms(pair[0], pair[1]);
                let own = k.and_then(|k| pass.get(2 * k as usize..2 * k as usize + 2));
                match own {
                    Some(p) => PassTiming {
                        id,
                        gpu_ms: ms(p[0], p[1]),
                        encoder_ms,
                        method: TimingMethod::PassTs,
                    },
                    None => PassTiming {
                        id,
                        gpu_ms: encoder_ms,
                        encoder_ms,
                        method: TimingMethod::EncoderTs,
                    },
                }
            })
            .collect())
    }
}
