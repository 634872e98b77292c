//! The viewer's keys and camera movement (orbit, fly, look).

use glam::{Quat, Vec3};
use himal::ViewBuffer;
use himal::passes::aa::AaMode;
use himal::passes::ao::AoMode;
use winit::keyboard::KeyCode;

use super::Viewer;
use crate::orbit::Orbit;

/// Movement keys held down.
#[derive(Default)]
pub(super) struct Held {
    pub(super) forward: f32,
    pub(super) right: f32,
    pub(super) up: f32,
    pub(super) fast: bool,
    pub(super) looking: bool,
    pub(super) orbiting: bool,
    pub(super) panning: bool,
}

impl Viewer {
    pub(super) fn toggle(&mut self, key: KeyCode) {
        let s = &mut self.settings;
        match key {
            KeyCode::Equal => s.exposure_ev = (s.exposure_ev + 0.5).min(10.0),
            KeyCode::Minus => s.exposure_ev = (s.exposure_ev - 0.5).max(-10.0),
            // Studio light or the physical sky: the environment is part of
            // the renderer's resources, rebuilt before the next frame.
            KeyCode::KeyB if self.renderer.world().is_none() => {
                self.scene.environment = match self.scene.environment {
                    Some(_) => None,
                    None => Some(himal::scene::EnvironmentDesc::new(himal::scene::STUDIO)),
                };
                self.rebuild_pending = true;
            }
            KeyCode::KeyT => s.sun.time_hours = (s.sun.time_hours + 0.5).rem_euclid(24.0),
            KeyCode::KeyG => s.sun.time_hours = (s.sun.time_hours - 0.5).rem_euclid(24.0),
            KeyCode::KeyV => {
                let names = ViewBuffer::NAMES;
                let now = names
                    .iter()
                    .position(|n| n.parse::<ViewBuffer>().ok() == Some(s.view))
                    .unwrap_or(0);
                if let Ok(v) = names[(now + 1) % names.len()].parse() {
                    s.view = v;
                }
            }
            KeyCode::Digit1 => {
                s.ao.mode = match s.ao.mode {
                    AoMode::Off => AoMode::HbaoStf,
                    _ => AoMode::Off,
                }
            }
            KeyCode::Digit2 => s.bloom.enabled = !s.bloom.enabled,
            KeyCode::Digit3 => {
                s.shadow_resolution = if s.shadow_resolution > 0 {
                    0
                } else {
                    himal::renderer::DEFAULT_SHADOW_RESOLUTION
                }
            }
            KeyCode::Digit4 => {
                let modes = ["none", "smaa", "smaa-t2x", "tfq", "taa", "hraa"];
                let now = modes
                    .iter()
                    .position(|m| AaMode::parse(m).ok() == Some(s.aa))
                    .unwrap_or(0);
                if let Ok(m) = AaMode::parse(modes[(now + 1) % modes.len()]) {
                    s.aa = m;
                }
            }
            KeyCode::Digit5 => s.environment_specular = !s.environment_specular,
            KeyCode::Digit6 => s.sky_occlusion = !s.sky_occlusion,
            KeyCode::Digit7 => {
                let on = !s.aa_buffers.any();
                s.aa_buffers = himal::passes::aa::AaBuffers { ao: on, motion: on };
            }
            KeyCode::Digit8 => {
                use himal::passes::sky::SkyModel;
                s.sky_model = match s.sky_model {
                    SkyModel::Bruneton => SkyModel::Preetham,
                    SkyModel::Preetham => SkyModel::Bruneton,
                };
            }
            KeyCode::Digit9 => {
                let next = s.tonemapper.next();
                self.set_tonemapper(next);
            }
            KeyCode::Tab => self.panel_shown = !self.panel_shown,
            KeyCode::Space => self.playing = !self.playing,
            KeyCode::BracketLeft | KeyCode::BracketRight => {
                let step = if key == KeyCode::BracketLeft {
                    -STEP_S
                } else {
                    STEP_S
                };
                self.clock = (self.clock + step).max(0.0);
                self.playing = false;
            }
            KeyCode::KeyN if !self.animations.is_empty() => {
                // The clips in order, then the rest pose, then round again.
                self.set_clip(match self.clip {
                    Some(c) if c + 1 < self.animations.len() => Some(c + 1),
                    Some(_) => None,
                    None => Some(0),
                })
            }
            KeyCode::KeyP | KeyCode::F12 => self.screenshot = true,
            KeyCode::KeyH => self.hud = !self.hud,
            // A world flies its path; anything else is framed.
            KeyCode::KeyF if self.path.is_some() => self.flying = !self.flying,
            KeyCode::KeyF => {
                self.orbit = Some(Orbit::framing(&self.scene.bounds, self.camera.fov_y_deg))
            }
            KeyCode::KeyO => {
                self.orbit = match self.orbit {
                    Some(_) => None,
                    None => Some(Orbit::around(&self.camera, &self.scene.bounds)),
                }
            }
            _ => {}
        }
    }

