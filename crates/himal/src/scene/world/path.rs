//! Named cameras spread over the world and the flight path across it,
//! placed from the terrain (so they follow the seed or the height map).

use glam::{Vec2, Vec3};

use super::World;
use crate::scene::{Camera, NamedCamera};

/// A camera path: a Catmull-Rom spline through `points`, flown at `speed`.
#[derive(Clone, Debug, PartialEq)]
pub struct FlightPath {
    /// Name `himal bench --path` selects it by.
    pub name: String,
    /// Control points in world metres, flown in order.
    pub points: Vec<Vec3>,
    /// Metres per second.
    pub speed: f32,
    /// Cumulative chord length at each point (for arc-length sampling).
    lengths: Vec<f32>,
}

impl FlightPath {
    /// A path through `points` flown at `speed` m/s; precomputes the chord lengths.
    pub fn new(name: impl Into<String>, points: Vec<Vec3>, speed: f32) -> FlightPath {
        let mut lengths = vec![0.0];
        for w in points.windows(2) {
            lengths.push(lengths.last().copied().unwrap_or(0.0) + w[0].distance(w[1]));
        }
        FlightPath {
            name: name.into(),
            points,
            speed,
            lengths,
        }
    }

    /// Length along the control polygon (the spline's within a few per cent).
    pub fn length(&self) -> f32 {
        self.lengths.last().copied().unwrap_or(0.0)
    }

    /// Seconds to fly the whole path.
    pub fn duration(&self) -> f32 {
        self.length() / self.speed.max(1e-3)
    }

    /// Position `s` metres along the path (clamped to its ends).
    pub fn position(&self, s: f32) -> Vec3 {
        let n = self.points.len();
        if n == 0 {
            return Vec3::ZERO;
        }
        if n == 1 {
            return self.points[0];
        }
        let s = s.clamp(0.0, self.length());
        let i = self.lengths.partition_point(|&l| l <= s).clamp(1, n - 1) - 1;
        let seg = (self.lengths[i + 1] - self.lengths[i]).max(1e-6);
        let t = (s - self.lengths[i]) / seg;
        let p = |k: isize| self.points[(i as isize + k).clamp(0, n as isize - 1) as usize];
        let (p0, p1, p2, p3) = (p(-1), p(0), p(1), p(2));
        let (t2, t3) = (t * t, t * t * t);
        0.5 * ((2.0 * p1)
            + (p2 - p0) * t
            + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
            + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3)
    }

    /// The camera at time `t` seconds: on the path, looking 120 m ahead and a little down.
    pub fn camera_at(&self, t: f32, fov_y_deg: f32) -> Camera {
        let s = t * self.speed;
        let p = self.position(s);
        let ahead = self.position(s + 120.0);
        let dir = if ahead.distance(p) > 1.0 {
            ahead - p
        } else {
            p - self.position(s - 120.0)
        };
        let target = p + dir.normalize_or(Vec3::NEG_Z) * 120.0 - Vec3::Y * 25.0;
        let mut c = Camera::look_at(p, target, fov_y_deg);
        c.near = 0.5;
        c
    }
}

/// Highest ground within `r` metres of `p` (a 9 x 9 probe).
fn highest(w: &World, p: Vec2, r: f32) -> f32 {
    let mut h = f32::MIN;
    for j in -4..=4 {
        for i in -4..=4 {
            let q = p + Vec2::new(i as f32, j as f32) * (r / 4.0);
            h = h.max(w.terrain.height(q.x, q.y));
        }
    }
    h
}

/// The flight "across": 9 km up the river valley from the south, 110 m
/// or more above the ground within 150 m.
pub fn flight(w: &World) -> FlightPath {
    let t = &w.terrain;
    let half = w.extent() * 0.5;
    let (z0, z1) = (half - 600.0, -half + 600.0);
    let steps = ((z0 - z1) / 500.0).ceil() as usize;
    let points = (0..=steps)
        .map(|i| {
            let z = z0 + (z1 - z0) * i as f32 / steps as f32;
            let x = t.river_x(z).clamp(-half + 300.0, half - 300.0);
            Vec3::new(x, highest(w, Vec2::new(x, z), 150.0) + 110.0, z)
        })
        .collect();
    FlightPath::new("across", points, 60.0)
}

fn camera(name: &str, position: Vec3, target: Vec3, fov: f32) -> NamedCamera {
    let mut camera = Camera::look_at(position, target, fov);
    camera.near = 0.5;
    NamedCamera {
        name: name.into(),
        camera,
        cinematic_shadows: None,
    }
}

