//! The scene's meshes and object transforms on the GPU: one vertex buffer,
//! one index buffer, one storage buffer of objects (instance index = object).

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu::{GpuContext, GpuError};
use crate::scene::{Scene, Vertex};

/// Twin of `Object` in `shaders/scene.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ObjectGpu {
    pub model: [[f32; 4]; 4],
    pub normal_matrix: [[f32; 4]; 4],
    pub prev_model: [[f32; 4]; 4],
}

/// One indexed draw of one object.
#[derive(Clone, Debug)]
pub struct Draw {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub object: u32,
}

pub struct SceneGpu {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub objects: wgpu::Buffer,
    pub draws: Vec<Draw>,
    pub triangles: u64,
    pub bytes: u64,
}

/// Vertex attributes of [`Vertex`], locations as in gbuffer.wgsl.
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2, 4 => Float32x4, 5 => Float32x4
];

pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

impl SceneGpu {
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut ranges = Vec::with_capacity(scene.meshes.len());
        for mesh in &scene.meshes {
            ranges.push((
                indices.len() as u32,
                mesh.indices.len() as u32,
                vertices.len() as i32,
            ));
            vertices.extend_from_slice(&mesh.vertices);
            indices.extend_from_slice(&mesh.indices);
        }
        let mut objects = Vec::with_capacity(scene.objects.len());
        let mut draws = Vec::with_capacity(scene.objects.len());
        let mut triangles = 0u64;
        for (i, object) in scene.objects.iter().enumerate() {
            let Some(&(first_index, index_count, base_vertex)) = ranges.get(object.mesh) else {
                return Err(GpuError::Other(format!(
                    "object \"{}\" names mesh {} of {}",
                    object.name,
                    object.mesh,
                    ranges.len()
                )));
            };
            let m = object.transform;
            objects.push(ObjectGpu {
                model: m.to_cols_array_2d(),
                normal_matrix: m.inverse().transpose().to_cols_array_2d(),
                prev_model: m.to_cols_array_2d(),
            });
            draws.push(Draw {
                first_index,
                index_count,
                base_vertex,
                object: i as u32,
            });
            triangles += index_count as u64 / 3;
        }
        if objects.is_empty() {
            objects.push(ObjectGpu::zeroed());
        }
        if indices.is_empty() {
            indices.extend([0, 0, 0]);
            vertices.push(Vertex::zeroed());
        }
        let bytes = (std::mem::size_of_val(vertices.as_slice())
            + std::mem::size_of_val(indices.as_slice())
            + std::mem::size_of_val(objects.as_slice())) as u64;
        ctx.scoped("scene upload", || {
            let init = |label, contents: &[u8], usage| {
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage,
                    })
            };
            SceneGpu {
                vertices: init(
                    "scene.vertices",
                    bytemuck::cast_slice(&vertices),
                    wgpu::BufferUsages::VERTEX,
                ),
                indices: init(
                    "scene.indices",
                    bytemuck::cast_slice(&indices),
                    wgpu::BufferUsages::INDEX,
                ),
                objects: init(
                    "scene.objects",
                    bytemuck::cast_slice(&objects),
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                ),
                draws,
                triangles,
                bytes,
            }
        })
    }

    /// Records every draw: one indexed draw per object, instance index = object.
    pub fn draw_all(&self, rp: &mut wgpu::RenderPass<'_>) {
        rp.set_vertex_buffer(0, self.vertices.slice(..));
        rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
        for d in &self.draws {
            let indices = d.first_index..d.first_index + d.index_count;
            rp.draw_indexed(indices, d.base_vertex, d.object..d.object + 1);
        }
    }
}
