//! Draw lists: the scene's indexed draws ([`Draw`]), how they are split by
//! pipeline at upload ([`DrawLists`]), merged into instanced runs and
//! material runs, culled on the CPU, and recorded ([`SceneGpu::draw_list`]).

use std::sync::atomic::Ordering;

use super::SceneGpu;
use crate::scene::{Object, Scene};

/// Bounds culling, the one CPU selection of draws by their object's box:
/// the draws of `draws` whose object has a box in `bounds` that `keep`
/// (object index, box) accepts. Used by the shadow cascades, the local
/// lights' projectors and atlas, and the sky-occlusion sectors.
pub fn cull<'d, I>(
    draws: I,
    bounds: &'d [crate::scene::Aabb],
    keep: impl Fn(usize, &crate::scene::Aabb) -> bool + 'd,
) -> impl Iterator<Item = Draw> + 'd
where
    I: IntoIterator<Item = &'d Draw>,
    I::IntoIter: 'd,
{
    draws.into_iter().filter_map(move |d| {
        let i = d.object as usize;
        bounds.get(i).filter(|b| keep(i, b)).map(|_| d.clone())
    })
}

/// What a G-buffer pass draws ([`SceneGpu::visible`]).
#[derive(Clone, Debug, Default)]
pub struct VisibleLists {
    /// Opaque objects inside the view (early-Z pipeline, no discard).
    pub opaque: Vec<Draw>,
    /// Alpha-tested, swaying vegetation inside the view.
    pub vegetation: Vec<Draw>,
    /// glTF draws with their material.
    pub textured: Vec<(Draw, usize)>,
    /// `Some((view, calls))`: opaque and vegetation objects come from view
    /// `view` of the GPU-culled lists instead, `calls` multi-draws (V6).
    pub gpu_view: Option<(u32, u32)>,
    /// Draws of the streamed pool from the CPU twin's lists (where the
    /// GPU path is off; `passes::cull::CullPath::Cpu`).
    pub pool_calls: u32,
}

impl VisibleLists {
    /// Draw calls these lists record in `scene` (its instancing and LOD
    /// settings); textured draws are merged within runs of one material.
    pub fn draw_calls(&self, scene: &SceneGpu) -> u32 {
        scene.draw_calls(&self.opaque)
            + scene.draw_calls(&self.vegetation)
            + material_runs(&self.textured)
                .map(|(_, draws)| scene.draw_calls(&draws))
                .sum::<u32>()
            + self.gpu_view.map_or(0, |(_, calls)| calls)
            + self.pool_calls
    }
}

/// Consecutive textured draws of one material (one bind group), as
/// (material, draws): each run is drawn as an ordinary list, so its objects
/// of one mesh are instanced (glTF instancing, repeated nodes).
pub fn material_runs(textured: &[(Draw, usize)]) -> impl Iterator<Item = (usize, Vec<Draw>)> + '_ {
    let mut i = 0;
    std::iter::from_fn(move || {
        let material = textured.get(i)?.1;
        let end = (i..textured.len())
            .find(|&k| textured[k].1 != material)
            .unwrap_or(textured.len());
        let draws = textured[i..end].iter().map(|(d, _)| d.clone()).collect();
        i = end;
        Some((material, draws))
    })
}

/// Consecutive draws of one mesh with consecutive objects, as one
/// instanced draw: (the first draw, instance count).
pub fn runs(draws: &[Draw]) -> impl Iterator<Item = (&Draw, u32)> {
    let mut i = 0;
    std::iter::from_fn(move || {
        let first = draws.get(i)?;
        let mut n = 1;
        while let Some(d) = draws.get(i + n as usize) {
            let same_mesh = (d.first_index, d.index_count, d.base_vertex)
                == (first.first_index, first.index_count, first.base_vertex);
            if !(same_mesh && d.object == first.object + n) {
                break;
            }
            n += 1;
        }
        i += n as usize;
        Some((first, n))
    })
}

/// The draws of `object` in `draws` (a list in object order, as every
/// list of [`SceneGpu`] is): a binary search, not a scan.
pub fn draws_of(draws: &[Draw], object: u32) -> &[Draw] {
    entries_of(draws, object, |d| d)
}

/// The entries of `object` in `list` (object order), `draw` naming each
/// entry's draw (e.g. `(Draw, material)` of the textured list).
pub fn entries_of<T>(list: &[T], object: u32, draw: impl Fn(&T) -> &Draw) -> &[T] {
    let start = list.partition_point(|e| draw(e).object < object);
    let end = list.partition_point(|e| draw(e).object <= object);
    &list[start..end.max(start)]
}

