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

use std::sync::{Mutex, MutexGuard};

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3};
use wgpu::util::DeviceExt;

use crate::budget::MemoryBudget;
use crate::gpu::pipeline::{Program, RenderSpec, target};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureHandle};
use crate::passes::cull::CullView;
use crate::passes::gbuffer::{
    ALBEDO_FORMAT, DEPTH_FORMAT, FRAME_FORMAT, GBuffer, MATERIAL_FORMAT, MOTION_FORMAT,
};
use reference::{Geometry, Heights, MAX_LEVELS, Patch, Pyramid, Ranges, SelectStats, Selector};

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

/// The detail pattern a layer's textures are generated with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DetailKind {
    /// Clumped grass blades with a hue variation.
    Grass,
    /// Ridged rock with strata and grain.
    Rock,
    /// Smooth drifts with glossiness sparkle.
    Snow,
    /// Soil with scattered pebbles.
    Soil,
}

/// One material layer; later layers paint over earlier ones where their
/// height and slope bands hold (the first is the base, everywhere).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainLayerDesc {
    /// Linear albedo.
    pub albedo: Vec3,
    /// Glossiness in 0..1 (the detail texture varies it around this).
    pub glossiness: f32,
    /// Heights in metres where the layer holds (infinite: no limit).
    pub height: [f32; 2],
    /// Slope angles in degrees from horizontal (0 and 90: no limit).
    pub slope_deg: [f32; 2],
    /// Width in metres of the transition at each height limit.
    pub height_blend: f32,
    /// Width in degrees of the transition at each slope limit.
    pub slope_blend: f32,
    /// Noise amplitude in metres added to the height before the test.
    pub jitter: f32,
    /// The pattern of the layer's procedural detail textures.
    pub detail: DetailKind,
    /// Metres per repeat of the near detail scale (the far one is 7.3x).
    pub detail_scale: f32,
    /// Strength of the detail normal.
    pub normal_strength: f32,
}

impl TerrainLayerDesc {
    /// Grass everywhere, soil on gentle slopes, rock on steep ones, snow high up.
    pub fn alpine() -> Vec<Self> {
        let any = Self {
            albedo: Vec3::new(0.16, 0.22, 0.07),
            glossiness: 0.25,
            height: [f32::NEG_INFINITY, f32::INFINITY],
            slope_deg: [0.0, 90.0],
            height_blend: 0.0,
            slope_blend: 0.0,
            jitter: 0.0,
            detail: DetailKind::Grass,
            detail_scale: 3.0,
            normal_strength: 0.6,
        };
        vec![
            any.clone(),
            Self {
                albedo: Vec3::new(0.24, 0.19, 0.13),
                glossiness: 0.2,
                slope_deg: [18.0, 90.0],
                slope_blend: 8.0,
                detail: DetailKind::Soil,
                detail_scale: 2.0,
                ..any.clone()
            },
            Self {
                albedo: Vec3::new(0.32, 0.3, 0.28),
                glossiness: 0.35,
                slope_deg: [34.0, 90.0],
                slope_blend: 8.0,
                detail: DetailKind::Rock,
                detail_scale: 6.0,
                normal_strength: 0.9,
                ..any.clone()
            },
            Self {
                albedo: Vec3::new(0.85, 0.87, 0.9),
                glossiness: 0.55,
                height: [150.0, f32::INFINITY],
                slope_deg: [0.0, 42.0],
                height_blend: 30.0,
                slope_blend: 10.0,
                jitter: 25.0,
                detail: DetailKind::Snow,
                detail_scale: 4.0,
                normal_strength: 0.4,
            },
        ]
    }
}

/// The terrain's height data and materials (plain data; see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainDesc {
    /// World x, z of the world's min corner.
    pub origin: Vec2,
    /// Sectors per side (160 in the real world).
    pub sectors: u32,
    /// Side of a sector in metres (one fine tile each).
    pub sector_size: f32,
    /// Fine samples per sector side including the shared edge (65: 1 m).
    pub tile_res: u32,
    /// The coarse grid's spacing: `(sectors sector_size / coarse_spacing + 1)^2` samples.
    pub coarse_spacing: f32,
    /// Row-major coarse heights, row = z index.
    pub coarse: Vec<f32>,
    /// Fine tiles resident at most (texture array layers).
    pub fine_slots: u32,
    /// Material layers, base first (1..=[`MAX_LAYERS`]).
    pub layers: Vec<TerrainLayerDesc>,
}

