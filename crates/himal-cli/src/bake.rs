//! `himal bake`: offline data, computed ahead of rendering with a progress
//! bar. L1: the Bruneton tables (default and/or Bruneton 2017's reference
//! sizes) into the table cache that `render`, `view` and `prewarm` read.
//! L5 (`--probes`): a scene's radiance-transfer probe cells, resumable
//! (cells already in the cache are kept).
//! V1 (`--trees`): the leaf LODs (visibility scores, card scales) of every
//! tree a scene places, into the tree cache scene loading reads, and V3's
//! impostor atlases (nine captures per tree) beside them.

use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use himal::passes::sky::bruneton::{AtmosphereConfig, BrunetonTables, cache_file};

use crate::GpuArgs;
use crate::render::parse_table_sizes;

#[derive(Args, Debug)]
pub struct BakeArgs {
    /// Bruneton table sizes to bake (`--sky-tables` picks them when
    /// rendering); default: `default`, none with `--probes` or `--trees`.
    #[arg(long, value_name = "default|reference|all", allow_hyphen_values = true)]
    pub tables: Option<String>,
    /// L5: bake the radiance-transfer probe cells of `--scene`.
    #[arg(long)]
    pub probes: bool,
    /// Recompute tables (and, with `--probes`, cells) the cache already holds.
    #[arg(long)]
    pub force: bool,
    /// V1/V3: bake the leaf LODs and impostor atlases of the trees `--scene` places (instead of sky tables).
    #[arg(long)]
    pub trees: bool,
    /// The scene whose probes (`--probes`) or trees (`--trees`) are baked:
    /// demo, world or a scene file.
    #[arg(long, default_value = "demo", value_name = "FILE|demo|world")]
    pub scene: String,
    /// L5 in a streamed world: bake the blocks within this many metres of
    /// each of the world's cameras (the whole 10 km world is 1,600 blocks).
    #[arg(
        long,
        default_value_t = 1000.0,
        value_name = "METRES",
        allow_hyphen_values = true
    )]
    pub radius: f32,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// L5: the world's blocks around its cameras, with a progress bar.
fn bake_world_probes(
    world: std::sync::Arc<himal::scene::world::World>,
    dir: &std::path::Path,
    args: &BakeArgs,
) -> Result<()> {
    use himal::passes::indirect::world::world_bake_settings;
    if !(args.radius.is_finite() && args.radius >= 0.0) {
        bail!(
            "--radius {}: give a distance in metres, 0 or more",
            args.radius
        );
    }
    let settings = world_bake_settings();
    let folder = himal::passes::indirect::world::world_cache_folder(dir, &world, &settings);
    if args.force && folder.exists() {
        std::fs::remove_dir_all(&folder)
            .map_err(|e| anyhow::anyhow!("{}: {e}", folder.display()))?;
    }
    let centres: Vec<glam::Vec2> = world
        .cameras
        .iter()
        .map(|c| glam::Vec2::new(c.camera.position.x, c.camera.position.z))
        .collect();
    let start = Instant::now();
    let (bar, progress) = crate::scene_source::probe_progress("L5 world", "blocks");
    let probes =
        himal::passes::indirect::WorldProbes::new(world, settings, Some(dir), Some(progress))
            .map_err(|e| anyhow::anyhow!("probe bake: {e}"))?;
    let report = probes
        .bake_around(&centres, args.radius)
        .map_err(|e| anyhow::anyhow!("probe bake: {e}"))?;
    bar.finish_and_clear();
    println!(
        "bake: {} world probe cells baked, {} from the cache, within {} m of {} cameras in {:.1} s, under {}",
        report.baked,
        report.cached,
        args.radius,
        centres.len(),
        start.elapsed().as_secs_f64(),
        folder.display()
    );
    Ok(())
}

