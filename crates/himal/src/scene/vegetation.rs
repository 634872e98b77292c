//! Vegetation meshes: grass fields of crossed cards and bushes of leaf
//! cards, drawn alpha-tested and swaying (`docs/techniques/vegetation.md`).
//!
//! Card conventions (read by `shaders/scene.wgsl`):
//! - `uv.x`: the integer part is a per-card pattern seed (0..15), the
//!   fraction runs across the card; `uv.y` runs 0 at the root (bottom) to 1
//!   at the tip (top).
//! - Grass normals lean toward up: `normalize(card_normal + 1.5 * up)`
//!   (56 degrees above the horizon), so a field shades like the ground it
//!   covers rather than like vertical walls; back faces mirror the
//!   horizontal part only (gbuffer.wgsl).
//! - Bush normals are the ellipsoid's outward normal at the card's centre,
//!   tilted a little up, on both faces: the bush shades as one round mass.

use glam::{Vec2, Vec3};

use super::noise::{hash_lattice, hash_to_unit};
use super::primitives::MeshBuilder;
use super::{MaterialDesc, Mesh};

/// How strongly grass normals lean toward up (added to the card normal).
const GRASS_UP_TILT: f32 = 1.5;
/// Pattern seeds per card: `uv.x` integer part in 0..PATTERN_SEEDS.
const PATTERN_SEEDS: u32 = 16;
/// Border raggedness of grass fields (fraction of the half size).
const EDGE_RAGGEDNESS: f32 = 0.3;
/// Most clumps one grass object may hold.
pub const MAX_CLUMPS: u32 = 200_000;

/// Deterministic stream of uniform numbers in [0, 1) (hash of seed and counter).
pub(crate) struct Rng {
    seed: u32,
    n: i32,
}

impl Rng {
    pub(crate) fn new(seed: u32, stream: i32) -> Self {
        Rng {
            seed: hash_lattice(seed, stream, 0x5eed),
            n: 0,
        }
    }

    pub(crate) fn next(&mut self) -> f32 {
        self.n += 1;
        hash_to_unit(hash_lattice(self.seed, self.n, 0))
    }

    pub(crate) fn pattern_seed(&mut self) -> f32 {
        (self.next() * PATTERN_SEEDS as f32).floor()
    }
}

/// Parameters of a procedural grass field: clumps of crossed alpha-tested cards on a jittered grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrassParams {
    /// Field extent [x, z] in metres, centred on the origin.
    pub size: [f32; 2],
    /// Clumps per square metre.
    pub density: f32,
    /// Mean card height (metres); each clump varies it by 0.75..1.25.
    pub height: f32,
    /// Mean card width (metres); 0.8..1.2 per card.
    pub width: f32,
    /// Crossed cards per clump (2 or 3).
    pub cards: u32,
    /// Seed of the placement and size variation (same seed, same field).
    pub seed: u32,
}

impl GrassParams {
    /// Clump grid: cells of 1 / sqrt(density) metres, one clump each.
    fn grid(&self) -> (u32, u32, f32) {
        let cell = 1.0 / self.density.sqrt();
        let n = |s: f32| (s / cell).round().max(1.0) as u32;
        (n(self.size[0]), n(self.size[1]), cell)
    }

    /// Grid cells over `size`: the most clumps the field holds (its ragged border drops some).
    pub fn clump_count(&self) -> u64 {
        let (nx, nz, _) = self.grid();
        nx as u64 * nz as u64
    }
}

