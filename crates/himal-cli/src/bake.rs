//! `himal bake`: offline data, computed ahead of rendering with a progress
//! bar. L1: the Bruneton tables (default and/or Bruneton 2017's reference
//! sizes) into the table cache that `render`, `view` and `prewarm` read.
//! L5 (`--probes`): a scene's radiance-transfer probe cells, resumable
//! (cells already in the cache are kept).

use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use himal::passes::sky::bruneton::{AtmosphereConfig, BrunetonTables, cache_file};

use crate::GpuArgs;
use crate::render::parse_table_sizes;

#[derive(Args, Debug)]
pub struct BakeArgs {
    /// Bruneton table sizes to bake (`--sky-tables` picks them when
    /// rendering); default: `default`, none with `--probes`.
    #[arg(long, value_name = "default|reference|all", allow_hyphen_values = true)]
    pub tables: Option<String>,
    /// L5: bake the radiance-transfer probe cells of `--scene`.
    #[arg(long)]
    pub probes: bool,
    /// The scene whose probes `--probes` bakes: `demo` or a scene file.
    #[arg(long, default_value = "demo")]
    pub scene: String,
    /// Recompute tables (and, with `--probes`, cells) the cache already holds.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

pub fn run(args: &BakeArgs) -> Result<()> {
    let Some(dir) = args.gpu.cache_dir() else {
        bail!(
            "bake needs a cache directory: --cache DIR (or ${})",
            crate::CACHE_ENV
        );
    };
    if args.probes {
        if crate::scene_source::world_of(&args.scene)?.is_some() {
            bail!("bake --probes: the streamed world's cells are not baked yet (issue #19)");
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
    let tables = match (&args.tables, args.probes) {
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