impl TerrainDesc {
    /// A world of `sectors`^2 sectors of 64 m (65 samples per tile side,
    /// 16 m coarse grid, 512 slots, [`TerrainLayerDesc::alpine`]) whose
    /// coarse grid samples `height(x, z)`.
    pub fn from_fn(origin: Vec2, sectors: u32, height: impl Fn(f32, f32) -> f32) -> Self {
        let mut d = Self {
            origin,
            sectors,
            sector_size: 64.0,
            tile_res: 65,
            coarse_spacing: 16.0,
            coarse: Vec::new(),
            fine_slots: 512,
            layers: TerrainLayerDesc::alpine(),
        };
        let n = (sectors as f32 * d.sector_size / d.coarse_spacing).round() as u32 + 1;
        d.coarse = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                height(
                    origin.x + i as f32 * d.coarse_spacing,
                    origin.y + j as f32 * d.coarse_spacing,
                )
            })
            .collect();
        d
    }

    /// The tile of sector (`sx`, `sz`) sampled from `height(x, z)`.
    pub fn tile_from_fn(&self, sx: u32, sz: u32, height: impl Fn(f32, f32) -> f32) -> Vec<f32> {
        let n = self.tile_res;
        let s = self.sector_size / (n - 1).max(1) as f32;
        let corner = self.origin + Vec2::new(sx as f32, sz as f32) * self.sector_size;
        (0..n * n)
            .map(|k| height(corner.x + (k % n) as f32 * s, corner.y + (k / n) as f32 * s))
            .collect()
    }
}

/// LOD knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainSettings {
    /// Target on-screen vertex spacing in pixels at the end of each range:
    /// `r_l = s_l f / target_px`.
    pub target_px: f32,
    /// Ranges scale by `2^lod_bias` (positive: finer farther).
    pub lod_bias: f32,
    /// Continuous morph; off, vertices snap halfway through the morph area
    /// (for the popping comparison).
    pub morph: bool,
    /// The morph area: the last `m` of `[r_{l-1}, r_l]`.
    pub morph_fraction: f32,
    /// Levels are added until the top range reaches this (metres).
    pub view_distance: f32,
}

impl Default for TerrainSettings {
    fn default() -> Self {
        Self {
            target_px: 12.0,
            lod_bias: 0.0,
            morph: true,
            morph_fraction: 0.3,
            view_distance: 6000.0,
        }
    }
}

/// What the selection needs of a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainView {
    /// The LOD eye (world).
    pub eye: Vec3,
    /// Culling volume (reverse-Z; jitter does no harm).
    pub view_proj: Mat4,
    /// `height / 2 / tan(fov_y / 2)`, pixels.
    pub focal_px: f32,
}

impl TerrainView {
    /// The view of `camera` rendering a frame of `size` (width, height; px).
    pub fn from_camera(camera: &crate::scene::Camera, size: (u32, u32)) -> Self {
        let (w, h) = (size.0.max(1) as f32, size.1.max(1) as f32);
        Self {
            eye: camera.position,
            view_proj: camera.view_projection(w / h),
            focal_px: h * 0.5 / (camera.fov_y_deg.to_radians() * 0.5).tan(),
        }
    }
}

/// One frame's selection.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainStats {
    /// The camera's per-level ranges and morph constants.
    pub ranges: Ranges,
    /// What the camera view's selection did.
    pub camera: SelectStats,
    /// Per shadow view.
    pub shadows: Vec<SelectStats>,
}

impl TerrainStats {
    /// Triangles the camera's draw submits.
    pub fn triangles(&self) -> u32 {
        self.camera.patches() * PATCH_TRIANGLES
    }
}

