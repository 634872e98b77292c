//! V2 grass ripple: the layout of the grid around the camera
//! (`shaders/ripple.wgsl`), its planning (the window follows the camera,
//! the halves alternate), and the CPU twins of `ripple.wgsl`'s step and of
//! the grass vertex stage's `ripple_bend`.

use bytemuck::{Pod, Zeroable};
use glam::Vec2;

use crate::scene::wind::WindGpu;

pub use crate::gpu_scene::ripple::{
    RIPPLE_CELL, RIPPLE_N, RIPPLE_SPEED, RippleHeader, header, ripple_bytes,
};

/// Longest step (s): c dt / dx stays below 1 / sqrt(2) (stable).
pub const RIPPLE_MAX_STEP: f32 = 1.0 / 30.0;
/// `RIPPLE_OMEGA`, `RIPPLE_DAMPING`, `RIPPLE_PUSH` of ripple.wgsl.
pub const RIPPLE_OMEGA: f32 = 5.0;
/// See [`RIPPLE_OMEGA`].
pub const RIPPLE_DAMPING: f32 = 1.5;
/// See [`RIPPLE_OMEGA`].
pub const RIPPLE_PUSH: f32 = 1.5;
/// `RIPPLE_BEND`, `RIPPLE_BEND_MAX` of shaders/ripple.wgsl.
pub const RIPPLE_BEND: f32 = 3.0;
/// See [`RIPPLE_BEND`].
pub const RIPPLE_BEND_MAX: f32 = 0.3;

/// Twin of `RippleStep` in ripple.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RippleStepGpu {
    /// Time at the end of the step (s); 1 = start from flat; 0, 0.
    pub time: [f32; 4],
    /// The sources (their centres at the step's end: `finish`).
    pub wind: WindGpu,
}

fn slot(c: (i32, i32), n: i32) -> usize {
    (c.0.rem_euclid(n) + c.1.rem_euclid(n) * n) as usize
}

/// The CPU twin of the grid: the header and every cell as the buffer
/// holds them.
#[derive(Clone, Debug, PartialEq)]
pub struct RippleCpu {
    /// As the GPU's header.
    pub header: RippleHeader,
    /// As the GPU's cells (4 parts of n x n).
    pub cells: Vec<[f32; 4]>,
}

impl RippleCpu {
    /// A flat grid of `n` cells per side (every slot tagged cell (0, 0)).
    pub fn new(n: i32) -> Self {
        RippleCpu {
            header: RippleHeader::default(),
            cells: vec![[0.0; 4]; 4 * (n * n) as usize],
        }
    }

    /// `ripple_entry`.
    pub fn entry(&self, c: (i32, i32), part: usize) -> Vec2 {
        let h = &self.header;
        let n = h.window[3];
        let l = (c.0 - h.window[0], c.1 - h.window[1]);
        if l.0 < 0 || l.1 < 0 || l.0 >= n || l.1 >= n {
            return Vec2::ZERO;
        }
        let e = self.cells[part * (n * n) as usize + slot(c, n)];
        if e[2] != c.0 as f32 || e[3] != c.1 as f32 {
            return Vec2::ZERO;
        }
        Vec2::new(e[0], e[1])
    }

    /// `cs_step` over the window with header `h` (the caller's frame),
    /// `reset`: from flat.
    pub fn step(&mut self, h: RippleHeader, step: &RippleStepGpu) {
        self.header = h;
        let n = h.window[3];
        let nn = (n * n) as usize;
        let (src, dst) = (h.window[2] as usize, 1 - h.window[2] as usize);
        let (dx, dt, speed) = (h.params[0], h.params[1], h.params[2]);
        let reset = step.time[1] != 0.0;
        let old = self.clone();
        let read = |c: (i32, i32)| {
            if reset { Vec2::ZERO } else { old.entry(c, src) }
        };
        let ns = (step.wind.global[3] as usize).min(crate::scene::wind::MAX_WIND_SOURCES);
        for j in 0..n {
            for i in 0..n {
                let c = (h.window[0] + i, h.window[1] + j);
                let own = read(c);
                let xp = read((c.0 + 1, c.1)).x;
                let xm = read((c.0 - 1, c.1)).x;
                let zp = read((c.0, c.1 + 1)).x;
                let zm = read((c.0, c.1 - 1)).x;
                let lap = (xp + xm + zp + zm - 4.0 * own.x) / (dx * dx);
                let centre = (Vec2::new(c.0 as f32, c.1 as f32) + 0.5) * dx;
                let force = |p: Vec2| {
                    let mut f = 0.0;
                    for s in &step.wind.sources[..ns] {
                        let d = p - Vec2::new(s.finish[0], s.finish[2]);
                        let q = (d.dot(d) / (s.start[3] * s.start[3])).min(1.0);
                        f -= RIPPLE_PUSH * s.finish[3] * (1.0 - q) * (1.0 - q);
                    }
                    f
                };
                let f = force(centre);
                let a = speed * speed * lap
                    - RIPPLE_OMEGA * RIPPLE_OMEGA * own.x
                    - RIPPLE_DAMPING * own.y
                    + f;
                let v = own.y + dt * a;
                let height = own.x + dt * v;
                let tag = [c.0 as f32, c.1 as f32];
                let s = slot(c, n);
                if reset {
                    let w2 = RIPPLE_OMEGA * RIPPLE_OMEGA;
                    let (ex, ez) = (Vec2::new(dx, 0.0), Vec2::new(0.0, dx));
                    let g = Vec2::new(
                        force(centre + ex) - force(centre - ex),
                        force(centre + ez) - force(centre - ez),
                    ) / (2.0 * dx * w2);
                    self.cells[dst * nn + s] = [f / w2, 0.0, tag[0], tag[1]];
                    self.cells[(2 + dst) * nn + s] = [g.x, g.y, tag[0], tag[1]];
                    continue;
                }
                self.cells[dst * nn + s] = [height, v, tag[0], tag[1]];
                self.cells[(2 + dst) * nn + s] = [
                    (xp - xm) / (2.0 * dx),
                    (zp - zm) / (2.0 * dx),
                    tag[0],
                    tag[1],
                ];
            }
        }
    }

    /// `ripple_bend` at world xz `p` (after a step: the half it wrote).
    pub fn bend(&self, p: Vec2) -> Vec2 {
        let h = &self.header;
        let q = p / h.params[0] - Vec2::splat(0.5);
        let c = q.floor();
        let f = q - c;
        let c = (c.x as i32, c.y as i32);
        let part = 3 - h.window[2] as usize;
        let e = |dx: i32, dz: i32| self.entry((c.0 + dx, c.1 + dz), part);
        let g = e(0, 0)
            .lerp(e(1, 0), f.x)
            .lerp(e(0, 1).lerp(e(1, 1), f.x), f.y);
        let b = g * RIPPLE_BEND;
        let l = b.length();
        if l > RIPPLE_BEND_MAX {
            b * (RIPPLE_BEND_MAX / l)
        } else {
            b
        }
    }
}
