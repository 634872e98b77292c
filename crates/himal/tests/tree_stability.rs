//! Issue #18's LOD-transition must-show for the V1 trees, on
//! `tests/scenes/tree_approach.toml` (one tree on a wide meadow): along an
//! approach from 500 m to 10 m, how much the visibility-driven leaf levels
//! change the image against chains whose levels keep clusters chosen
//! without visibility. The issue asks for no more change than a naive
//! chain: met by both species, narrowly for the larch; their difference
//! from LOD0 is larger than the naive chain's, which the bars record.
//! Figures and commands: `docs/techniques/V1.md` "Stability".

mod common;

use glam::Vec3;
use himal::FrameSettings;
use himal::passes::ao::AoMode;
use himal::passes::vegetation::VegetationMotion;
use himal::scene::tree::{self, LEVELS, LeafLods, Species, TreeModel, visibility};
use himal::scene::{Camera, Mesh, Scene};

const SEED: u32 = 1;

fn tree_scene(species: Species) -> Scene {
    let to = format!("species = \"{}\"", species.name());
    common::scene_with("tree_approach", &[("species = \"larch\"", &to)])
}

fn object_mesh(scene: &Scene, name: &str) -> usize {
    (scene.objects.iter().find(|o| o.name == name))
        .unwrap_or_else(|| panic!("object {name}"))
        .mesh
}

/// The tree's leaves with each level's clusters and card scale, in the
/// scene's materials.
fn leaves_keeping(
    scene: &Scene,
    model: &TreeModel,
    kept: &[Vec<usize>; LEVELS],
    scale: [f32; LEVELS],
) -> Mesh {
    let material = |name: &str| {
        (scene.materials.iter().find(|m| m.name == name)).unwrap_or_else(|| panic!("{name}"))
    };
    let leaves = material("leaves");
    // The scene loader's default tint (build_vegetation.rs).
    let tint = (leaves.albedo * Vec3::new(1.3, 1.15, 0.55)).min(Vec3::ONE);
    tree::meshes_keeping(
        model,
        kept,
        scale,
        "approach",
        material("bark"),
        leaves,
        tint,
    )
    .leaves
}

/// A cluster's place in a fixed pseudo-random order (no visibility).
fn random_score(c: usize) -> f32 {
    let h = (c as u64 + 1).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    ((h >> 40) as f32) / (1u64 << 24) as f32
}