pub fn run(args: &BakeArgs) -> Result<()> {
    let Some(dir) = args.gpu.cache_dir() else {
        bail!(
            "bake needs a cache directory: --cache DIR (or ${})",
            crate::CACHE_ENV
        );
    };
    if args.probes {
        if let Some(world) = crate::scene_source::world_of(&args.scene)? {
            return bake_world_probes(world, &dir, args);
        }
        let scene = crate::scene_source::load_scene(&args.scene)?;
        let start = Instant::now();
        let store = crate::scene_source::probe_cells(&scene, Some(&dir), args.force)?;
        println!(
            "bake: {} probe cells of {} (mips 0-4) in {:.1} s, under {}",
            store.len(),
            args.scene,
            start.elapsed().as_secs_f64(),
            dir.join("probes").display()
        );
    }
    if args.trees {
        bake_trees(&dir, args)?;
    }
    let tables = match (&args.tables, args.probes || args.trees) {
        (Some(t), _) => t.as_str(),
        (None, true) => return Ok(()),
        (None, false) => "default",
    };
    let names = match tables {
        "all" => vec!["default", "reference"],
        one @ ("default" | "reference") => vec![one],
        other => bail!("--tables {other}: expected default, reference or all"),
    };
    let ctx = args.gpu.context()?;
    for name in names {
        let config = AtmosphereConfig::earth(parse_table_sizes(name)?);
        let path = cache_file(&dir, &config);
        if !args.force && BrunetonTables::load(&ctx, config.clone(), &path).is_ok() {
            println!("bake: {name} sky tables already baked: {}", path.display());
            continue;
        }
        let (x, y, z) = config.sizes.scattering_extent();
        let bar = indicatif::ProgressBar::new(1);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{prefix} [{bar:30}] {pos}/{len} steps, {elapsed} {msg}",
            )?
            .progress_chars("=> "),
        );
        bar.set_prefix(format!("{name} sky tables"));
        let start = Instant::now();
        let tables =
            BrunetonTables::compute_with_progress(&ctx, config, &mut |done, steps, id| {
                bar.set_length(steps as u64);
                bar.set_position(done as u64);
                bar.set_message(id.to_string());
            })?;
        bar.finish_and_clear();
        tables.save(&ctx, &path)?;
        println!(
            "bake: {name} sky tables (scattering {x}x{y}x{z}) in {:.1} s: {}",
            start.elapsed().as_secs_f64(),
            path.display()
        );
    }
    Ok(())
}

/// `bake --trees`: each (species, seed) of the scene's `tree` objects,
/// generated and ranked by visibility, written to the tree cache.
fn bake_trees(dir: &std::path::Path, args: &BakeArgs) -> Result<()> {
    use himal::scene::tree::{self, bake};
    let text = if args.scene == "demo" {
        himal::scene::DEMO_TOML.to_string()
    } else {
        std::fs::read_to_string(&args.scene)
            .map_err(|e| anyhow::anyhow!("--scene {}: {e}", args.scene))?
    };
    let trees =
        bake::trees_in(&text).map_err(|e| anyhow::anyhow!("--scene {}: {e}", args.scene))?;
    if trees.is_empty() {
        println!("bake: {} places no trees", args.scene);
        return Ok(());
    }
    let bar = indicatif::ProgressBar::new(trees.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{prefix} [{bar:30}] {pos}/{len} trees, {elapsed} {msg}",
        )?
        .progress_chars("=> "),
    );
    bar.set_prefix("trees");
    let start = Instant::now();
    let (mut baked, mut cached) = (0, 0);
    for (species, seed) in &trees {
        bar.set_message(format!("{} seed {seed}", species.name()));
        let model = tree::generate(*species, *seed, 1.0);
        let path = bake::cache_file(dir, *species, *seed);
        if args.force {
            let _ = std::fs::remove_file(&path);
        }
        let imp_path = tree::impostor::cache_file(dir, *species, *seed);
        if args.force {
            let _ = std::fs::remove_file(&imp_path);
        }
        let ao_path = tree::ao::cache_file(dir, *species, *seed);
        if args.force {
            let _ = std::fs::remove_file(&ao_path);
        }
        let (_, read) = bake::load_or_bake_in(dir, &model, *seed);
        // V3: the nine impostor captures beside the leaf LODs.
        let (_, imp_read) = tree::impostor::load_or_bake_in(dir, &model, *seed);
        // V4: the occlusion volume.
        let (_, ao_read) = tree::ao::load_or_bake_in(dir, &model, *seed);
        if read && imp_read && ao_read {
            cached += 1;
        } else {
            baked += 1;
            for p in [&path, &imp_path, &ao_path] {
                if !p.exists() {
                    bail!("bake: could not write {}", p.display());
                }
            }
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    println!(
        "bake: {baked} trees baked, {cached} already baked, in {:.1} s: {}",
        start.elapsed().as_secs_f64(),
        dir.join("trees").display()
    );
    Ok(())
}
