//! V3 in the frame: a tree's impostor as the leaves mesh's last two levels
//! (after LOD2). The first is the 16 x 16 grid of [`super::impostor`],
//! 17 x 17 vertices marked `uv1.x < 0`; the second, for far trees, the same
//! vertices indexed every [`FAR_STEP`]th (4 x 4 cells, 32 triangles instead
//! of 512). The G-buffer and shadow vertex
//! stages (`shaders/impostor_atlas.wgsl`) face it to the viewer and
//! displace it by the captured depth, and the fragment stages read the
//! atlas layer `-1 - uv1.x`. Other passes see every grid vertex at the
//! capture centre: zero-area triangles, nothing drawn.
//! Method and figures: `docs/techniques/V3.md` "In the frame".

use std::sync::Arc;

use glam::Vec3;

use super::ao::AoVolume;
use super::impostor::{self, GRID, Impostor, grid_point};
use super::{Species, generate};
use crate::scene::lod::Level;
use crate::scene::{MaterialDesc, Mesh, Vertex};
use glam::Vec2;

/// The impostor of tree (`species`, `seed`) through the tree cache
/// ([`super::bake::cache_dir`]), or baked in memory without one; once per
/// process ([`super::bake::Memo`]).
pub fn cached(species: Species, seed: u32) -> Arc<Impostor> {
    static MEMO: super::bake::Memo<Impostor> = super::bake::Memo::new();
    let model = generate(species, seed, 1.0);
    MEMO.get_or(&model, seed, || match super::bake::cache_dir() {
        Some(dir) => impostor::load_or_bake_in(&dir, &model, seed).0,
        None => impostor::bake(&model),
    })
}

/// The atlas layers of a scene's impostors, one per (species, seed), and
/// the trees' V4 occlusion volumes in the same order.
#[derive(Clone, Debug, Default)]
pub struct Layers {
    /// (species, seed) of each layer.
    pub keys: Vec<(Species, u32)>,
    /// The captures of each layer.
    pub atlases: Vec<Arc<Impostor>>,
    /// V4: the occlusion volume of each layer's tree (`super::ao::cached`).
    pub volumes: Vec<Arc<AoVolume>>,
}

impl Layers {
    /// The layer of tree (`species`, `seed`), baked or read on first use.
    pub fn layer(&mut self, species: Species, seed: u32) -> (u32, Arc<Impostor>) {
        if let Some(i) = self.keys.iter().position(|k| *k == (species, seed)) {
            return (i as u32, self.atlases[i].clone());
        }
        let imp = cached(species, seed);
        let model = generate(species, seed, 1.0);
        self.volumes.push(super::ao::cached(&model, seed));
        self.keys.push((species, seed));
        self.atlases.push(imp.clone());
        ((self.keys.len() - 1) as u32, imp)
    }
}

/// The colours and materials an impostor pixel mixes (`impostor::albedo`).
#[derive(Clone, Copy, Debug)]
pub struct Colours {
    /// Bark albedo (linear).
    pub bark: Vec3,
    /// Bark glossiness (the rest of the bark's material is the leaves').
    pub bark_glossiness: f32,
    /// Leaf albedo (linear) and material AO.
    pub leaf: [f32; 4],
    /// Leaf material (`Vertex::surface`).
    pub leaf_surface: [f32; 4],
    /// The cluster tint colour (linear).
    pub tint: Vec3,
}

impl Colours {
    /// The colours of a tree with these materials and tint.
    pub fn new(bark: &MaterialDesc, leaves: &MaterialDesc, tint: Vec3) -> Self {
        Colours {
            bark: bark.albedo,
            bark_glossiness: bark.glossiness,
            leaf: leaves.vertex_color(),
            leaf_surface: leaves.vertex_surface(),
            tint,
        }
    }
}

/// Whether `v` is an impostor grid vertex (`uv1.x < 0`; leaf cards carry
/// their cluster index there).
pub fn is_impostor_vertex(v: &Vertex) -> bool {
    v.uv1[0] < 0.0
}

