//! The world's shared meshes, one per [`InstanceKind`] (and a tree kind's
//! leaves, [`super::forest`]), built once: the instances only move, turn,
//! scale and tint them. Each mesh's local origin
//! is at its base (where it meets the ground), not its centre.

use std::sync::Arc;

use glam::Vec3;

use super::{InstanceKind, forest};
use crate::scene::noise;
use crate::scene::primitives::{self, MeshBuilder};
use crate::scene::tree::impostor::Impostor;
use crate::scene::{Aabb, MaterialDesc, Mesh};

fn material(name: &str, albedo: [f32; 3], glossiness: f32) -> MaterialDesc {
    MaterialDesc {
        name: name.into(),
        albedo: Vec3::from(albedo),
        glossiness,
        ..MaterialDesc::default()
    }
}

/// Moves every vertex by `d` (centred primitives to base origins).
fn offset(mut m: Mesh, d: Vec3) -> Mesh {
    for v in &mut m.vertices {
        v.position = (Vec3::from(v.position) + d).to_array();
    }
    m.bounds = Aabb::new(m.bounds.min + d, m.bounds.max + d);
    m
}

/// Appends `b`'s triangles to `a`.
fn merge(mut a: Mesh, b: Mesh) -> Mesh {
    let base = a.vertices.len() as u32;
    a.indices.extend(b.indices.iter().map(|i| i + base));
    a.vertices.extend(b.vertices);
    a.bounds = a.bounds.union(&b.bounds);
    a
}

/// A boulder: a sphere displaced by seeded noise, normals recomputed, unit size.
fn rock(seed: u32) -> Mesh {
    let m = material("rock", [0.36, 0.35, 0.33], 0.28);
    let mut mesh = primitives::uv_sphere(format!("rock{seed}"), 0.5, 28, 14, &m);
    let f = noise::Fractal {
        octaves: 4,
        ..Default::default()
    };
    for v in &mut mesh.vertices {
        let n = Vec3::from(v.normal);
        let k = noise::fbm(seed, n.x * 1.7 + n.y * 0.3, n.z * 1.7 - n.y * 0.9, f);
        // Flattened underside, lumpy top.
        let p = n * 0.5 * (1.0 + 0.45 * k);
        v.position = [p.x, p.y.max(-0.28), p.z];
    }
    recompute_normals(&mut mesh);
    let b = Aabb::from_points(mesh.vertices.iter().map(|v| Vec3::from(v.position)));
    let lift = Vec3::Y * -b.min.y;
    let mesh = Mesh { bounds: b, ..mesh };
    offset(mesh, lift)
}

/// Area-weighted vertex normals (shared vertices; seams keep their own).
fn recompute_normals(m: &mut Mesh) {
    let mut acc = vec![Vec3::ZERO; m.vertices.len()];
    for t in m.indices.chunks_exact(3) {
        let p = |i: u32| Vec3::from(m.vertices[i as usize].position);
        let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
        for &i in t {
            acc[i as usize] += n;
        }
    }
    for (v, n) in m.vertices.iter_mut().zip(acc) {
        let n = n.normalize_or(Vec3::Y);
        let t = Vec3::from_slice(&v.tangent[..3]);
        let t = (t - n * n.dot(t)).normalize_or(n.any_orthonormal_vector());
        v.normal = n.to_array();
        v.tangent = [t.x, t.y, t.z, 1.0];
    }
}

/// Unit walls (1 x 1 x 1 m box standing on its base); instances scale it.
fn house() -> Mesh {
    let m = material("plaster", [0.95, 0.95, 0.95], 0.25);
    offset(
        primitives::cuboid("house".into(), Vec3::ONE, &m),
        Vec3::Y * 0.5,
    )
}

/// Unit roof prism on its base; instances scale it to the house.
fn roof() -> Mesh {
    let tiles = material("roof", [0.95, 0.95, 0.95], 0.35);
    let gable = material("gable", [0.8, 0.78, 0.74], 0.25);
    offset(
        primitives::prism("roof".into(), Vec3::ONE, &tiles, &gable),
        Vec3::Y * 0.5,
    )
}

