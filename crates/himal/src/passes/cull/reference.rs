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
    let first = batch.first_chunk as usize;
    let chunks = &layout.chunks[first..][..batch.chunks as usize];
    let boxes = layout.chunk_boxes.get(first..).unwrap_or_default();
    let kept = |i: usize| match boxes.get(i).copied().flatten() {
        Some(b) => !chunk_culled(&b, view, batch, lod),
        // Not computed, or no object with a box: test each object.
        None => true,
    };
    for o in (chunks.iter().enumerate())
        .filter(|&(i, _)| kept(i))
        .flat_map(|(_, c)| c.first_object..c.first_object + c.count)
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

/// Whether `view` or `batch`'s draw distance culls every object inside
/// `b` (the box around a chunk's boxes): the plane test and the distance
/// test of a box bound those of every box inside it.
pub fn chunk_culled(
    b: &super::ChunkBox,
    view: &CullView,
    batch: &super::BatchGpu,
    lod: &LodView,
) -> bool {
    let outside = view.planes.iter().any(|p| {
        let n = glam::Vec3::from_slice(&p[..3]);
        n.dot(b.center) + p[3] + n.abs().dot(b.half_extent) < 0.0
    });
    outside
        || (batch.max_distance > 0.0
            && distance_to_box(lod.eye, b.center, b.half_extent) > batch.max_distance)
}

/// First entry of `batch`'s instances in view `v`'s lists (`cull.wgsl`:
/// the identity's `objects` entries, then two per object and view).
pub fn region(layout: &CullLayout, v: usize, batch: &super::BatchGpu) -> u32 {
    layout.objects + 2 * (v as u32 * layout.objects + batch.first_object)
}

/// One mip of a Hi-Z pyramid: `width` x `height` depths, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct HizMip {
    /// Texels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Reverse-Z depths (0: the far plane).
    pub depth: Vec<f32>,
}

impl HizMip {
    fn at(&self, x: u32, y: u32) -> f32 {
        self.depth[(y * self.width + x) as usize]
    }
}

/// Mip k + 1 from mip k (`cs_reduce` in `hiz.wgsl`): each texel the
/// minimum (farthest) of its 2 x 2 parents; the last texel of a row or
/// column reaches the parent's end (three wide where the parent is odd).
pub fn hiz_reduce(parent: &HizMip) -> HizMip {
    let (w, h) = ((parent.width >> 1).max(1), (parent.height >> 1).max(1));
    let span = |i: u32, n: u32, pn: u32| {
        let p0 = 2 * i;
        let p1 = if i == n - 1 {
            pn - 1
        } else {
            (p0 + 1).min(pn - 1)
        };
        p0..=p1
    };
    let mut depth = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut z = 3.0e38_f32;
            for py in span(y, h, parent.height) {
                for px in span(x, w, parent.width) {
                    z = z.min(parent.at(px, py));
                }
            }
            depth.push(z);
        }
    }
    HizMip {
        width: w,
        height: h,
        depth,
    }
}

/// The whole pyramid of a `width` x `height` depth image (mip 0 is the
/// depth itself; down to 1 x 1, as `cull.hiz`).
pub fn hiz_build(depth: &[f32], width: u32, height: u32) -> Vec<HizMip> {
    let mut mips = vec![HizMip {
        width,
        height,
        depth: depth.to_vec(),
    }];
    for _ in 1..super::hiz::mip_count(width, height) {
        let next = hiz_reduce(mips.last().expect("mip 0"));
        mips.push(next);
    }
    mips
}

/// Whether the box (centre `c`, half extent `e`) is hidden behind the
/// pyramid `hiz` rendered with `view_proj` (`hiz_occluded` in
/// `shaders/hiz.wgsl`, the same steps): every corner in front of the eye
/// and behind the near plane, the screen rectangle inside the screen, and
/// the box's nearest depth (max z/w) below the farthest depth of the (at
/// most 2 x 2) texels of the finest mip that covers the rectangle so.
pub fn hiz_occluded(hiz: &[HizMip], view_proj: glam::Mat4, c: glam::Vec3, e: glam::Vec3) -> bool {
    use glam::{UVec2, Vec2, Vec3};
    let Some(top) = hiz.first() else {
        return false;
    };
    let size = UVec2::new(top.width, top.height);
    let screen = size.as_vec2();
    let (mut lo, mut hi, mut z_near) = (Vec2::splat(3.0e38), Vec2::splat(-3.0e38), -3.0e38_f32);
    for i in 0..8u32 {
        let sign = |bit: u32| if i & bit != 0 { 1.0 } else { -1.0 };
        let s = Vec3::new(sign(1), sign(2), sign(4));
        let p = view_proj * (c + s * e).extend(1.0);
        if p.w <= 0.0 || p.z > p.w {
            return false;
        }
        let ndc = p.truncate() / p.w;
        let px = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * screen;
        lo = lo.min(px);
        hi = hi.max(px);
        z_near = z_near.max(ndc.z);
    }
    if lo.x < 0.0 || lo.y < 0.0 || hi.x > screen.x || hi.y > screen.y {
        return false;
    }
    let a = lo.as_uvec2();
    let b = hi.as_uvec2().min(size - 1);
    let mut level = 0u32;
    while (level as usize) + 1 < hiz.len() {
        let span = (b >> level) - (a >> level);
        if span.x <= 1 && span.y <= 1 {
            break;
        }
        level += 1;
    }
    let mip = &hiz[level as usize];
    let last = UVec2::new(mip.width - 1, mip.height - 1);
    let (ak, bk) = ((a >> level).min(last), (b >> level).min(last));
    let farthest = (mip.at(ak.x, ak.y).min(mip.at(bk.x, ak.y)))
        .min(mip.at(ak.x, bk.y).min(mip.at(bk.x, bk.y)));
    z_near < farthest
}