/// Twin of `TerrainParams` in `shaders/terrain.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct ParamsGpu {
    origin: [f32; 2],
    world_size: f32,
    sector_size: f32,
    coarse_spacing: f32,
    fine_spacing: f32,
    coarse_n: u32,
    sectors: u32,
    tile_res: u32,
    layers: u32,
    morph: u32,
    levels: u32,
    eye: [f32; 4],
    level: [[f32; 4]; MAX_LEVELS],
}

/// Twin of `TerrainLayer` in `terrain.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct LayerGpu {
    albedo: [f32; 4],
    height: [f32; 4],
    slope: [f32; 4],
    detail: [f32; 4],
}

/// Stands for an open limit in the shader's band (finite, so no NaN).
const FAR: f32 = 1e30;

impl LayerGpu {
    fn new(l: &TerrainLayerDesc, index: usize) -> Self {
        let open = |v: f32, no_limit: f32| {
            if v.is_finite() { v } else { no_limit }
        };
        // As the scene's layers: slope limits at 0 and 90 degrees are open.
        let lo_slope = if l.slope_deg[0] > 0.0 {
            l.slope_deg[0]
        } else {
            -FAR
        };
        let hi_slope = if l.slope_deg[1] < 90.0 {
            l.slope_deg[1]
        } else {
            FAR
        };
        Self {
            albedo: l.albedo.extend(l.glossiness).to_array(),
            height: [
                open(l.height[0], -FAR),
                open(l.height[1], FAR),
                l.height_blend,
                l.jitter,
            ],
            slope: [lo_slope, hi_slope, l.slope_blend, l.normal_strength],
            detail: [l.detail_scale, l.detail_scale * 7.3, index as f32, 0.0],
        }
    }
}

/// Patch instances: origin (x, z) and level (twin of [`Patch`]).
const PATCH_ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x2,
        offset: 0,
        shader_location: 0,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Uint32,
        offset: 8,
        shader_location: 1,
    },
];