/// Draw calls `draws` records: with instancing, one per run of
/// consecutive objects of one mesh; without, one per draw.
pub fn draw_calls(draws: &[Draw], instancing: bool) -> u32 {
    if instancing {
        runs(draws).count() as u32
    } else {
        draws.len() as u32
    }
}

/// One indexed draw of one object.
#[derive(Clone, Debug)]
pub struct Draw {
    /// First index in the index buffer.
    pub first_index: u32,
    /// Indices drawn.
    pub index_count: u32,
    /// Offset added to each index (the mesh's first vertex).
    pub base_vertex: i32,
    /// The object record (GPU order) the draw is placed by.
    pub object: u32,
}

/// The scene's draw lists as [`SceneGpu::upload_with_pool`] fills them,
/// one object at a time in GPU order (each list stays in object order).
#[derive(Default)]
pub(super) struct DrawLists {
    /// [`SceneGpu::draws_opaque`].
    pub(super) opaque: Vec<Draw>,
    /// [`SceneGpu::draws_vegetation`].
    pub(super) vegetation: Vec<Draw>,
    /// [`SceneGpu::draws_textured`].
    pub(super) textured: Vec<(Draw, usize)>,
    /// [`SceneGpu::draws_blend`].
    pub(super) blend: Vec<(Draw, usize, glam::Vec3)>,
    /// [`SceneGpu::draws_transmissive`].
    pub(super) transmissive: Vec<(Draw, usize)>,
    /// [`SceneGpu::draws_emissive`].
    pub(super) emissive: Vec<(Draw, usize)>,
    /// [`SceneGpu::draws_layered`].
    pub(super) layered: Vec<(Draw, usize)>,
    /// [`SceneGpu::draws_unlit`].
    pub(super) unlit: Vec<(Draw, usize)>,
}

impl DrawLists {
    /// Files `draw` of `object` by its material and foliage: a glTF
    /// material's transmissive, BLEND (with its world bounds' centre) or
    /// textured draw (opaque / mask, also listed as emissive, unlit and
    /// layered where the material is); without one, vegetation or opaque.
    pub(super) fn push(&mut self, scene: &Scene, object: &Object, draw: Draw) {
        match (scene.pbr.material_of(object.mesh), object.foliage) {
            (Some(material), _) => {
                let m = scene.pbr.materials.get(material);
                if m.is_some_and(|m| m.transmits()) {
                    self.transmissive.push((draw, material));
                } else if m.is_some_and(|m| m.alpha_mode == crate::scene::gltf::AlphaMode::Blend) {
                    let bounds = scene.meshes[object.mesh]
                        .bounds
                        .transform(&object.transform);
                    self.blend.push((draw, material, bounds.center()));
                } else {
                    if m.is_some_and(|m| m.emits()) {
                        self.emissive.push((draw.clone(), material));
                    }
                    if m.is_some_and(|m| m.unlit) {
                        self.unlit.push((draw.clone(), material));
                    }
                    if m.is_some_and(|m| m.layered()) {
                        self.layered.push((draw.clone(), material));
                    }
                    self.textured.push((draw, material));
                }
            }
            (None, Some(_)) => self.vegetation.push(draw),
            (None, None) => self.opaque.push(draw),
        }
    }
}

impl SceneGpu {
    /// Binds the shared vertex and index buffers.
    pub fn bind_geometry(&self, rp: &mut wgpu::RenderPass<'_>) {
        rp.set_vertex_buffer(0, self.vertices.slice(..));
        rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }

    /// Draw calls [`Self::draw_list`] records for `draws`.
    pub fn draw_calls(&self, draws: &[Draw]) -> u32 {
        draw_calls(&self.at_lod(draws), self.instancing())
    }

    /// Records `draws` (geometry bound) at this frame's LOD: with
    /// instancing one draw per run of consecutive objects of one mesh and
    /// level (V6), else one draw per object.
    pub fn draw_list(&self, rp: &mut wgpu::RenderPass<'_>, draws: &[Draw]) {
        self.draw_placed(rp, &self.at_lod(draws));
    }

    /// Records `draws` as they are: already at their level
    /// ([`Self::split_at_lod`]; [`Self::draw_list`] places them itself).
    pub fn draw_placed(&self, rp: &mut wgpu::RenderPass<'_>, draws: &[Draw]) {
        if self.instancing.load(Ordering::Relaxed) {
            for (d, n) in runs(draws) {
                let indices = d.first_index..d.first_index + d.index_count;
                rp.draw_indexed(indices, d.base_vertex, d.object..d.object + n);
            }
        } else {
            for d in draws {
                let indices = d.first_index..d.first_index + d.index_count;
                rp.draw_indexed(indices, d.base_vertex, d.object..d.object + 1);
            }
        }
    }

