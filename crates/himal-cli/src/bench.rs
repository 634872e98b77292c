//! `himal bench`: per-pass GPU time from a fixed camera (or `--dolly`,
//! `--path`), each pass's per-run cost and how often it ran, grouped like
//! the Far Cry 4 frame budget (TECHNIQUES E5), with the render thread's
//! CPU time beside it; `--compare A B` runs two settings interleaved.
//! How it measures: docs/performance.md, "How the bench measures".

use std::collections::BTreeMap;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use himal::FrameSettings;
use himal::graph::{PassTiming, TimingMethod};

use crate::GpuArgs;
use crate::render::{PostArgs, ShadowArgs, parse_size, pick_camera, world_haze};
use crate::scene_source::{load_scene, open_renderer};

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
    /// Frames measured (after one warm-up frame); with --compare, per side.
    #[arg(long, default_value_t = 16, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub frames: u32,
    /// Move the camera this many metres forward per frame (default: a
    /// fixed camera; the bench used to dolly 0.5 m per frame).
    #[arg(long, value_name = "METRES", allow_hyphen_values = true)]
    pub dolly: Option<f32>,
    /// Advance the scene's clock 1/30 s per frame (default: time 0), so
    /// animated glTF files (skins, morph weights) deform while measured.
    #[arg(long)]
    pub play: bool,
    /// Frames run after the measured ones with every pass submitted alone
    /// and timed by the wall clock: compute passes whose timestamps read
    /// under half that time are counted at it (`timing` isolated-wall).
    #[arg(long, default_value_t = 3, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub isolation_frames: u32,
    /// Run two settings interleaved in one process and print each pass's
    /// and the frame's medians, the ratio B/A and its spread, e.g.
    /// `--compare "--ao off" "--ao hbao"`: each side is whitespace-separated
    /// bench options applied over the others on the command line.
    #[arg(long, num_args = 2, value_names = ["A", "B"], allow_hyphen_values = true)]
    pub compare: Option<Vec<String>>,
    /// With --compare: frames per side before switching to the other
    /// (1: alternate frames). The ratio's spread is over these blocks.
    #[arg(long, default_value_t = 1, allow_hyphen_values = true, value_parser = crate::whole_number)]
    pub block: u32,
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
    /// of the fixed camera, and report per-frame CPU, GPU, draws, triangles,
    /// streaming and pool use; `--frames` frames spread over the path.
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub path: Option<String>,
    /// With --path: seconds of the path per frame (default: the frames
    /// cover the whole path).
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub dt: Option<f32>,
    /// Write a CSV file: one row per pass (`pass,group,timing,run_ms,runs,
    /// frames,frame_ms,...`); with --path, one row per frame; with
    /// --compare, one row per pass and side.
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
    // The world's terrain and the vegetation draw into the G-buffer and
    // into the sun maps.
    if ["terrain.shadow", "terrain.static", "vegetation.shadow"]
        .iter()
        .any(|p| pass.starts_with(p))
    {
        return "shadows";
    }
    if pass == "vegetation.gbuffer" || pass == "vegetation.impostor" {
        return "G-buffer";
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

/// The vegetation's per-frame ms by the talk's tree rows: simulation
/// (`vegetation.simulate`, `.ripple`), shadow (`vegetation.shadow*`),
/// G-buffer (`vegetation.gbuffer` and `.impostor`), and of that the
/// impostors alone.
fn vegetation_ms(rows: &[PassRow]) -> [f64; 4] {
    // From +0: an empty sum of f64 is -0 and would print as "-0.000".
    let sum = |f: &dyn Fn(&str) -> bool| {
        (rows.iter().filter(|r| f(&r.id)))
            .map(|r| r.frame_ms)
            .fold(0.0, |a, b| a + b)
    };
    [
        sum(&|id| id == "vegetation.simulate" || id == "vegetation.ripple"),
        sum(&|id| id.starts_with("vegetation.shadow")),
        sum(&|id| id == "vegetation.gbuffer" || id == "vegetation.impostor"),
        sum(&|id| id == "vegetation.impostor"),
    ]
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

/// A compute pass's timestamps are credible within this factor of its
/// isolated wall time, either way: lavapipe's read ~0.03 ms where the pass
/// alone takes milliseconds, or absorb earlier passes' deferred work (a
/// 0.27 ms `envmap...mirror` read 9.1 ms; docs/performance.md).
pub(crate) const CREDIBLE_FACTOR: f64 = 2.0;

/// One pass's GPU time over the measured frames.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PassRow {
    pub id: String,
    /// Frames the pass ran in (k of n).
    pub runs: usize,
    /// Per-run cost: median over the frames it ran in.
    pub run_ms: f64,
    /// Counted per frame: `run_ms * runs / frames`.
    pub frame_ms: f64,
    /// How `run_ms` was measured.
    pub timing: TimingMethod,
    /// Per-run median of the pass's timestamps (pass-level where it wrote
    /// them): `run_ms` unless the isolated time replaced it.
    pub ts_ms: f64,
    /// Median of the encoder timestamps around the pass over its runs.
    pub encoder_ms: f64,
    /// Median wall time of the pass submitted alone, over the isolation
    /// frames that ran it.
    pub isolated_ms: Option<f64>,
}

/// Per-pass GPU times of a run. A pass that runs in k of n frames (time
/// slices, on change) counts k/n of its per-run cost in the frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PassStats {
    pub rows: Vec<PassRow>,
    pub frames: usize,
    /// GPU ms per frame: the sum of the rows' `frame_ms`.
    pub total: f64,
    /// Median over frames of the frame's own summed timestamps (a
    /// cross-check; it counts compute passes at their timestamps).
    pub frame_sum_median: f64,
}

