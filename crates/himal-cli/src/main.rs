//! `himal`: render the demo world or a scene headless, time every pass,
//! list adapters.

mod aa_patterns;
mod ao;
mod bake;
mod bench;
mod bench_ao;
mod bench_compare;
mod bench_envmap;
mod bench_path;
mod camera;
mod options;
mod orbit;
mod prewarm;
mod render;
mod scene_source;
mod soak;
mod view;

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "himal",
    version,
    about = "Open-world real-time renderer: headless render, per-pass timings, adapter info"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Memory the scene and the frame may plan to hold (mesh segments,
    /// height fields, images, frame size), e.g. 4GiB; default:
    /// $HIMAL_MEMORY_BUDGET, else half of this machine's memory.
    #[arg(long, global = true, value_name = "SIZE", allow_hyphen_values = true)]
    memory_budget: Option<String>,
}

/// A whole number for clap, with the reason a value is refused ("-1" is
/// parsed and rejected, not taken for a flag).
pub fn whole_number(s: &str) -> Result<u32, String> {
    s.trim().parse::<u32>().map_err(|_| {
        if s.trim().starts_with('-') {
            "must not be negative: expected a whole number in 0..=4294967295".to_string()
        } else {
            "expected a whole number in 0..=4294967295".to_string()
        }
    })
}

/// The memory budget of `--memory-budget`, else the environment's.
pub fn memory_budget() -> Result<himal::budget::MemoryBudget> {
    himal::budget::MemoryBudget::from_env().map_err(|e| anyhow::anyhow!("--memory-budget: {e}"))
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to PNG (sRGB) or EXR (linear float).
    Render(render::RenderArgs),
    /// Open a window on a scene (X11): fly camera, time of day, technique
    /// toggles, debug views, screenshots; takes the render options (--frames N
    /// > 1: render N frames, write the last to --out and exit).
    View(view::ViewArgs),
    /// Render frames from a fixed camera (or --dolly, --path) and print each
    /// pass's GPU time per run and per frame, and the CPU time per frame.
    Bench(bench::BenchArgs),
    /// Render many frames (the camera dollying forward and back) and report
    /// resident and GPU memory over time: they must stay flat.
    Soak(soak::SoakArgs),
    /// Compile every pipeline permutation the renderer can use and write the pipeline cache.
    Prewarm(prewarm::PrewarmArgs),
    /// Compute offline data into the cache with a progress bar: the L1 sky
    /// tables (default and/or reference sizes), L5 probe cells (a scene's,
    /// or a streamed world's around its cameras) and V1 tree LODs.
    Bake(bake::BakeArgs),
    /// List adapters, the chosen one, its features and limits.
    Info(GpuArgs),
    /// A5: error estimate of six anti-aliasing sample patterns (CPU only).
    AaPatterns(aa_patterns::AaPatternsArgs),
}

/// Adapter choice shared by every command.
#[derive(Args, Clone, Debug, Default)]
pub struct GpuArgs {
    /// Adapter name substring or backend (vulkan, gl, metal, dx12); default: $HIMAL_ADAPTER, else hardware first.
    #[arg(long, value_name = "NAME|BACKEND", allow_hyphen_values = true)]
    pub adapter: Option<String>,
    /// Pipeline cache directory, or off; default: $HIMAL_CACHE_DIR, else $XDG_CACHE_HOME/himal, else ~/.cache/himal.
    #[arg(long, value_name = "DIR|off", allow_hyphen_values = true)]
    pub cache: Option<String>,
}

/// Environment variable naming the pipeline cache directory (`off` disables it).
pub const CACHE_ENV: &str = "HIMAL_CACHE_DIR";

impl GpuArgs {
    /// The pipeline cache directory (E1); `None` = memory only.
    pub fn cache_dir(&self) -> Option<PathBuf> {
        let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty());
        let chosen = self
            .cache
            .clone()
            .map(PathBuf::from)
            .or_else(|| env(CACHE_ENV).map(PathBuf::from));
        match chosen {
            Some(d) if d.as_os_str() == "off" => None,
            Some(d) => Some(d),
            None => env("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| env("HOME").map(|h| PathBuf::from(h).join(".cache")))
                .map(|d| d.join("himal")),
        }
    }

