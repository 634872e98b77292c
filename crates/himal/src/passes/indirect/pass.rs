//! The per-frame GPU work of L5: cells streamed into the fixed pool,
//! `probes.transfer` (SH probes for this frame's sky and sun) and
//! `probes.inject` (the camera-centred clip map deferred lighting samples).

use std::sync::Arc;

use glam::Vec2;
use half::f16;

use super::cell::{Cell, GRID_SECTORS, PROBES_PER_CELL, TRANSFER_FLOATS};
use super::pool::{CellPool, NO_CELL, POOL_CELLS};
use super::reference::{
    CASCADES, CLIP_RES, ClipMap, Sh4, ground_sh2, lighting_sh, sky_radiance_sh,
};
use super::store::CellSource;
use crate::gpu::pipeline::{Program, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferDesc, FrameGraph, TextureDesc, TextureHandle};
use crate::math::sh::{Sh9Gpu, Sh9Rgb};
use crate::passes::sky::SkyLight;
use crate::passes::sky::reference::{sky_and_ground_irradiance_sh, sky_irradiance_sh};

/// Words of one probe's transfer on the GPU (f16 pairs).
const PROBE_WORDS: usize = TRANSFER_FLOATS / 2;
/// Probes in the pool.
pub const POOL_PROBES: usize = POOL_CELLS * PROBES_PER_CELL;
/// Format of the three clip-map textures (one colour channel's SH2 each).
pub const CLIP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// `IndirectParams` in `shaders/indirect.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct IndirectParams {
    /// The lighting SH2, rgb per coefficient (w unused).
    pub lighting: [[f32; 4]; 4],
    /// Grid origin (x, z), camera (x, z).
    pub origin_camera: [f32; 4],
    /// Per cascade: global probe index of texel (0, 0).
    pub base: [[i32; 4]; CASCADES],
    /// x: sectors per axis of the combined page table.
    pub grid: [i32; 4],
    /// The sky SH's flat ground bounce (what the probes replace).
    pub ground: Sh9Gpu,
    /// x: probes in the pool.
    pub counts: [u32; 4],
    /// The flat ground bounce as SH2 radiance, per channel (r, g, b).
    pub fallback: [[f32; 4]; 3],
}

/// The sky and sun the probes transfer, and the ground they replace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IndirectLight {
    /// Sky above the horizon plus the sun, SH2 radiance.
    pub lighting: Sh4,
    /// The flat ground bounce inside the sky irradiance SH.
    pub ground: Sh9Rgb,
}

impl IndirectLight {
    /// The lighting of `light`'s time of day: its sky (above the horizon)
    /// and sun in SH2, and the flat ground in its irradiance SH.
    pub fn of_sky(light: &SkyLight) -> IndirectLight {
        let sky = sky_radiance_sh(|d| light.sky.radiance(d));
        let with_ground =
            sky_and_ground_irradiance_sh(&light.sky, light.sun_direction, light.sun_illuminance);
        IndirectLight {
            lighting: lighting_sh(&sky, light.sun_direction, light.sun_illuminance),
            ground: with_ground.add(&sky_irradiance_sh(&light.sky).scale(-1.0)),
        }
    }
}

impl IndirectLight {
    /// Under an HDR environment: its radiance above the horizon
    /// (`above_horizon`, SH9 of radiance) plus the analytic sun where the
    /// scene keeps it (zero illuminance otherwise: the image holds its
    /// sun), and the irradiance of the image below the horizon
    /// (`ground_irradiance`), which the probes replace as they replace the
    /// sky's flat ground.
    pub fn of_environment(
        above_horizon: &Sh9Rgb,
        ground_irradiance: &Sh9Rgb,
        sun_direction: glam::Vec3,
        sun_illuminance: glam::Vec3,
    ) -> IndirectLight {
        IndirectLight {
            lighting: lighting_sh(above_horizon, sun_direction, sun_illuminance),
            ground: *ground_irradiance,
        }
    }

    /// [`ground_sh2`] of the flat ground, the clip map's texel where no cell is.
    pub fn fallback(&self) -> Sh4 {
        ground_sh2(&self.ground)
    }