/// A grass field: one clump per cell of a jittered grid (stratified, so
/// no bald patches) inside a ragged rounded rectangle (`EDGE_RAGGEDNESS`),
/// each `cards` vertical quads crossed at random yaw.
/// `root_y(x, z)` gives the local height of a clump's root (0 on a plane,
/// the height field under it when snapped); `Err((x, z))` names a root it
/// could not place.
pub fn grass(
    name: String,
    p: &GrassParams,
    m: &MaterialDesc,
    mut root_y: impl FnMut(f32, f32) -> Option<f32>,
) -> Result<Mesh, Vec2> {
    let mut b = MeshBuilder::new(m);
    let (nx, nz, _) = p.grid();
    let cell = Vec2::new(p.size[0] / nx as f32, p.size[1] / nz as f32);
    let origin = Vec2::new(-p.size[0], -p.size[1]) * 0.5;
    for j in 0..nz {
        for i in 0..nx {
            let mut rng = Rng::new(p.seed, (j * nx + i) as i32);
            let xz =
                origin + (Vec2::new(i as f32, j as f32) + Vec2::new(rng.next(), rng.next())) * cell;
            // Ragged, rounded border: keep clumps inside a superellipse whose
            // radius varies by 30 % per clump, so patches are not rectangles.
            let q = (xz / (0.5 * Vec2::from(p.size))).abs().powf(4.0);
            if (q.x + q.y).powf(0.25) > 1.0 - EDGE_RAGGEDNESS * rng.next() {
                continue;
            }
            let y = root_y(xz.x, xz.y).ok_or(xz)?;
            let root = Vec3::new(xz.x, y, xz.y);
            let height = p.height * (0.75 + 0.5 * rng.next());
            let yaw0 = rng.next() * std::f32::consts::PI;
            for k in 0..p.cards {
                let yaw = yaw0 + k as f32 * std::f32::consts::PI / p.cards as f32;
                let across = Vec3::new(yaw.cos(), 0.0, -yaw.sin());
                let width = p.width * (0.8 + 0.4 * rng.next());
                let seed = rng.pattern_seed();
                card(&mut b, root, across, width, height, seed);
            }
        }
    }
    Ok(b.finish(name))
}

/// One vertical grass card standing on `root`, front face toward
/// `across x up`, u = seed + 0..1 along `across`, v = 0..1 up.
fn card(b: &mut MeshBuilder, root: Vec3, across: Vec3, width: f32, height: f32, seed: f32) {
    let facing = across.cross(Vec3::Y);
    let normal = (facing + GRASS_UP_TILT * Vec3::Y).normalize();
    let half = across * (0.5 * width);
    let up = Vec3::Y * height;
    let corners = [
        (root - half, [seed, 0.0]),
        (root + half, [seed + 1.0, 0.0]),
        (root + half + up, [seed + 1.0, 1.0]),
        (root - half + up, [seed, 1.0]),
    ];
    let i = corners.map(|(p, uv)| b.vertex(p, normal, across, uv));
    b.triangle(i[0], i[1], i[2]);
    b.triangle(i[0], i[2], i[3]);
}

/// Parameters of a procedural bush: leaf cards scattered in an ellipsoid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BushParams {
    /// Ellipsoid semi-axes (metres).
    pub radii: [f32; 3],
    /// Number of leaf cards.
    pub cards: u32,
    /// Leaf card edge (metres).
    pub card_size: f32,
    /// Seed of the card positions and orientations.
    pub seed: u32,
}

/// A bush: `cards` square leaf cards with centres uniform inside the
/// ellipsoid and uniformly random orientations.
pub fn bush(name: String, p: &BushParams, m: &MaterialDesc) -> Mesh {
    let mut b = MeshBuilder::new(m);
    let radii = Vec3::from(p.radii);
    let mut rng = Rng::new(p.seed, -1);
    for _ in 0..p.cards {
        // Rejection sampling in the unit ball (accepts ~52%).
        let q = loop {
            let q = Vec3::new(rng.next(), rng.next(), rng.next()) * 2.0 - 1.0;
            if q.length_squared() <= 1.0 {
                break q;
            }
        };
        let centre = q * radii;
        // Uniform direction: z uniform in [-1, 1], azimuth uniform.
        let z = rng.next() * 2.0 - 1.0;
        let az = rng.next() * std::f32::consts::TAU;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let facing = Vec3::new(r * az.cos(), z, r * az.sin());
        let (t0, b0) = facing.any_orthonormal_pair();
        let spin = rng.next() * std::f32::consts::TAU;
        let t = t0 * spin.cos() + b0 * spin.sin();
        let bt = facing.cross(t);
        // Outward normal of the ellipsoid (gradient of |p / radii|^2), a little up.
        let outward = (centre / (radii * radii)).normalize_or(Vec3::Y);
        let normal = (outward + 0.3 * Vec3::Y).normalize();
        let tangent = (t - normal * normal.dot(t)).normalize_or(normal.any_orthonormal_vector());
        let seed = rng.pattern_seed();
        let h = 0.5 * p.card_size;
        let corners = [
            (centre - t * h - bt * h, [seed, 0.0]),
            (centre + t * h - bt * h, [seed + 1.0, 0.0]),
            (centre + t * h + bt * h, [seed + 1.0, 1.0]),
            (centre - t * h + bt * h, [seed, 1.0]),
        ];
        let i = corners.map(|(p, uv)| b.vertex(p, normal, tangent, uv));
        b.triangle(i[0], i[1], i[2]);
        b.triangle(i[0], i[2], i[3]);
    }
    b.finish(name)
}

