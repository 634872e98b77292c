//! Sky occlusion outside a frame (tests and tools): render given sectors,
//! run the kernels on given height images, read pool layers back.

use glam::{Vec2, Vec4};

use super::pool::Sector;
use super::resources::{self, Intermediates, PoolTextures};
use super::{
    MAX_SECTORS_PER_FRAME, POOL_LAYERS, RENDER_TEXELS, SECTOR_TEXELS, SectorReadback, SkyOccPass,
    reference,
};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::SceneGpu;
use crate::graph::{FrameGraph, TexturePool};

/// Compiles, records and submits a graph of side-effect nodes.
fn run_graph(ctx: &GpuContext, graph: FrameGraph<'_>) -> Result<(), GpuError> {
    let err = |e: crate::graph::GraphError| GpuError::Other(e.to_string());
    let commands = graph
        .compile()
        .map_err(err)?
        .execute(&ctx.device, &mut TexturePool::new(), None)
        .map_err(err)?;
    ctx.queue.submit([commands]);
    Ok(())
}

impl SkyOccPass {
    /// Tests and tools: renders `sectors` (at most [`MAX_SECTORS_PER_FRAME`])
    /// through the three passes outside a frame and reads them back.
    pub fn render_sectors(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        sectors: &[Sector],
    ) -> Result<Vec<SectorReadback>, GpuError> {
        self.jobs.clear();
        let planned = self.pool.plan(sectors, MAX_SECTORS_PER_FRAME);
        let layers: Vec<u32> = sectors.iter().filter_map(|s| self.pool.layer(*s)).collect();
        self.plan_jobs(ctx, scene, &planned, sectors);
        let mut graph = FrameGraph::new();
        self.add(&mut graph, scene, super::SkyOccSources::default());
        run_graph(ctx, graph)?;
        ctx.check("skyocc.render_sectors")?;
        let mut out = Vec::new();
        for (i, layer) in layers.into_iter().enumerate() {
            out.push(self.read_layer(ctx, layer, i as u32)?);
        }
        Ok(out)
    }

    /// Tests: runs the blur and visibility kernels on given raw height
    /// images and their terrain-only images (pairs of [`RENDER_TEXELS`]²,
    /// origin = world x, z of texel (0, 0)), writing pool layers 0..n.
    pub fn run_kernels(
        &mut self,
        ctx: &GpuContext,
        images: &[(reference::HeightImage, reference::HeightImage)],
    ) -> Result<Vec<SectorReadback>, GpuError> {
        if self.textures.layers < POOL_LAYERS {
            self.textures = PoolTextures::new(ctx, POOL_LAYERS, SECTOR_TEXELS as u32);
        }
        let work = self
            .work
            .get_or_insert_with(|| Intermediates::new(ctx, MAX_SECTORS_PER_FRAME as u32));
        let n = images.len().min(MAX_SECTORS_PER_FRAME) as u32;
        let mut jobs = Vec::new();
        for (i, (raw, ground)) in images.iter().take(n as usize).enumerate() {
            for (what, image) in [("raw", raw), ("ground", ground)] {
                if image.size != RENDER_TEXELS {
                    return Err(GpuError::Other(format!(
                        "{what} height image {i} is {}², not {RENDER_TEXELS}²",
                        image.size
                    )));
                }
            }
            resources::write_layer(ctx, &work.raw, i as u32, &raw.h);
            resources::write_layer(ctx, &work.ground, i as u32, &ground.h);
            jobs.push(resources::JobGpu {
                origin: [raw.origin.x, raw.origin.y, 0.0, 0.0],
                layer: [i as u32, 0, 0, 0],
            });
        }
        if n == 0 {
            return Ok(Vec::new());
        }
        ctx.queue
            .write_buffer(&work.jobs, 0, bytemuck::cast_slice(&jobs));
        let work = self
            .work
            .as_ref()
            .ok_or_else(|| GpuError::Other("no work".into()))?;
        let mut graph = FrameGraph::new();
        let images = (
            graph.import_texture("skyocc.raw", &work.raw),
            graph.import_texture("skyocc.ground", &work.ground),
        );
        let pool = (
            graph.import_texture("skyocc.vis", &self.textures.vis),
            graph.import_texture("skyocc.heights", &self.textures.heights),
        );
        self.add_kernels(&mut graph, work, images, pool, n);
        run_graph(ctx, graph)?;
        ctx.check("skyocc.run_kernels")?;
        (0..n).map(|i| self.read_layer(ctx, i, i)).collect()
    }

    fn read_layer(
        &self,
        ctx: &GpuContext,
        layer: u32,
        job: u32,
    ) -> Result<SectorReadback, GpuError> {
        let vis = crate::gpu::read_texture(ctx, &self.textures.vis, 0, layer)?.to_rgba_f32()?;
        let heights = crate::gpu::read_texture(ctx, &self.textures.heights, 0, layer)?;
        let heights: Vec<Vec2> = bytemuck::pod_collect_to_vec::<u8, f32>(&heights.bytes)
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect();
        let work = self
            .work
            .as_ref()
            .ok_or_else(|| GpuError::Other("no work".into()))?;
        let image = |t: &wgpu::Texture| -> Result<Vec<f32>, GpuError> {
            let texels = crate::gpu::read_texture(ctx, t, 0, job)?.to_rgba_f32()?;
            Ok(texels.iter().map(|v| v[0]).collect())
        };
        Ok(SectorReadback {
            sh: vis.iter().map(|v| Vec4::from_array(*v)).collect(),
            heights,
            raw: image(&work.raw)?,
            blurred: image(&work.blurred)?,
        })
    }

    /// Reads back a resident sector's SH2 visibility and heights (tests);
    /// `None` when the sector has no layer.
    pub fn read_sector(
        &self,
        ctx: &GpuContext,
        sector: Sector,
    ) -> Result<Option<SectorReadback>, GpuError> {
        match self.pool.layer(sector) {
            Some(layer) => Ok(Some(self.read_layer(ctx, layer, 0)?)),
            None => Ok(None),
        }
    }
}
