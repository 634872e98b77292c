//! `himal bench`: per-pass GPU time over a fixed camera path, grouped like
//! the Far Cry 4 frame budget (TECHNIQUES E5).

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::{Result, bail};
use clap::Args;
use himal::FrameSettings;

use crate::GpuArgs;
use crate::render::{
    PostArgs, ShadowArgs, load_scene, open_renderer, parse_size, pick_camera, world_haze,
};

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[arg(
        long,
        default_value = "demo",
        value_name = "FILE|demo",
        allow_hyphen_values = true
    )]
    pub scene: String,
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    #[arg(
        long,
        default_value = "1280x720",
        value_name = "WxH",
        allow_hyphen_values = true
    )]
    pub size: String,
    /// Frames measured (after one warm-up frame).
    #[arg(long, default_value_t = 16, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub frames: u32,
    #[command(flatten)]
    pub shadows: ShadowArgs,
    #[command(flatten)]
    pub ao: crate::ao::AoArgs,
    /// Compare AO variants (HBAO, + STF, brute-force blur) in one interleaved run and print the ratios.
    #[arg(long)]
    pub compare_ao: bool,
    #[command(flatten)]
    pub post: PostArgs,
    /// Capture and filter the environment cube every frame (normally only
    /// when the sky changes), to time `envmap.*`.
    #[arg(long)]
    pub envmap_every_frame: bool,
    /// Time the environment map's relighting, mips and filter by wall clock
    /// (static vs re-captured vs relit cube, interleaved) and print the ratios.
    #[arg(long)]
    pub compare_envmap: bool,
    /// Re-render every wanted sky occlusion sector each frame (normally only
    /// when one becomes visible), to time `skyocc.*` (L2).
    #[arg(long)]
    pub skyocc_every_frame: bool,
    /// Fly the world's named path (`--scene world --path across`) instead
    /// of the dolly, and report per-frame CPU, GPU, draws, triangles,
    /// streaming and pool use; `--frames` frames spread over the path.
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub path: Option<String>,
    /// With --path: seconds of the path per frame (default: the frames
    /// cover the whole path).
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub dt: Option<f32>,
    /// With --path: write one row per frame to this CSV file.
    #[arg(long, value_name = "FILE", allow_hyphen_values = true)]
    pub csv: Option<std::path::PathBuf>,
    /// With --path: count every frame's triangles and sub-pixel triangles
    /// under all-LOD0, triangle-size and object-size selection (E2), and
    /// FLIP six frames of each against LOD0.
    #[arg(long)]
    pub compare_lod: bool,
    /// With --path: write each frame's image to DIR/frame_NNNN.png (e.g.
    /// to compare two runs, `--occlusion hiz` against `off`).
    #[arg(long, value_name = "DIR", allow_hyphen_values = true)]
    pub images: Option<std::path::PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub gpu: GpuArgs,
}

/// Budget group of a pass id (E5: shadows, G-buffer, lighting, blended, post, anti-aliasing, misc).
pub fn group(pass: &str) -> &'static str {
    // The world's terrain draws into the G-buffer and into the sun maps.
    if pass.starts_with("terrain.shadow") || pass.starts_with("terrain.static") {
        return "shadows";
    }
    // See-through surfaces are the talk's blended passes; the forward
    // additions to opaque surfaces (emission, unlit, layers) are lighting.
    // E4's particles (simulation, lighting, quads) are blended effects too.
    if [
        "forward.blend",
        "forward.transmission",
        "forward.scene_color",
        "forward.particles",
        "particles.",
    ]
    .iter()
    .any(|p| pass.starts_with(p))
    {
        return "blended";
    }
    match pass.split('.').next().unwrap_or("") {
        "shadows" => "shadows",
        "terrain" => "G-buffer",
        "gbuffer" => "G-buffer",
        "lighting" | "sky" | "skyocc" | "ao" | "envmap" | "forward" => "lighting",
        "blended" => "blended",
        "post" => "post",
        "aa" => "anti-aliasing",
        _ => "misc",
    }
}

