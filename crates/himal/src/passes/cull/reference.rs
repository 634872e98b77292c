//! CPU twin of `cull.wgsl`: the same plane test, offsets and ranks, in the
//! same order, so the GPU's lists can be compared entry by entry.

use super::LISTS;
use super::{CullLayout, CullView};
use crate::gpu_scene::{LodView, ObjectBounds as BoundsGpu};
use crate::scene::lod::{MAX_LODS, choice_for, distance_to_box, fade_step};

/// Per (view, batch, kind, level), view-major, `kind` as
/// [`super::Kind`]: the indirect arguments (index count, instance count,
/// first index, base vertex, first instance) and the instance entries
/// (object | fade code << 24, in object order).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CullResult {
    /// The indirect arguments of each list.
    pub args: Vec<[u32; 5]>,
    /// The instance entries of each list.
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

/// The level and fade the box draws at under `lod` in `batch` (as
/// `lod_choice` in `cull.wgsl`).
pub fn lod_of(b: &BoundsGpu, batch: &super::BatchGpu, lod: &LodView) -> (u32, Option<f32>) {
    let d = distance_to_box(lod.eye, b.center(), b.half_extent());
    let errors = &batch.error[..(batch.lods as usize).min(MAX_LODS)];
    let radius = b.half_extent().length();
    choice_for(
        d,
        b.center[3],
        radius,
        b.half_extent[3],
        errors,
        &lod.selection,
    )
}

/// Per-class distance culling: beyond `batch`'s distance from the LOD eye
/// (as `too_far` in `cull.wgsl`).
pub fn too_far(b: &BoundsGpu, batch: &super::BatchGpu, lod: &LodView) -> bool {
    batch.max_distance > 0.0
        && distance_to_box(lod.eye, b.center(), b.half_extent()) > batch.max_distance
}

/// The culled lists of `views` over `layout`, levels chosen from `lod`.
pub fn cull(layout: &CullLayout, views: &[CullView], lod: &LodView) -> CullResult {
    let mut result = CullResult::default();
    let mut lists: [Vec<u32>; LISTS] = Default::default();
    for (v, view) in views.iter().enumerate() {
        for batch in &layout.batches {
            let args = cull_batch(layout, v, view, batch, lod, &mut lists);
            result.args.extend(args);
            result.instances.extend(lists.iter().cloned());
        }
    }
    result
}

/// One batch's lists in view `v` (`view`): the entries of each list (kind,
/// level) into `lists` (cleared first) and their draw arguments, the
/// instances at the batch's region of that view, lists one after another
/// (the CPU path writes `lists` there and draws the arguments directly).
pub fn cull_batch(
    layout: &CullLayout,
    v: usize,
    view: &CullView,
    batch: &super::BatchGpu,
    lod: &LodView,
    lists: &mut [Vec<u32>; LISTS],
) -> [[u32; 5]; LISTS] {
    lists.iter_mut().for_each(Vec::clear);
    let chunks = &layout.chunks[batch.first_chunk as usize..][..batch.chunks as usize];
    for o in chunks
        .iter()
        .flat_map(|c| c.first_object..c.first_object + c.count)
    {
        let Some(b) = layout.bounds.get(o as usize) else {
            continue;
        };
        if outside(b, view) || too_far(b, batch, lod) {
            continue;
        }
        match lod_of(b, batch, lod) {
            (l, None) => lists[l as usize].push(o),
            (l, Some(t)) => {
                let q = fade_step(t);
                lists[MAX_LODS + l as usize].push(o | ((1 + q) << 24));
                lists[2 * MAX_LODS + l as usize + 1].push(o | ((128 + q) << 24));
            }
        }
    }
    let region = region(layout, v, batch);
    let mut base = 0;
    std::array::from_fn(|j| {
        let l = j % MAX_LODS;
        let n = lists[j].len() as u32;
        let args = [
            batch.lod[l][1],
            n,
            batch.lod[l][0],
            batch.base_vertex as u32,
            region + base,
        ];
        base += n;
        args
    })
}

/// First entry of `batch`'s instances in view `v`'s lists (`cull.wgsl`:
/// the identity's `objects` entries, then two per object and view).
pub fn region(layout: &CullLayout, v: usize, batch: &super::BatchGpu) -> u32 {
    layout.objects + 2 * (v as u32 * layout.objects + batch.first_object)
}