/// The grid vertex `(i, j)` of layer `layer`. Packing (read by
/// `impostor_atlas.wgsl`): position = capture centre (tree space, m),
/// tangent = (bark albedo, R), normal = tint colour, uv = grid point in
/// [-1, 1]², colour = leaf albedo and AO, surface = leaf material,
/// uv1 = (-1 - layer, bark glossiness).
fn grid_vertex(imp: &Impostor, layer: u32, c: &Colours, i: usize, j: usize) -> Vertex {
    let xy = grid_point(i, j);
    Vertex {
        position: imp.centre.to_array(),
        normal: c.tint.to_array(),
        tangent: c.bark.extend(imp.radius).to_array(),
        uv: xy.to_array(),
        color: c.leaf,
        surface: c.leaf_surface,
        uv1: [-1.0 - layer as f32, c.bark_glossiness],
    }
}

/// Levels [`append`] adds: the impostor and the far impostor.
pub const LEVELS: usize = 2;
/// The levels of a leaves mesh that are impostors (after V1's
/// [`super::LEVELS`]), as the culled lists number them.
pub fn frame_levels() -> std::ops::Range<u32> {
    super::LEVELS as u32..(super::LEVELS + LEVELS) as u32
}

/// The far impostor's grid step (in fine cells): 4 x 4 cells.
pub const FAR_STEP: usize = 4;

/// Two triangles per cell of the grid whose vertices start at `first`,
/// every `step`th fine vertex (counter-clockwise seen from the viewer, `+w`).
fn grid_indices(first: u32, step: usize) -> Vec<u32> {
    let g = GRID + 1;
    let cells = GRID / step;
    let mut indices = Vec::with_capacity(cells * cells * 6);
    for j in 0..cells {
        for i in 0..cells {
            let v = |i: usize, j: usize| first + (j * step * g + i * step) as u32;
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
            // i right, j down: (a, d, c) turns counter-clockwise.
            indices.extend([a, d, c, a, c, b]);
        }
    }
    indices
}

/// The far level's geometric error (m, tree space): the mean distance
/// between a fine grid point's reconstructed position
/// ([`impostor::displace`]) and the coarse cell's bilinear interpolation
/// of its corners' (the surface the far level draws there), over the nine
/// capture directions, the eight between them and eight at 45° elevation.
/// The mean, not the maximum: the maximum is set by grid points past the
/// crown's silhouette, whose dilated depth jumps (larch seed 3: mean
/// 0.78 m, 90th percentile 2.0 m, maximum 9.4 m, of R = 9.1 m).
pub fn far_error(imp: &Impostor) -> f32 {
    use std::f32::consts::TAU;
    let around = |a: f32, y: f32| {
        let h = (1.0 - y * y).sqrt();
        Vec3::new(a.sin() * h, y, a.cos() * h)
    };
    let n = impostor::AROUND;
    let mut dirs: Vec<Vec3> = (0..impostor::CAPTURES).map(impostor::capture_dir).collect();
    for k in 0..n {
        let a = (k as f32 + 0.5) * TAU / n as f32;
        dirs.push(around(a, 0.0));
        dirs.push(around(
            k as f32 * TAU / n as f32,
            std::f32::consts::FRAC_1_SQRT_2,
        ));
    }
    let g = GRID + 1;
    let (mut sum, mut n) = (0.0f32, 0usize);
    for dir in dirs {
        let basis = impostor::view_basis(dir);
        let p: Vec<Vec3> = (0..g * g)
            .map(|v| impostor::displace(imp, basis, grid_point(v % g, v / g)))
            .collect();
        for j in 0..GRID {
            for i in 0..GRID {
                let (ci, cj) = (i / FAR_STEP * FAR_STEP, j / FAR_STEP * FAR_STEP);
                let f = Vec2::new((i - ci) as f32, (j - cj) as f32) / FAR_STEP as f32;
                let at = |i: usize, j: usize| p[j * g + i];
                let (a, b) = (at(ci, cj), at(ci + FAR_STEP, cj));
                let (c, d) = (at(ci, cj + FAR_STEP), at(ci + FAR_STEP, cj + FAR_STEP));
                let coarse = a.lerp(b, f.x).lerp(c.lerp(d, f.x), f.y);
                sum += coarse.distance(at(i, j));
                n += 1;
            }
        }
    }
    sum / n.max(1) as f32 * imp.radius
}

