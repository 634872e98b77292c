//! E2 levels of detail on the CPU side: each mesh's levels in the index
//! buffer with their triangle areas, and the level each CPU-recorded draw
//! takes this frame.

use super::{Draw, SceneGpu};
use crate::scene::Mesh;

/// E2 LOD selection of one frame: the eye and how levels are chosen
/// (`scale` 0: every object at LOD0; the band dithers on the GPU path
/// only, the CPU path pops).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LodView {
    /// Camera position (distances to boxes).
    pub eye: glam::Vec3,
    /// Thresholds, band and scale of the selection.
    pub selection: crate::scene::lod::Selection,
}

/// One level of a mesh in the index buffer (E2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodRange {
    /// First index of the level in the index buffer.
    pub first_index: u32,
    /// Indices of the level.
    pub index_count: u32,
    /// Geometric error (mesh units; 0 for LOD0).
    pub error: f32,
}

/// Appends `mesh`'s indices to `indices` and, after them, its LOD chain
/// where it has one: its levels, LOD0 first, and per level its triangles'
/// areas (E2 statistics).
pub(super) fn append_levels(
    mesh: &Mesh,
    indices: &mut Vec<u32>,
) -> (Vec<LodRange>, Vec<crate::scene::lod::AreaHistogram>) {
    let mut levels = vec![LodRange {
        first_index: indices.len() as u32,
        index_count: mesh.indices.len() as u32,
        error: 0.0,
    }];
    let area = |i: &[u32]| crate::scene::lod::AreaHistogram::new(&mesh.vertices, i);
    let mut histograms = vec![area(&mesh.indices)];
    indices.extend_from_slice(&mesh.indices);
    // E2: terrain-sized meshes are always near somewhere; no chain.
    if mesh.bounds.extent().max_element() <= crate::scene::lod::MAX_EXTENT {
        // Trees bring their own levels (V1); the rest are simplified.
        let chain = if mesh.levels.is_empty() {
            crate::scene::lod::lod_chain(mesh)
        } else {
            mesh.levels.clone()
        };
        for lod in chain {
            histograms.push(area(&lod.indices));
            levels.push(LodRange {
                first_index: indices.len() as u32,
                index_count: lod.indices.len() as u32,
                error: lod.error,
            });
            indices.extend_from_slice(&lod.indices);
        }
    }
    (levels, histograms)
}

impl SceneGpu {
    /// The level `object` draws at under `lod` (E2; 0 without a chain).
    pub fn lod_level(&self, object: u32, lod: &LodView) -> u32 {
        let (Some(b), Some(&mesh)) = (
            self.cull_bounds.get(object as usize),
            self.object_mesh.get(object as usize),
        ) else {
            return 0;
        };
        let Some(levels) = self.lods.get(mesh as usize) else {
            return 0;
        };
        let mut errors = [0.0; crate::scene::lod::MAX_LODS];
        let mut n = levels.len().min(errors.len());
        // V3 `--impostors off`: the impostor levels go, LOD2 stays.
        if !self.impostors.load(std::sync::atomic::Ordering::Relaxed)
            && self
                .impostor_mesh
                .get(mesh as usize)
                .copied()
                .unwrap_or(false)
        {
            let impostors = crate::scene::tree::impostor_level::LEVELS;
            n = n.min(levels.len().saturating_sub(impostors)).max(1);
        }
        for (e, l) in errors.iter_mut().zip(levels) {
            *e = l.error;
        }
        let d = crate::scene::lod::distance_to_box(lod.eye, b.center(), b.half_extent());
        // The CPU path pops: no band.
        let selection = crate::scene::lod::Selection {
            band: 0.0,
            ..lod.selection
        };
        let radius = b.half_extent().length();
        crate::scene::lod::choice_for(
            d,
            b.center[3],
            radius,
            b.half_extent[3],
            &errors[..n],
            &selection,
        )
        .0
    }

    /// `draws` at this frame's LOD (E2): each draw's index range replaced
    /// by its object's level; borrowed unchanged when LOD is off or no
    /// mesh has a chain.
    pub fn at_lod<'d>(&self, draws: &'d [Draw]) -> std::borrow::Cow<'d, [Draw]> {
        let lod = self.lod.lock().map(|l| *l).unwrap_or_default();
        let (leveled, hide) = self.lod_state(&lod);
        if !leveled && !hide {
            return std::borrow::Cow::Borrowed(draws);
        }
        let placed = draws
            .iter()
            .filter_map(|d| self.placed(d, &lod, leveled, hide));
        std::borrow::Cow::Owned(placed.map(|(_, d)| d).collect())
    }

    /// [`Self::at_lod`] with each draw in its level's list, ready for
    /// [`Self::draw_placed`] (V3's impostor levels in a pass of their own:
    /// one level choice per object for both vegetation passes).
    pub fn split_at_lod(&self, draws: &[Draw]) -> [Vec<Draw>; crate::scene::lod::MAX_LODS] {
        let lod = self.lod.lock().map(|l| *l).unwrap_or_default();
        let (leveled, hide) = self.lod_state(&lod);
        let mut out: [Vec<Draw>; crate::scene::lod::MAX_LODS] = Default::default();
        for (level, d) in draws
            .iter()
            .filter_map(|d| self.placed(d, &lod, leveled, hide))
        {
            out[level.min(out.len() - 1)].push(d);
        }
        out
    }

    /// Whether levels are chosen this frame, and whether `--vegetation off`
    /// hides the foliage and trunks.
    fn lod_state(&self, lod: &LodView) -> (bool, bool) {
        let leveled = lod.selection.enabled() && self.has_lods;
        let hide = !self.vegetation.load(std::sync::atomic::Ordering::Relaxed)
            && self.vegetation_objects.contains(&true);
        (leveled, hide)
    }

    /// `d` at its object's level (and that level), or `None` when hidden.
    fn placed(&self, d: &Draw, lod: &LodView, leveled: bool, hide: bool) -> Option<(usize, Draw)> {
        let vegetation = (self.vegetation_objects.get(d.object as usize)).copied();
        if hide && vegetation.unwrap_or(false) {
            return None;
        }
        if !leveled {
            return Some((0, d.clone()));
        }
        let level = self.lod_level(d.object, lod) as usize;
        let range = (self.object_mesh.get(d.object as usize))
            .and_then(|&m| self.lods.get(m as usize)?.get(level));
        Some(match range {
            Some(r) if level > 0 => (
                level,
                Draw {
                    first_index: r.first_index,
                    index_count: r.index_count,
                    ..d.clone()
                },
            ),
            _ => (level, d.clone()),
        })
    }

    /// `draws` by the level [`Self::draw_list`] draws each at this frame
    /// (`--view lod`); all at 0 when LOD is off.
    pub fn split_levels(&self, draws: &[Draw]) -> [Vec<Draw>; crate::scene::lod::MAX_LODS] {
        let lod = self.lod.lock().map(|l| *l).unwrap_or_default();
        let mut out: [Vec<Draw>; crate::scene::lod::MAX_LODS] = Default::default();
        for d in draws {
            let level = if lod.selection.enabled() && self.has_lods {
                self.lod_level(d.object, &lod) as usize
            } else {
                0
            };
            out[level.min(out.len() - 1)].push(d.clone());
        }
        out
    }
}
