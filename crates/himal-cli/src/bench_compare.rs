//! `himal bench --compare A B`: two settings in one process, their frames
//! interleaved in blocks (`--block`, default 1: alternating frames, the
//! side going first alternating too), so both see the same machine state.
//! Each side is the command line's bench options with the side's own
//! (whitespace-separated) options applied over them. Prints each pass's
//! per-frame GPU cost on both sides (as `himal bench` counts it: per-run
//! median x k/n), the ratio B/A of those, and the median and interquartile
//! range of the per-block ratios; the same for the frame's GPU total and
//! the render thread's CPU time.

use anyhow::{Context, Result, bail};
use clap::Parser;
use himal::graph::{PassTiming, TimingMethod};
use himal::scene::Camera;

use crate::bench::{BenchArgs, PassStats, frame_settings};
use crate::render::{parse_size, pick_camera, world_haze};
use crate::scene_source::{load_scene, open_renderer};

/// One side's options, parsed like `himal bench`'s (later options win).
#[derive(Parser, Debug)]
#[command(name = "himal bench", args_override_self = true)]
struct Side {
    #[command(flatten)]
    bench: BenchArgs,
    /// The global option, accepted where the command line had it.
    #[arg(long, hide = true, allow_hyphen_values = true)]
    memory_budget: Option<String>,
}

/// The bench options on this process's command line, less `--compare`'s
/// and `--block`'s (the sides' options are applied over them).
fn base_tokens() -> Vec<String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(at) = args.iter().position(|a| a == "bench") else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut it = args[at + 1..].iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--compare" => {
                it.next();
                it.next();
            }
            "--block" => {
                it.next();
            }
            _ if a.starts_with("--block=") => {}
            _ => out.push(a.clone()),
        }
    }
    out
}

/// The options of one side: `base` with `side`'s tokens after them.
fn side_args(base: &[String], side: &str, name: &str) -> Result<BenchArgs> {
    let tokens: Vec<&str> = side.split_whitespace().collect();
    for bad in ["--compare", "--path", "--compare-ao", "--compare-envmap"] {
        if tokens.iter().any(|t| t.split('=').next() == Some(bad)) {
            bail!("--compare {name}: {bad} cannot be one side of a comparison");
        }
    }
    let all = std::iter::once("himal bench")
        .chain(base.iter().map(String::as_str))
        .chain(tokens);
    let side = Side::try_parse_from(all)
        .map_err(|e| anyhow::anyhow!("--compare {name} ({side:?}): {}", e.render()))?;
    Ok(side.bench)
}

