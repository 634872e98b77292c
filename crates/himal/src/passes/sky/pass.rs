//! Sky pass (TECHNIQUES L1): Preetham or Bruneton radiance and the sun disk
//! drawn where the G-buffer left depth at its cleared value (reverse-Z 0);
//! with the Bruneton model also the capture of the sky into the environment
//! cube (`sky.capture`). Shaders: `passes/sky/draw.wgsl`,
//! `passes/sky/bruneton/capture.wgsl`; CPU twins: `passes/sky/preetham.rs`,
//! `passes/sky/bruneton/reference.rs`.

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{Fallback, FrameGraph, TextureHandle};
use crate::graph::{PassTimer, PassTiming};
use crate::passes::common::target;
use crate::passes::gbuffer::DEPTH_FORMAT;
use crate::passes::lighting::HDR_FORMAT;
use crate::passes::sky::bruneton::{
    AtmosphereConfig, BrunetonTables, SkyShProjector, TableSizes, TableViews, moon_light,
};
use crate::passes::sky::{SkyLight, SkyModel};

/// The Bruneton tables and what draws from them.
pub struct BrunetonSky {
    pub tables: BrunetonTables,
    views: TableViews,
    pipeline: wgpu::RenderPipeline,
    capture_program: Program,
    capture: wgpu::ComputePipeline,
    /// GPU SH projection of the table sky (`sky.sh`).
    pub sh: SkyShProjector,
}

impl BrunetonSky {
    /// L1 sky light from the tables: the GPU-projected SH3 sky irradiance
    /// replaces `light`'s, and at night the moon takes the sun's place as
    /// the directional light. Returns the projection's timings (`sky.sh`).
    pub fn update_light(
        &self,
        ctx: &GpuContext,
        light: &mut SkyLight,
        timer: Option<&mut PassTimer>,
    ) -> Result<Vec<PassTiming>, GpuError> {
        let (sh, timings) = self
            .sh
            .project(ctx, &self.tables, light.sun_direction, timer)?;
        light.irradiance_sh = sh.radiance_to_irradiance_coeffs();
        if let Some((dir, e)) = moon_light(light.sun_direction) {
            light.sun_direction = dir;
            light.sun_illuminance = e;
        }
        Ok(timings)
    }
}

/// The sky drawn behind the scene into the HDR target: Preetham, Bruneton or an HDR environment.
pub struct SkyPass {
    program: Program,
    pipeline: wgpu::RenderPipeline,
    /// An HDR environment drawn instead of the Preetham sky (issue #8):
    /// its pipeline (`ENVIRONMENT`, `ENV_ROTATION`), image view and sampler.
    environment: Option<(wgpu::RenderPipeline, wgpu::TextureView, wgpu::Sampler)>,
    /// Samples the environment and the tables' slots when they are absent.
    sampler: wgpu::Sampler,
    bruneton: Option<BrunetonSky>,
    /// The model drawn (Bruneton needs [`SkyPass::set_bruneton`] first).
    pub model: SkyModel,
}

fn sky_depth_test() -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        // the triangle sits at depth 0: passes only where nothing was drawn
        depth_compare: Some(wgpu::CompareFunction::Equal),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