/// A 1 x 1 m field of 16 crop rows along x: alternating crop and soil strips.
fn field() -> Mesh {
    let crop = material("crop", [1.0, 1.0, 1.0], 0.15);
    let soil = material("soil", [0.55, 0.45, 0.38], 0.1);
    let mut b = MeshBuilder::new(&crop);
    let rows = 16;
    for r in 0..rows {
        b.set_material(if r % 2 == 0 { &crop } else { &soil });
        let (z0, z1) = (
            r as f32 / rows as f32 - 0.5,
            (r + 1) as f32 / rows as f32 - 0.5,
        );
        b.planar_polygon(
            &[
                Vec3::new(-0.5, 0.0, z0),
                Vec3::new(-0.5, 0.0, z1),
                Vec3::new(0.5, 0.0, z1),
                Vec3::new(0.5, 0.0, z0),
            ],
            Vec3::Y,
            Vec3::X,
        );
    }
    b.finish("field".into())
}

/// A 4 m fence segment along x: two posts and two rails.
fn fence() -> Mesh {
    let wood = material("wood", [0.42, 0.32, 0.22], 0.2);
    let post = |x: f32| {
        offset(
            primitives::cuboid("post".into(), Vec3::new(0.12, 1.2, 0.12), &wood),
            Vec3::new(x, 0.6, 0.0),
        )
    };
    let rail = |y: f32| {
        offset(
            primitives::cuboid("rail".into(), Vec3::new(4.0, 0.1, 0.06), &wood),
            Vec3::new(0.0, y, 0.0),
        )
    };
    let mut m = merge(merge(post(-1.9), post(1.9)), merge(rail(0.55), rail(1.0)));
    m.name = "fence".into();
    m
}

/// A unit water quad (1 x 1 m, facing +Y, at y = 0): dark, glossy, the
/// sky's reflection does the rest.
fn water() -> Mesh {
    let m = MaterialDesc {
        reflectance: 0.02,
        ..material("water", [0.02, 0.045, 0.05], 0.92)
    };
    primitives::plane("water".into(), [1.0, 1.0], [1, 1], &m)
}

/// The mesh of a kind that is not a tree (`None` for trees: [`super::forest`]).
fn kind_mesh(kind: InstanceKind) -> Option<Mesh> {
    Some(match kind {
        InstanceKind::Rock0 => rock(11),
        InstanceKind::Rock1 => rock(23),
        InstanceKind::Rock2 => rock(37),
        InstanceKind::HouseWalls => house(),
        InstanceKind::Roof => roof(),
        InstanceKind::Field => field(),
        InstanceKind::Fence => fence(),
        InstanceKind::Larch | InstanceKind::Rosewood => return None,
        InstanceKind::Water => water(),
    })
}

/// Per kind in [`InstanceKind::ALL`] order its mesh, `None` for the tree
/// kinds (what the probe bake traces: it skips trees, so nothing is baked).
pub fn solid_meshes() -> Vec<Option<Mesh>> {
    InstanceKind::ALL.iter().map(|&k| kind_mesh(k)).collect()
}

/// The world's meshes: one per kind in [`InstanceKind::ALL`] order (a
/// tree kind's trunk), then each tree kind's leaves
/// ([`super::forest::regions`]); and the trees' impostors, in atlas layer
/// order ([`super::forest::layer`]).
pub fn world_meshes() -> (Vec<Mesh>, Vec<Arc<Impostor>>) {
    let mut meshes = Vec::new();
    let mut leaves = Vec::new();
    let mut impostors = Vec::new();
    for &k in &InstanceKind::ALL {
        match k.species() {
            Some(species) => {
                let t = forest::tree(species);
                meshes.push(t.trunk.clone());
                leaves.push(t.leaves.clone());
                impostors.push((forest::layer(species), t.impostor.clone()));
            }
            None => meshes.extend(kind_mesh(k)),
        }
    }
    meshes.extend(leaves);
    impostors.sort_by_key(|(layer, _)| *layer);
    (meshes, impostors.into_iter().map(|(_, i)| i).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meshes_stand_on_their_base_and_are_well_formed() {
        let meshes = InstanceKind::ALL
            .iter()
            .filter_map(|&k| Some((k, kind_mesh(k)?)));
        for (k, m) in meshes {
            assert!(
                m.bounds.min.y.abs() < 1e-4,
                "{} starts at y {}",
                k.name(),
                m.bounds.min.y
            );
            assert_eq!(m.indices.len() % 3, 0);
            assert!(m.indices.iter().all(|&i| (i as usize) < m.vertices.len()));
            for v in &m.vertices {
                let n = Vec3::from(v.normal);
                assert!((n.length() - 1.0).abs() < 1e-3, "{}: normal {n}", k.name());
            }
        }
    }
}