    /// [`Self::fallback`] per colour channel, as the clip map's textures hold it.
    fn fallback_channels(&self) -> [[f32; 4]; 3] {
        let f = self.fallback();
        std::array::from_fn(|c| [f[0][c], f[1][c], f[2][c], f[3][c]])
    }
}

/// What streaming did this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IndirectStats {
    /// Cells resident after the update.
    pub resident: u32,
    /// Cells uploaded this frame.
    pub uploaded: u32,
    /// Cells freed (streamed out) or evicted this frame.
    pub released: u32,
}

/// Bytes of the combined page table: one per sector of the 160 x 160 grid.
pub const TABLE_BYTES: usize = (GRID_SECTORS * GRID_SECTORS) as usize;

/// A cell's transfer as the GPU stores it: f16 pairs, channel-major.
pub fn pack_cell(cell: &Cell) -> Vec<u32> {
    cell.probes
        .iter()
        .flat_map(|p| {
            p.m.chunks_exact(2).map(|pair| {
                let lo = f16::from_f32(pair[0]).to_bits() as u32;
                let hi = f16::from_f32(pair[1]).to_bits() as u32;
                lo | (hi << 16)
            })
        })
        .collect()
}

/// The clip map of this frame as graph textures (r, g, b channels' SH2).
#[derive(Clone, Copy, Debug)]
pub struct IndirectFrame {
    /// `probes.clip_r`, `_g`, `_b`: 32 x 32, 5 layers.
    pub clip: [TextureHandle; 3],
}

/// L5's GPU state: the cell pool, its page table, the two passes.
pub struct IndirectPass {
    transfer: Program,
    inject: Program,
    transfer_pipeline: wgpu::ComputePipeline,
    inject_pipeline: wgpu::ComputePipeline,
    /// Transfer of every pool slot (f16 pairs).
    pub cells: wgpu::Buffer,
    /// The combined page table, one byte per sector (25 KiB).
    pub table: wgpu::Buffer,
    /// `IndirectParams`.
    pub params: wgpu::Buffer,
    pool: CellPool,
    store: Option<Arc<dyn CellSource>>,
    light: Option<IndirectLight>,
    /// `--view indirect|probe-cells|clipmap` as `IndirectView`'s number.
    pub view: u32,
}

