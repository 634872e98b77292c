//! CPU twin of `cull.wgsl`: the same plane test, offsets and ranks, in the
//! same order, so the GPU's lists can be compared entry by entry.

use super::{BoundsGpu, CullLayout, CullView};

/// Per (view, batch), view-major: the indirect arguments (index count,
/// instance count, first index, base vertex, first instance) and the
/// instance list (objects, in order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CullResult {
    pub args: Vec<[u32; 5]>,
    pub instances: Vec<Vec<u32>>,
}

/// The smallest signed distance-like value of the box to `view`'s planes:
/// negative when it is wholly outside one (`outside` in `cull.wgsl`).
pub fn margin(b: &BoundsGpu, view: &CullView) -> f32 {
    let c = glam::Vec3::from_slice(&b.center[..3]);
    let e = glam::Vec3::from_slice(&b.half_extent[..3]);
    view.planes
        .iter()
        .map(|p| {
            let n = glam::Vec3::from_slice(&p[..3]);
            n.dot(c) + p[3] + n.abs().dot(e)
        })
        .fold(f32::INFINITY, f32::min)
}

/// Whether `view` culls the box.
pub fn outside(b: &BoundsGpu, view: &CullView) -> bool {
    margin(b, view) < 0.0
}

/// The culled lists of `views` over `layout`.
pub fn cull(layout: &CullLayout, views: &[CullView]) -> CullResult {
    let mut result = CullResult::default();
    for (v, view) in views.iter().enumerate() {
        for batch in &layout.batches {
            let chunks = &layout.chunks[batch.first_chunk as usize..][..batch.chunks as usize];
            let list: Vec<u32> = chunks
                .iter()
                .flat_map(|c| c.first_object..c.first_object + c.count)
                .filter(|&o| {
                    layout
                        .bounds
                        .get(o as usize)
                        .is_some_and(|b| !outside(b, view))
                })
                .collect();
            result.args.push([
                batch.index_count,
                list.len() as u32,
                batch.first_index,
                batch.base_vertex as u32,
                (v as u32 + 1) * layout.objects + batch.first_object,
            ]);
            result.instances.push(list);
        }
    }
    result
}
