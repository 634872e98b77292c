//! Creating the pass: checks of the description, the height and detail
//! textures, the buffers and the pipelines ([`TerrainPass::new`]).

use std::sync::Mutex;

use bytemuck::Zeroable;
use wgpu::util::DeviceExt;

use super::layout::{LayerGpu, ParamsGpu};
use super::reference::{self, Heights, Patch, Pyramid};
use super::shadow::sun_view_pipeline;
use super::{
    MAX_LAYERS, MAX_PATCHES, MAX_VIEWS, SHADOW_DEPTH_FORMAT, TerrainCpu, TerrainDesc, TerrainPass,
    TerrainSettings, other, textures,
};
use crate::budget::MemoryBudget;
use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};

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
        let write = |t, origin, size, mip, texel, bytes: &[u8]| {
            super::stream::write_region(&ctx.queue, t, origin, size, mip, texel, bytes)
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
            for (target, levels) in [
                (&albedo, textures::mips(a)),
                (&normal, textures::normal_mips(n)),
            ] {
                for (mip, data) in levels.iter().enumerate() {
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
            specular_aa: true,
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
}
