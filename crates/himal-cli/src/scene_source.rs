//! What `--scene` names: the built-in demo, the streamed world, a scene
//! file (with or without a `[world]` table) or a glTF model; loaded once
//! per process and opened as a renderer.

use std::sync::Arc;

use himal::passes::indirect::{BakeSettings, ProbeStore};
use himal::scene::raycast::RayScene;
use std::path::Path;

use anyhow::Result;
use himal::Renderer;
use himal::scene::Scene;

/// The built-in streamed open world (`--scene world`).
pub const WORLD: &str = "world";

/// The world of `--scene world` (generated per sector from its seed).
pub fn world() -> std::sync::Arc<himal::scene::world::World> {
    std::sync::Arc::new(himal::scene::world::World::new(Default::default()))
}

pub(crate) fn is_gltf(spec: &str) -> bool {
    let lower = spec.to_ascii_lowercase();
    lower.ends_with(".gltf") || lower.ends_with(".glb")
}

/// The streamed world `spec` names: the built-in one, or a scene file with
/// a `[world]` table (its cameras first, then the world's); `None` for a
/// scene of objects. Each spec is read and built once per process (the
/// scene and the renderer both ask, and the viewer again after a device
/// loss).
pub fn world_of(spec: &str) -> Result<Option<std::sync::Arc<himal::scene::world::World>>> {
    type Worlds =
        std::collections::HashMap<String, Option<std::sync::Arc<himal::scene::world::World>>>;
    static WORLDS: std::sync::OnceLock<std::sync::Mutex<Worlds>> = std::sync::OnceLock::new();
    if spec == "demo" || is_gltf(spec) {
        return Ok(None);
    }
    let worlds = WORLDS.get_or_init(Default::default);
    if let Some(w) = worlds.lock().ok().and_then(|m| m.get(spec).cloned()) {
        return Ok(w);
    }
    let world = if spec == WORLD {
        Some(world())
    } else {
        let file = himal::scene::world::WorldFile::load(Path::new(spec))?;
        file.map(|f| std::sync::Arc::new(f.into_world()))
    };
    if let Ok(mut m) = worlds.lock() {
        m.insert(spec.to_string(), world.clone());
    }
    Ok(world)
}

/// The renderer for `spec` (see [`load_scene`]): the streamed world or `scene`.
pub fn open_renderer(spec: &str, ctx: himal::gpu::GpuContext, scene: &Scene) -> Result<Renderer> {
    Ok(match world_of(spec)? {
        Some(world) => Renderer::with_world(ctx, world)?,
        None => Renderer::new(ctx, scene)?,
    })
}

/// Loads `demo`, `world` or a scene file with a `[world]` table (its
/// meshes, cameras and sun; sectors stream in the renderer), a glTF model
/// (.gltf / .glb) or a scene file.
pub fn load_scene(spec: &str) -> Result<Scene> {
    Ok(if spec == "demo" {
        Scene::demo()?
    } else if is_gltf(spec) {
        Scene::from_gltf(Path::new(spec))?
    } else if let Some(world) = world_of(spec)? {
        world.scene()
    } else {
        Scene::load(Path::new(spec))?
    })
}

/// A progress bar on stderr and the callback a bake drives it with.
pub fn probe_progress(
    prefix: &'static str,
    unit: &'static str,
) -> (
    indicatif::ProgressBar,
    himal::passes::indirect::world::Progress,
) {
    let bar = indicatif::ProgressBar::new(0);
    if let Ok(style) = indicatif::ProgressStyle::with_template(&format!(
        "{{prefix}} [{{bar:30}}] {{pos}}/{{len}} {unit}, {{elapsed}} (eta {{eta}})"
    )) {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(prefix);
    let b = bar.clone();
    (
        bar,
        Box::new(move |done, total| {
            b.set_length(total as u64);
            b.set_position(done as u64);
            if done == total {
                b.finish_and_clear();
            }
        }),
    )
}

/// L5: hands `renderer` its probe cells: a scene's ([`probe_cells`]), or
/// the streamed world's, baked per block around the camera as it goes
/// (before each frame that needs them, or on a background thread with
/// `background`, the viewer's choice).
pub fn attach_probes(
    renderer: &mut Renderer,
    scene: &Scene,
    cache: Option<&Path>,
    background: bool,
) -> Result<()> {
    if let Some(world) = renderer.shared_world() {
        let (_bar, progress) = probe_progress("L5 world probes", "blocks");
        let probes = himal::passes::indirect::WorldProbes::new(
            world,
            himal::passes::indirect::world::world_bake_settings(),
            cache,
            Some(progress),
        )
        .map_err(|e| anyhow::anyhow!("L5 world probes: {e}"))?;
        if background {
            probes.start();
        }
        renderer.set_probe_cells(Some(Arc::new(probes)));
        return Ok(());
    }
    renderer.set_probe_cells(Some(probe_cells(scene, cache, false)?));
    Ok(())
}

/// L5: `scene`'s probe cells, read from `cache` where an earlier bake
/// left them (unless `force`), the rest baked now with a progress bar (stderr).
pub fn probe_cells(scene: &Scene, cache: Option<&Path>, force: bool) -> Result<Arc<ProbeStore>> {
    let geometry = RayScene::from_scene(scene, None);
    let settings = BakeSettings::default();
    if let Some(dir) = cache.filter(|_| force) {
        let folder = himal::passes::indirect::store::cache_folder(dir, &geometry, &settings);
        if folder.exists() {
            std::fs::remove_dir_all(&folder)
                .map_err(|e| anyhow::anyhow!("{}: {e}", folder.display()))?;
        }
    }
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} cells, {elapsed} (eta {eta}) {msg}",
        )?
        .progress_chars("=> "),
    );
    bar.set_prefix("L5 probes");
    let start = std::time::Instant::now();
    let (store, report) = ProbeStore::bake(&geometry, &settings, cache, &mut |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    })
    .map_err(|e| anyhow::anyhow!("probe bake: {e}"))?;
    bar.finish_and_clear();
    if report.baked > 0 {
        eprintln!(
            "L5 probes: baked {} cells ({} from the cache) in {:.1} s{}",
            report.baked,
            report.cached,
            start.elapsed().as_secs_f64(),
            if cache.is_none() {
                "; no cache directory: baked again next run"
            } else {
                ""
            }
        );
    }
    Ok(Arc::new(store))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The world file was parsed twice per run (once for the scene, once
    /// for the renderer): the second ask gets the same world.
    #[test]
    fn a_world_is_read_once_per_spec() {
        let spec = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../himal/tests/scenes/world_heightmap.toml"
        );
        let (a, b) = (world_of(spec).expect("a"), world_of(spec).expect("b"));
        assert!(std::sync::Arc::ptr_eq(
            &a.expect("a world"),
            &b.expect("a world")
        ));
        let (a, b) = (world_of(WORLD).expect("a"), world_of(WORLD).expect("b"));
        assert!(std::sync::Arc::ptr_eq(
            &a.expect("world"),
            &b.expect("world")
        ));
        assert!(world_of("demo").expect("demo").is_none());
    }
}