/// `air` (high over the middle, north up the valley), `river` (low over
/// the water), `village` (the village nearest the middle), `peak` (the
/// flank of the highest ground near the middle, looking out), `grazing`
/// (1.8 m above a meadow toward the horizon), `top` (straight down from
/// 1.2 km), `street` (eye height in that village, along its street),
/// `forest` (over the densest forest within 2 km of the middle, looking
/// across it), `valley-forest` (the flight "across" at 7 km, over the
/// forests of the upper valley).
pub fn cameras(w: &World) -> Vec<NamedCamera> {
    let t = &w.terrain;
    let ground = |x: f32, z: f32| t.height(x, z);
    let rx = t.river_x(0.0);
    let mut out = vec![camera(
        "air",
        Vec3::new(
            rx + 900.0,
            highest(w, Vec2::new(rx + 900.0, 1800.0), 400.0) + 700.0,
            1800.0,
        ),
        Vec3::new(rx, ground(rx, -1500.0), -1500.0),
        60.0,
    )];
    let rz = 600.0;
    let rxz = t.river_x(rz);
    out.push(camera(
        "river",
        Vec3::new(rxz, t.river_level(rz) + 6.0, rz),
        Vec3::new(
            t.river_x(rz - 300.0),
            t.river_level(rz - 300.0) + 2.0,
            rz - 300.0,
        ),
        60.0,
    ));
    if let Some(v) = t
        .villages()
        .min_by(|a, b| a.center.length().total_cmp(&b.center.length()))
    {
        let from = v.center
            + Vec2::new(v.street.cos(), v.street.sin()) * 150.0
            + Vec2::new(-v.street.sin(), v.street.cos()) * 60.0;
        out.push(camera(
            "village",
            Vec3::new(from.x, ground(from.x, from.y).max(v.height) + 28.0, from.y),
            Vec3::new(v.center.x, v.height + 4.0, v.center.y),
            55.0,
        ));
    }
    // Highest of a coarse search within 2 km of the middle.
    let mut peak = (f32::MIN, Vec2::ZERO);
    for j in -10..=10 {
        for i in -10..=10 {
            let p = Vec2::new(i as f32, j as f32) * 200.0;
            let h = ground(p.x, p.y);
            if h > peak.0 {
                peak = (h, p);
            }
        }
    }
    let flank = peak.1 + (Vec2::ZERO - peak.1).normalize_or(Vec2::X) * 250.0;
    out.push(camera(
        "peak",
        Vec3::new(
            flank.x,
            ground(flank.x, flank.y).max(peak.0 - 150.0) + 40.0,
            flank.y,
        ),
        Vec3::new(flank.x * 0.2, peak.0 * 0.4, flank.y * 0.2 - 3000.0),
        65.0,
    ));
    let m = Vec2::new(rx + 180.0, 0.0);
    out.push(camera(
        "grazing",
        Vec3::new(m.x, ground(m.x, m.y) + 1.8, m.y),
        Vec3::new(m.x + 2000.0, ground(m.x, m.y) + 30.0, m.y - 2000.0),
        60.0,
    ));
    out.push(camera(
        "top",
        Vec3::new(rx, highest(w, Vec2::new(rx, 0.0), 600.0) + 1200.0, 0.0),
        Vec3::new(rx, 0.0, 0.0),
        60.0,
    ));
    if let Some(v) = t
        .villages()
        .min_by(|a, b| a.center.length().total_cmp(&b.center.length()))
    {
        let along = Vec2::new(v.street.cos(), v.street.sin());
        let (from, to) = (v.center - along * 45.0, v.center + along * 60.0);
        let eye = |p: Vec2, up: f32| Vec3::new(p.x, ground(p.x, p.y).max(v.height) + up, p.y);
        out.push(camera("street", eye(from, 1.7), eye(to, 3.0), 65.0));
    }
    // The strongest forest mask on a coarse grid, well below the tree line.
    let mut forest = (f32::MIN, Vec2::ZERO);
    for j in -10..=10 {
        for i in -10..=10 {
            let p = Vec2::new(i as f32, j as f32) * 200.0;
            let m = super::sector::forest_mask(t, p);
            if ground(p.x, p.y) < t.shape.tree_line - 150.0 && m > forest.0 {
                forest = (m, p);
            }
        }
    }
    let c = forest.1;
    let from = c + Vec2::new(-160.0, 120.0);
    out.push(camera(
        "forest",
        Vec3::new(from.x, ground(from.x, from.y) + 30.0, from.y),
        Vec3::new(c.x, ground(c.x, c.y) + 8.0, c.y),
        60.0,
    ));
    // Issue #18's forest of >= 50,000 trees: the flight 7 km up the valley,
    // where the most trees stand within the stream radius (docs/world.md).
    let path = flight(w);
    out.push(NamedCamera {
        name: "valley-forest".into(),
        camera: path.camera_at(7000.0 / path.speed, 60.0),
        cinematic_shadows: None,
    });
    out
}