impl PassStats {
    /// `order`: pass ids in first-seen order; `frames`: each frame's
    /// timings, passes that did not run absent.
    pub fn new(order: &[String], frames: &[Vec<PassTiming>]) -> PassStats {
        let n = frames.len();
        let rows = order
            .iter()
            .map(|id| {
                let runs: Vec<&PassTiming> = frames
                    .iter()
                    .flat_map(|f| f.iter().filter(|t| &t.id == id))
                    .collect();
                let mut ms: Vec<f64> = runs.iter().map(|t| t.gpu_ms).collect();
                let mut enc: Vec<f64> = runs.iter().map(|t| t.encoder_ms).collect();
                // A pass timed by its own writes in any frame is a compute pass.
                let timing = match runs.iter().any(|t| t.method == TimingMethod::PassTs) {
                    true => TimingMethod::PassTs,
                    false => TimingMethod::EncoderTs,
                };
                let run_ms = median(&mut ms);
                PassRow {
                    id: id.clone(),
                    runs: runs.len(),
                    run_ms,
                    frame_ms: run_ms * runs.len() as f64 / n.max(1) as f64,
                    timing,
                    ts_ms: run_ms,
                    encoder_ms: median(&mut enc),
                    isolated_ms: None,
                }
            })
            .collect();
        let mut sums: Vec<f64> = frames
            .iter()
            .map(|f| f.iter().map(|t| t.gpu_ms).sum())
            .collect();
        let mut stats = PassStats {
            rows,
            frames: n,
            total: 0.0,
            frame_sum_median: median(&mut sums),
        };
        stats.retotal();
        stats
    }

    fn retotal(&mut self) {
        let n = self.frames.max(1) as f64;
        for r in &mut self.rows {
            r.frame_ms = r.run_ms * r.runs as f64 / n;
        }
        self.total = self.rows.iter().map(|r| r.frame_ms).sum();
    }