    /// Tone mapper `t` (key 9, the panel's combo).
    pub(super) fn set_tonemapper(&mut self, t: himal::passes::post::Tonemapper) {
        let s = &mut self.settings;
        s.tonemapper = t;
        // The white point is Reinhard's: kept for it, dropped for the others.
        s.white_point = (t == himal::passes::post::Tonemapper::Reinhard)
            .then_some(self.args.post.white_point)
            .flatten();
    }

    /// Plays clip `clip` of `self.animations` (`None`: the rest pose).
    pub(super) fn set_clip(&mut self, clip: Option<usize>) {
        self.clip = clip.filter(|&c| c < self.animations.len());
        let name = self.clip.map(|c| self.animations[c].clone());
        // Known names: the scene's own list.
        self.scene.set_animation(name.as_deref()).ok();
        self.renderer.set_animation(name.as_deref());
    }

    pub(super) fn step_camera(&mut self, dt: f32) {
        if let Some(o) = &self.orbit {
            self.camera = o.camera(self.camera.fov_y_deg);
            return;
        }
        // A 10 km world is crossed at flying speed, a valley at walking speed.
        let base = if self.path.is_some() { 40.0 } else { 4.0 };
        let speed = if self.held.fast { 5.0 * base } else { base } * dt;
        let c = &mut self.camera;
        let right = c.forward.cross(Vec3::Y).normalize_or(Vec3::X);
        c.position += (c.forward * self.held.forward + right * self.held.right) * speed
            + Vec3::Y * self.held.up * speed;
    }

    pub(super) fn look(&mut self, dx: f32, dy: f32) {
        let c = &mut self.camera;
        let right = c.forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let yaw = Quat::from_axis_angle(Vec3::Y, -dx * 0.003);
        let pitched = Quat::from_axis_angle(right, -dy * 0.003) * c.forward;
        // Stop short of the poles, where yaw would flip.
        let forward = if pitched.y.abs() < 0.98 {
            pitched
        } else {
            c.forward
        };
        c.forward = (yaw * forward).normalize();
        c.up = Vec3::Y;
    }
}

/// One scrub step of [ and ]: a frame at 30 fps.
pub(super) const STEP_S: f32 = 1.0 / 30.0;

/// The keys a script may press ($HIMAL_VIEW_KEYS), by winit's names.
const SCRIPT_KEYS: [(&str, KeyCode); 23] = [
    ("Space", KeyCode::Space),
    ("BracketLeft", KeyCode::BracketLeft),
    ("BracketRight", KeyCode::BracketRight),
    ("KeyN", KeyCode::KeyN),
    ("KeyF", KeyCode::KeyF),
    ("KeyO", KeyCode::KeyO),
    ("KeyB", KeyCode::KeyB),
    ("KeyV", KeyCode::KeyV),
    ("KeyT", KeyCode::KeyT),
    ("KeyG", KeyCode::KeyG),
    ("KeyH", KeyCode::KeyH),
    ("Minus", KeyCode::Minus),
    ("Equal", KeyCode::Equal),
    ("Digit1", KeyCode::Digit1),
    ("Digit2", KeyCode::Digit2),
    ("Digit3", KeyCode::Digit3),
    ("Digit4", KeyCode::Digit4),
    ("Digit5", KeyCode::Digit5),
    ("Digit6", KeyCode::Digit6),
    ("Digit7", KeyCode::Digit7),
    ("Digit8", KeyCode::Digit8),
    ("Digit9", KeyCode::Digit9),
    ("Tab", KeyCode::Tab),
];