/// Appends the impostor levels to a leaves mesh (its levels LOD1 and LOD2
/// already there): the grid's vertices after the mesh's, then the full
/// grid (LOD2's error: it takes over where LOD2 would) and the far grid
/// (error at least [`far_error`], so the 1-pixel guard keeps it away until
/// its coarser depth cannot show).
pub fn append(leaves: &mut Mesh, imp: &Impostor, layer: u32, colours: &Colours) {
    let g = GRID + 1;
    let first = leaves.vertices.len() as u32;
    leaves
        .vertices
        .extend((0..g * g).map(|v| grid_vertex(imp, layer, colours, v % g, v / g)));
    let error = leaves.levels.last().map_or(0.0, |l| l.error);
    leaves.levels.push(Level {
        indices: grid_indices(first, 1),
        error,
    });
    leaves.levels.push(Level {
        indices: grid_indices(first, FAR_STEP),
        error: error.max(far_error(imp)),
    });
}

/// Whether `mesh`'s last level is an impostor ([`append`]).
pub fn has_impostor(mesh: &Mesh) -> bool {
    layer_of(mesh).is_some()
}

/// The atlas layer of `mesh`'s impostor level (`None`: no impostor), also
/// the index of its tree's V4 volume ([`Layers::volumes`]).
pub fn layer_of(mesh: &Mesh) -> Option<u32> {
    (mesh.levels.last())
        .and_then(|l| l.indices.first())
        .and_then(|&i| mesh.vertices.get(i as usize))
        .filter(|v| is_impostor_vertex(v))
        .map(|v| (-1.0 - v.uv1[0]).round().max(0.0) as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_level_is_the_marked_grid() {
        let model = generate(Species::Larch, 3, 0.2);
        let imp = impostor::bake(&model);
        let m = MaterialDesc::default();
        let lods = super::super::bake::bake(&model);
        let mut meshes = super::super::meshes(&model, &lods, "l", &m, &m, Vec3::ONE);
        assert!(!has_impostor(&meshes.leaves));
        let n = meshes.leaves.vertices.len();
        append(
            &mut meshes.leaves,
            &imp,
            2,
            &Colours::new(&m, &m, Vec3::ONE),
        );
        assert!(has_impostor(&meshes.leaves));
        assert_eq!(layer_of(&meshes.leaves), Some(2));
        assert_eq!(meshes.leaves.levels.len(), 2 + LEVELS);
        let (near, far) = (&meshes.leaves.levels[2], &meshes.leaves.levels[3]);
        assert_eq!(near.indices.len(), GRID * GRID * 6);
        assert_eq!(far.indices.len(), (GRID / FAR_STEP).pow(2) * 6);
        // Its corners are the fine grid's, and it is a coarser surface.
        assert!(far.indices.iter().all(|i| near.indices.contains(i)));
        assert!(
            far.error > near.error && far.error < imp.radius,
            "{}",
            far.error
        );
        assert_eq!(meshes.leaves.vertices.len(), n + (GRID + 1) * (GRID + 1));
        let v = &meshes.leaves.vertices[n];
        assert_eq!(v.uv1[0], -3.0);
        assert_eq!(v.tangent[3], imp.radius);
        // LOD0..2 hold no grid vertex.
        assert!(meshes.leaves.indices.iter().all(|&i| (i as usize) < n));
    }
}
