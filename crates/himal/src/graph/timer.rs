//! GPU timestamps around each pass.

use std::sync::mpsc;

use super::GraphError;

/// GPU time of one pass.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// Id of the pass.
    pub id: String,
    /// Time between the timestamps around the pass, in milliseconds.
    pub gpu_ms: f64,
}

/// A timestamp query set with two queries per pass, its resolve buffer and
/// a mappable read-back buffer. One `execute` per `read_timings`.
pub struct PassTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    /// Nanoseconds per tick.
    period_ns: f64,
    /// Pass ids recorded by the last execute, awaiting read-back.
    pending: Vec<String>,
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
        let count = 2 * capacity;
        let query_set = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("himal.pass_timer"),
            ty: wgpu::QueryType::Timestamp,
            count,
        });
        let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
        let resolve = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("himal.pass_timer.resolve"),
            size: bytes,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("himal.pass_timer.readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Some(PassTimer {
            query_set,
            resolve,
            readback,
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
        &self.query_set
    }

    /// Resolves the pass pairs and copies them to the read-back buffer.
    pub(crate) fn record_resolve(&mut self, encoder: &mut wgpu::CommandEncoder, ids: Vec<String>) {
        let count = 2 * ids.len() as u32;
        if count > 0 {
            encoder.resolve_query_set(&self.query_set, 0..count, &self.resolve, 0);
            let bytes = count as u64 * wgpu::QUERY_SIZE as u64;
            encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, bytes);
        }
        self.pending = ids;
    }

    /// After the command buffer from `execute` was submitted: waits for it,
    /// returns each pass's GPU milliseconds in execution order. Empty when
    /// nothing is pending.
    pub fn read_timings(&mut self, device: &wgpu::Device) -> Result<Vec<PassTiming>, GraphError> {
        let ids = std::mem::take(&mut self.pending);
        if ids.is_empty() {
            return Ok(Vec::new());
        }
        let bytes = 2 * ids.len() as u64 * wgpu::QUERY_SIZE as u64;
        let slice = self.readback.slice(0..bytes);
        let (tx, rx) = mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GraphError::Device(format!("waiting for timestamps: {e}")))?;
        rx.recv()
            .map_err(|_| GraphError::Device("timestamp map callback never ran".into()))?
            .map_err(|e| GraphError::Device(format!("mapping timestamps: {e}")))?;
        let ticks: Vec<u64> = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| GraphError::Device(format!("reading timestamps: {e}")))?;
            view.chunks_exact(8)
                .map(|c| u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
                .collect()
        };
        self.readback.unmap();
        Ok(ids
            .into_iter()
            .zip(ticks.chunks_exact(2))
            .map(|(id, pair)| PassTiming {
                id,
                // Some drivers reorder or reset counters: clamp to zero.
                gpu_ms: pair[1].saturating_sub(pair[0]) as f64 * self.period_ns / 1.0e6,
            })
            .collect())
    }
}