    /// The GPU context with the pipeline cache opened (a bad cache file is
    /// ignored with a warning).
    pub fn context(&self) -> Result<himal::gpu::GpuContext> {
        if let Some(dir) = self.cache_dir()
            && dir.exists()
            && !dir.is_dir()
        {
            anyhow::bail!(
                "--cache {}: not a directory (give a folder for the pipeline and sky-table caches, or off)",
                dir.display()
            );
        }
        let ctx = himal::gpu::GpuContext::new(&himal::gpu::GpuOptions {
            adapter: self.adapter.clone(),
        })
        .map_err(|e| match &self.adapter {
            Some(a) => anyhow::anyhow!("--adapter {a}: {e}"),
            None => e.into(),
        })?;
        if let Some(dir) = self.cache_dir() {
            let status = ctx.open_pipeline_cache(&dir);
            log::info!("pipeline cache: {status:?}");
        }
        Ok(ctx)
    }
}

/// Writes the pipeline cache if this run created pipelines; a failure only warns.
pub fn save_cache(ctx: &himal::gpu::GpuContext) {
    let stats = ctx.pipelines.stats();
    if stats.compiles + stats.disk_hits == 0 {
        return;
    }
    match ctx.save_pipeline_cache() {
        Ok(Some(path)) => log::info!("pipeline cache written: {}", path.display()),
        Ok(None) => {}
        Err(e) => log::warn!("{e}"),
    }
}

fn info(args: &GpuArgs) -> Result<()> {
    println!("adapters (preference order):");
    for a in himal::gpu::adapters() {
        println!("  {a}");
    }
    let ctx = args.context()?;
    println!("chosen: {}", ctx.info);
    println!(
        "per-pass GPU timestamps: {}",
        if ctx.timestamps { "yes" } else { "no" }
    );
    let mut features: Vec<String> = ctx
        .adapter
        .features()
        .iter_names()
        .map(|(n, _)| n.to_string())
        .collect();
    features.sort();
    println!("features: {}", features.join(", "));
    let l = ctx.device.limits();
    println!("limits:");
    println!("  max_texture_dimension_2d: {}", l.max_texture_dimension_2d);
    println!("  max_bind_groups: {}", l.max_bind_groups);
    println!(
        "  max_storage_buffer_binding_size: {}",
        l.max_storage_buffer_binding_size
    );
    println!(
        "  max_compute_workgroup_size: {}x{}x{}",
        l.max_compute_workgroup_size_x,
        l.max_compute_workgroup_size_y,
        l.max_compute_workgroup_size_z
    );
    println!("  max_color_attachments: {}", l.max_color_attachments);
    Ok(())
}

fn main() -> Result<()> {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Some(b) = &cli.memory_budget {
        himal::budget::MemoryBudget::parse(b)
            .map_err(|e| anyhow::anyhow!("--memory-budget {b}: {e}"))?;
        // The library reads the budget from the environment; no other
        // thread exists yet.
        unsafe { std::env::set_var(himal::budget::MEMORY_BUDGET_ENV, b) };
    }
    // V1: scene loading reads baked trees from (and bakes missing ones into) the cache.
    let gpu = match &cli.command {
        Command::Render(a) => Some(&a.gpu),
        Command::View(a) => Some(&a.render.gpu),
        Command::Soak(a) => Some(&a.render.gpu),
        Command::Bench(a) => Some(&a.gpu),
        Command::Prewarm(a) => Some(&a.gpu),
        Command::Bake(a) => Some(&a.gpu),
        _ => None,
    };
    himal::scene::tree::bake::set_cache_dir(gpu.and_then(|g| g.cache_dir()));
    match cli.command {
        Command::Render(a) => render::run(&a),
        Command::View(a) => view::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Soak(a) => soak::run(&a),
        Command::Prewarm(a) => prewarm::run(&a),
        Command::Bake(a) => bake::run(&a),
        Command::Info(a) => info(&a),
        Command::AaPatterns(a) => aa_patterns::run(&a),
    }
}