/// The `q` quantile (0..=1) of `v`, linearly interpolated; 0 when empty.
pub(crate) fn quantile(v: &[f64], q: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let x = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (lo, hi) = (x.floor() as usize, x.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (x - lo as f64)
}

/// Ratios B/A of per-block values where A is positive.
fn block_ratios(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter()
        .zip(b)
        .filter(|(a, _)| **a > 0.0)
        .map(|(a, b)| b / a)
        .collect()
}

/// One side of the comparison while it runs.
struct Running {
    renderer: himal::Renderer,
    settings: himal::FrameSettings,
    camera: Camera,
    dolly: f32,
    frames: Vec<Vec<PassTiming>>,
    /// Index of each frame's block.
    block_of: Vec<usize>,
    cpu: Vec<himal::renderer::CpuTimes>,
}

/// A pass's (or the frame's) figures on both sides.
struct Compared {
    id: String,
    timing: String,
    a: f64,
    b: f64,
    /// Median, first and third quartile of the per-block ratios (`None`
    /// where the pass is counted at its isolated time, one figure per
    /// side, or where A never ran).
    blocks: Option<[f64; 3]>,
}

impl Compared {
    fn ratio(&self) -> f64 {
        if self.a > 0.0 {
            self.b / self.a
        } else {
            f64::NAN
        }
    }

    fn json(&self) -> String {
        let num = |v: f64| match v.is_finite() {
            true => format!("{v:.4}"),
            false => "null".into(),
        };
        let blocks = self.blocks.map_or("null".into(), |[m, q1, q3]| {
            format!(
                "{{\"median\":{},\"q1\":{},\"q3\":{}}}",
                num(m),
                num(q1),
                num(q3)
            )
        });
        format!(
            "{{\"id\":\"{}\",\"timing\":\"{}\",\"a_ms\":{},\"b_ms\":{},\"ratio\":{},\"block_ratio\":{blocks}}}",
            self.id,
            self.timing,
            num(self.a),
            num(self.b),
            num(self.ratio())
        )
    }

    fn row(&self) -> String {
        let blocks = self.blocks.map_or("-".to_string(), |[m, q1, q3]| {
            format!("{m:.3} [{q1:.3}, {q3:.3}]")
        });
        format!(
            "{:<24} {:<27} {:>9.3} {:>9.3} {:>7.3} {}",
            self.id,
            self.timing,
            self.a,
            self.b,
            self.ratio(),
            blocks
        )
    }
}

fn open(args: &BenchArgs) -> Result<Running> {
    let (width, height) = parse_size(&args.size)?;
    let scene = load_scene(&args.scene)?;
    let camera = pick_camera(&scene, args.camera.as_deref())?;
    let mut settings = frame_settings(args, &scene, width, height)?;
    let mut renderer = open_renderer(&args.scene, args.gpu.context()?, &scene)?;
    world_haze(&renderer, &mut settings);
    // The sky tables from the cache: a comparison does not time them.
    args.post.configure(&mut renderer, &args.gpu, &scene)?;
    // A world with every sector around the camera resident (bench.rs).
    renderer.settle_world(&camera, std::time::Duration::from_secs(600))?;
    renderer.render(&camera, &settings)?; // warm-up: pools, first-use costs
    let dolly = args.dolly.unwrap_or(0.0);
    Ok(Running {
        renderer,
        settings,
        camera,
        dolly,
        frames: Vec::new(),
        block_of: Vec::new(),
        cpu: Vec::new(),
    })
}

pub fn run(args: &BenchArgs, sides: &[String]) -> Result<()> {
    let [a, b] = sides else {
        bail!("--compare takes two settings, e.g. --compare \"--ao off\" \"--ao hbao\"");
    };
    if args.block == 0 {
        bail!("--block must be at least 1");
    }
    let base = base_tokens();
    let (args_a, args_b) = (side_args(&base, a, "A")?, side_args(&base, b, "B")?);
    let mut runs = [open(&args_a)?, open(&args_b)?];
    let frames = args.frames as usize;
    let block = args.block as usize;
    let blocks = frames.div_ceil(block);
    for k in 0..blocks {
        // The side going first alternates, so neither always follows the other.
        for s in [k % 2, 1 - k % 2] {
            let r = &mut runs[s];
            for f in k * block..((k + 1) * block).min(frames) {
                let mut cam = r.camera.clone();
                cam.position += cam.forward * (r.dolly * f as f32);
                let frame = r.renderer.render(&cam, &r.settings)?;
                r.frames.push(frame.timings);
                r.block_of.push(k);
                r.cpu.push(frame.cpu);
            }
        }
    }
    // Both sides' pass ids, A's order first.
    let mut order: Vec<String> = Vec::new();
    for r in &runs {
        for t in r.frames.iter().flatten() {
            if !order.contains(&t.id) {
                order.push(t.id.clone());
            }
        }
    }
    let mut stats: Vec<PassStats> = runs
        .iter()
        .map(|r| PassStats::new(&order, &r.frames))
        .collect();
    if args.isolation_frames > 0 {
        for (r, s) in runs.iter_mut().zip(&mut stats) {
            r.renderer.set_isolated_timing(true);
            let mut iso = Vec::new();
            for f in 0..args.isolation_frames as usize {
                let mut cam = r.camera.clone();
                cam.position += cam.forward * (r.dolly * (frames + f) as f32);
                if let Some(i) = r.renderer.render(&cam, &r.settings)?.isolated {
                    iso.push(i.passes);
                }
            }
            r.renderer.set_isolated_timing(false);
            s.apply_isolated(&iso);
        }
    }
    // One timing per pass on both sides: isolated on both where either
    // side's timestamps were not credible.
    for i in 0..order.len() {
        if stats
            .iter()
            .any(|s| s.rows[i].timing == TimingMethod::IsolatedWall)
        {
            stats.iter_mut().for_each(|s| s.use_isolated(i));
        }
    }
    // Per block: each pass's mean GPU ms per frame (0 where it did not
    // run), and the frame's.
    let per_block = |r: &Running, pass: Option<&str>| -> Vec<f64> {
        let mut sum = vec![0.0; blocks];
        let mut count = vec![0usize; blocks];
        for (f, k) in r.frames.iter().zip(&r.block_of) {
            count[*k] += 1;
            sum[*k] += f
                .iter()
                .filter(|t| pass.is_none_or(|p| t.id == p))
                .map(|t| t.gpu_ms)
                .sum::<f64>();
        }
        sum.iter()
            .zip(&count)
            .map(|(s, c)| s / (*c).max(1) as f64)
            .collect()
    };
    let spread = |a: &[f64], b: &[f64]| {
        let r = block_ratios(a, b);
        (!r.is_empty()).then(|| [quantile(&r, 0.5), quantile(&r, 0.25), quantile(&r, 0.75)])
    };
    // Each side's frame per block: timestamped passes by block, isolated
    // ones at their (whole-run) per-frame cost.
    let mut frame_blocks = [vec![0.0; blocks], vec![0.0; blocks]];
    let mut rows = Vec::new();
    for (i, id) in order.iter().enumerate() {
        let (ra, rb) = (&stats[0].rows[i], &stats[1].rows[i]);
        let isolated = ra.timing == TimingMethod::IsolatedWall;
        let timing = match (ra.runs > 0, rb.runs > 0) {
            (true, true) if ra.timing == rb.timing => ra.timing.name().to_string(),
            (true, true) => format!("{}/{}", ra.timing.name(), rb.timing.name()),
            (true, false) => ra.timing.name().to_string(),
            _ => rb.timing.name().to_string(),
        };
        let (pa, pb) = match isolated {
            true => (vec![ra.frame_ms; blocks], vec![rb.frame_ms; blocks]),
            false => (per_block(&runs[0], Some(id)), per_block(&runs[1], Some(id))),
        };
        for (acc, p) in frame_blocks.iter_mut().zip([&pa, &pb]) {
            acc.iter_mut().zip(p).for_each(|(a, v)| *a += v);
        }
        rows.push(Compared {
            id: id.clone(),
            timing,
            a: ra.frame_ms,
            b: rb.frame_ms,
            // Isolated rows have one figure per side, no blocks.
            blocks: (!isolated).then(|| spread(&pa, &pb)).flatten(),
        });
    }
    let frame = Compared {
        id: "frame GPU".into(),
        timing: "sum of frame ms".into(),
        a: stats[0].total,
        b: stats[1].total,
        blocks: spread(&frame_blocks[0], &frame_blocks[1]),
    };
    let frame_ts = Compared {
        id: "frame GPU (timestamps)".into(),
        timing: "each frame's summed ts".into(),
        a: stats[0].frame_sum_median,
        b: stats[1].frame_sum_median,
        blocks: spread(&per_block(&runs[0], None), &per_block(&runs[1], None)),
    };
    let cpu_block = |r: &Running| -> Vec<f64> {
        let mut sum = vec![0.0; blocks];
        let mut count = vec![0usize; blocks];
        for (c, k) in r.cpu.iter().zip(&r.block_of) {
            sum[*k] += c.thread_ms;
            count[*k] += 1;
        }
        sum.iter()
            .zip(&count)
            .map(|(s, c)| s / (*c).max(1) as f64)
            .collect()
    };
    let cpu_median = |r: &Running| {
        crate::bench::median(&mut r.cpu.iter().map(|c| c.thread_ms).collect::<Vec<_>>())
    };
    let cpu = Compared {
        id: "frame CPU (thread)".into(),
        timing: "render thread CPU clock".into(),
        a: cpu_median(&runs[0]),
        b: cpu_median(&runs[1]),
        blocks: spread(&cpu_block(&runs[0]), &cpu_block(&runs[1])),
    };
    if let Some(path) = &args.csv {
        let mut text = String::from("pass,timing,a_ms,b_ms,ratio,block_median,block_q1,block_q3\n");
        for r in rows.iter().chain([&frame, &frame_ts, &cpu]) {
            let [m, q1, q3] = r.blocks.unwrap_or([f64::NAN; 3]);
            let num = |v: f64| match v.is_finite() {
                true => format!("{v:.4}"),
                false => String::new(),
            };
            text.push_str(&format!(
                "{},{},{},{},{},{},{},{}\n",
                r.id,
                r.timing,
                num(r.a),
                num(r.b),
                num(r.ratio()),
                num(m),
                num(q1),
                num(q3)
            ));
        }
        std::fs::write(path, text)
            .with_context(|| format!("--csv {}: cannot write the file", path.display()))?;
    }
    let adapter = runs[0].renderer.context().info.to_string();
    crate::save_cache(runs[0].renderer.context());
    if args.json {
        let passes: Vec<String> = rows.iter().map(Compared::json).collect();
        println!(
            "{{\"adapter\":{adapter:?},\"a\":{a:?},\"b\":{b:?},\"frames\":{frames},\"block\":{block},\"blocks\":{blocks},\"passes\":[{}],\"frame\":{},\"frame_timestamps\":{},\"cpu\":{}}}",
            passes.join(","),
            frame.json(),
            frame_ts.json(),
            cpu.json()
        );
        return Ok(());
    }
    let s = &runs[0].settings;
    println!(
        "himal bench --compare: {adapter}, A = {a:?}, B = {b:?}, {}x{}, {frames} frames per side in {blocks} interleaved blocks of {block}",
        s.width, s.height
    );
    println!(
        "{:<24} {:<27} {:>9} {:>9} {:>7} block ratio B/A: median [q1, q3]",
        "pass", "timing (A/B)", "A ms", "B ms", "B/A"
    );
    for r in &rows {
        println!("{}", r.row());
    }
    println!("{}", frame.row());
    println!("{}", frame_ts.row());
    println!("{}", cpu.row());
    println!(
        "(ms per frame: per-run median x runs/frames; a pass absent on one side reads 0 there)"
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_interpolate() {
        let v = [4.0, 1.0, 3.0, 2.0, 5.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert_eq!(quantile(&v, 0.25), 2.0);
        assert_eq!(quantile(&[1.0, 2.0], 0.5), 1.5);
        assert_eq!(quantile(&[], 0.5), 0.0);
    }

    /// A side's options override the command line's (the later one wins).
    #[test]
    fn a_side_overrides_the_base_options() {
        let base: Vec<String> = ["--size", "32x18", "--ao", "hbao"]
            .map(String::from)
            .to_vec();
        let a = side_args(&base, "--ao off", "A").expect("parses");
        assert_eq!(a.size, "32x18");
        let b = side_args(&base, "", "B").expect("parses");
        assert_eq!(b.size, "32x18");
        let err = side_args(&base, "--path across", "B").unwrap_err();
        assert!(err.to_string().contains("--path"), "{err}");
        let err = side_args(&base, "--no-such-option", "A").unwrap_err();
        assert!(err.to_string().contains("--compare A"), "{err}");
    }
}
