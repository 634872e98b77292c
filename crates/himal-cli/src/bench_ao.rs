//! `himal bench --compare-ao`: the AO cost ratios of TECHNIQUES O2/O3 in one
//! run. Four renderers (HBAO + blur; + selective temporal filter; + STF with
//! a brute-force blur; O4 SSDO) draw the same camera (fixed unless
//! `--dolly`) with their frames interleaved, so all see the same machine
//! state.

use std::collections::BTreeMap;

use anyhow::Result;
use himal::passes::ao::{AoMode, AoSettings};
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer};

use crate::GpuArgs;

const VARIANTS: [(&str, AoMode, bool); 4] = [
    ("hbao", AoMode::Hbao, true),
    ("hbao+stf", AoMode::HbaoStf, true),
    ("hbao+stf, brute-force blur", AoMode::HbaoStf, false),
    ("ssdo (O4)", AoMode::Ssdo, true),
];

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { 0.0 } else { v[v.len() / 2] }
}

pub fn run(
    gpu: &GpuArgs,
    scene: &Scene,
    camera: &Camera,
    base: &FrameSettings,
    frames: u32,
    dolly: f32,
) -> Result<()> {
    let mut runs = Vec::new();
    for (name, mode, adaptive) in VARIANTS {
        let mut settings = base.clone();
        settings.ao = AoSettings {
            mode,
            adaptive_blur: adaptive,
            ..base.ao.clone()
        };
        let mut renderer = Renderer::new(gpu.context()?, scene)?;
        renderer.render(camera, &settings)?; // warm-up
        runs.push((
            name,
            settings,
            renderer,
            BTreeMap::<String, Vec<f64>>::new(),
        ));
    }
    for i in 0..frames {
        let mut cam = camera.clone();
        cam.position += cam.forward * (dolly * i as f32);
        // Rotate which variant goes first so none always follows the same one.
        let n = runs.len();
        for k in 0..n {
            let (_, settings, renderer, times) = &mut runs[(k + i as usize) % n];
            for t in renderer.render(&cam, settings)?.timings {
                times.entry(t.id).or_default().push(t.gpu_ms);
            }
        }
    }
    println!(
        "AO cost, {}x{}, {frames} frames interleaved, median GPU ms per pass ({})",
        base.width,
        base.height,
        runs[0].2.context().info
    );
    let mut totals = Vec::new();
    let mut frames_ms = Vec::new();
    for (name, _, _, times) in runs.iter_mut() {
        let mut rows: Vec<(String, f64)> = times
            .iter_mut()
            .filter(|(id, _)| id.starts_with("ao."))
            .map(|(id, v)| (id.clone(), median(v)))
            .collect();
        rows.sort_by(|a, b| a.0.cmp(&b.0));
        let total: f64 = rows.iter().map(|r| r.1).sum();
        let frame: f64 = times.values_mut().map(|v| median(v)).sum();
        println!("  {name}: AO {total:.3} ms of {frame:.3} ms");
        frames_ms.push(frame);
        for (id, ms) in &rows {
            println!("    {id:<18} {ms:8.3}");
        }
        totals.push((total, rows));
    }
    let get = |k: usize, id: &str| totals[k].1.iter().find(|r| r.0 == id).map_or(0.0, |r| r.1);
    let stf = totals[1].0 / totals[0].0 - 1.0;
    println!(
        "  STF adds {:+.1}% to the AO total (talk: +16%, 2.5 -> 2.9 ms)",
        100.0 * stf
    );
    // The filter's own steps, free of the noise in the passes it leaves alone.
    let own = get(1, "ao.blur_y_stf") - get(0, "ao.blur_y") + get(1, "ao.stability");
    println!(
        "  STF's own steps (blur_y_stf - blur_y + stability): {own:.3} ms, {:+.1}% of the HBAO total",
        100.0 * own / totals[0].0
    );
    let blur_x = 1.0 - get(1, "ao.blur_x") / get(2, "ao.blur_x");
    println!(
        "  adaptive vs brute-force blur (radius {}): BlurX {:.1}% faster (talk: 29%), AO total {:.1}% faster (talk: blur total 13%)",
        base.ao.blur_radius,
        100.0 * blur_x,
        100.0 * (1.0 - totals[1].0 / totals[2].0)
    );
    println!(
        "  SSDO (O4) vs hbao+stf: AO {:+.1}%, frame {:+.3} ms",
        100.0 * (totals[3].0 / totals[1].0 - 1.0),
        frames_ms[3] - frames_ms[1]
    );
    Ok(())
}