    /// Adds each pass's isolated wall time (median over the isolation
    /// frames that ran it); a compute pass whose timestamps read outside
    /// [`CREDIBLE_FACTOR`] of it is counted at its isolated time instead.
    pub fn apply_isolated(&mut self, isolated: &[Vec<PassTiming>]) {
        for r in &mut self.rows {
            let mut ms: Vec<f64> = isolated
                .iter()
                .flat_map(|f| f.iter().filter(|t| t.id == r.id).map(|t| t.gpu_ms))
                .collect();
            if ms.is_empty() {
                continue;
            }
            let iso = median(&mut ms);
            r.isolated_ms = Some(iso);
            let off = r.ts_ms < iso / CREDIBLE_FACTOR || r.ts_ms > iso * CREDIBLE_FACTOR;
            if r.timing == TimingMethod::PassTs && off {
                r.run_ms = iso;
                r.timing = TimingMethod::IsolatedWall;
            }
        }
        self.retotal();
    }

    /// Counts pass `i` at its isolated time where it has one (`--compare`:
    /// both sides timed alike once one side's timestamps were not credible).
    pub fn use_isolated(&mut self, i: usize) {
        if let Some(r) = self.rows.get_mut(i)
            && let Some(iso) = r.isolated_ms
        {
            r.run_ms = iso;
            r.timing = TimingMethod::IsolatedWall;
        }
        self.retotal();
    }

    /// Share of the frame.
    pub fn share(&self, frame_ms: f64) -> f64 {
        if self.total > 0.0 {
            frame_ms / self.total
        } else {
            0.0
        }
    }
}

/// Medians over the measured frames of the render thread's CPU phases (ms).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct CpuStats {
    pub total: f64,
    pub thread: f64,
    pub plan: f64,
    pub cull: f64,
    pub upload: f64,
    pub record: f64,
    pub submit: f64,
}

impl CpuStats {
    pub fn new(frames: &[himal::renderer::CpuTimes]) -> CpuStats {
        let m = |f: fn(&himal::renderer::CpuTimes) -> f64| {
            median(&mut frames.iter().map(f).collect::<Vec<_>>())
        };
        CpuStats {
            total: m(|c| c.total_ms()),
            thread: m(|c| c.thread_ms),
            plan: m(|c| c.plan_ms),
            cull: m(|c| c.cull_ms),
            upload: m(|c| c.upload_ms),
            record: m(|c| c.record_ms),
            submit: m(|c| c.submit_ms),
        }
    }

    pub fn json(&self) -> String {
        format!(
            "{{\"total\":{:.3},\"thread\":{:.3},\"plan\":{:.3},\"cull\":{:.3},\"upload\":{:.3},\"record\":{:.3},\"submit\":{:.3}}}",
            self.total, self.thread, self.plan, self.cull, self.upload, self.record, self.submit
        )
    }
}