fn patch_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Patch>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &PATCH_ATTRIBUTES,
    }
}

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
    /// Checks `desc`, uploads the coarse grid, generates the layers' detail
    /// textures and creates the pipelines; no tile is resident.
    pub fn new(ctx: &GpuContext, desc: &TerrainDesc) -> Result<Self, GpuError> {
        let heights = Heights::new(desc).map_err(other)?;
        let g = heights.geometry;
        if desc.layers.is_empty() || desc.layers.len() > MAX_LAYERS {
            return Err(other(format!(
                "terrain: {} material layers (1..={MAX_LAYERS})",
                desc.layers.len()
            )));
        }
        for (i, l) in desc.layers.iter().enumerate() {
            let numbers = [
                l.glossiness,
                l.slope_deg[0],
                l.slope_deg[1],
                l.height_blend,
                l.slope_blend,
                l.jitter,
                l.detail_scale,
                l.normal_strength,
            ];
            if !l.albedo.is_finite()
                || numbers.iter().any(|v| !v.is_finite())
                || l.height.iter().any(|v| v.is_nan())
                || l.detail_scale <= 0.0
            {
                return Err(other(format!(
                    "terrain: layer {i} has a non-finite number or a detail scale <= 0"
                )));
            }
        }
        let limits = ctx.device.limits();
        let dim = limits.max_texture_dimension_2d;
        if g.coarse_n > dim || g.tile_res > dim || g.sectors > dim {
            return Err(other(format!(
                "terrain: the coarse grid ({0} x {0}) exceeds the adapter's {dim} texels per side",
                g.coarse_n
            )));
        }
        if g.fine_slots > limits.max_texture_array_layers {
            return Err(other(format!(
                "terrain: {} fine slots exceed the adapter's {} texture array layers",
                g.fine_slots, limits.max_texture_array_layers
            )));
        }
        // GPU textures plus the CPU mirror (twin and bounds): about twice the data.
        let samples = u64::from(g.coarse_n).pow(2)
            + u64::from(g.fine_slots) * u64::from(g.tile_res).pow(2)
            + u64::from(g.sectors).pow(2);
        MemoryBudget::from_env()
            .and_then(|b| {
                b.check(
                    "the terrain's height data",
                    samples * 4 * 2 + samples * 8 / 3,
                )
            })
            .map_err(other)?;

        let pyramid = Pyramid::new(&heights);
        let program = Program::new(ctx, "passes/terrain/terrain.wgsl")?;
        let shadow_program = Program::new(ctx, "passes/terrain/shadow.wgsl")?;
        let shadow_pipeline = sun_view_pipeline(ctx, &shadow_program, SHADOW_DEPTH_FORMAT)?;
        let static_pipeline =
            sun_view_pipeline(ctx, &shadow_program, crate::passes::shadows::STATIC_FORMAT)?;

        let layer_count = desc.layers.len() as u32;
        let mut layers = [LayerGpu::default(); MAX_LAYERS];
        for (i, l) in desc.layers.iter().enumerate() {
            layers[i] = LayerGpu::new(l, i);
        }
        // Grazing views want anisotropic filtering; lavapipe's (Mesa 22-24)
        // returns per-pixel noise with it, so the CPU adapter filters
        // trilinearly.
        let anisotropy = if ctx.adapter.get_info().device_type == wgpu::DeviceType::Cpu {
            1
        } else {
            8
        };
        let made = ctx.scoped("terrain", || {
            let texture = |label: &str, size: (u32, u32, u32), format, mips: u32| {
                ctx.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: size.2,
                    },
                    mip_level_count: mips,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                })
            };
            let r32 = wgpu::TextureFormat::R32Float;
            let coarse = texture("terrain.coarse", (g.coarse_n, g.coarse_n, 1), r32, 1);
            let fine = texture(
                "terrain.fine",
                (g.tile_res, g.tile_res, g.fine_slots),
                r32,
                1,
            );
            let pages = texture(
                "terrain.pages",
                (g.sectors, g.sectors, 1),
                wgpu::TextureFormat::R32Uint,
                1,
            );
            let d = textures::DETAIL_SIZE;
            let rgba = wgpu::TextureFormat::Rgba8Unorm;
            let mips = textures::mip_count();
            let albedo = texture("terrain.detail_albedo", (d, d, layer_count), rgba, mips);
            let normal = texture("terrain.detail_normal", (d, d, layer_count), rgba, mips);
            let array = wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            };
            let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("terrain.detail"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                anisotropy_clamp: anisotropy,
                ..Default::default()
            });
            let storage = |label: &str, bytes: &[u8]| {
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents: bytes,
                        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    })
            };
            let instances = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("terrain.patches"),
                size: (MAX_VIEWS * MAX_PATCHES * std::mem::size_of::<Patch>()) as u64,
                usage: wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let index_data = reference::patch_indices();
            let indices = ctx
                .device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("terrain.indices"),
                    contents: bytemuck::cast_slice(&index_data),
                    usage: wgpu::BufferUsages::INDEX,
                });
            (
                [coarse, fine, pages, albedo, normal],
                array,
                sampler,
                storage("terrain.params", bytemuck::bytes_of(&ParamsGpu::zeroed())),
                storage("terrain.layers", bytemuck::cast_slice(&layers)),
                instances,
                indices,
                index_data.len() as u32,
            )
        })?;
        let (
            [coarse, fine, pages, albedo, normal],
            array,
            sampler,
            params,
            layers,
            instances,
            indices,
            index_count,
        ) = made;
        let write = |t: &wgpu::Texture,
                     origin: (u32, u32, u32),
                     size: (u32, u32),
                     mip: u32,
                     texel: u32,
                     bytes: &[u8]| {
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: t,
                    mip_level: mip,
                    origin: wgpu::Origin3d {
                        x: origin.0,
                        y: origin.1,
                        z: origin.2,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size.0 * texel),
                    rows_per_image: Some(size.1),
                },
                wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
            )
        };
        write(
            &coarse,
            (0, 0, 0),
            (g.coarse_n, g.coarse_n),
            0,
            4,
            bytemuck::cast_slice(&heights.coarse),
        );
        write(
            &pages,
            (0, 0, 0),
            (g.sectors, g.sectors),
            0,
            4,
            bytemuck::cast_slice(&heights.pages),
        );
        for (i, l) in desc.layers.iter().enumerate() {
            let (a, n) = textures::detail_maps(l.detail, i as u32 * 0x9e37 + 17);
            for (target, level0) in [(&albedo, a), (&normal, n)] {
                for (mip, data) in textures::mips(level0).iter().enumerate() {
                    let side = textures::DETAIL_SIZE >> mip;
                    write(
                        target,
                        (0, 0, i as u32),
                        (side, side),
                        mip as u32,
                        4,
                        bytemuck::cast_slice(data),
                    );
                }
            }
        }
        ctx.check("terrain")?;
        Ok(Self {
            lod_view: false,
            geometry: g,
            settings: TerrainSettings::default(),
            program,
            shadow_program,
            shadow_pipeline,
            static_pipeline,
            params,
            layers,
            layer_count,
            coarse_view: coarse.create_view(&Default::default()),
            coarse,
            fine_view: fine.create_view(&array),
            fine,
            pages_view: pages.create_view(&Default::default()),
            pages,
            detail_albedo: albedo.create_view(&array),
            detail_normal: normal.create_view(&array),
            sampler,
            instances,
            indices,
            index_count,
            cpu: Mutex::new(TerrainCpu { heights, pyramid }),
            counts: [0; MAX_VIEWS],
            selection: Vec::new(),
        })
    }

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

    fn write_texels(
        &self,
        queue: &wgpu::Queue,
        t: &wgpu::Texture,
        origin: (u32, u32, u32),
        side: (u32, u32),
        bytes: &[u8],
    ) {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: t,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: origin.0,
                    y: origin.1,
                    z: origin.2,
                },
                aspect: wgpu::TextureAspect::All,
            },
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side.0 * 4),
                rows_per_image: Some(side.1),
            },
            wgpu::Extent3d {
                width: side.0,
                height: side.1,
                depth_or_array_layers: 1,
            },
        );
    }

    fn write_page(&self, queue: &wgpu::Queue, cpu: &TerrainCpu, (sx, sz): (u32, u32)) {
        let page = cpu.heights.pages[(sz * self.geometry.sectors + sx) as usize];
        self.write_texels(
            queue,
            &self.pages,
            (sx, sz, 0),
            (1, 1),
            bytemuck::bytes_of(&page),
        );
    }

    /// Makes `heights` (`tile_res^2`, row = z) the tile of sector
    /// (`sector_x`, `sector_z`) in `slot`, replacing what the slot or the
    /// sector held; the coarse points inside the sector take the tile's
    /// values there (so coarse and fine levels meet exactly). Bad slot,
    /// sector or size: an error, nothing changed.
    pub fn upload_tile(
        &self,
        queue: &wgpu::Queue,
        slot: u32,
        sector_x: u32,
        sector_z: u32,
        heights: &[f32],
    ) -> Result<(), GpuError> {
        let mut guard = self.lock();
        let cpu = &mut *guard;
        cpu.heights
            .check_tile(slot, sector_x, sector_z, heights)
            .map_err(other)?;
        let g = self.geometry;
        let before_slot = cpu.heights.slots[slot as usize];
        let (i0, j0, side) = cpu
            .heights
            .upload(slot, sector_x, sector_z, heights)
            .map_err(other)?;
        self.write_texels(
            queue,
            &self.fine,
            (0, 0, slot),
            (g.tile_res, g.tile_res),
            bytemuck::cast_slice(heights),
        );
        let n = g.coarse_n;
        let block: Vec<f32> = (0..side * side)
            .map(|k| cpu.heights.coarse[((j0 + k / side) * n + i0 + k % side) as usize])
            .collect();
        self.write_texels(
            queue,
            &self.coarse,
            (i0, j0, 0),
            (side, side),
            bytemuck::cast_slice(&block),
        );
        self.write_page(queue, cpu, (sector_x, sector_z));
        if let Some(old) = before_slot.filter(|&s| s != (sector_x, sector_z)) {
            self.write_page(queue, cpu, old);
            cpu.pyramid.update_sector(&cpu.heights, old.0, old.1);
        }
        cpu.pyramid.update_sector(&cpu.heights, sector_x, sector_z);
        Ok(())
    }

    /// Frees `slot` (its sector falls back to the coarse grid). A slot out
    /// of range is an error; an empty one is left as it is.
    pub fn evict(&self, queue: &wgpu::Queue, slot: u32) -> Result<(), GpuError> {
        if slot >= self.geometry.fine_slots {
            return Err(other(format!(
                "terrain: slot {slot} is outside the pool of {}",
                self.geometry.fine_slots
            )));
        }
        let mut guard = self.lock();
        let cpu = &mut *guard;
        if let Some(sector) = cpu.heights.evict(slot) {
            self.write_page(queue, cpu, sector);
            cpu.pyramid.update_sector(&cpu.heights, sector.0, sector.1);
        }
        Ok(())
    }

    /// The ranges this pass's settings give at focal length `focal_px`.
    pub fn ranges(&self, focal_px: f32) -> Ranges {
        Ranges::new(&self.geometry, &self.settings, focal_px)
    }

    /// Plans a frame: selects the camera's patches and, with the camera's
    /// levels and morph, those of each shadow view (`shadow_views`: light
    /// view-projections, at most `MAX_VIEWS - 1`), and uploads the lists and
    /// the morph parameters. O(selected nodes).
    pub fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        camera: &TerrainView,
        shadow_views: &[Mat4],
    ) -> TerrainStats {
        let g = self.geometry;
        let ranges = self.ranges(camera.focal_px);
        let shadow_views = &shadow_views[..shadow_views.len().min(MAX_VIEWS - 1)];
        let cpu = self.cpu.get_mut().unwrap_or_else(|e| e.into_inner());
        let frustum = CullView::clip(camera.view_proj);
        let select = |frustum: &CullView, out: &mut Vec<Patch>| {
            Selector {
                geometry: &g,
                pyramid: &cpu.pyramid,
                ranges: &ranges,
                eye: camera.eye,
                frustum,
                capacity: MAX_PATCHES,
            }
            .select(out)
        };
        self.selection.clear();
        let stats = select(&frustum, &mut self.selection);
        let size = std::mem::size_of::<Patch>() as u64;
        let view_bytes = MAX_PATCHES as u64 * size;
        queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.selection));
        self.counts = [0; MAX_VIEWS];
        self.counts[0] = self.selection.len() as u32;
        let mut shadows = Vec::with_capacity(shadow_views.len());
        let mut list = Vec::new();
        for (i, light) in shadow_views.iter().enumerate() {
            list.clear();
            let caster = CullView::caster(*light);
            shadows.push(select(&caster, &mut list));
            queue.write_buffer(
                &self.instances,
                (i as u64 + 1) * view_bytes,
                bytemuck::cast_slice(&list),
            );
            self.counts[i + 1] = list.len() as u32;
        }
        let mut level = [[0.0; 4]; MAX_LEVELS];
        for (l, v) in level.iter_mut().enumerate().take(ranges.levels as usize) {
            let coarse = if g.coarse_only(l as u32) { 1.0 } else { 0.0 };
            *v = [
                ranges.morph_start[l],
                ranges.morph_scale[l],
                g.spacing(l as u32),
                coarse,
            ];
        }
        let params = ParamsGpu {
            origin: g.origin.to_array(),
            world_size: g.world_size,
            sector_size: g.sector_size,
            coarse_spacing: g.coarse_spacing,
            fine_spacing: g.fine_spacing,
            coarse_n: g.coarse_n,
            sectors: g.sectors,
            tile_res: g.tile_res,
            layers: self.layer_count,
            morph: u32::from(ranges.morph),
            levels: ranges.levels,
            eye: camera.eye.extend(0.0).to_array(),
            level,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        TerrainStats {
            ranges,
            camera: stats,
            shadows,
        }
    }

    /// The camera's patches of the last [`Self::prepare`].
    pub fn selection(&self) -> &[Patch] {
        &self.selection
    }

    /// Patches of `view` (0 the camera, 1 + i shadow view i) this frame.
    pub fn count(&self, view: usize) -> u32 {
        self.counts.get(view).copied().unwrap_or(0)
    }

    /// Reads back the uploaded patch list of `view` (tests).
    pub fn read_patches(&self, ctx: &GpuContext, view: usize) -> Result<Vec<Patch>, GpuError> {
        let bytes = crate::gpu::read_buffer(ctx, &self.instances)?;
        let all: Vec<Patch> = bytemuck::pod_collect_to_vec(&bytes);
        let start = view * MAX_PATCHES;
        Ok(all
            .get(start..start + self.count(view) as usize)
            .unwrap_or_default()
            .to_vec())
    }

    /// The G-buffer pipeline, through the shared cache (`lod_view`: albedo
    /// shows each patch's level, `--view lod`).
    pub fn pipeline(
        &self,
        ctx: &GpuContext,
        lod_view: bool,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let targets = [
            target(ALBEDO_FORMAT),
            target(FRAME_FORMAT),
            target(MATERIAL_FORMAT),
            target(MOTION_FORMAT),
        ];
        self.program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "terrain",
                vertex_entry: "vs_main",
                fragment_entry: Some("fs_main"),
                vertex_buffers: &[Some(patch_layout())],
                targets: &targets,
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    // reverse-Z: nearer is larger; equal keeps ties with objects drawn first
                    depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                primitive: wgpu::PrimitiveState {
                    cull_mode: Some(wgpu::Face::Back),
                    ..Default::default()
                },
                constants: if lod_view { &[("LOD_VIEW", 1.0)] } else { &[] },
            },
        )
    }

    fn draw_view(&self, rp: &mut wgpu::RenderPass<'_>, view: usize) -> u32 {
        let count = self.count(view);
        if count > 0 {
            let size = std::mem::size_of::<Patch>() as u64;
            let start = (view * MAX_PATCHES) as u64 * size;
            rp.set_vertex_buffer(
                0,
                self.instances.slice(start..start + u64::from(count) * size),
            );
            rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint16);
            rp.draw_indexed(0..self.index_count, 0, 0..count);
        }
        count
    }

    /// The `terrain` node: the camera's patches into `gbuffer` (after the
    /// `gbuffer` node; targets loaded, depth GreaterEqual), seen through
    /// `view` (the frame's view uniform: view_proj, prev_view_proj).
    /// Returns the G-buffer's new versions.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        gbuffer: GBuffer,
        view: &'a wgpu::Buffer,
    ) -> GBuffer {
        let pipeline = self.pipeline(ctx, self.lod_view);
        let load = wgpu::LoadOp::Load;
        let written = graph
            .raster("terrain", &self.program)
            .pipeline(pipeline)
            .uniform("view", view)
            .uniform("terrain", &self.params)
            .uniform("layers", &self.layers)
            .external("coarse_load", &self.coarse_view)
            .external("fine_load", &self.fine_view)
            .external("pages", &self.pages_view)
            .external("detail_albedo", &self.detail_albedo)
            .external("detail_normal", &self.detail_normal)
            .sampler("detail_sampler", &self.sampler)
            .color(gbuffer.albedo, load)
            .color(gbuffer.frame, load)
            .color(gbuffer.material, load)
            .color(gbuffer.motion, load)
            .depth(
                gbuffer.depth,
                None,
                wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            )
            .record(move |_, rp| {
                self.draw_view(rp, 0);
                Ok(())
            });
        let colour = |i: usize, h: TextureHandle| written.colors.get(i).copied().unwrap_or(h);
        GBuffer {
            albedo: colour(0, gbuffer.albedo),
            frame: colour(1, gbuffer.frame),
            material: colour(2, gbuffer.material),
            motion: colour(3, gbuffer.motion),
            depth: written.depth.unwrap_or(gbuffer.depth),
        }
    }

    /// Records shadow view `cascade`'s patches into the caller's depth pass
    /// (a cascade layer, [`SHADOW_DEPTH_FORMAT`], standard depth):
    /// `shadow_view` is the cascade's `ShadowViewGpu` buffer (its
    /// `light_view_proj` is read). Sets its own pipeline, bind group 0 and
    /// vertex/index buffers: the caller sets its own again after. Returns
    /// the patches drawn.
    pub fn draw_shadow(
        &self,
        device: &wgpu::Device,
        rp: &mut wgpu::RenderPass<'_>,
        shadow_view: &wgpu::Buffer,
        cascade: usize,
    ) -> Result<u32, GpuError> {
        self.draw_sun_view(device, rp, shadow_view, cascade, &self.shadow_pipeline)
    }

    /// [`Self::draw_shadow`] with `pipeline` (its depth format).
    fn draw_sun_view(
        &self,
        device: &wgpu::Device,
        rp: &mut wgpu::RenderPass<'_>,
        shadow_view: &wgpu::Buffer,
        cascade: usize,
        pipeline: &wgpu::RenderPipeline,
    ) -> Result<u32, GpuError> {
        let view = cascade + 1;
        if view >= MAX_VIEWS {
            return Err(other(format!(
                "terrain: shadow view {cascade} (at most {})",
                MAX_VIEWS - 1
            )));
        }
        if self.count(view) == 0 {
            return Ok(0);
        }
        let group = self.shadow_program.bind(
            device,
            0,
            &[
                ("shadow", shadow_view.as_entire_binding()),
                ("terrain", self.params.as_entire_binding()),
                (
                    "coarse_load",
                    wgpu::BindingResource::TextureView(&self.coarse_view),
                ),
                (
                    "fine_load",
                    wgpu::BindingResource::TextureView(&self.fine_view),
                ),
                (
                    "pages",
                    wgpu::BindingResource::TextureView(&self.pages_view),
                ),
            ],
        )?;
        rp.set_pipeline(pipeline);
        rp.set_bind_group(0, &group, &[]);
        Ok(self.draw_view(rp, view))
    }

    /// A node `terrain.shadow{cascade}` drawing [`Self::draw_shadow`] into
    /// layer `layer` of `cascades` (depth loaded: after the cascade's own
    /// node). Returns the new version of `cascades`.
    pub fn add_shadow<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        cascades: TextureHandle,
        layer: u32,
        shadow_view: &'a wgpu::Buffer,
        cascade: usize,
    ) -> TextureHandle {
        let view = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..Default::default()
        };
        let written = graph
            .raster(&format!("terrain.shadow{cascade}"), &self.shadow_program)
            .external_group(0)
            .depth(
                cascades,
                Some(view),
                wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            )
            .record(move |ctx, rp| {
                self.draw_shadow(ctx.device, rp, shadow_view, cascade)
                    .map(|_| ())
            });
        written.depth.unwrap_or(cascades)
    }
}

