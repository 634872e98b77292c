//! The world's forests (V1 in the open world, issue #18 item 6): each tree
//! kind ([`InstanceKind::species`]) draws one of V1's generated trees, its
//! trunk (opaque) and its leaves (alpha-tested, with the impostor as the
//! last level, V3) in two pool regions of equal capacity: slot `s` of the
//! kind is slot `s` of both. Trees come from the tree cache
//! ([`crate::scene::tree::bake::cache_dir`]) when one is set, else are
//! baked in memory, once per process ([`tree`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

use glam::Vec3;

use super::InstanceKind;
use crate::scene::tree::{self, Species, impostor::Impostor, impostor_level};
use crate::scene::{AlphaPattern, Foliage, MaterialDesc, Mesh};

/// The generator seed of each species' world tree (the demo scene's).
pub fn seed(species: Species) -> u32 {
    match species {
        Species::Larch => 3,
        Species::Rosewood => 5,
    }
}

/// A world tree: its trunk and leaves meshes (the leaves' last level the
/// impostor of atlas layer [`layer`]) and the impostor's captures.
#[derive(Debug)]
pub struct WorldTree {
    /// Trunk and branches, three levels.
    pub trunk: Mesh,
    /// Leaf cards, three levels and the impostor.
    pub leaves: Mesh,
    /// The captures the leaves' impostor level reads.
    pub impostor: Arc<Impostor>,
}

/// The impostor atlas layer of `species` in the world's scene (the
/// species' order: every world scene holds both).
pub fn layer(species: Species) -> u32 {
    Species::ALL.iter().position(|s| *s == species).unwrap_or(0) as u32
}

fn srgb(c: [f32; 3]) -> Vec3 {
    Vec3::from(c).map(crate::scene::build::srgb_to_linear)
}

fn material(name: &str, albedo: [f32; 3], glossiness: f32) -> MaterialDesc {
    MaterialDesc {
        name: name.into(),
        albedo: srgb(albedo),
        glossiness,
        ..MaterialDesc::default()
    }
}

/// The materials and cluster tint of `species` (the demo scene's larches
/// and rosewoods).
fn look(species: Species) -> (MaterialDesc, MaterialDesc, Vec3) {
    let bark = material("bark", [0.30, 0.24, 0.18], 0.2);
    match species {
        Species::Larch => {
            let needles = material("needles", [0.16, 0.30, 0.10], 0.35);
            // The scene files' default tint: yellower and lighter.
            let tint = (needles.albedo * Vec3::new(1.3, 1.15, 0.55)).min(Vec3::ONE);
            (bark, needles, tint)
        }
        Species::Rosewood => {
            let leaves = material("foliage", [0.22, 0.38, 0.10], 0.4);
            (bark, leaves, srgb([0.42, 0.48, 0.12]))
        }
    }
}

/// The process's world trees by (species, seed).
type Memo = Mutex<HashMap<(Species, u32), Arc<WorldTree>>>;

/// The world tree of `species`, built (or read from the tree cache) on
/// first use and shared by every later world scene of the process.
pub fn tree(species: Species) -> Arc<WorldTree> {
    static MEMO: OnceLock<Memo> = OnceLock::new();
    let key = (species, seed(species));
    let memo = MEMO.get_or_init(Default::default);
    // Held while building: a second scene waits for the first's trees.
    let mut memo = memo.lock().unwrap_or_else(|e| e.into_inner());
    memo.entry(key)
        .or_insert_with(|| Arc::new(build(species)))
        .clone()
}

fn build(species: Species) -> WorldTree {
    let (bark, leaves, tint) = look(species);
    let s = seed(species);
    let name = format!("world-{}/{s}", species.name());
    let mut m = tree::cached(species, s, &name, &bark, &leaves, tint);
    let impostor = impostor_level::cached(species, s);
    let colours = impostor_level::Colours::new(&bark, &leaves, tint);
    impostor_level::append(&mut m.leaves, &impostor, layer(species), &colours);
    WorldTree {
        trunk: m.trunk,
        leaves: m.leaves,
        impostor,
    }
}

/// The leaves' foliage parameters (scene files' `tree` defaults): leaf
/// cards, swaying up the crown by the mesh's height.
pub fn foliage(leaves: &Mesh) -> Foliage {
    let b = leaves.bounds;
    Foliage {
        pattern: AlphaPattern::Leaves,
        sway: crate::scene::build_vegetation::TREE_SWAY,
        sway_base: b.min.y,
        sway_inv_height: 1.0 / b.extent().y.max(1e-3),
    }
}

/// One streamed pool region of the world: which kind's instances it holds,
/// the scene mesh it draws, and whether it is a tree's leaves (vegetation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Region {
    /// The kind whose instances fill it (slot for slot).
    pub kind: InstanceKind,
    /// Its mesh in the world's scene.
    pub mesh: usize,
    /// A tree's leaves: drawn with the vegetation, else opaque.
    pub leaves: bool,
}

/// The world's pool regions in order: per kind its own mesh (a tree's
/// trunk), then per tree kind its leaves, whose meshes follow the kinds'
/// in the scene ([`super::World::scene`]).
pub fn regions() -> Vec<Region> {
    let n = InstanceKind::ALL.len();
    let own = InstanceKind::ALL
        .iter()
        .enumerate()
        .map(|(k, &kind)| Region {
            kind,
            mesh: k,
            leaves: false,
        });
    let trees = InstanceKind::ALL.iter().filter(|k| k.species().is_some());
    let leaves = trees.enumerate().map(|(j, &kind)| Region {
        kind,
        mesh: n + j,
        leaves: true,
    });
    own.chain(leaves).collect()
}
