//! GPU resources of the sky occlusion: the pool (SH2 visibility and heights
//! per layer, sector table), the per-frame intermediates, pipelines.

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::vertex_layout;

use super::reference::{self, RENDER_TEXELS};

pub const VIS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const HEIGHTS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;
pub const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const TABLE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Sint;

/// Twin of `SectorView` in `heightfield.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SectorViewGpu {
    pub view_proj: [[f32; 4]; 4],
    /// xy world x, z of texel (0, 0)'s corner; z the texel size.
    pub origin: [f32; 4],
}

/// Twin of `SectorJob` in `visibility.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct JobGpu {
    pub origin: [f32; 4],
    pub layer: [u32; 4],
}

fn texture(
    ctx: &GpuContext,
    label: &str,
    size: u32,
    layers: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    crate::gpu::texture_2d(&ctx.device, label, (size, size), layers, format, usage)
}

/// A view of every layer as a 2D array (also for single-layer textures).
pub fn array_view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// The descriptor of [`array_view`] (every layer).
pub fn array_view_desc() -> wgpu::TextureViewDescriptor<'static> {
    wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    }
}

/// The descriptor of [`layer_view`] (one layer, render attachment).
pub fn layer_view_desc(layer: u32) -> wgpu::TextureViewDescriptor<'static> {
    wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    }
}

/// Writes f32 texels into one layer of an R32Float texture.
pub fn write_layer(ctx: &GpuContext, t: &wgpu::Texture, layer: u32, data: &[f32]) {
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: t,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytemuck::cast_slice(data),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(t.width() * 4),
            rows_per_image: Some(t.height()),
        },
        wgpu::Extent3d {
            width: t.width(),
            height: t.height(),
            depth_or_array_layers: 1,
        },
    );
}

/// The pool lighting reads: SH2 visibility and (surface, blurred) heights
/// per layer, the 32x32 sector table, a bilinear clamp sampler.
pub struct PoolTextures {
    pub layers: u32,
    pub vis: wgpu::Texture,
    pub heights: wgpu::Texture,
    pub vis_view: wgpu::TextureView,
    pub heights_view: wgpu::TextureView,
    pub table: wgpu::Texture,
    pub table_view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
}

impl PoolTextures {
    /// `layers` of `size`²; (1, 1) is the placeholder bound while the
    /// sky occlusion has never run (an empty table: open sky everywhere).
    pub fn new(ctx: &GpuContext, layers: u32, size: u32) -> Self {
        use wgpu::TextureUsages as U;
        let usage = U::TEXTURE_BINDING | U::STORAGE_BINDING | U::COPY_SRC;
        // Two layers at least, so the default view is an array everywhere.
        let layers = layers.max(2);
        let vis = texture(ctx, "skyocc.vis", size, layers, VIS_FORMAT, usage);
        let heights = texture(ctx, "skyocc.heights", size, layers, HEIGHTS_FORMAT, usage);
        let n = super::pool::TABLE_SIZE as u32;
        let table = crate::gpu::texture_2d(
            &ctx.device,
            "skyocc.table",
            (n, n),
            1,
            TABLE_FORMAT,
            U::TEXTURE_BINDING | U::COPY_DST,
        );
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("skyocc.sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let pool = Self {
            layers: if size == 1 { 1 } else { layers },
            vis_view: array_view(&vis),
            heights_view: array_view(&heights),
            table_view: table.create_view(&Default::default()),
            vis,
            heights,
            table,
            sampler,
        };
        pool.write_table(ctx, &vec![[0; 4]; (n * n) as usize]);
        pool
    }

    pub fn write_table(&self, ctx: &GpuContext, table: &[[i32; 4]]) {
        let n = super::pool::TABLE_SIZE as u32;
        ctx.queue.write_texture(
            self.table.as_image_copy(),
            bytemuck::cast_slice(table),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(n * 16),
                rows_per_image: Some(n),
            },
            wgpu::Extent3d {
                width: n,
                height: n,
                depth_or_array_layers: 1,
            },
        );
    }
}

