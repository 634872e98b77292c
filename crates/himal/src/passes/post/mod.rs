//! HDR post (TECHNIQUES H2, H3): log-average luminance reduced on the GPU,
//! light adaptation kept on the GPU, Kawase bloom, bloom composite and
//! Reinhard `L/(1+L)` (optionally with a white point) at key 0.18, or the
//! Khronos PBR Neutral, ACES or AgX curve ([`Tonemapper`]).
//! CPU twin: [`mod@reference`].

pub mod bloom;
pub mod params;
pub mod reference;
mod tonemap;

pub use bloom::{BloomInputs, BloomPass};
pub use params::{AdaptationSettings, BloomSettings, FrameDelta, PostUniform};
pub use tonemap::{PostInputs, TonemapKey, TonemapPass, Tonemapper};

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferAccess, BufferHandle, FrameGraph, TextureHandle};

/// Tile edge in pixels of `post.luminance` (16x16 threads, 4x4 pixels each).
pub const TILE: u32 = 64;
/// Reinhard's key: the scaled luminance the log-average luminance is exposed to (middle grey, 0.18).
pub const KEY: f64 = 0.18;

/// Buffers of the luminance reduction, sized for one frame size.
pub struct LuminanceBuffers {
    /// Per 64x64 tile: (sum of log luminance, pixel count), two f32 each.
    pub partials: wgpu::Buffer,
    /// (log average, average, tiles, pixels)
    pub result: wgpu::Buffer,
}

impl LuminanceBuffers {
    /// Buffers for a frame of `size` = (width, height) pixels.
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let tiles = size.0.div_ceil(TILE) as u64 * size.1.div_ceil(TILE) as u64;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
        Self {
            partials: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("post.luminance.partials"),
                size: tiles * 8,
                usage: storage,
                mapped_at_creation: false,
            }),
            result: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("post.luminance.result"),
                size: 16,
                usage: storage,
                mapped_at_creation: false,
            }),
        }
    }
}

/// `post.luminance`: reduces the HDR image to its log-average luminance in two compute steps (tiles, then one workgroup).
pub struct LuminancePass {
    program: Program,
    partial: wgpu::ComputePipeline,
    last: wgpu::ComputePipeline,
}

impl LuminancePass {
    /// Compiles the reduction's two compute pipelines.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/post/luminance.wgsl")?;
        let partial = program.compute_pipeline(ctx, "cs_partial", &[])?;
        let last = program.compute_pipeline(ctx, "cs_final", &[])?;
        Ok(Self {
            program,
            partial,
            last,
        })
    }

    /// Reduces `hdr` into `buffers.result`; returns its handle.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        size: (u32, u32),
        buffers: &'a LuminanceBuffers,
    ) -> BufferHandle {
        let partials = graph.import_buffer("luminance.partials", &buffers.partials);
        let result = graph.import_buffer("luminance.result", &buffers.result);
        let last = &self.last;
        graph
            .compute("post.luminance", &self.program)
            .compute_pipeline(Ok(self.partial.clone()))
            .read("hdr", hdr)
            .write_buffer("partials", partials)
            .write_buffer("result", result)
            .dispatch_with(move |cp| {
                cp.dispatch_workgroups(size.0.div_ceil(TILE), size.1.div_ceil(TILE), 1);
                cp.set_pipeline(last);
                cp.dispatch_workgroups(1, 1, 1);
            })
            .buffer(result)
    }
}

/// `post.adapt`: moves the adapted luminance (persistent, on the GPU)
/// toward this frame's log-average; see `adapt.wgsl`.
pub struct AdaptPass {
    program: Program,
    pipeline: wgpu::ComputePipeline,
}

/// Bytes of the adapted-luminance buffer: (log L_a, L_a, L_avg, frames since reset).
pub const ADAPTED_BYTES: u64 = 16;

/// The persistent adapted-luminance buffer (survives frames and size changes).
pub fn adapted_buffer(device: &wgpu::Device) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("post.adapt.state"),
        size: ADAPTED_BYTES,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

impl AdaptPass {
    /// Compiles the adaptation compute pipeline.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/post/adapt.wgsl")?;
        let pipeline = program.compute_pipeline(ctx, "cs_main", &[])?;
        Ok(Self { program, pipeline })
    }

    /// Reads `measured` (the luminance result), updates `adapted`; returns its handle.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        measured: BufferHandle,
        adapted_buffer: &'a wgpu::Buffer,
        post: &'a wgpu::Buffer,
    ) -> BufferHandle {
        let adapted = graph.import_buffer("adapt.state", adapted_buffer);
        graph
            .compute("post.adapt", &self.program)
            .compute_pipeline(Ok(self.pipeline.clone()))
            .uniform("post", post)
            .read_buffer("measured", measured, BufferAccess::StorageRead)
            .write_buffer("adapted", adapted)
            .dispatch([1, 1, 1])
            .buffer(adapted)
    }
}

/// Post settings and persistent buffers of one frame (see `frame::build`).
pub struct PostFrame<'a> {
    /// `PostUniform`, written for this frame.
    pub uniform: &'a wgpu::Buffer,
    /// Adapted-luminance state (persistent).
    pub adapted: &'a wgpu::Buffer,
    /// Kawase passes; `None` = no bloom chain.
    pub bloom_passes: Option<u32>,
    /// Expose for the adapted luminance (else for this frame's log-average).
    pub adaptation: bool,
    /// The tonemap permutation (curve, bloom composite) this frame draws with.
    pub tonemap: TonemapKey,
}