impl crate::passes::shadows::CascadeCaster for TerrainPass {
    fn add_cascade<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        cascades: TextureHandle,
        layer: u32,
        view: &'a wgpu::Buffer,
    ) -> TextureHandle {
        self.add_shadow(graph, cascades, layer, view, layer as usize)
    }

    fn add_static_tile<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        map: TextureHandle,
        index: usize,
        view: &'a wgpu::Buffer,
        rect: [u32; 4],
    ) -> TextureHandle {
        let written = graph
            .raster(&format!("terrain.static{index}"), &self.shadow_program)
            .external_group(0)
            .depth(
                map,
                None,
                wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            )
            .side_effect()
            .record(move |ctx, rp| {
                crate::passes::shadows::depth::set_rect(rp, rect);
                let pipeline = &self.static_pipeline;
                (self.draw_sun_view(ctx.device, rp, view, index, pipeline)).map(|_| ())
            });
        written.depth.unwrap_or(map)
    }
}

/// The sun-view pipeline writing `format` (cascades: 32-bit, the world's
/// static map: 16-bit).
fn sun_view_pipeline(
    ctx: &GpuContext,
    program: &Program,
    format: wgpu::TextureFormat,
) -> Result<wgpu::RenderPipeline, GpuError> {
    program.render_pipeline(
        ctx,
        &RenderSpec {
            label: "terrain.shadow",
            vertex_entry: "vs_main",
            fragment_entry: None,
            vertex_buffers: &[Some(patch_layout())],
            targets: &[],
            // As the scene's casters.
            depth_stencil: Some(crate::passes::shadows::depth::caster_depth(format)),
            // Both faces cast: the sun may see the ground from below the horizon line.
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            constants: &[],
        },
    )
}
