//! The viewer's HUD: the honest frame rate and the state and timing lines.

use himal::passes::ao::AoMode;
use himal::present::Hud;
use himal::{FrameSettings, ViewBuffer};

use super::Viewer;

/// Longest simulation step (camera, clock, flight path): a stall must not
/// throw the camera across the world. The HUD's rate is not clamped.
const MAX_STEP_S: f32 = 0.25;

pub(super) fn sim_step(interval_s: f32) -> f32 {
    interval_s.min(MAX_STEP_S)
}

/// The HUD's frame rate: an exponential average of the real frame
/// intervals (not of their reciprocals, which over-weights fast frames).
#[derive(Default)]
pub(super) struct FrameRate {
    interval_s: Option<f32>,
}

impl FrameRate {
    pub(super) fn record(&mut self, interval_s: f32) {
        self.interval_s = Some(match self.interval_s {
            None => interval_s,
            Some(avg) => 0.9 * avg + 0.1 * interval_s,
        });
    }

    pub(super) fn fps(&self) -> f32 {
        self.interval_s.map_or(0.0, |s| 1.0 / s.max(1e-6))
    }

    pub(super) fn frame_ms(&self) -> f32 {
        self.interval_s.map_or(0.0, |s| 1e3 * s)
    }
}

impl Viewer {
    /// The HUD's text: state, then the GPU time of every pass in frame order.
    pub(super) fn hud_text(
        &self,
        settings: &FrameSettings,
        timings: &[himal::graph::PassTiming],
        world: Option<&himal::WorldFrame>,
    ) -> Hud {
        let s = settings;
        let on = |b: bool| if b { "on" } else { "off" };
        let total: f64 = timings.iter().map(|t| t.gpu_ms).sum();
        let mut lines = vec![
            format!(
                "himal {:5.1} fps ({:.1} ms)  {}x{}  {:02}:{:02}  GPU {total:.2} ms",
                self.rate.fps(),
                self.rate.frame_ms(),
                s.width,
                s.height,
                s.sun.time_hours as u32,
                (s.sun.time_hours.fract() * 60.0) as u32
            ),
            format!(
                "[1] AO {}  [2] bloom {}  [3] shadows {}",
                on(s.ao.mode != AoMode::Off),
                on(s.bloom.enabled),
                on(s.shadow_resolution > 0)
            ),
            format!(
                "[4] AA {}  [5] env specular {}  [6] sky occlusion {}",
                s.aa.name(),
                on(s.environment_specular),
                on(s.sky_occlusion)
            ),
            format!(
                "[7] TAA on AO+motion {}  [8] sky {:?}  [V] {}",
                on(s.aa_buffers.any()),
                s.sky_model,
                view_name(s.view)
            ),
            format!(
                "[9] tone {}  [-/=] {:+.1} EV  [B] light {}",
                s.tonemapper.name(),
                s.exposure_ev,
                match &self.scene.environment {
                    None => "sky".to_string(),
                    Some(e) if e.path.as_os_str() == himal::scene::STUDIO => "studio".to_string(),
                    Some(e) => e.path.display().to_string(),
                }
            ),
        ];
        if !self.animations.is_empty() {
            lines.push(format!(
                "[N] anim {}  {:.2} s  [Space] {}  [ [ ] ] step",
                self.clip
                    .map_or("rest pose", |c| self.animations[c].as_str()),
                self.clock,
                if self.playing { "playing" } else { "paused" }
            ));
        }
        if let Some(w) = world {
            let s = &w.stream;
            lines.push(format!(
                "world {} sectors +{}  tiles {}/{}  inst {}k/{}k",
                s.resident,
                s.missing,
                s.tiles_used,
                s.tiles_total,
                s.instances / 1000,
                s.instances_total / 1000
            ));
            lines.push(format!(
                "stream {:.1} ms {:.0} KiB  terrain {}k tris  [F] fly {}",
                w.stream_ms,
                s.upload_bytes as f64 / 1024.0,
                w.terrain.as_ref().map_or(0, |t| t.triangles() / 1000),
                on(self.flying)
            ));
        }
        if timings.is_empty() {
            lines.push("no GPU timestamps on this adapter".into());
        }
        if let Some(notice) = &self.notice {
            // The HUD is one bitmap line: the start of the message.
            lines.push(notice.chars().take(NOTICE_CHARS).collect());
        }
        Hud {
            lines,
            timings: timing_groups(timings),
        }
    }
}

/// The GPU time of each pass group (the id before the first '.'), in frame
/// order: a full list of steps does not fit a small window. The HUD and the
/// panel show these.
pub(super) fn timing_groups(timings: &[himal::graph::PassTiming]) -> Vec<(String, f64)> {
    let mut groups: Vec<(String, f64)> = Vec::new();
    for t in timings {
        let group = t.id.split('.').next().unwrap_or(&t.id);
        match groups.iter_mut().find(|(g, _)| g == group) {
            Some((_, ms)) => *ms += t.gpu_ms,
            None => groups.push((group.to_string(), t.gpu_ms)),
        }
    }
    groups
}

/// The longest notice (an error) the HUD shows; the panel shows it whole.
const NOTICE_CHARS: usize = 72;

/// The `--view` name of `v`.
pub(super) fn view_name(v: ViewBuffer) -> &'static str {
    ViewBuffer::NAMES
        .iter()
        .find(|n| n.parse::<ViewBuffer>().ok() == Some(v))
        .copied()
        .unwrap_or("?")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The HUD capped the frame time at 0.25 s (never below 4 fps): a
    /// 2-second frame on a software adapter read 4 fps.
    #[test]
    fn the_hud_rate_is_the_real_one_and_only_the_step_is_clamped() {
        let mut rate = FrameRate::default();
        assert_eq!(rate.fps(), 0.0);
        rate.record(2.0);
        assert_eq!(rate.fps(), 0.5);
        assert_eq!(rate.frame_ms(), 2000.0);
        assert_eq!(sim_step(2.0), MAX_STEP_S);
        assert_eq!(sim_step(0.016), 0.016);
        // Averaged intervals: 10 ms frames then one 1 s stall.
        let mut rate = FrameRate::default();
        for _ in 0..50 {
            rate.record(0.010);
        }
        rate.record(1.0);
        assert!((rate.frame_ms() - 109.0).abs() < 0.5, "{}", rate.frame_ms());
    }
}
