//! Environment map for ambient specular (TECHNIQUES L4, M4): the sky captured
//! into a cube, its box-filtered mip chain, GGX filtered importance sampling
//! per roughness mip, and the split-sum DFG table computed on the GPU. The
//! lighting pass reads the filtered cube along the M4 reflection vector.
//! Re-run whenever the sky changes (time of day), not every frame.
//! Math and figures: `docs/techniques/L4.md`; CPU twin: [`mod@reference`].

pub mod probe;
pub mod reference;
mod view;

pub use view::{EnvView, EnvViewPass};

use wgpu::util::DeviceExt;

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureHandle};

/// Texel format of the source and filtered cubes and of the DFG table (HDR radiance in half floats).
pub const ENVMAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Face size of the captured and filtered cubes (the talk: 128x128x6).
pub const ENVMAP_SIZE: u32 = 128;
/// Filtered mips: perceptual roughness m / (levels - 1) in mip m; 128 down to 4.
pub const FILTERED_LEVELS: u32 = 6;
/// GGX samples per filtered texel; measured against a 16k-sample reference
/// in `tests/envmap.rs`.
pub const FILTER_SAMPLES: u32 = 128;
/// DFG table size (n.v x perceptual roughness).
pub const DFG_SIZE: u32 = 64;

const WORKGROUP: u32 = 8;

/// Twin of `FilterParams` in `filter.wgsl`; one per filtered mip, 256-byte aligned.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct FilterParams {
    p: [f32; 4],
    _pad: [f32; 60],
}

/// Pipelines, the cubes and the DFG table.
pub struct EnvMapPass {
    /// Face size in texels of the source and filtered cubes (mip 0).
    pub size: u32,
    capture_program: Program,
    capture: wgpu::ComputePipeline,
    mips_program: Program,
    downsample: wgpu::ComputePipeline,
    filter_program: Program,
    filter: wgpu::ComputePipeline,
    copy: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    source: wgpu::Texture,
    filtered: wgpu::Texture,
    /// Filtered cube, all mips (what lighting samples).
    pub filtered_cube: wgpu::TextureView,
    /// The split-sum DFG table ([`DFG_SIZE`]², x = n.v, y = perceptual roughness; r = scale A, g = bias B), computed once.
    pub dfg: wgpu::Texture,
    /// View of [`Self::dfg`].
    pub dfg_view: wgpu::TextureView,
    /// Trilinear, clamped: for the cubes and the DFG table.
    pub sampler: wgpu::Sampler,
    /// Capture and filter in the next frame (the sky changed).
    pub dirty: bool,
    /// The source came from an HDR environment: never captured from the sky.
    pub fixed_source: bool,
}

/// One mip of a cube texture seen as `dimension`.
pub fn mip_view_desc(
    mip: u32,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::TextureViewDescriptor<'static> {
    wgpu::TextureViewDescriptor {
        dimension: Some(dimension),
        base_mip_level: mip,
        mip_level_count: Some(1),
        ..Default::default()
    }
}

fn cube_texture(device: &wgpu::Device, label: &str, size: u32, mips: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 6,
        },
        mip_level_count: mips,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: ENVMAP_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Number of mips of a full chain for `size`.
pub fn full_mip_count(size: u32) -> u32 {
    32 - size.max(1).leading_zeros()
}