impl SkyPass {
    /// The Preetham sky pipeline; Bruneton needs [`SkyPass::set_bruneton`] or
    /// [`SkyPass::prepare_bruneton`].
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/sky/draw.wgsl")?;
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("sky", &targets);
        spec.depth_stencil = Some(sky_depth_test());
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self {
            program,
            pipeline,
            environment: None,
            sampler: ctx.device.create_sampler(&Default::default()),
            bruneton: None,
            model: SkyModel::Preetham,
        })
    }

    /// Draws from `tables` whenever [`SkyPass::model`] is Bruneton.
    pub fn set_bruneton(
        &mut self,
        ctx: &GpuContext,
        tables: BrunetonTables,
    ) -> Result<(), GpuError> {
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("sky.bruneton", &targets);
        spec.depth_stencil = Some(sky_depth_test());
        let constants = [("SKY_MODEL", 1.0)];
        spec.constants = &constants;
        let pipeline = self.program.render_pipeline(ctx, &spec)?;
        let capture_program = Program::new(ctx, "passes/sky/bruneton/capture.wgsl")?;
        let capture = capture_program.compute_pipeline(ctx, "cs_capture_bruneton", &[])?;
        self.bruneton = Some(BrunetonSky {
            views: tables.views(),
            tables,
            pipeline,
            capture_program,
            capture,
            sh: SkyShProjector::new(ctx)?,
        });
        Ok(())
    }

    /// L1: loads (cache file in `cache_dir`) or computes the Bruneton tables
    /// at `sizes` once (again when the sizes change) and creates their
    /// pipelines; returns the computation's timings.
    pub fn prepare_bruneton(
        &mut self,
        ctx: &GpuContext,
        sizes: TableSizes,
        cache_dir: Option<&std::path::Path>,
        timer: Option<&mut PassTimer>,
    ) -> Result<Vec<PassTiming>, GpuError> {
        if self
            .bruneton
            .as_ref()
            .is_some_and(|b| b.tables.config.sizes == sizes)
        {
            return Ok(Vec::new());
        }
        let config = AtmosphereConfig::earth(sizes);
        let (tables, timings) = BrunetonTables::load_or_compute(ctx, config, cache_dir, timer)?;
        self.set_bruneton(ctx, tables)?;
        Ok(timings)
    }

    /// The Bruneton tables and what draws from them, once set.
    pub fn bruneton(&self) -> Option<&BrunetonSky> {
        self.bruneton.as_ref()
    }

    /// The Bruneton sky is drawn (model Bruneton, tables present, no HDR environment).
    pub fn draws_bruneton(&self) -> bool {
        self.model == SkyModel::Bruneton && self.bruneton.is_some() && self.environment.is_none()
    }

    /// `sky.capture`: the Bruneton sky (from `sky`'s sun direction) into
    /// mip 0 of the environment source cube behind `source`, edge `size`.
    /// Call only when [`SkyPass::draws_bruneton`].
    pub fn add_capture<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        source: TextureHandle,
        size: u32,
        sky: &'a wgpu::Buffer,
    ) -> Result<TextureHandle, GpuError> {
        let b = self
            .bruneton
            .as_ref()
            .ok_or_else(|| GpuError::Other("sky.capture without Bruneton tables".into()))?;
        let level0 = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            base_mip_level: 0,
            mip_level_count: Some(1),
            ..Default::default()
        };
        let written = graph
            .compute("sky.capture", &b.capture_program)
            .compute_pipeline(Ok(b.capture.clone()))
            .externals(b.views.bindings(&b.tables.params, &b.tables.sampler))
            .uniform("sky", sky)
            .storage_view("out_texture", source, level0)
            .dispatch([size.div_ceil(8), size.div_ceil(8), 6]);
        Ok(written.storage[0])
    }

    /// Draws `image` (equirectangular, turned by `rotation` radians about +Y)
    /// as the background instead of the Preetham sky.
    pub fn set_environment(
        &mut self,
        ctx: &GpuContext,
        image: &wgpu::TextureView,
        sampler: &wgpu::Sampler,
        rotation: f32,
    ) -> Result<(), GpuError> {
        let targets = [target(HDR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("sky.environment", &targets);
        spec.depth_stencil = Some(sky_depth_test());
        let constants = [("ENVIRONMENT", 1.0), ("ENV_ROTATION", f64::from(rotation))];
        spec.constants = &constants;
        let pipeline = self.program.render_pipeline(ctx, &spec)?;
        self.environment = Some((pipeline, image.clone(), sampler.clone()));
        Ok(())
    }

    /// Draws the sky where `depth` is clear into `hdr`, with the graph's
    /// frame constants (`view`, and `sky` unless `sky` overrides it).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        sky: Option<&'a wgpu::Buffer>,
    ) -> TextureHandle {
        let (pipeline, image, sampler) = match &self.environment {
            Some((p, i, s)) => (p, Some(i), s),
            None => (&self.pipeline, None, &self.sampler),
        };
        let mut node = graph.fullscreen("sky", &self.program);
        node = match &self.bruneton {
            Some(b) if self.draws_bruneton() => node
                .pipeline(Ok(b.pipeline.clone()))
                .externals(b.views.bindings(&b.tables.params, &b.tables.sampler)),
            // Preetham or an HDR image: SKY_MODEL 0 reads no table.
            _ => node
                .pipeline(Ok(pipeline.clone()))
                .optional_buffer("atmosphere", None)
                .optional_external("transmittance_load", None, Fallback::Black)
                .optional_external("scattering", None, Fallback::Black3d)
                .optional_external("single_mie", None, Fallback::Black3d)
                .optional_external("irradiance", None, Fallback::Black)
                .sampler("table_sampler", &self.sampler),
        };
        node = node
            .optional_external("environment", image, Fallback::Black)
            .sampler("environment_sampler", sampler);
        if let Some(sky) = sky {
            node = node.uniform("sky", sky);
        }
        node.color(hdr, wgpu::LoadOp::Load).depth_test(depth).draw()
    }
}
