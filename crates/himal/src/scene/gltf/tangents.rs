//! Tangents for primitives without a TANGENT attribute: MikkTSpace, as the
//! glTF specification asks (the same algorithm that baked the normal maps).
//! MikkTSpace works per face corner; the mesh is unwelded, the tangents
//! generated, and equal corners welded back.

use std::collections::HashMap;

use glam::Vec3;

use crate::scene::Vertex;

struct Corners<'a> {
    vertices: &'a mut [Vertex],
    /// The vertex UV slot the normal texture reads (0: `uv`, 1: `uv1`).
    set: u32,
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.vertices.len() / 3
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertices[face * 3 + vert].position
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.vertices[face * 3 + vert].normal
    }
    /// v flipped: glTF's v runs down the image, MikkTSpace's (Blender's) up;
    /// without the flip every handedness sign comes out inverted (tested
    /// against NormalTangentMirrorTest's exported tangents).
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let corner = &self.vertices[face * 3 + vert];
        let [u, v] = if self.set == 1 { corner.uv1 } else { corner.uv };
        [u, 1.0 - v]
    }
    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.vertices[face * 3 + vert].tangent = tangent;
    }
}

/// MikkTSpace tangents (w = handedness, bitangent = cross(n, t) * w) for an
/// indexed triangle list, along UV set `set` (the normal texture's); returns the re-welded vertices, indices, and each
/// new vertex's original (attributes the `Vertex` does not hold, such as
/// joints and weights, follow it). Degenerate UVs keep a tangent
/// perpendicular to the normal.
pub(super) fn generate(
    vertices: &[Vertex],
    indices: &[u32],
    set: u32,
) -> (Vec<Vertex>, Vec<u32>, Vec<u32>) {
    let mut corners: Vec<Vertex> = indices.iter().map(|&i| vertices[i as usize]).collect();
    let ok = mikktspace::generate_tangents(&mut Corners {
        vertices: &mut corners,
        set,
    });
    if !ok {
        log::warn!("MikkTSpace failed; tangents follow the normals' perpendicular");
    }
    for v in &mut corners {
        let n = Vec3::from(v.normal);
        let t = Vec3::from_slice(&v.tangent[..3]);
        if !t.is_finite() || t.length_squared() < 1e-12 {
            let t = n.any_orthonormal_vector();
            v.tangent = [t.x, t.y, t.z, 1.0];
        }
    }
    weld(corners, indices)
}

/// Merges bit-identical corners of one original vertex.
fn weld(corners: Vec<Vertex>, origins: &[u32]) -> (Vec<Vertex>, Vec<u32>, Vec<u32>) {
    const WORDS: usize = std::mem::size_of::<Vertex>() / 4;
    let mut map: HashMap<([u32; WORDS], u32), u32> = HashMap::with_capacity(corners.len());
    let (mut vertices, mut remap) = (Vec::new(), Vec::new());
    let mut indices = Vec::with_capacity(corners.len());
    for (v, &origin) in corners.into_iter().zip(origins) {
        let key: [u32; WORDS] = bytemuck::cast(v);
        let i = *map.entry((key, origin)).or_insert_with(|| {
            vertices.push(v);
            remap.push(origin);
            vertices.len() as u32 - 1
        });
        indices.push(i);
    }
    (vertices, indices, remap)
}

/// Per-vertex normals (area-weighted face normals) for primitives without NORMAL.
/// glTF asks for flat normals; shared vertices get the average instead.
pub(super) fn flat_normals(positions: &[[f32; 3]], indices: &[u32]) -> Vec<[f32; 3]> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let p = |k: usize| Vec3::from(positions[t[k] as usize]);
        let face = (p(1) - p(0)).cross(p(2) - p(0));
        for &i in t {
            n[i as usize] += face;
        }
    }
    n.into_iter()
        .map(|v| v.normalize_or(Vec3::Y).to_array())
        .collect()
}
