//! `himal bench --scene world --path NAME`: flies a world's named path and
//! reports, per frame, the CPU halves (planning with culling and
//! streaming, recording, submit), GPU time, draw calls, triangles,
//! resident sectors, pool use and upload bytes (issue #17, V6 and E2).

use std::io::Write;
use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use himal::scene::Camera;
use himal::{FrameSettings, Renderer};

use crate::bench::median;

/// One measured frame of the flight.
#[derive(Clone, Debug, Default)]
pub struct PathFrame {
    /// Seconds along the path.
    pub t: f32,
    pub plan_ms: f64,
    /// Streaming on the render thread (inside `plan_ms`).
    pub stream_ms: f64,
    /// The streamer's own update (inside `stream_ms`; the rest writes the pools).
    pub update_ms: f64,
    /// Streaming's other phases (inside `stream_ms`): terrain tiles,
    /// pool records, L2 and S2 told of new sectors.
    pub tiles_ms: f64,
    pub records_ms: f64,
    pub follow_ms: f64,
    pub record_ms: f64,
    pub submit_ms: f64,
    /// The render thread's own CPU time over plan, record and submit, and
    /// over its streaming ([`himal::clock`]: without the time the
    /// scheduler gave its core to other threads).
    pub thread_ms: f64,
    pub stream_thread_ms: f64,
    pub gpu_ms: f64,
    /// GPU time of the `cull` node and of the Hi-Z pyramid (`cull.hiz*`).
    pub cull_ms: f64,
    pub hiz_ms: f64,
    pub gbuffer_draws: u32,
    pub shadow_draws: u32,
    /// S2 static-map tiles rendered (`--shadows csm+static`).
    pub static_tiles: u32,
    pub static_texels: u64,
    /// Triangles of the culled object lists (all levels) and of the terrain.
    pub object_triangles: u64,
    pub terrain_triangles: u64,
    /// Instances drawn per LOD level.
    pub instances: [u64; himal::scene::lod::MAX_LODS],
    pub resident: u32,
    pub missing: u32,
    pub tiles_used: u32,
    pub tiles_total: u32,
    pub instances_live: u32,
    pub instances_total: u32,
    pub uploaded: u32,
    pub upload_bytes: u64,
    pub evicted: u32,
    /// Process resident memory after the frame (bytes; 0 where unknown).
    pub memory: u64,
}

impl PathFrame {
    pub fn cpu_ms(&self) -> f64 {
        self.plan_ms + self.record_ms + self.submit_ms
    }

    /// `cpu_ms` less streaming, and `thread_ms` less streaming.
    fn cpu_without_streaming(&self, thread: bool) -> f64 {
        if thread {
            self.thread_ms - self.stream_thread_ms
        } else {
            self.cpu_ms() - self.stream_ms
        }
    }
}

const CSV_HEADER: &str = "frame,t_s,plan_ms,stream_ms,update_ms,tiles_ms,records_ms,follow_ms,record_ms,submit_ms,cpu_ms,thread_ms,stream_thread_ms,gpu_ms,gbuffer_draws,shadow_draws,static_tiles,static_texels,object_triangles,terrain_triangles,lod0,lod1,lod2,lod3,lod4,resident_sectors,missing_sectors,tiles_used,tiles_total,instances_live,instances_total,uploaded,upload_bytes,evicted,resident_bytes";

fn csv_row(i: usize, f: &PathFrame) -> String {
    format!(
        "{i},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        f.t,
        f.plan_ms,
        f.stream_ms,
        f.update_ms,
        f.tiles_ms,
        f.records_ms,
        f.follow_ms,
        f.record_ms,
        f.submit_ms,
        f.cpu_ms(),
        f.thread_ms,
        f.stream_thread_ms,
        f.gpu_ms,
        f.gbuffer_draws,
        f.shadow_draws,
        f.static_tiles,
        f.static_texels,
        f.object_triangles,
        f.terrain_triangles,
        f.instances[0],
        f.instances[1],
        f.instances[2],
        f.instances[3],
        f.instances[4],
        f.resident,
        f.missing,
        f.tiles_used,
        f.tiles_total,
        f.instances_live,
        f.instances_total,
        f.uploaded,
        f.upload_bytes,
        f.evicted,
        f.memory
    )
}