pub fn run(args: &BenchArgs) -> Result<()> {
    let (width, height) = parse_size(&args.size)?;
    if args.frames == 0 {
        bail!("--frames must be at least 1");
    }
    let scene = load_scene(&args.scene)?;
    let camera = pick_camera(&scene, args.camera.as_deref())?;
    let settings = frame_settings(args, &scene, width, height)?;
    let path_only = args.dt.is_some() || args.compare_lod;
    if args.path.is_none() && (path_only || args.images.is_some()) {
        bail!("--dt, --compare-lod and --images need --path NAME (a world's flight path)");
    }
    if args.path.is_some() && args.dolly.is_some() {
        bail!("--dolly moves the fixed camera; --path flies the world's path: choose one");
    }
    if args.compare_lod && args.json {
        bail!("--compare-lod prints a table: leave out --json");
    }
    let dolly = args.dolly.unwrap_or(0.0);
    if !dolly.is_finite() {
        bail!("--dolly must be a finite number of metres per frame");
    }
    if let Some(sides) = &args.compare {
        return crate::bench_compare::run(args, sides);
    }
    if args.compare_ao {
        return crate::bench_ao::run(&args.gpu, &scene, &camera, &settings, args.frames, dolly);
    }
    if args.compare_envmap {
        return crate::bench_envmap::run(&args.gpu, &scene, &camera, &settings, args.frames);
    }
    let mut settings = settings;
    let mut renderer = open_renderer(&args.scene, args.gpu.context()?, &scene)?;
    world_haze(&renderer, &mut settings);
    if settings.indirect {
        let cache = args.gpu.cache_dir();
        crate::scene_source::attach_probes(&mut renderer, &scene, cache.as_deref(), false)?;
    }
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
    // A world is measured with every sector around the camera resident (as
    // `render` does): frames that stream in are not the fixed view's cost.
    renderer.settle_world(&camera, std::time::Duration::from_secs(600))?;
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
    // Each measured frame's timings: passes that did not run that frame
    // are absent, not zero.
    let mut per_frame: Vec<Vec<PassTiming>> = Vec::new();
    let mut order: Vec<String> = Vec::new();
    let mut wall = Vec::new();
    // Shadow draw calls per measured frame (S2: the static map saves them).
    let mut shadow_draws: Vec<u32> = Vec::new();
    let mut gbuffer_draws: Vec<u32> = Vec::new();
    // The culling that ran (V6: GPU, or the CPU path where it cannot).
    let mut culling = himal::Culling::Off;
    let mut cpu: Vec<himal::renderer::CpuTimes> = Vec::new();
    // L2 sky occlusion sectors rendered per measured frame.
    let mut sectors: Vec<u32> = Vec::new();
    // S2 in the world: static-map tiles rendered per frame.
    let mut tiles: Vec<u32> = Vec::new();
    // Resident memory after each measured frame (issue #16: flat over time).
    let mut resident: Vec<himal::soak::SoakSample> = Vec::new();
    let mut gpu_first: Vec<(String, u64)> = Vec::new();
    let dollied = |i: u32| {
        let mut cam = camera.clone();
        cam.position += cam.forward * (dolly * i as f32);
        cam
    };
    for i in 0..args.frames {
        // A fixed camera unless --dolly moves it.
        let cam = dollied(i);
        if args.play {
            settings.time_s = (i + 1) as f32 / 30.0;
        }
        let t = Instant::now();
        let frame = renderer.render(&cam, &settings)?;
        wall.push(t.elapsed().as_secs_f64() * 1e3);
        shadow_draws.push(frame.shadows.draws);
        gbuffer_draws.push(frame.gbuffer_draws);
        culling = frame.culling;
        cpu.push(frame.cpu);
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
        per_frame.push(frame.timings);
    }
    let mut stats = PassStats::new(&order, &per_frame);
    // Isolation frames after the measured ones (which they would otherwise
    // shift in the time slices): each pass submitted alone, by wall clock.
    let mut empty_submit = Vec::new();
    if !stats.rows.is_empty() && args.isolation_frames > 0 {
        renderer.set_isolated_timing(true);
        let mut isolated = Vec::new();
        for i in 0..args.isolation_frames {
            let frame = renderer.render(&dollied(args.frames + i), &settings)?;
            if let Some(iso) = frame.isolated {
                empty_submit.push(iso.empty_submit_ms);
                isolated.push(iso.passes);
            }
        }
        renderer.set_isolated_timing(false);
        stats.apply_isolated(&isolated);
    }
    let empty_submit = median(&mut empty_submit);
    let total = stats.total;
    let wall_median = median(&mut wall);
    let draws_mean = shadow_draws.iter().sum::<u32>() as f64 / shadow_draws.len().max(1) as f64;
    let draws_max = shadow_draws.iter().copied().max().unwrap_or(0);
    let g_mean = gbuffer_draws.iter().sum::<u32>() as f64 / gbuffer_draws.len().max(1) as f64;
    let cpu = CpuStats::new(&cpu);
    let adapter = renderer.context().info.to_string();
    let cache = renderer.context().pipelines.stats();
    crate::save_cache(renderer.context());
    let culling = format!("{culling:?}").to_lowercase();
    if let Some(path) = &args.csv {
        write_csv(path, &stats)?;
    }
    if args.json {
        let passes: Vec<String> = stats.rows.iter().map(|r| row_json(r, &stats)).collect();
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
            "{{\"adapter\":{adapter:?},\"size\":[{width},{height}],\"frames\":{},\"dolly_m\":{dolly},\"isolation_frames\":{},\"empty_submit_ms\":{empty_submit:.4},\"gpu_frame_ms\":{total:.4},\"gpu_frame_sum_median_ms\":{:.4},\"wall_ms_median\":{wall_median:.3},\"triangles\":{},\"gbuffer_draws_mean\":{g_mean:.2},\"culling\":{culling:?},\"cpu_ms_median\":{},\"shadow_draws\":{{\"mean\":{draws_mean:.2},\"max\":{draws_max}}},\"pipelines\":{{\"memory_hits\":{},\"disk_hits\":{},\"compiles\":{},\"disk_ms\":{:.3},\"compile_ms\":{:.3}}},\"passes\":[{}],\"one_off\":[{}],\"memory\":[{}],\"resident_bytes\":[{}]}}",
            args.frames,
            args.isolation_frames,
            stats.frame_sum_median,
            renderer.scene_triangles(),
            cpu.json(),
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
    let camera_line = match dolly {
        0.0 => "fixed camera".to_string(),
        d => format!("camera dollying {d} m per frame"),
    };
    println!(
        "himal bench: {adapter}, {width}x{height}, {camera_line}, {} frames (+ {} isolation), {} triangles",
        args.frames,
        args.isolation_frames,
        renderer.scene_triangles()
    );
    if stats.rows.is_empty() {
        println!("(this adapter has no timestamp queries: no per-pass GPU times)");
    }
    print_table(&stats);
    let mut groups: BTreeMap<&str, f64> = BTreeMap::new();
    for r in &stats.rows {
        *groups.entry(group(&r.id)).or_default() += r.frame_ms;
    }
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
            "  {:<14} {:>10.3} ms {:>6.1}%  (per frame)",
            g,
            ms,
            100.0 * stats.share(ms)
        );
    }
    let vegetation = vegetation_ms(&stats.rows);
    if vegetation.iter().any(|&ms| ms > 0.0) {
        let [simulate, shadow, gbuffer, impostor] = vegetation;
        // The impostors are part of the G-buffer row, not added again.
        let all = simulate + shadow + gbuffer;
        println!(
            "vegetation (issue #18; Far Cry 4 PS4 trees: simulation 0.28, shadow 0.95, G-buffer 5.50 = 6.73 ms, 28.8% of 23.4): simulation {simulate:.3}, shadow {shadow:.3}, G-buffer {gbuffer:.3} (of which impostors {impostor:.3}) = {all:.3} ms, {:.1}% of the frame",
            100.0 * stats.share(all)
        );
        if let Some(w) = renderer.world_stats() {
            println!(
                "  the world's trees resident: {} of {} instances",
                w.trees, w.instances
            );
        }
    }
    println!(
        "per frame (medians): GPU {total:.2} ms | CPU {:.2} ms wall, {:.2} ms thread CPU = plan {:.2} (culling {:.2}, uploads {:.2}) + record {:.2} + submit {:.2}",
        cpu.total, cpu.thread, cpu.plan, cpu.cull, cpu.upload, cpu.record, cpu.submit
    );
    println!(
        "GPU frame cross-check: median of each frame's summed timestamps {:.2} ms; empty submit+wait {empty_submit:.3} ms (subtracted from isolated times)",
        stats.frame_sum_median
    );
    println!("G-buffer draw calls per frame: mean {g_mean:.1} (culling: {culling})");
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

