//! V3: the scene's impostor atlases on the GPU, one `texture_2d_array` per
//! plane (colour, normal, depth), one layer per (species, seed); one 1 x 1
//! layer when the scene has no tree, so the pipelines bind the same layout.
//! Read by `shaders/impostor_atlas.wgsl` with `textureLoad` (manual taps).

use wgpu::util::DeviceExt;

use crate::scene::tree::impostor::{ATLAS_SIZE, Impostor};

/// The three planes' array views.
pub struct ImpostorAtlas {
    /// RGBA8 unorm: tint t, leaf fraction, material AO, coverage.
    pub color: wgpu::TextureView,
    /// RGBA8 unorm: tree-space normal * 0.5 + 0.5.
    pub normal: wgpu::TextureView,
    /// R32 float: depth * 0.5 + 0.5 (the file's unorm16, exactly).
    pub depth: wgpu::TextureView,
    /// Layers (0: the fallback only).
    pub layers: u32,
    /// GPU bytes of the three planes.
    pub bytes: u64,
}

impl ImpostorAtlas {
    /// Uploads `atlases` (the scene's [`crate::scene::Scene::impostors`]).
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        atlases: &[std::sync::Arc<Impostor>],
    ) -> Self {
        let (size, layers) = if atlases.is_empty() {
            (1, 1)
        } else {
            (ATLAS_SIZE as u32, atlases.len() as u32)
        };
        let texels = (size * size * layers) as usize;
        let mut color = Vec::with_capacity(texels * 4);
        let mut normal = Vec::with_capacity(texels * 4);
        let mut depth: Vec<f32> = Vec::with_capacity(texels);
        if atlases.is_empty() {
            color.extend([0u8; 4]);
            normal.extend([0u8; 4]);
            depth.push(0.5);
        }
        for a in atlases {
            color.extend(a.color.iter().flatten());
            normal.extend(a.normal.iter().flatten());
            depth.extend(a.depth.iter().map(|&d| f32::from(d) / 65535.0));
        }
        let plane = |label, format, data: &[u8]| {
            let t = device.create_texture_with_data(
                queue,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size,
                        height: size,
                        depth_or_array_layers: layers,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                data,
            );
            t.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let rgba = wgpu::TextureFormat::Rgba8Unorm;
        ImpostorAtlas {
            color: plane("impostor.color", rgba, &color),
            normal: plane("impostor.normal", rgba, &normal),
            depth: plane(
                "impostor.depth",
                wgpu::TextureFormat::R32Float,
                bytemuck::cast_slice(&depth),
            ),
            layers: if atlases.is_empty() { 0 } else { layers },
            bytes: (color.len() + normal.len() + depth.len() * 4) as u64,
        }
    }
}
