//! `himal soak`: renders many frames and reports resident and GPU memory
//! over time (issue #16: memory must stay flat).

use anyhow::{Result, bail};
use clap::Args;
use himal::soak::{SoakSample, resident_bytes, slope};

use crate::render::{RenderArgs, setup};

#[derive(Args, Debug)]
pub struct SoakArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    /// Print a sample every N frames (default: --frames / 20).
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub every: Option<u32>,
    /// The frame after which memory must be flat (warm-up: pools, caches,
    /// sky-occlusion sectors and probes fill before it).
    #[arg(long, default_value_t = 100, value_name = "FRAME", allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub baseline: u32,
    /// Exit with an error when resident memory after the last frame exceeds
    /// that after --baseline by more than PCT percent.
    #[arg(long, value_name = "PCT", allow_hyphen_values = true)]
    pub max_growth: Option<f64>,
}

/// The camera goes forward and back over this many frames, so a long soak
/// streams sectors and moves every history without leaving the world.
const DOLLY_PERIOD: u32 = 200;

pub fn run(args: &SoakArgs) -> Result<()> {
    let r = &args.render;
    if let Some(p) = args.max_growth
        && !(p.is_finite() && p >= 0.0)
    {
        bail!("--max-growth must be a finite percentage >= 0 (got {p})");
    }
    if r.frames < 2 {
        bail!("--frames must be at least 2 for a soak (got {})", r.frames);
    }
    if args.baseline >= r.frames {
        bail!(
            "--baseline {} must be below --frames {}",
            args.baseline,
            r.frames
        );
    }
    let (scene, camera, mut settings) = setup(r)?;
    let mut renderer = r.open_renderer(r.gpu.context()?, &scene)?;
    crate::render::world_haze(&renderer, &mut settings);
    r.post.configure(&mut renderer, &r.gpu, &scene)?;
    let every = args.every.unwrap_or((r.frames / 20).max(1)).max(1);
    println!(
        "soak: {} frames at {}x{} on {}",
        r.frames,
        settings.width,
        settings.height,
        renderer.context().info.name
    );
    println!("{:>8} {:>13} {:>9}", "frame", "resident MB", "GPU MB");
    let mut samples = Vec::new();
    let mut at_baseline = None;
    let mut gpu_at_baseline: Vec<(String, u64)> = Vec::new();
    for i in 0..r.frames {
        let mut cam = camera.clone();
        let phase = i % DOLLY_PERIOD;
        let along = phase.min(DOLLY_PERIOD - phase) as f32;
        cam.position += cam.forward * (r.speed * along);
        settings.time_s = i as f32 / 30.0;
        renderer.render(&cam, &settings)?;
        let frame = u64::from(i) + 1;
        let memory = renderer.memory();
        let sample = SoakSample {
            frame,
            resident: resident_bytes().unwrap_or(0),
            gpu: memory.iter().map(|(_, b)| b).sum(),
        };
        if frame == u64::from(args.baseline) {
            at_baseline = Some(sample);
            gpu_at_baseline = memory;
        }
        if frame % u64::from(every) == 0 || frame == u64::from(r.frames) {
            let mb = |b: u64| b as f64 / (1024.0 * 1024.0);
            println!(
                "{frame:>8} {:>13.1} {:>9.1}",
                mb(sample.resident),
                mb(sample.gpu)
            );
            if frame >= u64::from(args.baseline) {
                samples.push(sample);
            }
        }
    }
    let Some(base) = at_baseline else {
        bail!("no sample at --baseline {}", args.baseline);
    };
    let last = *samples.last().unwrap_or(&base);
    println!(
        "GPU memory by subsystem, after frame {} -> after frame {}:",
        base.frame, last.frame
    );
    print_memory_change(&gpu_at_baseline, &renderer.memory());
    if base.resident == 0 {
        println!("resident memory is not available on this platform");
        return Ok(());
    }
    let growth = 100.0 * (last.resident as f64 - base.resident as f64) / base.resident as f64;
    println!(
        "resident after frame {}: {:.1} MB, after frame {}: {:.1} MB ({growth:+.2} %); \
         slope {:.1} kB/frame; GPU memory {:+.1} MB",
        base.frame,
        base.resident as f64 / 1048576.0,
        last.frame,
        last.resident as f64 / 1048576.0,
        slope(&samples, |s| s.resident) / 1024.0,
        (last.gpu as f64 - base.gpu as f64) / 1048576.0,
    );
    if let Some(max) = args.max_growth
        && growth > max
    {
        bail!(
            "resident memory grew {growth:.2} % after frame {}, above --max-growth {max} %",
            base.frame
        );
    }
    Ok(())
}

/// One line per subsystem: its GPU bytes `before` -> `after` (MiB).
pub fn print_memory_change(before: &[(String, u64)], after: &[(String, u64)]) {
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    for (what, bytes) in after {
        let was = before
            .iter()
            .find(|(w, _)| w == what)
            .map_or(0, |(_, b)| *b);
        println!("  {what:<22} {:>8.2} -> {:>8.2} MiB", mib(was), mib(*bytes));
    }
}
