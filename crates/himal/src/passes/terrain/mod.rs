//! CDLOD terrain (Strugar 2009): a quadtree of fixed grid nodes selected on
//! the CPU each frame by distance ranges, vertices morphed to the next
//! coarser grid over the last part of each range (no cracks, no popping),
//! drawn as one instanced draw into the G-buffer after the `gbuffer` node
//! (node `terrain`), and into sun cascades for shadows.
//!
//! Height data: a coarse grid over the whole world (16 m) and a fixed pool
//! of fine tiles (one per 64 m sector, 1 m) streamed in and out
//! ([`TerrainPass::upload_tile`], [`TerrainPass::evict`]), found through a
//! page table. Levels whose vertex spacing is at least the coarse spacing
//! read only the coarse grid; finer ones read a tile where one is resident.
//! Materials: layers by height and slope with procedural detail textures
//! ([`textures`]) sampled at two scales, triplanar on steep slopes.
//!
//! CPU twin: [`mod@reference`] (selection, morph, heights). Equations and
//! figures: docs/techniques/terrain.md.

pub mod reference;
pub mod textures;

mod create;
mod desc;
mod draw;
mod layout;
mod select;
mod shadow;
mod stream;

use std::sync::{Mutex, MutexGuard};

use crate::gpu::GpuError;
use crate::gpu::pipeline::Program;
use reference::{Geometry, Heights, Patch, Pyramid};

pub use desc::{DetailKind, TerrainDesc, TerrainLayerDesc, TerrainSettings};
pub use select::{TerrainStats, TerrainView};

/// Material layers at most.
pub const MAX_LAYERS: usize = 8;
/// Views per frame: the camera, then up to seven shadow views.
pub const MAX_VIEWS: usize = 8;
/// Patches one view may draw (the list is cut there and the cut counted).
pub const MAX_PATCHES: usize = 16384;
/// Triangles per patch (16 x 16 quads).
pub const PATCH_TRIANGLES: u32 = 2 * reference::PATCH_QUADS * reference::PATCH_QUADS;
/// Depth format of the sun cascades (`passes/shadows`).
pub const SHADOW_DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// What `terrain_height` in `shaders/terrain.wgsl` binds: the parameters,
/// the coarse grid, the tile array and the page table.
#[derive(Clone, Copy)]
pub struct TerrainHeights<'a> {
    /// The `TerrainParams` uniform.
    pub params: &'a wgpu::Buffer,
    /// The coarse height grid over the whole world.
    pub coarse: &'a wgpu::TextureView,
    /// The fine tile pool (one array layer per slot).
    pub fine: &'a wgpu::TextureView,
    /// The page table: per sector the slot of its tile, or [`reference::NONE`].
    pub pages: &'a wgpu::TextureView,
}

/// The CPU side of the height data (behind a lock: tiles stream in through `&self`).
pub struct TerrainCpu {
    /// Coarse grid, page table and resident tiles (a mirror of the textures).
    pub heights: Heights,
    /// Min/max heights that bound the selection's nodes.
    pub pyramid: Pyramid,
}

/// The CDLOD terrain: height textures and tile streaming, material layers, the per-view patch
/// selection, and the G-buffer and shadow pipelines.
pub struct TerrainPass {
    /// `--view lod` this frame (`frame::plan`).
    pub lod_view: bool,
    /// E3 specular anti-aliasing this frame (`FrameSettings::specular_aa`):
    /// the detail normals' variance widens the G-buffer roughness.
    pub specular_aa: bool,
    /// The world's layout (sectors, spacings, levels).
    pub geometry: Geometry,
    /// LOD knobs the ranges and selection read each frame.
    pub settings: TerrainSettings,
    program: Program,
    shadow_program: Program,
    shadow_pipeline: wgpu::RenderPipeline,
    /// The same into the world's static map (S2, 16-bit depth).
    static_pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    layers: wgpu::Buffer,
    layer_count: u32,
    coarse: wgpu::Texture,
    coarse_view: wgpu::TextureView,
    fine: wgpu::Texture,
    fine_view: wgpu::TextureView,
    pages: wgpu::Texture,
    pages_view: wgpu::TextureView,
    detail_albedo: wgpu::TextureView,
    detail_normal: wgpu::TextureView,
    sampler: wgpu::Sampler,
    /// [`MAX_VIEWS`] lists of [`MAX_PATCHES`] patches.
    instances: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    cpu: Mutex<TerrainCpu>,
    /// Patches per view this frame.
    counts: [u32; MAX_VIEWS],
    /// The camera's patches this frame (reused allocation).
    selection: Vec<Patch>,
}

fn other(e: String) -> GpuError {
    GpuError::Other(e)
}

impl TerrainPass {
    fn lock(&self) -> MutexGuard<'_, TerrainCpu> {
        // A panic elsewhere while holding the lock leaves consistent data
        // (every update finishes before the next starts).
        self.cpu.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The CPU copy of the height data and bounds (twin, tests, tools).
    pub fn cpu(&self) -> MutexGuard<'_, TerrainCpu> {
        self.lock()
    }

    /// The height data's bindings (`shaders/terrain.wgsl`), for passes
    /// that sample the ground outside the terrain's own draws (L2).
    pub fn heights(&self) -> TerrainHeights<'_> {
        TerrainHeights {
            params: &self.params,
            coarse: &self.coarse_view,
            fine: &self.fine_view,
            pages: &self.pages_view,
        }
    }
}
