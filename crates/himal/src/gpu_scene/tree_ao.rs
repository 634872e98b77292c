//! V4: the scene's tree occlusion volumes on the GPU, uploaded once with the
//! scene: one R8Unorm 3D atlas (each (species, seed) volume a slab stacked
//! along z, in the order of `Scene::ao_volumes`), a record per volume (its
//! box and slab), and one entry per tree (the GPU index of its leaves
//! object, its volume), read by `passes/tree_ao/decal.wgsl`. Nothing here
//! changes per frame: the decal reads each tree's transform from the
//! scene's object buffer.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::scene::tree::ao::AoVolume;

/// Twin of `AoVolume` in `passes/tree_ao/decal.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct AoVolumeGpu {
    /// xyz: the box's minimum (tree space, m); w: the slab's first texel along z.
    pub min: [f32; 4],
    /// xyz: the box's extent (m); w: 0.
    pub extent: [f32; 4],
    /// xyz: voxels per axis; w: 0.
    pub res: [u32; 4],
}

/// The atlas, the volume records and the tree list.
pub struct TreeAoGpu {
    /// R8Unorm 3D, `(max res.x, max res.y, Σ res.z)`; 1 x 1 x 1 white without trees.
    pub atlas: wgpu::TextureView,
    /// `array<AoVolume>` (one zeroed record without trees).
    pub volumes: wgpu::Buffer,
    /// `array<vec2u>`: (leaves object's GPU index, volume) per tree.
    pub trees: wgpu::Buffer,
    /// Trees listed (0: the decal draws nothing).
    pub count: u32,
    /// GPU bytes of the three.
    pub bytes: u64,
}

/// The voxels of `volumes` as the atlas's bytes (x fastest, then y, then
/// the slabs' z), its size, and each volume's record: visibility
/// quantised to 8 bits, padding white.
pub fn atlas(volumes: &[std::sync::Arc<AoVolume>]) -> (Vec<u8>, [u32; 3], Vec<AoVolumeGpu>) {
    if volumes.is_empty() {
        return (vec![255], [1, 1, 1], vec![AoVolumeGpu::zeroed()]);
    }
    let w = volumes.iter().map(|v| v.res.x).max().unwrap_or(1);
    let h = volumes.iter().map(|v| v.res.y).max().unwrap_or(1);
    let d: u32 = volumes.iter().map(|v| v.res.z).sum();
    let mut bytes = vec![255u8; (w * h * d) as usize];
    let mut records = Vec::with_capacity(volumes.len());
    let mut z0 = 0;
    for v in volumes {
        for z in 0..v.res.z {
            for y in 0..v.res.y {
                for x in 0..v.res.x {
                    let a = v.visibility[((z * v.res.y + y) * v.res.x + x) as usize];
                    bytes[(((z0 + z) * h + y) * w + x) as usize] =
                        (a.clamp(0.0, 1.0) * 255.0).round() as u8;
                }
            }
        }
        records.push(AoVolumeGpu {
            min: v.bounds.min.extend(z0 as f32).to_array(),
            extent: v.bounds.extent().extend(0.0).to_array(),
            res: v.res.extend(0).to_array(),
        });
        z0 += v.res.z;
    }
    (bytes, [w, h, d], records)
}

impl TreeAoGpu {
    /// Uploads `volumes` and the list `trees` of (object, volume).
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        volumes: &[std::sync::Arc<AoVolume>],
        trees: &[[u32; 2]],
    ) -> Self {
        let (voxels, size, records) = atlas(volumes);
        let texture = device.create_texture_with_data(
            queue,
            &wgpu::TextureDescriptor {
                label: Some("tree_ao.atlas"),
                size: wgpu::Extent3d {
                    width: size[0],
                    height: size[1],
                    depth_or_array_layers: size[2],
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &voxels,
        );
        let list: Vec<[u32; 2]> = if trees.is_empty() {
            vec![[0, 0]]
        } else {
            trees.to_vec()
        };
        let init = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        TreeAoGpu {
            atlas: texture.create_view(&Default::default()),
            volumes: init("tree_ao.volumes", bytemuck::cast_slice(&records)),
            trees: init("tree_ao.trees", bytemuck::cast_slice(&list)),
            count: if volumes.is_empty() {
                0
            } else {
                trees.len() as u32
            },
            bytes: (voxels.len()
                + std::mem::size_of_val(records.as_slice())
                + std::mem::size_of_val(list.as_slice())) as u64,
        }
    }
}