/// A chain's name, each level's clusters and each level's card scale.
type Chain = (&'static str, [Vec<usize>; LEVELS], [f32; LEVELS]);

/// The chains compared, each level with as many clusters as himal's and
/// cards scaled by the same coverage compensation for what it keeps:
/// himal's (the most visible per height band), the same bands filled in a
/// random order (what the visibility ranking adds within them), and a
/// naive one: random clusters over the whole crown.
fn chains(model: &TreeModel) -> [Chain; 3] {
    let ours = tree::bake::bake(model);
    let kept = std::array::from_fn(|l| ours.kept(model, l));
    let random = LeafLods {
        score: (0..model.clusters.len()).map(random_score).collect(),
        card_scale: [1.0; LEVELS],
    };
    let banded: [Vec<usize>; LEVELS] = std::array::from_fn(|l| random.kept(model, l));
    let mut order: Vec<usize> = (0..model.clusters.len()).collect();
    order.sort_by(|&a, &b| random_score(b).total_cmp(&random_score(a)));
    let naive: [Vec<usize>; LEVELS] = std::array::from_fn(|l| {
        let mut k = order[..kept[l].len()].to_vec();
        k.sort_unstable();
        k
    });
    let scales = |k: &[Vec<usize>; LEVELS]| {
        std::array::from_fn(|l| {
            if l == 0 {
                1.0
            } else {
                visibility::compensation(model, &k[l])
            }
        })
    };
    let (s_banded, s_naive) = (scales(&banded), scales(&naive));
    [
        ("visibility", kept, ours.card_scale),
        ("random in bands", banded, s_banded),
        ("naive", naive, s_naive),
    ]
}

fn luminance(c: [f32; 4]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Perceptual luminance of linear HDR `c` at exposure `e` (Reinhard).
fn tone(c: [f32; 4], e: f32) -> f32 {
    let y = luminance(c) * e;
    y / (1.0 + y)
}

/// Mean of |a − b| over `pixels`.
fn mean_abs(a: &[f32], b: &[f32], pixels: &[usize]) -> f64 {
    let sum: f64 = pixels.iter().map(|&i| f64::from((a[i] - b[i]).abs())).sum();
    sum / pixels.len().max(1) as f64
}

/// Over the tree's pixels (`footprint` per frame): the mean change from
/// the previous frame, and the mean difference from `reference` (LOD0) at
/// the same camera; and the per-frame differences.
fn change_and_error(
    frames: &[Vec<f32>],
    reference: &[Vec<f32>],
    footprint: &[Vec<usize>],
) -> (f64, f64, Vec<f64>) {
    let n = frames.len();
    let change = (1..n)
        .map(|k| mean_abs(&frames[k], &frames[k - 1], &footprint[k]))
        .sum::<f64>()
        / (n - 1) as f64;
    let errors: Vec<f64> = (0..n)
        .map(|k| mean_abs(&frames[k], &reference[k], &footprint[k]))
        .collect();
    (change, errors.iter().sum::<f64>() / n as f64, errors)
}

/// Along the approach (24 cameras, 500 m to 10 m in equal ratios, at half
/// the tree's height): the visibility-driven levels against the other
/// chains, all against LOD0 at the same camera. 256 x 144 (focal length
/// 174 px): with E2's 4 px threshold the leaves switch to LOD1 at about
/// 25 m and to LOD2 at about 40 m, both inside the path. Impostors are
/// off, so the chains differ only in which clusters their levels keep.
#[test]
fn visibility_driven_levels_change_the_approach_less_than_naive_ones() {
    let size = (256u32, 144u32);
    let steps = 24;
    let mut ratios = Vec::new();
    for species in Species::ALL {
        let mut scene = tree_scene(species);
        let model = tree::generate(species, SEED, 1.0);
        let leaves = object_mesh(&scene, "tree/leaves");
        let top = scene.meshes[leaves].bounds.max.y;
        let target = Vec3::new(0.0, 0.5 * top, 0.0);
        let cameras: Vec<Camera> = (0..steps)
            .map(|k| {
                let d = 500.0 * (10.0f32 / 500.0).powf(k as f32 / (steps - 1) as f32);
                Camera::look_at(target + Vec3::new(0.0, 0.0, d), target, 45.0)
            })
            .collect();
        let mut settings = FrameSettings::new(size.0, size.1, scene.sun.clone());
        settings.view = "lighting".parse().expect("view");
        settings.raw = true;
        settings.impostors = false;
        settings.ao.mode = AoMode::Off;
        settings.lod_threshold_px = 4.0;
        // At rest: the frames differ by the camera and the levels alone.
        settings.vegetation_motion = VegetationMotion::Off;
        let sequence = |scene: &Scene, s: &FrameSettings| -> Vec<Vec<[f32; 4]>> {
            let mut r = common::renderer(scene);
            cameras
                .iter()
                .map(|c| common::render_rgba(&mut r, c, s))
                .collect()
        };
        let mut lod0 = settings.clone();
        lod0.lod_threshold_px = 0.0;
        let chains = chains(&model);
        let (_, all, one) = &chains[0];
        scene.meshes[leaves] = leaves_keeping(&scene, &model, all, *one);
        let reference = sequence(&scene, &lod0);
        let runs: Vec<Vec<Vec<[f32; 4]>>> = (chains.iter())
            .map(|(_, kept, scale)| {
                scene.meshes[leaves] = leaves_keeping(&scene, &model, kept, *scale);
                sequence(&scene, &settings)
            })
            .collect();
        // One exposure per camera, from the reference frame's mean.
        let exposure: Vec<f32> = (reference.iter())
            .map(|f| f.len() as f32 / f.iter().map(|&c| luminance(c)).sum::<f32>().max(1e-6))
            .collect();
        // The tree's pixels: rays through its bounds.
        let bounds = scene.meshes[leaves].bounds;
        let footprint: Vec<Vec<usize>> = (cameras.iter())
            .map(|c| {
                (0..size.0 * size.1)
                    .filter(|&i| {
                        let d = common::pixel_ray(c, size, i % size.0, i / size.0);
                        common::hits_box(c.position, d, (bounds.min, bounds.max), f32::INFINITY)
                    })
                    .map(|i| i as usize)
                    .collect()
            })
            .collect();
        let toned = |frames: &[Vec<[f32; 4]>]| -> Vec<Vec<f32>> {
            (frames.iter().zip(&exposure))
                .map(|(f, &e)| f.iter().map(|&c| tone(c, e)).collect())
                .collect()
        };
        let reference = toned(&reference);
        let (lod0_change, _, _) = change_and_error(&reference, &reference, &footprint);
        let results: Vec<(f64, f64, Vec<f64>)> = (runs.iter())
            .map(|r| change_and_error(&toned(r), &reference, &footprint))
            .collect();
        for k in 0..steps {
            eprintln!(
                "{:6.1} m {:5} px: {:.4} {:.4} {:.4}",
                (cameras[k].position - target).length(),
                footprint[k].len(),
                results[0].2[k],
                results[1].2[k],
                results[2].2[k]
            );
        }
        eprintln!(
            "{}: LOD0 throughout: mean change per step {lod0_change:.5}",
            species.name()
        );
        for ((name, ..), (change, error, _)) in chains.iter().zip(&results) {
            eprintln!(
                "  {name}: mean change per step {change:.5}, mean difference from LOD0 {error:.5}"
            );
        }
        let (ours, naive) = (&results[0], &results[2]);
        ratios.push((species, ours.0 / naive.0, ours.1 / naive.1));
    }
    eprintln!("visibility / naive (change per step, difference from LOD0): {ratios:?}");
    for (species, change, error) in ratios {
        // Measured (256 x 144, 24 steps, lavapipe, trees at rest): change
        // 0.996 (larch), 0.943 (rosewood) of the naive chain's: the issue's
        // bar, 1, is met, narrowly for the larch (1.035 at 320 x 180 over
        // 36 steps). The difference from LOD0 is larger than naive's: 1.064
        // and 1.358; its bars hold that standing (V1.md "Stability").
        let (change_bar, error_bar) = match species {
            Species::Larch => (1.0, 1.15),
            Species::Rosewood => (1.0, 1.45),
        };
        assert!(change <= change_bar, "{}: change {change}", species.name());
        assert!(error <= error_bar, "{}: error {error}", species.name());
    }
}