/// The frame settings of the bench's options (before the world's haze).
pub(crate) fn frame_settings(
    args: &BenchArgs,
    scene: &himal::scene::Scene,
    width: u32,
    height: u32,
) -> Result<FrameSettings> {
    let mut settings = FrameSettings::new(width, height, scene.sun.clone());
    args.shadows.apply(&mut settings)?;
    args.shadows
        .apply_cinematic(&mut settings, scene, args.camera.as_deref())?;
    args.post.apply(&mut settings)?;
    settings.envmap_every_frame = args.envmap_every_frame;
    settings.sky_occlusion_every_frame = args.skyocc_every_frame;
    settings.ao = args.ao.settings()?;
    Ok(settings)
}

/// One pass's row as (CSV header name, value) pairs: the JSON object and
/// the CSV line are written from the same list.
fn row_fields(r: &PassRow, stats: &PassStats) -> [(&'static str, String); 11] {
    let ms = |v: f64| format!("{v:.4}");
    [
        ("pass", r.id.clone()),
        ("group", group(&r.id).to_string()),
        ("timing", r.timing.name().to_string()),
        ("run_ms", ms(r.run_ms)),
        ("runs", r.runs.to_string()),
        ("frames", stats.frames.to_string()),
        ("frame_ms", ms(r.frame_ms)),
        ("share", ms(stats.share(r.frame_ms))),
        ("ts_ms", ms(r.ts_ms)),
        ("encoder_ms", ms(r.encoder_ms)),
        ("isolated_ms", r.isolated_ms.map_or(String::new(), ms)),
    ]
}

fn row_json(r: &PassRow, stats: &PassStats) -> String {
    let fields: Vec<String> = row_fields(r, stats)
        .into_iter()
        .map(|(name, value)| match name {
            // Strings quoted; JSON names the pass `id`.
            "pass" => format!("\"id\":\"{value}\""),
            "group" | "timing" => format!("\"{name}\":\"{value}\""),
            "isolated_ms" if value.is_empty() => format!("\"{name}\":null"),
            _ => format!("\"{name}\":{value}"),
        })
        .collect();
    format!("{{{}}}", fields.join(","))
}

pub(crate) const CSV_HEADER: &str =
    "pass,group,timing,run_ms,runs,frames,frame_ms,share,ts_ms,encoder_ms,isolated_ms";

pub(crate) fn csv_rows(stats: &PassStats) -> Vec<String> {
    stats
        .rows
        .iter()
        .map(|r| {
            let values: Vec<String> = row_fields(r, stats).into_iter().map(|(_, v)| v).collect();
            values.join(",")
        })
        .collect()
}

fn write_csv(path: &std::path::Path, stats: &PassStats) -> Result<()> {
    let mut text = format!("{CSV_HEADER}\n");
    for row in csv_rows(stats) {
        text.push_str(&row);
        text.push('\n');
    }
    std::fs::write(path, text)
        .with_context(|| format!("--csv {}: cannot write the file", path.display()))
}

fn print_table(stats: &PassStats) {
    // "run ms": per-run cost (median over the frames it ran in); "runs":
    // k/n frames; "frame ms" = run ms x k/n, summed into the total.
    println!(
        "{:<22} {:<14} {:<13} {:>9} {:>7} {:>9} {:>7} {:>9}",
        "pass", "group", "timing", "run ms", "runs", "frame ms", "share", "alone ms"
    );
    for r in &stats.rows {
        println!(
            "{:<22} {:<14} {:<13} {:>9.3} {:>7} {:>9.3} {:>6.1}% {:>9}",
            r.id,
            group(&r.id),
            r.timing.name(),
            r.run_ms,
            format!("{}/{}", r.runs, stats.frames),
            r.frame_ms,
            100.0 * stats.share(r.frame_ms),
            r.isolated_ms.map_or("-".to_string(), |v| format!("{v:.3}"))
        );
    }
    println!(
        "{:<22} {:<14} {:<13} {:>9} {:>7} {:>9.3} {:>6.1}%",
        "total (per frame)", "", "", "", "", stats.total, 100.0
    );
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

    /// Issue #18's rows: the vegetation's passes fall in the talk's groups
    /// and sum into its tree rows.
    #[test]
    fn vegetation_passes_fall_in_the_talks_rows() {
        assert_eq!(group("vegetation.gbuffer"), "G-buffer");
        assert_eq!(group("vegetation.impostor"), "G-buffer");
        assert_eq!(group("vegetation.shadow2"), "shadows");
        assert_eq!(group("vegetation.simulate"), "misc");
        let ids = [
            ("gbuffer", 5.0),
            ("vegetation.simulate", 0.5),
            ("vegetation.gbuffer", 2.0),
            ("vegetation.impostor", 1.0),
            ("vegetation.shadow0", 0.25),
            ("vegetation.shadow3", 0.75),
        ];
        let order: Vec<String> = ids.iter().map(|(id, _)| id.to_string()).collect();
        let frame: Vec<PassTiming> = ids.iter().map(|&(id, ms)| timing(id, ms)).collect();
        let s = PassStats::new(&order, &[frame]);
        assert_eq!(vegetation_ms(&s.rows), [0.5, 1.0, 3.0, 1.0]);
    }

    fn timing(id: &str, ms: f64) -> PassTiming {
        PassTiming {
            id: id.to_string(),
            gpu_ms: ms,
            encoder_ms: ms,
            method: TimingMethod::EncoderTs,
        }
    }

    /// A pass that runs one frame in eight counts 1/8 of its per-run cost:
    /// 1 ms every frame + 8 ms one frame in eight is 2 ms per frame (it
    /// read 9 ms when per-pass medians were summed).
    #[test]
    fn a_pass_that_runs_now_and_then_counts_k_of_n() {
        let order = vec!["gbuffer".to_string(), "skyocc.sector".to_string()];
        let frames: Vec<Vec<PassTiming>> = (0..8)
            .map(|i| {
                let mut f = vec![timing("gbuffer", 1.0)];
                if i == 3 {
                    f.push(timing("skyocc.sector", 8.0));
                }
                f
            })
            .collect();
        let s = PassStats::new(&order, &frames);
        assert_eq!(s.frames, 8);
        assert_eq!(s.total, 2.0);
        assert_eq!(s.frame_sum_median, 1.0);
        let sky = &s.rows[1];
        assert_eq!((sky.runs, sky.run_ms, sky.frame_ms), (1, 8.0, 1.0));
        let shares: f64 = s.rows.iter().map(|r| s.share(r.frame_ms)).sum();
        assert!((shares - 1.0).abs() < 1e-12, "shares sum to {shares}");
    }

    /// A compute pass whose timestamps read under half or over twice its
    /// isolated time is counted at the isolated time; one that reads
    /// credibly keeps its own.
    #[test]
    fn incredible_compute_timestamps_yield_to_isolation() {
        let order = vec!["a".to_string(), "b".to_string(), "c".to_string()];
        let pass_ts = |id: &str, ms: f64| PassTiming {
            method: TimingMethod::PassTs,
            ..timing(id, ms)
        };
        let frames = vec![vec![pass_ts("a", 0.03), pass_ts("b", 1.8), timing("c", 0.03)]; 3];
        let mut s = PassStats::new(&order, &frames);
        let iso = vec![vec![timing("a", 2.0), timing("b", 2.0), timing("c", 2.0)]];
        let mut over = PassStats::new(&order[..1], &[vec![pass_ts("a", 9.1)]]);
        over.apply_isolated(&[vec![timing("a", 0.27)]]);
        assert_eq!(over.rows[0].timing, TimingMethod::IsolatedWall);
        assert_eq!((over.rows[0].run_ms, over.rows[0].ts_ms), (0.27, 9.1));
        s.apply_isolated(&iso);
        let t: Vec<_> = s.rows.iter().map(|r| (r.timing, r.run_ms)).collect();
        assert_eq!(
            t,
            [
                (TimingMethod::IsolatedWall, 2.0),
                (TimingMethod::PassTs, 1.8),
                // Render passes keep their encoder timestamps.
                (TimingMethod::EncoderTs, 0.03)
            ]
        );
        assert!((s.total - 3.83).abs() < 1e-9, "{}", s.total);
    }
}