/// Per-frame work textures (one layer per sector of the frame), created on
/// the first frame with sky occlusion: raw heights, depth, blur scratch,
/// blurred heights; the sector views and the job list.
pub struct Intermediates {
    /// Highest surface per texel (every opaque draw).
    pub raw: wgpu::Texture,
    /// Highest ground surface per texel (terrain objects only).
    pub ground: wgpu::Texture,
    pub depth: wgpu::Texture,
    pub scratch: wgpu::Texture,
    pub blurred: wgpu::Texture,
    /// SH2 visibility of the sector and a `SMOOTH_BORDER` ring, before smoothing.
    pub vis_ext: wgpu::Texture,
    pub views: Vec<wgpu::Buffer>,
    pub jobs: wgpu::Buffer,
}

impl Intermediates {
    pub fn new(ctx: &GpuContext, jobs: u32) -> Self {
        use wgpu::TextureUsages as U;
        let n = RENDER_TEXELS as u32;
        let all = U::TEXTURE_BINDING | U::STORAGE_BINDING | U::COPY_SRC;
        let layers = jobs.max(2);
        Self {
            raw: texture(
                ctx,
                "skyocc.raw",
                n,
                layers,
                RAW_FORMAT,
                all | U::RENDER_ATTACHMENT | U::COPY_DST,
            ),
            ground: texture(
                ctx,
                "skyocc.ground",
                n,
                layers,
                RAW_FORMAT,
                all | U::RENDER_ATTACHMENT | U::COPY_DST,
            ),
            depth: texture(
                ctx,
                "skyocc.depth",
                n,
                layers,
                DEPTH_FORMAT,
                U::RENDER_ATTACHMENT,
            ),
            scratch: texture(ctx, "skyocc.scratch", n, layers, RAW_FORMAT, all),
            blurred: texture(ctx, "skyocc.blurred", n, layers, RAW_FORMAT, all),
            vis_ext: texture(
                ctx,
                "skyocc.vis_ext",
                (reference::SECTOR_TEXELS + 2 * reference::SMOOTH_BORDER) as u32,
                layers,
                wgpu::TextureFormat::Rgba32Float,
                U::TEXTURE_BINDING | U::STORAGE_BINDING,
            ),
            views: (0..jobs)
                .map(|i| {
                    crate::gpu::pipeline::uniform_buffer(
                        ctx,
                        &format!("skyocc.sector{i}"),
                        &<SectorViewGpu as bytemuck::Zeroable>::zeroed(),
                    )
                })
                .collect(),
            jobs: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("skyocc.jobs"),
                size: (jobs.max(1) as usize * std::mem::size_of::<JobGpu>()) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

/// The Poisson disk of [`reference::poisson_disk`] as `array<vec2f>`.
pub fn disk_buffer(ctx: &GpuContext) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    let disk: Vec<[f32; 2]> = reference::poisson_disk(reference::SAMPLES)
        .iter()
        .map(|p| p.to_array())
        .collect();
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("skyocc.disk"),
            contents: bytemuck::cast_slice(&disk),
            usage: wgpu::BufferUsages::STORAGE,
        })
}

/// Top-down height render: position only, depth LessEqual (highest surface
/// wins, depth 0 at the top), no culling (single-sided terrain), no bias.
pub fn height_pipeline(
    ctx: &GpuContext,
    program: &Program,
) -> Result<wgpu::RenderPipeline, GpuError> {
    let mut layout = vertex_layout();
    layout.attributes = &layout.attributes[..1];
    let targets = [crate::passes::common::target(RAW_FORMAT)];
    program.render_pipeline(
        ctx,
        &RenderSpec {
            label: "skyocc.heightfield",
            vertex_entry: "vs_main",
            fragment_entry: Some("fs_main"),
            vertex_buffers: &[Some(layout)],
            targets: &targets,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            constants: &[],
        },
    )
}

/// The world's terrain into a sector's raw and ground images
/// (`terrain.wgsl`): full-screen, depth written from the height, always.
pub fn terrain_pipeline(
    ctx: &GpuContext,
    program: &Program,
) -> Result<wgpu::RenderPipeline, GpuError> {
    let targets = [
        crate::passes::common::target(RAW_FORMAT),
        crate::passes::common::target(RAW_FORMAT),
    ];
    program.render_pipeline(
        ctx,
        &RenderSpec {
            label: "skyocc.terrain",
            vertex_entry: "vs_main",
            fragment_entry: Some("fs_main"),
            vertex_buffers: &[],
            targets: &targets,
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            primitive: wgpu::PrimitiveState::default(),
            constants: &[],
        },
    )
}