impl IndirectPass {
    /// Compiles both passes and allocates the fixed pool (80 cells).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let transfer = Program::new(ctx, "passes/indirect/transfer.wgsl")?;
        let inject = Program::new(ctx, "passes/indirect/inject.wgsl")?;
        let storage = |label: &str, size: usize| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let table = storage("himal.indirect.table", TABLE_BYTES);
        ctx.queue.write_buffer(&table, 0, &[NO_CELL; TABLE_BYTES]);
        Ok(Self {
            transfer_pipeline: transfer.compute_pipeline(ctx, "cs_main", &[])?,
            inject_pipeline: inject.compute_pipeline(ctx, "cs_main", &[])?,
            transfer,
            inject,
            cells: storage("himal.indirect.cells", POOL_PROBES * PROBE_WORDS * 4),
            table,
            params: uniform_buffer(
                ctx,
                "himal.indirect.params",
                &<IndirectParams as bytemuck::Zeroable>::zeroed(),
            ),
            pool: CellPool::default(),
            store: None,
            light: None,
            view: 0,
        })
    }

    /// The cells to stream from (`None`: no indirect light); the pool empties.
    pub fn set_store(&mut self, store: Option<Arc<dyn CellSource>>) {
        self.store = store;
        self.pool = CellPool::default();
    }

    /// This time of day's lighting (the renderer sets it with the sky).
    pub fn set_light(&mut self, light: IndirectLight) {
        self.light = Some(light);
    }

    /// The cells streamed from, if any.
    pub fn store(&self) -> Option<&Arc<dyn CellSource>> {
        self.store.as_ref()
    }

    /// Streams the cells the camera (x, z) wants into the pool
    /// ([`CellPool::stream`]), uploads them and the page tables, and writes
    /// this frame's parameters.
    pub fn update(&mut self, ctx: &GpuContext, camera: Vec2) -> IndirectStats {
        let mut stats = IndirectStats::default();
        let (Some(store), Some(light)) = (self.store.clone(), self.light) else {
            return stats;
        };
        let origin = store.origin();
        store.follow(camera);
        let step = self.pool.stream(origin, camera, |k| store.contains(k));
        stats.released = step.released;
        let changed = step.released > 0 || !step.uploads.is_empty();
        for (slot, k) in step.uploads {
            let Some(cell) = store.fetch(k) else {
                // Dropped by the source since `contains` (a world source trims far cells).
                self.pool.release(k);
                continue;
            };
            let words = pack_cell(&cell);
            let offset = slot as u64 * (PROBES_PER_CELL * PROBE_WORDS * 4) as u64;
            ctx.queue
                .write_buffer(&self.cells, offset, bytemuck::cast_slice(&words));
            stats.uploaded += 1;
        }
        if changed {
            ctx.queue
                .write_buffer(&self.table, 0, &self.pool.combined_table());
        }
        stats.resident = self.pool.used() as u32;
        let params = self.params_for(origin, camera, &light);
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        stats
    }

    fn params_for(&self, origin: Vec2, camera: Vec2, light: &IndirectLight) -> IndirectParams {
        let bases = ClipMap::bases(origin, camera);
        IndirectParams {
            lighting: light.lighting.map(|c| c.extend(0.0).to_array()),
            origin_camera: [origin.x, origin.y, camera.x, camera.y],
            base: bases.map(|b| [b.x, b.y, 0, 0]),
            grid: [GRID_SECTORS, 0, 0, 0],
            ground: Sh9Gpu::from(&light.ground),
            counts: [POOL_PROBES as u32, self.view, 0, 0],
            fallback: light.fallback_channels(),
        }
    }

    /// `probes.transfer` then `probes.inject`; `None` without baked cells
    /// or lighting.
    pub fn add<'a>(&'a self, g: &mut FrameGraph<'a>) -> Option<IndirectFrame> {
        self.store.as_ref()?;
        self.light.as_ref()?;
        let sh = g.create_buffer("probes.sh", BufferDesc::new((POOL_PROBES * 3 * 16) as u64));
        let sh = g
            .compute("probes.transfer", &self.transfer)
            .compute_pipeline(Ok(self.transfer_pipeline.clone()))
            .uniform("params", &self.params)
            .uniform("cells", &self.cells)
            .write_buffer("sh_probes", sh)
            .dispatch([(POOL_PROBES as u32).div_ceil(64), 1, 1])
            .buffer(sh);
        let desc = TextureDesc {
            depth_or_layers: CASCADES as u32,
            ..TextureDesc::new_2d(CLIP_RES as u32, CLIP_RES as u32, CLIP_FORMAT)
        };
        let clip = ["probes.clip_r", "probes.clip_g", "probes.clip_b"]
            .map(|n| g.create_texture(n, desc.clone()));
        let written = g
            .compute("probes.inject", &self.inject)
            .compute_pipeline(Ok(self.inject_pipeline.clone()))
            .uniform("params", &self.params)
            .uniform("table", &self.table)
            .read_buffer("sh_probes", sh, crate::graph::BufferAccess::StorageRead)
            .storage("clip_r", clip[0])
            .storage("clip_g", clip[1])
            .storage("clip_b", clip[2])
            .dispatch([
                (CLIP_RES as u32).div_ceil(8),
                (CLIP_RES as u32).div_ceil(8),
                CASCADES as u32,
            ]);
        // The new versions, in declaration order.
        Some(IndirectFrame {
            clip: [written.storage[0], written.storage[1], written.storage[2]],
        })
    }

    /// GPU bytes that outlive a frame, by name (the clip map is a frame
    /// target: 3 x 32 x 32 x 5 RGBA16F = 120 KiB, in the frame pool).
    pub fn memory(&self) -> Vec<(String, u64)> {
        vec![
            ("probes.cells (80-cell pool)".to_string(), self.cells.size()),
            (
                "probes.page table (160 x 160 sectors)".to_string(),
                self.table.size(),
            ),
            ("probes.params".to_string(), self.params.size()),
        ]
    }
}