/// What to fly.
pub struct PathRun<'a> {
    pub name: &'a str,
    pub frames: u32,
    /// Path seconds per frame (`None`: the frames spread over the whole path).
    pub dt: Option<f32>,
    pub fov_y_deg: f32,
    pub csv: Option<&'a Path>,
    pub json: bool,
    /// E2: also count every frame under all-LOD0, triangle-size and
    /// object-size selection, and FLIP sampled frames against LOD0.
    pub compare_lod: bool,
    /// Each frame's image written here as `frame_NNNN.png`.
    pub images: Option<&'a Path>,
}

/// The E2 comparison's selections: all LOD0, by triangle size (the run's
/// `--lod-threshold`, else 4 px), by object size (`--lod-object`, else 24 px).
fn lod_variants(settings: &FrameSettings) -> [(&'static str, FrameSettings); 3] {
    let mut lod0 = settings.clone();
    lod0.lod_threshold_px = 0.0;
    lod0.lod_object_px = 0.0;
    let mut triangle = lod0.clone();
    triangle.lod_threshold_px = if settings.lod_threshold_px > 0.0 {
        settings.lod_threshold_px
    } else {
        4.0
    };
    let mut object = lod0.clone();
    object.lod_object_px = if settings.lod_object_px > 0.0 {
        settings.lod_object_px
    } else {
        24.0
    };
    [
        ("all LOD0", lod0),
        ("triangle size", triangle),
        ("object size", object),
    ]
}

/// Per selection: triangles and sub-pixel triangles per frame, FLIP
/// against LOD0 on the sampled frames.
#[derive(Default)]
struct LodTally {
    triangles: Vec<f64>,
    subpixel: f64,
    flip: Vec<f64>,
}

/// The image of `settings` from `camera` as linear RGB (a first frame).
fn linear_image(
    renderer: &mut Renderer,
    camera: &Camera,
    settings: &FrameSettings,
) -> Result<Vec<[f32; 3]>> {
    let mut s = settings.clone();
    s.raw = true;
    // Every wanted sky-occlusion sector rendered in this frame: no image
    // sees a later stage of its time-sliced fill than another.
    s.sky_occlusion_every_frame = true;
    // SMAA 1x: no projection jitter, whose phase follows the frame count
    // (consecutive images would differ by it, not by their levels).
    s.aa = himal::passes::aa::AaMode::Smaa;
    renderer.reset_history();
    let f = renderer.render(camera, &s)?;
    Ok(f.image
        .to_rgba_f32()
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .into_iter()
        .map(|p| [p[0], p[1], p[2]])
        .collect())
}

/// Flies `run` in `renderer`'s world with `settings` and prints the report.
pub fn run(renderer: &mut Renderer, settings: &FrameSettings, run: &PathRun<'_>) -> Result<()> {
    let Some(world) = renderer.world() else {
        bail!(
            "--path {}: the scene has no flight paths (a world scene has: --scene world)",
            run.name
        );
    };
    let Some(path) = world.paths.iter().find(|p| p.name == run.name).cloned() else {
        let names: Vec<&str> = world.paths.iter().map(|p| p.name.as_str()).collect();
        bail!(
            "--path {}: no such path (this world has: {})",
            run.name,
            names.join(", ")
        );
    };
    let duration = path.duration();
    let dt = run.dt.unwrap_or(duration / (run.frames.max(2) - 1) as f32);
    if !(dt.is_finite() && dt > 0.0) {
        bail!("--dt {dt}: must be a positive number of seconds");
    }
    let camera_at = |i: u32| -> (f32, Camera) {
        let t = (i as f32 * dt).min(duration);
        (t, path.camera_at(t, run.fov_y_deg))
    };
    // Warm-up: everything around the start resident, pipelines compiled.
    let (_, start) = camera_at(0);
    renderer.settle_world(&start, Duration::from_secs(600))?;
    renderer.render(&start, settings)?;
    renderer.reset_history();
    let mut csv = match run.csv {
        Some(p) => {
            let mut f = std::fs::File::create(p)
                .with_context(|| format!("--csv {}: cannot create the file", p.display()))?;
            writeln!(f, "{CSV_HEADER}")?;
            Some((p, f))
        }
        None => None,
    };
    let bar = indicatif::ProgressBar::new(u64::from(run.frames));
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{msg} [{bar:40}] {pos}/{len} frames, {elapsed} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.set_message(format!("flying {}", run.name));
    let mut frames = Vec::with_capacity(run.frames as usize);
    let variants = lod_variants(settings);
    let mut tallies: Vec<LodTally> = variants.iter().map(|_| LodTally::default()).collect();
    // FLIP on six frames spread over the run (three renders each).
    let flip_every = (run.frames / 6).max(1);
    let wall = Instant::now();
    for i in 0..run.frames {
        let (t, camera) = camera_at(i);
        let frame = renderer.draw(&camera, settings)?;
        // Counting stalls on a read-back: after the timed frame, not in it.
        let counts = renderer.count_drawn(&camera, settings)?;
        let world = frame.world.clone().unwrap_or_else(|| himal::WorldFrame {
            stream: Default::default(),
            stream_ms: 0.0,
            stream_times: Default::default(),
            terrain: None,
        });
        let st = world.stream_times;
        let s = world.stream;
        let f = PathFrame {
            t,
            plan_ms: frame.cpu.plan_ms,
            stream_ms: world.stream_ms,
            update_ms: s.cpu_s * 1e3,
            tiles_ms: st.tiles.wall_ms,
            records_ms: st.records.wall_ms,
            follow_ms: st.follow.wall_ms,
            record_ms: frame.cpu.record_ms,
            submit_ms: frame.cpu.submit_ms,
            thread_ms: frame.cpu.thread_ms,
            stream_thread_ms: st.total.cpu_ms,
            gpu_ms: frame.timings.iter().map(|t| t.gpu_ms).sum(),
            cull_ms: pass_ms(&frame.timings, |id| id == "cull"),
            hiz_ms: pass_ms(&frame.timings, |id| id.starts_with("cull.hiz")),
            gbuffer_draws: frame.gbuffer_draws,
            shadow_draws: frame.shadows.draws,
            static_tiles: frame.shadows.static_tiles.len() as u32,
            static_texels: frame.shadows.static_texels,
            object_triangles: counts.total_triangles(),
            terrain_triangles: world.terrain.as_ref().map_or(0, |t| t.triangles().into()),
            instances: counts.instances,
            resident: s.resident,
            missing: s.missing,
            tiles_used: s.tiles_used,
            tiles_total: s.tiles_total,
            instances_live: s.instances,
            instances_total: s.instances_total,
            uploaded: s.uploaded,
            upload_bytes: s.upload_bytes,
            evicted: s.evicted,
            memory: himal::soak::resident_bytes().unwrap_or(0),
        };
        if run.compare_lod {
            for ((_, s), tally) in variants.iter().zip(&mut tallies) {
                let c = renderer.count_drawn(&camera, s)?;
                tally.triangles.push(c.total_triangles() as f64);
                tally.subpixel += c.subpixel.iter().sum::<f64>();
            }
            if i % flip_every == flip_every / 2 {
                // The three images see one resident set: streaming settled first.
                renderer.settle_world(&camera, Duration::from_secs(600))?;
                let (w, h) = (settings.width as usize, settings.height as usize);
                let reference = linear_image(renderer, &camera, &variants[0].1)?;
                for ((_, s), tally) in variants.iter().zip(&mut tallies).skip(1) {
                    let test = linear_image(renderer, &camera, s)?;
                    let flip = himal_reference::flip::flip_mean(
                        &reference,
                        &test,
                        w,
                        h,
                        himal_reference::flip::DEFAULT_PIXELS_PER_DEGREE,
                    )
                    .map_err(|e| anyhow::anyhow!("FLIP: {e}"))?;
                    tally.flip.push(f64::from(flip));
                }
                renderer.reset_history();
            }
        }
        if let Some(dir) = run.images {
            let output = renderer
                .output(settings)
                .ok_or_else(|| anyhow::anyhow!("no output image"))?;
            let image = himal::gpu::read_texture(renderer.context(), output, 0, 0)?;
            let file = dir.join(format!("frame_{i:04}.png"));
            himal::image_io::save(&file, &image)
                .with_context(|| format!("--images: cannot write {}", file.display()))?;
        }
        if let Some((p, file)) = csv.as_mut() {
            writeln!(file, "{}", csv_row(i as usize, &f))
                .with_context(|| format!("--csv {}: cannot write", p.display()))?;
        }
        frames.push(f);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let report = Report::new(&frames);
    let adapter = renderer.context().info.to_string();
    crate::save_cache(renderer.context());
    let flown = path.camera_at(0.0, 60.0).position.distance(
        path.camera_at((run.frames.saturating_sub(1)) as f32 * dt, 60.0)
            .position,
    );
    if run.json {
        println!("{}", report.json(&adapter, run.name, dt, flown));
    } else {
        report.print(&adapter, run.name, dt, flown, settings, wall.elapsed());
    }
    if run.compare_lod {
        println!(
            "E2 over the flight (camera lists; sub-pixel: expected share under 1 px; FLIP vs all LOD0 on {} settled frames):",
            tallies.get(1).map_or(0, |t| t.flip.len())
        );
        println!(
            "{:<16} {:>16} {:>16} {:>12} {:>12}",
            "selection", "triangles (k)", "total (M)", "sub-pixel", "FLIP mean"
        );
        for ((name, _), t) in variants.iter().zip(&mut tallies) {
            let total: f64 = t.triangles.iter().sum();
            let flip = if t.flip.is_empty() {
                "-".to_string()
            } else {
                format!("{:.4}", t.flip.iter().sum::<f64>() / t.flip.len() as f64)
            };
            println!(
                "{:<16} {:>16.1} {:>16.2} {:>11.1}% {:>12}",
                name,
                median(&mut t.triangles) / 1e3,
                total / 1e6,
                100.0 * t.subpixel / total.max(1.0),
                flip
            );
        }
    }
    Ok(())
}

/// GPU milliseconds of the passes whose id `wanted` accepts.
fn pass_ms(timings: &[himal::graph::PassTiming], wanted: impl Fn(&str) -> bool) -> f64 {
    timings
        .iter()
        .filter(|t| wanted(&t.id))
        .map(|t| t.gpu_ms)
        .sum()
}

/// Median, max and min of one column.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stat {
    pub median: f64,
    pub max: f64,
    pub min: f64,
}

impl Stat {
    fn of(frames: &[PathFrame], f: impl Fn(&PathFrame) -> f64) -> Stat {
        let mut v: Vec<f64> = frames.iter().map(f).collect();
        let max = v.iter().copied().fold(f64::MIN, f64::max);
        let min = v.iter().copied().fold(f64::MAX, f64::min);
        Stat {
            median: median(&mut v),
            max: if v.is_empty() { 0.0 } else { max },
            min: if v.is_empty() { 0.0 } else { min },
        }
    }

    /// max / min (1 for a flat or empty column).
    pub fn spread(&self) -> f64 {
        if self.min > 0.0 {
            self.max / self.min
        } else if self.max > 0.0 {
            f64::INFINITY
        } else {
            1.0
        }
    }

    fn json(&self) -> String {
        format!(
            "{{\"median\":{:.4},\"max\":{:.4},\"min\":{:.4}}}",
            self.median, self.max, self.min
        )
    }
}

/// The flight's summary.
pub struct Report {
    pub frames: usize,
    pub plan: Stat,
    pub stream: Stat,
    pub update: Stat,
    pub tiles_ms: Stat,
    pub records: Stat,
    pub follow: Stat,
    pub record: Stat,
    pub submit: Stat,
    pub cpu: Stat,
    pub thread: Stat,
    pub stream_thread: Stat,
    pub gpu: Stat,
    pub cull: Stat,
    pub hiz: Stat,
    pub gbuffer_draws: Stat,
    pub shadow_draws: Stat,
    pub static_tiles: Stat,
    pub static_texels: Stat,
    pub object_triangles: Stat,
    pub terrain_triangles: Stat,
    pub instances: Stat,
    pub resident: Stat,
    pub missing: Stat,
    pub tiles: Stat,
    pub instances_live: Stat,
    pub upload_bytes: Stat,
    pub memory: Stat,
    pub tiles_total: u32,
    pub instances_total: u32,
    pub uploaded: u64,
    pub upload_total: u64,
    pub evicted: u64,
    /// Frames whose CPU time exceeds twice the median, and how many of
    /// them only because of streaming (under twice the median without it) ...
    pub slow: usize,
    pub slow_streaming: usize,
    /// ... and the same on the render thread's CPU clock.
    pub slow_thread: usize,
    pub slow_thread_streaming: usize,
}

/// Frames over twice the median of `total`, and how many of them are
/// under it without their streaming.
fn slow_frames(f: &[PathFrame], thread: bool) -> (usize, usize) {
    let total = |x: &PathFrame| if thread { x.thread_ms } else { x.cpu_ms() };
    let bar = 2.0 * Stat::of(f, total).median;
    let slow: Vec<&PathFrame> = f.iter().filter(|x| total(x) > bar).collect();
    let streaming = slow
        .iter()
        .filter(|x| x.cpu_without_streaming(thread) <= bar)
        .count();
    (slow.len(), streaming)
}

impl Report {
    pub fn new(f: &[PathFrame]) -> Report {
        let cpu = Stat::of(f, PathFrame::cpu_ms);
        let (slow, slow_streaming) = slow_frames(f, false);
        let (slow_thread, slow_thread_streaming) = slow_frames(f, true);
        Report {
            frames: f.len(),
            plan: Stat::of(f, |x| x.plan_ms),
            stream: Stat::of(f, |x| x.stream_ms),
            update: Stat::of(f, |x| x.update_ms),
            tiles_ms: Stat::of(f, |x| x.tiles_ms),
            records: Stat::of(f, |x| x.records_ms),
            follow: Stat::of(f, |x| x.follow_ms),
            record: Stat::of(f, |x| x.record_ms),
            submit: Stat::of(f, |x| x.submit_ms),
            cpu,
            thread: Stat::of(f, |x| x.thread_ms),
            stream_thread: Stat::of(f, |x| x.stream_thread_ms),
            gpu: Stat::of(f, |x| x.gpu_ms),
            cull: Stat::of(f, |x| x.cull_ms),
            hiz: Stat::of(f, |x| x.hiz_ms),
            gbuffer_draws: Stat::of(f, |x| x.gbuffer_draws.into()),
            shadow_draws: Stat::of(f, |x| x.shadow_draws.into()),
            static_tiles: Stat::of(f, |x| x.static_tiles.into()),
            static_texels: Stat::of(f, |x| x.static_texels as f64),
            object_triangles: Stat::of(f, |x| x.object_triangles as f64),
            terrain_triangles: Stat::of(f, |x| x.terrain_triangles as f64),
            instances: Stat::of(f, |x| x.instances.iter().sum::<u64>() as f64),
            resident: Stat::of(f, |x| x.resident.into()),
            missing: Stat::of(f, |x| x.missing.into()),
            tiles: Stat::of(f, |x| x.tiles_used.into()),
            instances_live: Stat::of(f, |x| x.instances_live.into()),
            upload_bytes: Stat::of(f, |x| x.upload_bytes as f64),
            memory: Stat::of(f, |x| x.memory as f64),
            tiles_total: f.first().map_or(0, |x| x.tiles_total),
            instances_total: f.first().map_or(0, |x| x.instances_total),
            uploaded: f.iter().map(|x| u64::from(x.uploaded)).sum(),
            upload_total: f.iter().map(|x| x.upload_bytes).sum(),
            evicted: f.iter().map(|x| u64::from(x.evicted)).sum(),
            slow,
            slow_streaming,
            slow_thread,
            slow_thread_streaming,
        }
    }

    fn print(
        &self,
        adapter: &str,
        name: &str,
        dt: f32,
        flown: f32,
        settings: &FrameSettings,
        wall: Duration,
    ) {
        let mib = |b: f64| b / (1024.0 * 1024.0);
        println!(
            "himal bench --path {name}: {adapter}, {}x{}, {} frames, {dt:.3} s of path per frame, {:.2} km flown, {:.0} s wall",
            settings.width,
            settings.height,
            self.frames,
            flown / 1000.0,
            wall.as_secs_f64()
        );
        println!(
            "{:<34} {:>12} {:>12} {:>12}",
            "per frame", "median", "max", "min"
        );
        let row = |label: &str, s: &Stat, unit: f64| {
            println!(
                "{:<34} {:>12.3} {:>12.3} {:>12.3}",
                label,
                s.median / unit,
                s.max / unit,
                s.min / unit
            );
        };
        row("CPU plan + culling (ms)", &self.plan, 1.0);
        row("  of which streaming (ms)", &self.stream, 1.0);
        row("    streamer update (ms)", &self.update, 1.0);
        row("    terrain tiles (ms)", &self.tiles_ms, 1.0);
        row("    pool records (ms)", &self.records, 1.0);
        row("    L2/S2 follow (ms)", &self.follow, 1.0);
        row("CPU record (ms)", &self.record, 1.0);
        row("CPU submit (ms)", &self.submit, 1.0);
        row("CPU total (ms)", &self.cpu, 1.0);
        row("render thread's CPU clock (ms)", &self.thread, 1.0);
        row("  of which streaming (ms)", &self.stream_thread, 1.0);
        row("GPU total (ms)", &self.gpu, 1.0);
        row("  of which cull (ms)", &self.cull, 1.0);
        if self.hiz.max > 0.0 {
            row("  of which cull.hiz (ms)", &self.hiz, 1.0);
        }
        row("G-buffer draw calls", &self.gbuffer_draws, 1.0);
        row("shadow draw calls", &self.shadow_draws, 1.0);
        row("static shadow-map updates", &self.static_tiles, 1.0);
        row("  their texels (k)", &self.static_texels, 1e3);
        row("object triangles (k)", &self.object_triangles, 1e3);
        row("terrain triangles (k)", &self.terrain_triangles, 1e3);
        row("instances drawn (camera)", &self.instances, 1.0);
        row("resident sectors", &self.resident, 1.0);
        row("wanted sectors not resident", &self.missing, 1.0);
        row("terrain tiles in use", &self.tiles, 1.0);
        row("instance slots in use", &self.instances_live, 1.0);
        row("upload (KiB)", &self.upload_bytes, 1024.0);
        row("process resident (MiB)", &self.memory, 1024.0 * 1024.0);
        println!(
            "pools: tiles {:.0}..{:.0} of {} (max/min {:.3}), instance slots {:.0}..{:.0} of {} (max/min {:.3})",
            self.tiles.min,
            self.tiles.max,
            self.tiles_total,
            self.tiles.spread(),
            self.instances_live.min,
            self.instances_live.max,
            self.instances_total,
            self.instances_live.spread()
        );
        println!(
            "streaming: {} sectors uploaded ({:.1} MiB), {} evicted; process resident max/min {:.3}",
            self.uploaded,
            mib(self.upload_total as f64),
            self.evicted,
            self.memory.spread()
        );
        let ratio = |s: &Stat| {
            if s.median > 0.0 {
                s.max / s.median
            } else {
                0.0
            }
        };
        println!(
            "CPU frame time (wall) max/median {:.2}; frames over 2x the median: {} ({} of them because of streaming)",
            ratio(&self.cpu),
            self.slow,
            self.slow_streaming
        );
        println!(
            "CPU frame time (thread clock) max/median {:.2}; frames over 2x the median: {} ({} of them because of streaming)",
            ratio(&self.thread),
            self.slow_thread,
            self.slow_thread_streaming
        );
        if self.gpu.max == 0.0 {
            println!("(this adapter has no timestamp queries: no GPU times)");
        }
    }

    fn json(&self, adapter: &str, name: &str, dt: f32, flown: f32) -> String {
        let stats = [
            ("plan_ms", &self.plan),
            ("stream_ms", &self.stream),
            ("update_ms", &self.update),
            ("tiles_ms", &self.tiles_ms),
            ("records_ms", &self.records),
            ("follow_ms", &self.follow),
            ("record_ms", &self.record),
            ("submit_ms", &self.submit),
            ("cpu_ms", &self.cpu),
            ("thread_ms", &self.thread),
            ("stream_thread_ms", &self.stream_thread),
            ("gpu_ms", &self.gpu),
            ("cull_ms", &self.cull),
            ("hiz_ms", &self.hiz),
            ("gbuffer_draws", &self.gbuffer_draws),
            ("shadow_draws", &self.shadow_draws),
            ("static_tiles", &self.static_tiles),
            ("static_texels", &self.static_texels),
            ("object_triangles", &self.object_triangles),
            ("terrain_triangles", &self.terrain_triangles),
            ("instances_drawn", &self.instances),
            ("resident_sectors", &self.resident),
            ("missing_sectors", &self.missing),
            ("tiles_used", &self.tiles),
            ("instances_live", &self.instances_live),
            ("upload_bytes", &self.upload_bytes),
            ("resident_bytes", &self.memory),
        ];
        let body: Vec<String> = stats
            .iter()
            .map(|(k, s)| format!("\"{k}\":{}", s.json()))
            .collect();
        format!(
            "{{\"adapter\":{adapter:?},\"path\":{name:?},\"frames\":{},\"dt_s\":{dt},\"flown_m\":{flown:.1},\"tiles_total\":{},\"instances_total\":{},\"uploaded\":{},\"upload_total_bytes\":{},\"evicted\":{},\"slow_frames\":{},\"slow_frames_streaming\":{},\"slow_frames_thread\":{},\"slow_frames_thread_streaming\":{},{}}}",
            self.frames,
            self.tiles_total,
            self.instances_total,
            self.uploaded,
            self.upload_total,
            self.evicted,
            self.slow,
            self.slow_streaming,
            self.slow_thread,
            self.slow_thread_streaming,
            body.join(",")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(wall: f64, stream_wall: f64, thread: f64, stream_thread: f64) -> PathFrame {
        PathFrame {
            plan_ms: wall,
            stream_ms: stream_wall,
            thread_ms: thread,
            stream_thread_ms: stream_thread,
            ..PathFrame::default()
        }
    }

    #[test]
    fn slow_frames_are_counted_on_each_clock_and_blamed_on_streaming_only_when_it_is_the_cause() {
        let mut f: Vec<PathFrame> = (0..9).map(|_| frame(2.0, 1.0, 2.0, 1.0)).collect();
        // Descheduled inside its streaming: slow on the wall clock alone.
        f.push(frame(9.0, 8.0, 2.2, 1.2));
        // Slow on both clocks, and still slow without its streaming.
        f.push(frame(12.0, 1.0, 11.0, 1.0));
        // Slow on both clocks because of its streaming.
        f.push(frame(7.0, 6.0, 6.5, 5.5));
        assert_eq!(slow_frames(&f, false), (3, 2));
        assert_eq!(slow_frames(&f, true), (2, 1));
        let r = Report::new(&f);
        assert_eq!((r.slow, r.slow_streaming), (3, 2));
        assert_eq!((r.slow_thread, r.slow_thread_streaming), (2, 1));
    }
}