pub(crate) fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// One pass's GPU time over the measured frames.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PassRow {
    pub id: String,
    /// Frames the pass ran in.
    pub ran: usize,
    /// Median over the frames it ran in.
    pub median_ran: f64,
    /// Mean over all measured frames (0 where it did not run).
    pub mean: f64,
}

/// Per-pass GPU times of a run. Passes that run on some frames only
/// (time-sliced, on change) would inflate a total of per-pass medians past
/// any real frame; the total is the median of the frames' own sums.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PassStats {
    pub rows: Vec<PassRow>,
    pub frames: usize,
    /// Median over frames of the frame's summed pass times.
    pub total_median: f64,
    /// Mean over frames of the same sums (= the sum of the rows' means).
    pub total_mean: f64,
}

impl PassStats {
    /// `order`: pass ids in first-seen order; `frames`: each frame's
    /// (pass, ms), passes that did not run absent.
    pub fn new(order: &[String], frames: &[Vec<(String, f64)>]) -> PassStats {
        let n = frames.len();
        let rows = order
            .iter()
            .map(|id| {
                let mut ms: Vec<f64> = frames
                    .iter()
                    .flat_map(|f| f.iter().filter(|(p, _)| p == id).map(|(_, ms)| *ms))
                    .collect();
                let sum: f64 = ms.iter().sum();
                PassRow {
                    id: id.clone(),
                    ran: ms.len(),
                    median_ran: median(&mut ms),
                    mean: sum / n.max(1) as f64,
                }
            })
            .collect();
        let mut totals: Vec<f64> = frames
            .iter()
            .map(|f| f.iter().map(|(_, ms)| ms).sum())
            .collect();
        let total_mean = totals.iter().sum::<f64>() / n.max(1) as f64;
        PassStats {
            rows,
            frames: n,
            total_median: median(&mut totals),
            total_mean,
        }
    }