// CPU twins of the vegetation functions in `shaders/scene.wgsl` (tests).

/// `foliage_hash`: PCG output permutation.
pub fn foliage_hash(n: u32) -> u32 {
    let state = n.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

fn foliage_unit(h: u32, shift: u32) -> f32 {
    ((h >> shift) & 255) as f32 / 255.0
}

fn split_seed(uv: [f32; 2]) -> (u32, f32) {
    let seed = uv[0].floor().max(0.0);
    (seed as u32, uv[0] - uv[0].floor())
}

/// `foliage_grass_alpha`: 1 inside one of the card's four tapered blades.
pub fn grass_alpha(uv: [f32; 2]) -> f32 {
    let (seed, u) = split_seed(uv);
    let v = uv[1];
    for i in 0..4u32 {
        let h = foliage_hash(seed.wrapping_mul(16).wrapping_add(i));
        let top = 0.55 + 0.45 * foliage_unit(h, 0);
        let centre = (i as f32 + 0.25 + 0.5 * foliage_unit(h, 8)) / 4.0;
        let lean = (foliage_unit(h, 16) - 0.5) * 0.25;
        let f = v / top;
        let half_width = 0.09 * (1.0 - f);
        if f < 1.0 && (u - centre - lean * f * f).abs() < half_width {
            return 1.0;
        }
    }
    0.0
}

/// `foliage_leaves_alpha`: 1 inside one of the card's five elliptic leaves.
pub fn leaves_alpha(uv: [f32; 2]) -> f32 {
    let (seed, u) = split_seed(uv);
    for i in 0..5u32 {
        let h = foliage_hash(seed.wrapping_mul(16).wrapping_add(i).wrapping_add(7));
        let c = Vec2::new(
            0.22 + 0.56 * foliage_unit(h, 0),
            0.22 + 0.56 * foliage_unit(h, 8),
        );
        let a = std::f32::consts::PI * foliage_unit(h, 16);
        let d = Vec2::new(u, uv[1]) - c;
        let q = Vec2::new(
            d.x * a.cos() + d.y * a.sin(),
            -d.x * a.sin() + d.y * a.cos(),
        );
        let size = Vec2::new(0.27, 0.13) * (0.8 + 0.4 * foliage_unit(h, 24));
        let e = q / size;
        if e.dot(e) < 1.0 {
            return 1.0;
        }
    }
    0.0
}

/// `foliage_alpha` for a pattern.
pub fn alpha(pattern: super::AlphaPattern, uv: [f32; 2]) -> f32 {
    match pattern {
        super::AlphaPattern::Grass => grass_alpha(uv),
        super::AlphaPattern::Leaves => leaves_alpha(uv),
    }
}

/// Angular frequencies (rad/s) of the two components of `foliage_sway`: 0.4 Hz and 1.1 Hz.
pub const SWAY_OMEGA: [f32; 2] = [std::f32::consts::TAU * 0.4, std::f32::consts::TAU * 1.1];
/// Amplitude weights of the two sway components (they sum to 1).
pub const SWAY_WEIGHTS: [f32; 2] = [0.7, 0.3];

/// `foliage_sway`: horizontal displacement of a vertex resting at world
/// `rest` (xz) with sway amplitude times weight `a`, at time `t`.
pub fn sway_offset(a: f32, rest: Vec2, t: f32) -> Vec3 {
    let [w1, w2] = SWAY_OMEGA;
    let phase = rest.dot(Vec2::new(0.9, 0.6));
    let x = 0.7 * (w1 * t + phase).sin() + 0.3 * (w2 * t + 1.7 * phase + 1.0).sin();
    let z = 0.7 * (w1 * t + phase + 1.9).sin() + 0.3 * (w2 * t + 2.3 * phase).sin();
    Vec3::new(x, 0.0, z) * a
}

/// Largest speed of one sway component per metre of `a` (m/s): the
/// derivative bound `0.7 w1 + 0.3 w2`.
pub fn sway_max_speed() -> f32 {
    SWAY_WEIGHTS[0] * SWAY_OMEGA[0] + SWAY_WEIGHTS[1] * SWAY_OMEGA[1]
}
