//! `himal`: render the demo world or a scene headless, time every pass,
//! list adapters.

mod ao;
mod bench;
mod bench_ao;
mod render;

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
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to PNG (sRGB) or EXR (linear float).
    Render(render::RenderArgs),
    /// Render a fixed camera path and print GPU time per pass.
    Bench(bench::BenchArgs),
    /// List adapters, the chosen one, its features and limits.
    Info(GpuArgs),
}

/// Adapter choice shared by every command.
#[derive(Args, Clone, Debug, Default)]
pub struct GpuArgs {
    /// Adapter name substring or backend (vulkan, gl, metal, dx12); default: $HIMAL_ADAPTER, else hardware first.
    #[arg(long, value_name = "NAME|BACKEND")]
    pub adapter: Option<String>,
}

impl GpuArgs {
    pub fn context(&self) -> Result<himal::gpu::GpuContext> {
        Ok(himal::gpu::GpuContext::new(&himal::gpu::GpuOptions {
            adapter: self.adapter.clone(),
        })?)
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
    match cli.command {
        Command::Render(a) => render::run(&a),
        Command::Bench(a) => bench::run(&a),
        Command::Info(a) => info(&a),
    }
}
