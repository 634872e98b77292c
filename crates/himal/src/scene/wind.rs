//! V2 wind (issue #18): one field that pushes trees, bushes, grass and
//! particles: the scene's global wind (`[wind]`, `--wind SPEED,DIR`) with
//! travelling gusts, plus local sources (`[[wind_source]]`, a hovering or
//! passing helicopter's downwash). CPU twin of `shaders/wind.wgsl`; the
//! equations are in `docs/techniques/V2.md`.
//!
//! ```toml
//! [[wind_source]]
//! position = [0.0, 8.0, 0.0]       # centre (m); or a path the source flies back and forth:
//! # path = [[-40.0, 10.0, 0.0], [40.0, 10.0, 0.0]]   # 2 to 16 points
//! # speed = 8.0                    # m/s along the path (path only), default 5
//! radius = 20.0                    # m, where the push falls to zero, (0, 1000]
//! strength = 12.0                  # m/s outward at the centre, [0, 100]
//! ```

use glam::{Vec2, Vec3};
use toml::Spanned;

use super::SceneError;
use super::build::Checker;
use super::file::FileWindSource;

/// Most local sources a scene may hold (the uniform's fixed array).
pub const MAX_WIND_SOURCES: usize = 8;
/// Most points of a source's path.
pub const MAX_PATH_POINTS: usize = 16;
/// Default speed of a source along its path (m/s).
pub const DEFAULT_SOURCE_SPEED: f32 = 5.0;

/// A local wind source: an outward push, strongest at its centre, gone at
/// `radius`, standing still or flying back and forth along a path.
#[derive(Clone, Debug, PartialEq)]
pub struct WindSource {
    /// One point (standing still) or a polyline flown back and forth.
    pub path: Vec<Vec3>,
    /// Speed along the path (m/s).
    pub speed: f32,
    /// Radius of influence (m).
    pub radius: f32,
    /// Outward wind at the centre (m/s).
    pub strength: f32,
}

impl WindSource {
    /// The centre at time `t` (s): along the path at `speed t`, ping-pong.
    pub fn centre_at(&self, t: f32) -> Vec3 {
        let Some(&first) = self.path.first() else {
            return Vec3::ZERO;
        };
        let total: f32 = self.path.windows(2).map(|w| w[0].distance(w[1])).sum();
        if total <= 0.0 || self.speed <= 0.0 {
            return first;
        }
        // f64: long runs keep their place.
        let s = (self.speed as f64 * t as f64).rem_euclid(2.0 * total as f64) as f32;
        let mut s = if s > total { 2.0 * total - s } else { s };
        for w in self.path.windows(2) {
            let l = w[0].distance(w[1]);
            if s <= l && l > 0.0 {
                return w[0].lerp(w[1], s / l);
            }
            s -= l;
        }
        *self.path.last().unwrap_or(&first)
    }
}

/// The wind field: global velocity (m/s; its horizontal part drives
/// vegetation) and the local sources.
#[derive(Clone, Debug, PartialEq)]
pub struct WindField {
    /// The scene's `[wind]` (or `--wind`).
    pub global: Vec3,
    /// `[[wind_source]]`s, at most [`MAX_WIND_SOURCES`].
    pub sources: Vec<WindSource>,
}

/// Gust factor of the global wind at horizontal `p` (m) and time `t` (s):
/// two waves travelling downwind and one across, 1 +- 0.45 at most.
/// `along`: unit downwind direction; `speed`: |global| (m/s).
pub fn gust(p: Vec2, along: Vec2, speed: f32, t: f32) -> f32 {
    let x = p.dot(along);
    let y = p.perp_dot(along);
    // Gusts travel with the wind at 0.8 of its speed, 40 and 13 m long.
    let c = 0.8 * speed;
    1.0 + 0.25 * (0.157 * (x - c * t)).sin()
        + 0.12 * (0.483 * (x - c * t) + 1.3).sin()
        + 0.08 * (0.11 * y + 0.9 * t).sin()
}

