//! Streamed regions of the objects buffer (the open world, V6): what is
//! reserved ([`PoolSpec`]), where it lies ([`PoolRegion`]), and the writes
//! that fill it.

use bytemuck::Zeroable;

use super::{ObjectBounds, ObjectGpu, SceneGpu};
use crate::gpu::GpuError;
use crate::scene::Foliage;

/// A streamed region of the objects buffer (the open world, V6): objects
/// `first_object..first_object + capacity` draw mesh `mesh`, opaque or as
/// vegetation; streaming
/// writes their records ([`SceneGpu::write_objects`]) and bounds, packed
/// from the front; `passes::cull` culls them per view (on the GPU, or its
/// CPU twin where that path is off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoolRegion {
    /// The scene mesh every object of the region draws.
    pub mesh: u32,
    /// First object record of the region.
    pub first_object: u32,
    /// Object records reserved.
    pub capacity: u32,
    /// Culled beyond this distance from the camera (m; 0: no limit).
    pub max_distance: f32,
    /// Vegetation (a tree's leaves): culled among the vegetation batches
    /// and drawn alpha-tested, each record's parameters these; `None`:
    /// opaque.
    pub foliage: Option<Foliage>,
    /// Part of the vegetation (a tree's trunk or leaves): hidden with
    /// `FrameSettings::vegetation` off.
    pub vegetation: bool,
}

/// A streamed region to reserve ([`SceneGpu::upload_with_pool`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoolSpec {
    /// The scene mesh every object of the region draws.
    pub mesh: usize,
    /// Object records to reserve.
    pub capacity: u32,
    /// Per-class distance culling (m; 0: no limit).
    pub max_distance: f32,
    /// Vegetation with these foliage parameters ([`PoolRegion::foliage`]); `None`: opaque.
    pub foliage: Option<Foliage>,
    /// Part of the vegetation ([`PoolRegion::vegetation`]).
    pub vegetation: bool,
}

/// Reserves the regions `pool` asks for after the objects laid out so far
/// (in order; `meshes`: the scene's mesh count): each region's records
/// empty (zeroed records, bounds no view keeps, the region's mesh). A
/// region naming a mesh the scene lacks is an error.
pub(super) fn reserve(
    pool: &[PoolSpec],
    meshes: usize,
    objects: &mut Vec<ObjectGpu>,
    cull_bounds: &mut Vec<ObjectBounds>,
    bounds: &mut Vec<crate::scene::Aabb>,
    object_mesh: &mut Vec<u32>,
) -> Result<Vec<PoolRegion>, GpuError> {
    let mut regions = Vec::with_capacity(pool.len());
    for &PoolSpec {
        mesh,
        capacity,
        max_distance,
        foliage,
        vegetation,
    } in pool
    {
        if mesh >= meshes {
            return Err(GpuError::Other(format!(
                "pool region names mesh {mesh} of {}",
                meshes
            )));
        }
        regions.push(PoolRegion {
            mesh: mesh as u32,
            first_object: objects.len() as u32,
            capacity,
            max_distance,
            foliage,
            vegetation,
        });
        let n = capacity as usize;
        objects.resize(objects.len() + n, ObjectGpu::zeroed());
        cull_bounds.resize(cull_bounds.len() + n, ObjectBounds::NONE);
        bounds.resize(bounds.len() + n, crate::scene::Aabb::EMPTY);
        object_mesh.resize(object_mesh.len() + n, mesh as u32);
    }
    Ok(regions)
}

impl SceneGpu {
    /// Writes object records from `first_object` on (streamed regions).
    pub fn write_objects(&self, queue: &wgpu::Queue, first_object: u32, objects: &[ObjectGpu]) {
        let offset = first_object as u64 * std::mem::size_of::<ObjectGpu>() as u64;
        queue.write_buffer(&self.objects, offset, bytemuck::cast_slice(objects));
    }
}

impl SceneGpu {
    /// Whether anything draws as vegetation: the scene's own objects or a
    /// streamed vegetation region.
    pub fn has_vegetation(&self) -> bool {
        !self.draws_vegetation.is_empty() || self.pool.iter().any(|r| r.foliage.is_some())
    }
}