    /// Share of the mean frame.
    pub fn share(&self, mean_ms: f64) -> f64 {
        if self.total_mean > 0.0 {
            mean_ms / self.total_mean
        } else {
            0.0
        }
    }
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let (width, height) = parse_size(&args.size)?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let scene = load_scene(&args.scene)?;
    let camera = pick_camera(&scene, args.camera.as_deref())?;
    let mut settings = FrameSettings::new(width, height, scene.sun.clone());
    args.shadows.apply(&mut settings)?;
    args.post.apply(&mut settings)?;
    settings.envmap_every_frame = args.envmap_every_frame;
    settings.sky_occlusion_every_frame = args.skyocc_every_frame;
    settings.ao = args.ao.settings()?;
    let path_only = args.dt.is_some() || args.csv.is_some() || args.compare_lod;
    if args.path.is_none() && (path_only || args.images.is_some()) {
        bail!("--dt, --csv, --compare-lod and --images need --path NAME (a world's flight path)");
    }
    if args.compare_lod && args.json {
        bail!("--compare-lod prints a table: leave out --json");
    }
    if args.compare_ao {
        return crate::bench_ao::run(&args.gpu, &scene, &camera, &settings, args.frames);
    }
    if args.compare_envmap {
        return crate::bench_envmap::run(&args.gpu, &scene, &camera, &settings, args.frames);
    }
    let mut renderer = open_renderer(&args.scene, args.gpu.context()?, &scene)?;
    world_haze(&renderer, &mut settings);
    if let Some(name) = &args.path {
        renderer.set_sky_table_sizes(args.post.table_sizes()?);
        let run = crate::bench_path::PathRun {
            name,
            frames: args.frames,
            dt: args.dt,
            fov_y_deg: camera.fov_y_deg,
            csv: args.csv.as_deref(),
            json: args.json,
            compare_lod: args.compare_lod,
            images: args.images.as_deref(),
        };
        return crate::bench_path::run(&mut renderer, &settings, &run);
    }
    // No table cache: the warm-up frame times the table computation.
    renderer.set_sky_table_sizes(args.post.table_sizes()?);
    let warm_up = renderer.render(&camera, &settings)?; // warm-up: pools, first-use costs
    // L1: the Bruneton tables (once) and the sky SH (per time of day) ran
    // before the warm-up frame: reported apart from the per-frame rows.
    let one_off: Vec<(String, f64)> = warm_up
        .timings
        .iter()
        .filter(|t| t.id.starts_with("sky."))
        .map(|t| (t.id.clone(), t.gpu_ms))
        .collect();
    if !args.json {
        for (id, ms) in &one_off {
            println!("one-off {id:<32} {ms:8.3} ms");
        }
    }
    // Each measured frame's (pass, GPU ms): passes that did not run that
    // frame are absent, not zero.
    let mut per_frame: Vec<Vec<(String, f64)>> = Vec::new();
    let mut order: Vec<String> = Vec::new();
    let mut wall = Vec::new();
    // Shadow draw calls per measured frame (S2: the static map saves them).
    let mut shadow_draws: Vec<u32> = Vec::new();
    let mut gbuffer_draws: Vec<u32> = Vec::new();
    // The culling that ran (V6: GPU, or the CPU path where it cannot).
    let mut culling = himal::Culling::Off;
    // CPU milliseconds per measured frame: plan, record, submit.
    let mut cpu: [Vec<f64>; 3] = Default::default();
    // L2 sky occlusion sectors rendered per measured frame.
    let mut sectors: Vec<u32> = Vec::new();
    // S2 in the world: static-map tiles rendered per frame.
    let mut tiles: Vec<u32> = Vec::new();
    // Resident memory after each measured frame (issue #16: flat over time).
    let mut resident: Vec<himal::soak::SoakSample> = Vec::new();
    let mut gpu_first: Vec<(String, u64)> = Vec::new();
    for i in 0..args.frames {
        // A fixed path: a slow dolly, the same for every run.
        let mut cam = camera.clone();
        cam.position += cam.forward * (0.5 * i as f32);
        let t = Instant::now();
        let frame = renderer.render(&cam, &settings)?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        shadow_draws.push(frame.shadows.draws);
        gbuffer_draws.push(frame.gbuffer_draws);
        culling = frame.culling;
        for (v, ms) in
            cpu.iter_mut()
                .zip([frame.cpu.plan_ms, frame.cpu.record_ms, frame.cpu.submit_ms])
        {
            v.push(ms);
        }
        sectors.push(frame.sky_occlusion.rendered);
        tiles.push(frame.shadows.static_tiles.len() as u32);
        let memory = renderer.memory();
        resident.push(himal::soak::SoakSample {
            frame: u64::from(i) + 1,
            resident: himal::soak::resident_bytes().unwrap_or(0),
            gpu: memory.iter().map(|(_, b)| b).sum(),
        });
        if i == 0 {
            gpu_first = memory;
        }
        for t in &frame.timings {
            if !order.contains(&t.id) {
                order.push(t.id.clone());
            }
        }
        per_frame.push(
            frame
                .timings
                .into_iter()
                .map(|t| (t.id, t.gpu_ms))
                .collect(),
        );
    }
    let stats = PassStats::new(&order, &per_frame);
    let total = stats.total_median;
    let wall_median = median(&mut wall);
    let draws_mean = shadow_draws.iter().sum::<u32>() as f64 / shadow_draws.len().max(1) as f64;
    let draws_max = shadow_draws.iter().copied().max().unwrap_or(0);
    let g_mean = gbuffer_draws.iter().sum::<u32>() as f64 / gbuffer_draws.len().max(1) as f64;
    let [mut plan, mut record, mut submit] = cpu;
    let (plan, record, submit) = (median(&mut plan), median(&mut record), median(&mut submit));
    let adapter = renderer.context().info.to_string();
    let cache = renderer.context().pipelines.stats();
    crate::save_cache(renderer.context());
    let culling = format!("{culling:?}").to_lowercase();
    if args.json {
        let passes: Vec<String> = stats
            .rows
            .iter()
            .map(|r| {
                format!(
                    "{{\"id\":\"{}\",\"group\":\"{}\",\"gpu_ms\":{:.4},\"mean_ms\":{:.4},\"ran_frames\":{},\"share\":{:.4}}}",
                    r.id,
                    group(&r.id),
                    r.median_ran,
                    r.mean,
                    r.ran,
                    stats.share(r.mean)
                )
            })
            .collect();
        let one_off: Vec<String> = one_off
            .iter()
            .map(|(id, ms)| format!("{{\"id\":\"{id}\",\"gpu_ms\":{ms:.4}}}"))
            .collect();
        let memory: Vec<String> = renderer
            .memory()
            .iter()
            .map(|(k, b)| format!("{{\"what\":\"{k}\",\"bytes\":{b}}}"))
            .collect();
        println!(
            "{{\"adapter\":{adapter:?},\"size\":[{width},{height}],\"frames\":{},\"gpu_total_ms\":{total:.4},\"gpu_total_mean_ms\":{:.4},\"wall_ms_median\":{wall_median:.3},\"triangles\":{},\"gbuffer_draws_mean\":{g_mean:.2},\"culling\":{culling:?},\"cpu_ms_median\":{{\"plan\":{plan:.3},\"record\":{record:.3},\"submit\":{submit:.3}}},\"shadow_draws\":{{\"mean\":{draws_mean:.2},\"max\":{draws_max}}},\"pipelines\":{{\"memory_hits\":{},\"disk_hits\":{},\"compiles\":{},\"disk_ms\":{:.3},\"compile_ms\":{:.3}}},\"passes\":[{}],\"one_off\":[{}],\"memory\":[{}],\"resident_bytes\":[{}]}}",
            args.frames,
            stats.total_mean,
            renderer.scene_triangles(),
            cache.memory_hits,
            cache.disk_hits,
            cache.compiles,
            cache.disk_ms,
            cache.compile_ms,
            passes.join(","),
            one_off.join(","),
            memory.join(","),
            resident
                .iter()
                .map(|s| s.resident.to_string())
                .collect::<Vec<_>>()
                .join(",")
        );
        return Ok(());
    }
    println!(
        "himal bench: {adapter}, {width}x{height}, {} frames (median), {} triangles",
        args.frames,
        renderer.scene_triangles()
    );
    if stats.rows.is_empty() {
        println!("(this adapter has no timestamp queries: no per-pass GPU times)");
    }
    // A pass that runs on some frames only shows its median over those
    // frames; shares and groups use the mean over all frames.
    println!(
        "{:<22} {:<14} {:>10} {:>10} {:>7} {:>8}",
        "pass", "group", "GPU ms", "mean ms", "ran", "share"
    );
    for r in &stats.rows {
        println!(
            "{:<22} {:<14} {:>10.3} {:>10.3} {:>7} {:>7.1}%",
            r.id,
            group(&r.id),
            r.median_ran,
            r.mean,
            format!("{}/{}", r.ran, stats.frames),
            100.0 * stats.share(r.mean)
        );
    }
    let mut groups: BTreeMap<&str, f64> = BTreeMap::new();
    for r in &stats.rows {
        *groups.entry(group(&r.id)).or_default() += r.mean;
    }
    println!(
        "{:<22} {:<14} {:>10.3} {:>10.3} {:>7} {:>7.1}%",
        "total (frame median)", "", total, stats.total_mean, "", 100.0
    );
    println!(
        "by budget group (Far Cry 4 PS4 ms: shadows 1.8, G-buffer 7.5, lighting 6.6, blended 1.7, post 2.8, AA 1.9, misc 1.1):"
    );
    for g in [
        "shadows",
        "G-buffer",
        "lighting",
        "blended",
        "post",
        "anti-aliasing",
        "misc",
    ] {
        let ms = groups.get(g).copied().unwrap_or(0.0);
        println!(
            "  {:<14} {:>10.3} ms {:>6.1}%  (mean per frame)",
            g,
            ms,
            100.0 * stats.share(ms)
        );
    }
    println!("G-buffer draw calls per frame: mean {g_mean:.1} (culling: {culling})");
    println!(
        "CPU per frame (median): plan + culling {plan:.2} ms, record {record:.2} ms, submit {submit:.2} ms"
    );
    println!("shadow draw calls per frame: mean {draws_mean:.1}, max {draws_max}");
    println!(
        "sky occlusion sectors rendered per frame: mean {:.2}, max {}",
        sectors.iter().sum::<u32>() as f64 / sectors.len().max(1) as f64,
        sectors.iter().copied().max().unwrap_or(0)
    );
    if tiles.iter().any(|&t| t > 0) {
        println!(
            "static shadow-map updates per frame: mean {:.2}, max {}",
            tiles.iter().sum::<u32>() as f64 / tiles.len().max(1) as f64,
            tiles.iter().copied().max().unwrap_or(0)
        );
    }
    println!("frame wall time (submit to read-back, median): {wall_median:.1} ms");
    println!("pipeline cache (whole run, E1): {cache}");
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    println!("memory (after frame 1 -> after frame {}):", args.frames);
    crate::soak::print_memory_change(&gpu_first, &renderer.memory());
    if let (Some(a), Some(b)) = (resident.first(), resident.last())
        && a.resident > 0
    {
        println!(
            "  {:<22} {:>8.1} -> {:>8.1} MiB (slope {:.1} kB/frame)",
            "process resident",
            mib(a.resident),
            mib(b.resident),
            himal::soak::slope(&resident, |s| s.resident) / 1024.0
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E5's groups: see-through surfaces are "blended", forward additions
    /// to opaque surfaces are lighting (both read "misc" before).
    #[test]
    fn forward_passes_fall_in_their_budget_groups() {
        for pass in [
            "forward.blend",
            "forward.transmission",
            "forward.scene_color",
            "forward.scene_color.mip3",
            "forward.particles",
            "particles.simulate",
            "particles.light",
        ] {
            assert_eq!(group(pass), "blended", "{pass}");
        }
        for pass in ["forward.emissive", "forward.unlit", "forward.layers"] {
            assert_eq!(group(pass), "lighting", "{pass}");
        }
        assert_eq!(group("shadows.mask"), "shadows");
    }

    /// A pass that runs one frame in eight used to add its median to the
    /// total: 1 ms every frame + 8 ms one frame in eight read 9 ms, where
    /// the median frame costs 1 ms and the mean frame 2 ms.
    #[test]
    fn a_pass_that_runs_now_and_then_does_not_inflate_the_total() {
        let order = vec!["gbuffer".to_string(), "skyocc.sector".to_string()];
        let frames: Vec<Vec<(String, f64)>> = (0..8)
            .map(|i| {
                let mut f = vec![("gbuffer".to_string(), 1.0)];
                if i == 3 {
                    f.push(("skyocc.sector".to_string(), 8.0));
                }
                f
            })
            .collect();
        let s = PassStats::new(&order, &frames);
        assert_eq!(s.frames, 8);
        assert_eq!(s.total_median, 1.0);
        assert_eq!(s.total_mean, 2.0);
        let sky = &s.rows[1];
        assert_eq!((sky.ran, sky.median_ran, sky.mean), (1, 8.0, 1.0));
        let shares: f64 = s.rows.iter().map(|r| s.share(r.mean)).sum();
        assert!((shares - 1.0).abs() < 1e-12, "shares sum to {shares}");
    }
}