    /// Whether draws merge into instanced ones (V6).
    pub fn instancing(&self) -> bool {
        self.instancing.load(Ordering::Relaxed)
    }

    /// The G-buffer's lists: every object (`view` None: probe cubes) or
    /// those whose bounds may be inside the frustum `view` (the camera).
    /// `gpu_view`: opaque and vegetation objects are culled on the GPU
    /// (V6, `passes::cull`; view, calls), only glTF draws here.
    pub fn visible(&self, view: Option<glam::Mat4>, gpu_view: Option<(u32, u32)>) -> VisibleLists {
        let Some(vp) = view else {
            return VisibleLists {
                opaque: self.draws_opaque.clone(),
                vegetation: self.draws_vegetation.clone(),
                textured: self.draws_textured.clone(),
                gpu_view: None,
                pool_calls: 0,
            };
        };
        let inside = |i: usize| self.bounds.get(i).is_some_and(|b| !b.outside_clip(vp));
        let keep = |d: &&Draw| inside(d.object as usize);
        let cpu = |draws: &[Draw]| match gpu_view {
            Some(_) => Vec::new(),
            None => draws.iter().filter(keep).cloned().collect(),
        };
        VisibleLists {
            opaque: cpu(&self.draws_opaque),
            vegetation: cpu(&self.draws_vegetation),
            textured: (self.draws_textured.iter())
                .filter(|(d, _)| inside(d.object as usize))
                .cloned()
                .collect(),
            gpu_view,
            pool_calls: 0,
        }
    }

    /// The glTF draws that cast sun and local-light shadows: the textured
    /// (opaque and MASK) and the BLEND ones (alpha-tested as casters,
    /// [`SceneGpu::alpha_casters`]); transmissive surfaces cast none.
    pub fn textured_casters(&self) -> impl Iterator<Item = &Draw> + '_ {
        (self.draws_textured.iter().map(|(d, _)| d))
            .chain(self.draws_blend.iter().map(|(d, _, _)| d))
    }

    /// The material of object `object` when its shadow is alpha-tested
    /// ([`SceneGpu::alpha_casters`]).
    pub fn alpha_caster(&self, object: u32) -> Option<usize> {
        self.alpha_casters.get(object as usize).copied().flatten()
    }

    /// Binds the geometry and records the opaque objects, glTF ones
    /// included (shadow casters; their alpha is not tested there).
    pub fn draw_opaque(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_opaque);
        for (d, _) in &self.draws_textured {
            self.draw_list(rp, std::slice::from_ref(d));
        }
    }

    /// Binds the geometry and records the vegetation (set a `VEGETATION` pipeline first).
    pub fn draw_vegetation(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_vegetation);
    }

    /// Records every draw, vegetation as plain cards (no alpha test, no
    /// sway); passes that need the true vegetation shape draw the two lists.
    pub fn draw_all(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_opaque);
        self.draw_list(rp, &self.draws_vegetation);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(mesh: u32, object: u32) -> Draw {
        Draw {
            first_index: mesh * 36,
            index_count: 36,
            base_vertex: 0,
            object,
        }
    }

    #[test]
    fn runs_merge_consecutive_objects_of_one_mesh_only() {
        // Objects 0-2 of mesh 0, a gap (4), mesh 1 at 5, then 6 of mesh 0.
        let draws = [
            draw(0, 0),
            draw(0, 1),
            draw(0, 2),
            draw(0, 4),
            draw(1, 5),
            draw(0, 6),
        ];
        let got: Vec<(u32, u32)> = runs(&draws).map(|(d, n)| (d.object, n)).collect();
        assert_eq!(got, vec![(0, 3), (4, 1), (5, 1), (6, 1)]);
        assert_eq!(draw_calls(&draws, true), 4);
        assert_eq!(draw_calls(&draws, false), 6);
        assert_eq!(draw_calls(&[], true), 0);
        let objects = |o| {
            draws_of(&draws, o)
                .iter()
                .map(|d| d.object)
                .collect::<Vec<_>>()
        };
        assert_eq!(objects(4), vec![4]);
        assert_eq!(objects(3), Vec::<u32>::new());
        assert_eq!(objects(7), Vec::<u32>::new());
    }
}