impl EnvMapPass {
    /// Creates the cubes (`size` per face, a power of two >= 32) and computes the DFG table.
    pub fn new(ctx: &GpuContext, size: u32) -> Result<Self, GpuError> {
        if !size.is_power_of_two() || size < 32 {
            return Err(GpuError::Other(format!(
                "environment map size {size}: must be a power of two >= 32"
            )));
        }
        let device = &ctx.device;
        let capture_program = Program::new(ctx, "passes/envmap/capture.wgsl")?;
        let mips_program = Program::new(ctx, "passes/envmap/mips.wgsl")?;
        let filter_program = Program::new(ctx, "passes/envmap/filter.wgsl")?;
        let source = cube_texture(device, "envmap.source", size, full_mip_count(size));
        let filtered = cube_texture(device, "envmap.filtered", size, FILTERED_LEVELS);
        let cube = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::Cube),
                ..Default::default()
            })
        };
        let params: Vec<FilterParams> = (0..FILTERED_LEVELS)
            .map(|m| {
                let roughness = m as f32 / (FILTERED_LEVELS - 1) as f32;
                FilterParams {
                    p: [
                        (roughness * roughness).max(crate::math::brdf::MIN_ALPHA),
                        FILTER_SAMPLES as f32,
                        size as f32,
                        full_mip_count(size) as f32,
                    ],
                    _pad: [0.0; 60],
                }
            })
            .collect();
        let dfg = crate::gpu::texture_2d(
            device,
            "envmap.dfg",
            (DFG_SIZE, DFG_SIZE),
            1,
            ENVMAP_FORMAT,
            wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        let pass = Self {
            size,
            capture: capture_program.compute_pipeline(ctx, "cs_capture", &[])?,
            capture_program,
            downsample: mips_program.compute_pipeline(ctx, "cs_downsample", &[])?,
            mips_program,
            filter: filter_program.compute_pipeline(ctx, "cs_filter", &[])?,
            copy: filter_program.compute_pipeline(ctx, "cs_copy", &[])?,
            filter_program,
            params: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("envmap.filter.params"),
                contents: bytemuck::cast_slice(&params),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            filtered_cube: cube(&filtered),
            source,
            filtered,
            dfg_view: dfg.create_view(&Default::default()),
            dfg,
            sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("envmap.sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                ..Default::default()
            }),
            dirty: true,
            fixed_source: false,
        };
        pass.compute_dfg(ctx)?;
        Ok(pass)
    }

    fn compute_dfg(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        let program = Program::new(ctx, "passes/envmap/dfg.wgsl")?;
        let pipeline = program.compute_pipeline(ctx, "cs_dfg", &[])?;
        let bg = program.bind(
            &ctx.device,
            0,
            &[(
                "out_texture",
                wgpu::BindingResource::TextureView(&self.dfg_view),
            )],
        )?;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut cp = encoder.begin_compute_pass(&Default::default());
            cp.set_pipeline(&pipeline);
            cp.set_bind_group(0, &bg, &[]);
            let n = DFG_SIZE.div_ceil(WORKGROUP);
            cp.dispatch_workgroups(n, n, 1);
        }
        ctx.queue.submit([encoder.finish()]);
        ctx.check("envmap.dfg")
    }

    /// The source cube (captured sky and its box mips), for tests.
    pub fn source(&self) -> &wgpu::Texture {
        &self.source
    }

    /// The filtered cube, for tests and debug views.
    pub fn filtered(&self) -> &wgpu::Texture {
        &self.filtered
    }

    /// Outside a frame: uploads `level0` (6 faces of `size`² linear RGB, rows
    /// top down) as the source instead of the sky, then builds the mips and
    /// filters (tests, HDR environments).
    pub fn filter_faces(
        &self,
        ctx: &GpuContext,
        level0: &[Vec<[f32; 3]>; 6],
    ) -> Result<(), crate::Error> {
        let texels = (self.size * self.size) as usize;
        for (face, texels_rgb) in level0.iter().enumerate() {
            if texels_rgb.len() != texels {
                return Err(crate::Error::InvalidSettings(format!(
                    "environment face {face}: {} texels, expected {texels}",
                    texels_rgb.len()
                )));
            }
            let bytes: Vec<half::f16> = texels_rgb
                .iter()
                .flat_map(|c| [c[0], c[1], c[2], 1.0].map(half::f16::from_f32))
                .collect();
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &self.source,
                    mip_level: 0,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: face as u32,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytemuck::cast_slice(&bytes),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.size * 8),
                    rows_per_image: Some(self.size),
                },
                wgpu::Extent3d {
                    width: self.size,
                    height: self.size,
                    depth_or_array_layers: 1,
                },
            );
        }
        let mut graph = FrameGraph::new();
        let filtered = self.add_steps(&mut graph, None);
        graph.mark_output(filtered);
        let commands =
            graph
                .compile()?
                .execute(&ctx.device, &mut crate::graph::TexturePool::new(), None)?;
        ctx.queue.submit([commands]);
        ctx.check("envmap.filter_faces")?;
        Ok(())
    }

    /// Adds capture, mips and filtering when [`Self::dirty`]; returns the
    /// filtered cube's handle for the lighting pass to read.
    pub fn add<'a>(&'a self, graph: &mut FrameGraph<'a>, sky: &'a wgpu::Buffer) -> TextureHandle {
        if self.dirty && !self.fixed_source {
            self.add_steps(graph, Some(sky))
        } else {
            graph.import_texture("envmap.filtered", &self.filtered)
        }
    }

    /// Capture (from `sky`; `None`: the source was uploaded), mips, filter.
    fn add_steps<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        sky: Option<&'a wgpu::Buffer>,
    ) -> TextureHandle {
        let mut source = self.import_source(graph);
        if let Some(sky) = sky {
            source = self.add_capture(graph, source, sky);
        }
        self.add_mips_and_filter(graph, source)
    }

    /// The source cube in `graph` (for passes that fill its level 0).
    pub fn import_source<'a>(&'a self, graph: &mut FrameGraph<'a>) -> TextureHandle {
        graph.import_texture("envmap.source", &self.source)
    }

    /// Box mips of the filled source, then GGX filtering; returns the filtered cube.
    pub fn add_mips_and_filter<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        source: TextureHandle,
    ) -> TextureHandle {
        let source = self.add_mips(graph, source);
        self.add_filter(graph, source)
    }

    /// `envmap.mip1..`: the box-filtered chain of the source cube below
    /// level 0, one node per mip (each reads its parent level).
    fn add_mips<'a>(&'a self, graph: &mut FrameGraph<'a>, source: TextureHandle) -> TextureHandle {
        let mut source = source;
        let array = wgpu::TextureViewDimension::D2Array;
        for mip in 1..full_mip_count(self.size) {
            let n = (self.size >> mip).max(1).div_ceil(WORKGROUP);
            let written = graph
                .compute(&format!("envmap.mip{mip}"), &self.mips_program)
                .compute_pipeline(Ok(self.downsample.clone()))
                .read_view("parent", source, mip_view_desc(mip - 1, array))
                .storage_view("child", source, mip_view_desc(mip, array))
                .dispatch([n, n, 6]);
            source = written.storage.first().copied().unwrap_or(source);
        }
        source
    }

    /// `envmap.filter0..`: GGX filtered importance sampling of each mip of
    /// the filtered cube (mip 0 copied), one node per mip.
    fn add_filter<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        source: TextureHandle,
    ) -> TextureHandle {
        let mut filtered = graph.import_texture("envmap.filtered", &self.filtered);
        let array = wgpu::TextureViewDimension::D2Array;
        for mip in 0..FILTERED_LEVELS {
            let params = wgpu::BufferBinding {
                buffer: &self.params,
                offset: u64::from(mip) * 256,
                size: wgpu::BufferSize::new(16),
            };
            let pipeline = if mip == 0 { &self.copy } else { &self.filter };
            let n = (self.size >> mip).max(1).div_ceil(WORKGROUP);
            let written = graph
                .compute(&format!("envmap.filter{mip}"), &self.filter_program)
                .compute_pipeline(Ok(pipeline.clone()))
                .externals([("params", wgpu::BindingResource::Buffer(params))])
                .read_cube("source", source)
                .sampler("source_sampler", &self.sampler)
                .storage_view("out_texture", filtered, mip_view_desc(mip, array))
                .dispatch([n, n, 6]);
            filtered = written.storage.first().copied().unwrap_or(filtered);
        }
        filtered
    }

    /// Wall-clock milliseconds (median of `repeats`) of the box mips and of
    /// the filter on the current source cube, each submitted alone and
    /// waited for. For cost ratios where encoder timestamps do not bracket
    /// compute work (lavapipe reads about 0.03 ms for both).
    pub fn time_mips_and_filter(
        &self,
        ctx: &GpuContext,
        repeats: u32,
    ) -> Result<(f64, f64), crate::Error> {
        let mut pool = crate::graph::TexturePool::new();
        let mut run = |filter: bool| -> Result<f64, crate::Error> {
            let mut graph = FrameGraph::new();
            let source = self.import_source(&mut graph);
            let out = if filter {
                self.add_filter(&mut graph, source)
            } else {
                self.add_mips(&mut graph, source)
            };
            graph.mark_output(out);
            let commands = graph.compile()?.execute(&ctx.device, &mut pool, None)?;
            ctx.wait("envmap timing")?;
            let start = std::time::Instant::now();
            ctx.queue.submit([commands]);
            ctx.wait("envmap timing")?;
            Ok(start.elapsed().as_secs_f64() * 1e3)
        };
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let (mut mips, mut filter) = (Vec::new(), Vec::new());
        for _ in 0..repeats.max(1) {
            mips.push(run(false)?);
            filter.push(run(true)?);
        }
        Ok((median(mips), median(filter)))
    }

    /// `envmap.capture`: the sky (`sky`'s parameters) into level 0 of the source.
    fn add_capture<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        source: TextureHandle,
        sky: &'a wgpu::Buffer,
    ) -> TextureHandle {
        let n = self.size.div_ceil(WORKGROUP);
        let level0 = mip_view_desc(0, wgpu::TextureViewDimension::D2Array);
        graph
            .compute("envmap.capture", &self.capture_program)
            .compute_pipeline(Ok(self.capture.clone()))
            .uniform("sky", sky)
            .storage_view("out_texture", source, level0)
            .dispatch([n, n, 6])
            .storage
            .first()
            .copied()
            .unwrap_or(source)
    }
}