#[cfg(test)]
mod tests {
    use super::super::{BatchGpu, CHUNK, ChunkBox, ChunkGpu, CullLayout, CullView};
    use super::*;
    use glam::Vec3;

    /// One batch of `n` objects: half in spatially coherent chunks (a grid
    /// walked in order), half scattered at random over 2 km, as a streamed
    /// region's swap-removes leave it.
    fn layout(n: u32) -> CullLayout {
        let mut seed = 7u32;
        let mut rnd = move || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        let bounds: Vec<BoundsGpu> = (0..n)
            .map(|i| {
                let c = if i < n / 2 {
                    Vec3::new(
                        (i % 40) as f32 * 25.0 - 500.0,
                        0.0,
                        (i / 40) as f32 * 25.0 - 500.0,
                    )
                } else {
                    Vec3::new(
                        rnd() * 2000.0 - 1000.0,
                        rnd() * 50.0,
                        rnd() * 2000.0 - 1000.0,
                    )
                };
                BoundsGpu {
                    center: c.extend(0.5).to_array(),
                    half_extent: [1.0 + rnd() * 3.0, 2.0, 1.0 + rnd(), 1.0],
                }
            })
            .collect();
        let chunks: Vec<ChunkGpu> = (0..n.div_ceil(CHUNK))
            .map(|c| ChunkGpu {
                batch: 0,
                first_object: c * CHUNK,
                count: (n - c * CHUNK).min(CHUNK),
                _pad: 0,
            })
            .collect();
        let batch = BatchGpu {
            first_chunk: 0,
            chunks: chunks.len() as u32,
            first_object: 0,
            lods: 1,
            base_vertex: 0,
            max_distance: 600.0,
            _pad: [0; 2],
            lod: [[0, 36], [0; 2], [0; 2], [0; 2], [0; 2]],
            error: [0.0; MAX_LODS],
            _tail: 0,
        };
        let mut l = CullLayout {
            batches: vec![batch],
            chunk_boxes: vec![None; chunks.len()],
            chunks,
            bounds,
            opaque_batches: 1,
            objects: n,
            pool_batches: vec![0],
            batch_mesh: vec![0],
            ..CullLayout::default()
        };
        l.refresh_chunk_boxes();
        l
    }

    #[test]
    fn chunk_boxes_skip_whole_chunks_and_keep_the_lists_exact() {
        let mut l = layout(5000);
        let eye = Vec3::new(-200.0, 30.0, -150.0);
        let camera = crate::scene::Camera::look_at(eye, Vec3::new(300.0, 0.0, 200.0), 60.0);
        let views = [
            CullView::clip(camera.view_projection(16.0 / 9.0)),
            CullView::prism(
                glam::Vec2::new(-300.0, -300.0),
                glam::Vec2::new(-100.0, -100.0),
            ),
            CullView::ALL,
        ];
        let lod = LodView {
            eye,
            selection: Default::default(),
        };
        let batch = l.batches[0];
        let run = |l: &CullLayout, v: usize, view: &CullView| {
            let mut lists: [Vec<u32>; LISTS] = Default::default();
            let args = cull_batch(l, v, view, &batch, &lod, &mut lists);
            (args, lists)
        };
        let mut plain = l.clone();
        plain.chunk_boxes.iter_mut().for_each(|b| *b = None);
        for (v, view) in views.iter().enumerate() {
            let (with, without) = (run(&l, v, view), run(&plain, v, view));
            assert_eq!(with, without, "view {v}");
            // Every object of a skipped chunk is culled on its own too.
            let skipped = (l.chunk_boxes.iter().flatten())
                .filter(|b| chunk_culled(b, view, &batch, &lod))
                .count();
            let kept: usize = with.1.iter().map(Vec::len).sum();
            // The camera and the prism skip coherent chunks, keep_all only
            // what the draw distance (600 m) drops.
            assert!(kept > 0, "view {v}");
            if v < 2 {
                assert!(
                    skipped >= 10,
                    "view {v}: {skipped} of {} chunks skipped",
                    l.chunks.len()
                );
            }
        }
        // Moved objects forget their chunk's box until it is recomputed.
        l.bounds[70].center[0] += 900.0;
        l.invalidate_chunk_boxes(70, 1);
        assert!(
            l.chunk_boxes[1].is_none() && l.chunk_boxes[0].is_some() && l.chunk_boxes[2].is_some()
        );
        l.refresh_chunk_boxes();
        let fresh = ChunkBox::around(&l.bounds[64..128]);
        assert_eq!(l.chunk_boxes[1], fresh);
    }
}
