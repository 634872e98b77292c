//! GPU twins of the terrain shader's structs and the patch instance layout.

use bytemuck::{Pod, Zeroable};

use super::TerrainLayerDesc;
use super::reference::{MAX_LEVELS, Patch};

/// Twin of `TerrainParams` in `shaders/terrain.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct ParamsGpu {
    pub(super) origin: [f32; 2],
    pub(super) world_size: f32,
    pub(super) sector_size: f32,
    pub(super) coarse_spacing: f32,
    pub(super) fine_spacing: f32,
    pub(super) coarse_n: u32,
    pub(super) sectors: u32,
    pub(super) tile_res: u32,
    pub(super) layers: u32,
    pub(super) morph: u32,
    pub(super) levels: u32,
    pub(super) eye: [f32; 4],
    pub(super) level: [[f32; 4]; MAX_LEVELS],
}

/// Twin of `TerrainLayer` in `terrain.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(super) struct LayerGpu {
    albedo: [f32; 4],
    height: [f32; 4],
    slope: [f32; 4],
    detail: [f32; 4],
}

/// Stands for an open limit in the shader's band (finite, so no NaN).
const FAR: f32 = 1e30;

impl LayerGpu {
    pub(super) fn new(l: &TerrainLayerDesc, index: usize) -> Self {
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

pub(super) fn patch_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Patch>() as u64,
        step_mode: wgpu::VertexStepMode::Instance,
        attributes: &PATCH_ATTRIBUTES,
    }
}
