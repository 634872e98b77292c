//! `sky.sh`: the Bruneton sky projected onto SH3 on the GPU (`sky_sh.wgsl`),
//! one workgroup, whenever the time of day changes. CPU twin:
//! `Sh9Rgb::project(CpuTables::sky_radiance, SKY_SH_SAMPLES)`.

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::BrunetonTables;
use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError, read_buffer};
use crate::graph::{FrameGraph, PassTimer, PassTiming};
use crate::math::sh::{SH9_COUNT, Sh9Rgb, gauss_legendre};
use crate::passes::sky::reference::SKY_SH_SAMPLES_PER_AXIS;

/// Quadrature of the projection: the Preetham sky's (`SKY_SH_SAMPLES_PER_AXIS`,
/// 2048 directions), whose convergence `tests/sky.rs` measured.
pub const SKY_SH_SAMPLES: u32 = SKY_SH_SAMPLES_PER_AXIS;

/// Pipeline and buffers of the GPU SH projection.
pub struct SkyShProjector {
    program: Program,
    pipeline: wgpu::ComputePipeline,
    rows: wgpu::Buffer,
    sun: wgpu::Buffer,
    output: wgpu::Buffer,
}

impl SkyShProjector {
    /// Creates the projection pipeline and its buffers (quadrature rows, sun, output).
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/sky/bruneton/sky_sh.wgsl")?;
        let pipeline = program.compute_pipeline(ctx, "cs_sky_sh", &[])?;
        // Rows as in Sh9Rgb::project: ceil(n/2) Gauss-Legendre nodes per
        // hemisphere, weight 0.5 w dphi with 2n azimuths (n even).
        let n = SKY_SH_SAMPLES;
        let dphi = std::f64::consts::TAU / f64::from(2 * n);
        let gl = gauss_legendre(n.div_ceil(2) as usize);
        let rows: Vec<[f32; 2]> = [-1.0f64, 1.0]
            .iter()
            .flat_map(|h| {
                gl.iter()
                    .map(move |&(x, w)| [(h * 0.5 * (x + 1.0)) as f32, (0.5 * w * dphi) as f32])
            })
            .collect();
        let rows = ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("sky.sh.rows"),
                contents: bytemuck::cast_slice(&rows),
                usage: wgpu::BufferUsages::STORAGE,
            });
        let sun = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sky.sh.sun"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("sky.sh.out"),
            size: (SH9_COUNT * 16) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Ok(Self {
            program,
            pipeline,
            rows,
            sun,
            output,
        })
    }

    /// Radiance SH of the table sky (sun disk excluded) for a sun towards
    /// `sun_direction`; convolve with `radiance_to_irradiance_coeffs`. With
    /// a `timer`, the GPU time of the projection (row `sky.sh`).
    pub fn project(
        &self,
        ctx: &GpuContext,
        tables: &BrunetonTables,
        sun_direction: Vec3,
        timer: Option<&mut PassTimer>,
    ) -> Result<(Sh9Rgb, Vec<PassTiming>), GpuError> {
        let sun = sun_direction.normalize_or(Vec3::Y).extend(0.0);
        ctx.queue
            .write_buffer(&self.sun, 0, bytemuck::bytes_of(&sun));
        let views = tables.views();
        let mut graph = FrameGraph::new();
        graph
            .compute("sky.sh", &self.program)
            .compute_pipeline(Ok(self.pipeline.clone()))
            .side_effect()
            .externals(views.bindings(&tables.params, &tables.sampler))
            .uniform("sun", &self.sun)
            .uniform("rows", &self.rows)
            .uniform("out_sh", &self.output)
            .dispatch([1, 1, 1]);
        let timings = crate::graph::run(ctx, graph, timer, "sky.sh")?;
        let bytes = read_buffer(ctx, &self.output)?;
        let v: &[[f32; 4]] = bytemuck::try_cast_slice(&bytes)
            .map_err(|e| GpuError::Other(format!("sky.sh read-back: {e}")))?;
        let c = std::array::from_fn(|k| Vec3::new(v[k][0], v[k][1], v[k][2]));
        Ok((Sh9Rgb { c }, timings))
    }
}