/// Horizontal push (m/s, x and z) of one source centred at `c` on a
/// point `p`: outward from the centre, `strength (1 - (d / radius)^2)^2`.
pub fn source_push(p: Vec3, c: Vec3, radius: f32, strength: f32) -> Vec2 {
    let d = p - c;
    let q = (d.length_squared() / (radius * radius)).min(1.0);
    let f = (1.0 - q) * (1.0 - q);
    let h = Vec2::new(d.x, d.z);
    // Within half a metre of the axis the push fades instead of flipping.
    let dir = h / h.length().max(0.5);
    dir * (strength * f)
}

impl WindField {
    /// A field with `global` and no sources.
    pub fn new(global: Vec3) -> Self {
        WindField {
            global,
            sources: Vec::new(),
        }
    }

    /// The horizontal wind (m/s, x and z) at `p` and time `t`, the sources
    /// at `centres` (their [`WindSource::centre_at`] for that time).
    pub fn at(&self, p: Vec3, t: f32, centres: &[Vec3]) -> Vec2 {
        let g = Vec2::new(self.global.x, self.global.z);
        let speed = g.length();
        let mut w = if speed > 0.0 {
            g * gust(Vec2::new(p.x, p.z), g / speed, speed, t)
        } else {
            Vec2::ZERO
        };
        for (s, c) in self.sources.iter().zip(centres) {
            w += source_push(p, *c, s.radius, s.strength);
        }
        w
    }

    /// The sources' centres at `t`.
    pub fn centres(&self, t: f32) -> Vec<Vec3> {
        self.sources.iter().map(|s| s.centre_at(t)).collect()
    }

    /// The uniform of `shaders/wind.wgsl` with the sources at `t0` (start of
    /// the frame's steps) and `t1` (its end); the shader interpolates.
    pub fn gpu(&self, t0: f32, t1: f32) -> WindGpu {
        let mut g = WindGpu {
            global: self.global.extend(self.sources.len() as f32).to_array(),
            ..bytemuck::Zeroable::zeroed()
        };
        for (i, s) in self.sources.iter().take(MAX_WIND_SOURCES).enumerate() {
            g.sources[i] = WindSourceGpu {
                start: s.centre_at(t0).extend(s.radius).to_array(),
                finish: s.centre_at(t1).extend(s.strength).to_array(),
            };
        }
        g
    }
}

/// Twin of `WindSourceGpu` in `shaders/wind.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WindSourceGpu {
    /// Centre at the first step's time; w: radius (m).
    pub start: [f32; 4],
    /// Centre at the last step's time; w: strength (m/s).
    pub finish: [f32; 4],
}

/// Twin of `Wind` in `shaders/wind.wgsl` (272 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct WindGpu {
    /// xyz: global velocity (m/s); w: source count.
    pub global: [f32; 4],
    /// The sources (the first `global.w`).
    pub sources: [WindSourceGpu; MAX_WIND_SOURCES],
}

impl WindGpu {
    /// The field as the shader sees it at fraction `s` of the frame's steps:
    /// CPU twin of `wind_at` (the sources' centres interpolated).
    pub fn at(&self, p: Vec3, t: f32, s: f32) -> Vec2 {
        let g = Vec2::new(self.global[0], self.global[2]);
        let speed = g.length();
        let w = if speed > 0.0 {
            g * gust(Vec2::new(p.x, p.z), g / speed, speed, t)
        } else {
            Vec2::ZERO
        };
        w + self.sources_push(p, s)
    }

    /// The local sources alone at `p` (`wind_sources_push`; particles add
    /// it to the global wind, which they follow without gusts).
    pub fn sources_push(&self, p: Vec3, s: f32) -> Vec2 {
        let n = (self.global[3] as usize).min(MAX_WIND_SOURCES);
        let mut w = Vec2::ZERO;
        for src in &self.sources[..n] {
            let c = Vec3::from_slice(&src.start[..3]).lerp(Vec3::from_slice(&src.finish[..3]), s);
            w += source_push(p, c, src.start[3], src.finish[3]);
        }
        w
    }
}