/// One scripted input ($HIMAL_VIEW_KEYS).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Scripted {
    /// A key press, through the keys' path (`Viewer::toggle`).
    Key(KeyCode),
    /// The pointer moved to (x, y) (window pixels) and the left button went
    /// down; it goes up before the next frame's `Release`.
    Press(f64, f64),
    /// The left button went up.
    Release,
    /// The pointer moved to (x, y).
    Move(f64, f64),
}

/// `FRAME:KEY`, `FRAME:click:X:Y` or `FRAME:move:X:Y`, comma-separated
/// (e.g. `0:Tab,2:click:400:30`): inputs before those frames. A click
/// presses the left button at window pixel (X, Y) before FRAME and releases
/// it before FRAME + 1, as winit would report a real one.
pub(super) fn parse_script(text: &str) -> anyhow::Result<Vec<(u32, Scripted)>> {
    let names = || SCRIPT_KEYS.map(|(n, _)| n).join(", ");
    let mut script = Vec::new();
    for entry in text.split(',').map(str::trim).filter(|e| !e.is_empty()) {
        let bad = |why: String| anyhow::anyhow!("HIMAL_VIEW_KEYS: \"{entry}\": {why}");
        let (frame, what) = entry
            .split_once(':')
            .ok_or_else(|| bad("not FRAME:KEY or FRAME:click:X:Y".into()))?;
        let frame = frame
            .parse::<u32>()
            .map_err(|_| bad(format!("{frame} is not a frame number")))?;
        let pointer = (what.strip_prefix("click:").map(|at| (at, true)))
            .or_else(|| what.strip_prefix("move:").map(|at| (at, false)));
        if let Some((at, click)) = pointer {
            let xy = at.split_once(':').and_then(|(x, y)| {
                let (x, y) = (x.parse::<f64>().ok()?, y.parse::<f64>().ok()?);
                (x.is_finite() && y.is_finite()).then_some((x, y))
            });
            let (x, y) = xy.ok_or_else(|| bad(format!("\"{at}\" is not X:Y (pixels)")))?;
            if click {
                script.push((frame, Scripted::Press(x, y)));
                script.push((frame + 1, Scripted::Release));
            } else {
                script.push((frame, Scripted::Move(x, y)));
            }
            continue;
        }
        let key = (SCRIPT_KEYS.iter().find(|(n, _)| *n == what))
            .map(|(_, k)| *k)
            .ok_or_else(|| {
                anyhow::anyhow!("HIMAL_VIEW_KEYS: no key \"{what}\" (keys: {})", names())
            })?;
        script.push((frame, Scripted::Key(key)));
    }
    Ok(script)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_scripts_name_frames_keys_and_clicks() {
        let keys = parse_script("0:Space, 2:BracketRight,2:KeyN,3:Tab").unwrap();
        assert_eq!(
            keys,
            [
                (0, Scripted::Key(KeyCode::Space)),
                (2, Scripted::Key(KeyCode::BracketRight)),
                (2, Scripted::Key(KeyCode::KeyN)),
                (3, Scripted::Key(KeyCode::Tab)),
            ]
        );
        let clicks = parse_script("1:click:400:30.5,3:move:2:3").unwrap();
        assert_eq!(
            clicks,
            [
                (1, Scripted::Press(400.0, 30.5)),
                (2, Scripted::Release),
                (3, Scripted::Move(2.0, 3.0))
            ]
        );
        let e = parse_script("1:KeyZ").unwrap_err().to_string();
        assert!(e.contains("no key \"KeyZ\"") && e.contains("Space"), "{e}");
        let e = parse_script("1:click:4").unwrap_err().to_string();
        assert!(e.contains("\"1:click:4\"") && e.contains("X:Y"), "{e}");
        assert!(parse_script("x:Space").is_err() && parse_script("Space").is_err());
        assert!(parse_script("1:click:nan:2").is_err());
    }
}
