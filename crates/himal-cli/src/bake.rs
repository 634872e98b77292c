//! `himal bake`: offline data, computed ahead of rendering with a progress
//! bar. L1: the Bruneton tables (default and/or Bruneton 2017's reference
//! sizes) into the table cache that `render`, `view` and `prewarm` read.

use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use himal::passes::sky::bruneton::{AtmosphereConfig, BrunetonTables, cache_file};

use crate::GpuArgs;
use crate::render::parse_table_sizes;

#[derive(Args, Debug)]
pub struct BakeArgs {
    /// Bruneton table sizes to bake (`--sky-tables` picks them when rendering).
    #[arg(
        long,
        default_value = "default",
        value_name = "default|reference|all",
        allow_hyphen_values = true
    )]
    pub tables: String,
    /// Recompute tables the cache already holds.
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
    let names = match args.tables.as_str() {
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
