//! `himal prewarm`: creates every pipeline permutation the renderer can use
//! for a scene and writes the pipeline cache (TECHNIQUES E1), so later runs
//! compile nothing.

use anyhow::{Result, bail};
use clap::Args;

use crate::GpuArgs;
use crate::scene_source::load_scene;

#[derive(Args, Debug)]
pub struct PrewarmArgs {
    /// Scene file (TOML), or `demo` for the built-in demo world.
    #[arg(
        long,
        default_value = "demo",
        value_name = "FILE|demo",
        allow_hyphen_values = true
    )]
    pub scene: String,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

pub fn run(args: &PrewarmArgs) -> Result<()> {
    let Some(dir) = args.gpu.cache_dir() else {
        bail!(
            "prewarm needs a cache directory: --cache DIR (or ${})",
            crate::CACHE_ENV
        );
    };
    let scene = load_scene(&args.scene)?;
    let mut renderer =
        crate::scene_source::open_renderer(&args.scene, args.gpu.context()?, &scene)?;
    renderer.prewarm()?;
    // L1: the Bruneton tables (cache file beside the pipelines) and pipelines.
    renderer.set_sky_table_cache(Some(dir.clone()));
    renderer.prepare_bruneton()?;
    let ctx = renderer.context();
    let stats = ctx.pipelines.stats();
    let path = ctx.save_pipeline_cache()?;
    println!(
        "prewarm: {} pipelines ({stats}); cache {}",
        ctx.pipelines.len(),
        path.unwrap_or(dir).display()
    );
    Ok(())
}