/// The `[[wind_source]]` tables, checked.
pub(crate) fn build_sources(
    ck: &Checker,
    file: &[FileWindSource],
) -> Result<Vec<WindSource>, SceneError> {
    if let Some(extra) = file.get(MAX_WIND_SOURCES) {
        return Err(ck.err(
            &extra.radius.span(),
            format!("at most {MAX_WIND_SOURCES} [[wind_source]] tables"),
        ));
    }
    file.iter().map(|f| build_source(ck, f)).collect()
}

fn build_source(ck: &Checker, f: &FileWindSource) -> Result<WindSource, SceneError> {
    let radius = ck.range(&f.radius, "wind_source radius", 1.0e-3, 1000.0)?;
    let strength = ck.range(
        &f.strength,
        "wind_source strength",
        0.0,
        super::emitters::MAX_WIND,
    )?;
    let path = match (&f.position, &f.path) {
        (Some(p), None) => {
            if let Some(s) = &f.speed {
                return Err(ck.err(&s.span(), "wind_source speed goes with a path"));
            }
            vec![ck.finite3(p, "wind_source position")?]
        }
        (None, Some(path)) => {
            let n = path.get_ref().len();
            if !(2..=MAX_PATH_POINTS).contains(&n) {
                return Err(ck.err(
                    &path.span(),
                    format!("wind_source path has {n} points; give 2 to {MAX_PATH_POINTS}"),
                ));
            }
            let mut pts = Vec::with_capacity(n);
            for p in path.get_ref() {
                pts.push(ck.finite3(&Spanned::new(path.span(), *p), "wind_source path point")?);
            }
            pts
        }
        (Some(p), Some(_)) => {
            return Err(ck.err(&p.span(), "wind_source: give position or path, not both"));
        }
        (None, None) => {
            return Err(ck.err(
                &f.radius.span(),
                "wind_source: position ([x, y, z] m) or path ([[x, y, z], ...]) is missing",
            ));
        }
    };
    let speed = match &f.speed {
        Some(s) => ck.range(s, "wind_source speed", 0.0, 1000.0)?,
        None => DEFAULT_SOURCE_SPEED,
    };
    Ok(WindSource {
        path,
        speed,
        radius,
        strength,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn source() -> WindSource {
        WindSource {
            path: vec![Vec3::new(-10.0, 5.0, 0.0), Vec3::new(10.0, 5.0, 0.0)],
            speed: 4.0,
            radius: 8.0,
            strength: 10.0,
        }
    }

    #[test]
    fn sources_fly_back_and_forth() {
        let s = source();
        assert_eq!(s.centre_at(0.0), Vec3::new(-10.0, 5.0, 0.0));
        assert!(s.centre_at(2.5).distance(Vec3::new(0.0, 5.0, 0.0)) < 1e-5);
        assert!(s.centre_at(5.0).distance(Vec3::new(10.0, 5.0, 0.0)) < 1e-5);
        assert!(s.centre_at(7.5).distance(Vec3::new(0.0, 5.0, 0.0)) < 1e-5);
        assert!(s.centre_at(10.0).distance(Vec3::new(-10.0, 5.0, 0.0)) < 1e-4);
    }

    #[test]
    fn pushes_outward_and_fades_at_the_radius() {
        let c = Vec3::new(0.0, 5.0, 0.0);
        let w = source_push(Vec3::new(3.0, 5.0, 0.0), c, 8.0, 10.0);
        assert!(w.x > 0.0 && w.y.abs() < 1e-6);
        assert_eq!(
            source_push(Vec3::new(9.0, 5.0, 0.0), c, 8.0, 10.0),
            Vec2::ZERO
        );
        // The uniform's twin agrees with the field at the same centres.
        let mut f = WindField::new(Vec3::new(3.0, 0.0, 1.0));
        f.sources.push(source());
        let g = f.gpu(1.0, 1.0);
        let p = Vec3::new(-6.0, 1.0, 2.0);
        assert!((g.at(p, 1.0, 0.5) - f.at(p, 1.0, &f.centres(1.0))).length() < 1e-5);
        assert_eq!(std::mem::size_of::<WindGpu>(), 272);
    }
}
