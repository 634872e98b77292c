//! V3 depth impostors (issue #18, part 2; Far Cry 4's vegetation talk,
//! `seeds/000_...`): per tree nine orthographic captures of LOD0 (eight
//! around at 45° steps, one top-down) of its albedo parameters, normal and
//! depth, rasterised on the CPU into one atlas; far away a tree is a 16 x 16
//! grid facing the camera, its vertices pushed toward the camera by the
//! captured depth (blended between the two nearest captures around, and the
//! top one by elevation). Method, layout and figures: `docs/techniques/V3.md`.
//!
//! Units: positions relative to the capture centre (the crown's bounding
//! box centre), in units of the bounding sphere radius `R`, so every
//! capture frame is the square [-1, 1]² and depth is in [-1, 1] (larger:
//! nearer the camera). The depth reconstruction has a WGSL twin,
//! `shaders/impostor.wgsl` (`tests/impostor_wgsl.rs`).
//!
//! The atlas holds no material colours, so one bake serves every scene's
//! materials: texel `color` = (cluster tint t, leaf fraction, 1, coverage),
//! the albedo is `mix(bark, mix(leaf, tint, t), leaf fraction)` and the
//! G-buffer material the leaf's or the bark's by the same fraction
//! ([`albedo`]).

use std::f32::consts::TAU;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::visibility::raster;
use super::{Species, TreeModel, cards_mesh, limb_mesh};
use crate::scene::primitives::MeshBuilder;
use crate::scene::{MaterialDesc, Mesh};

/// Captures per tree: [`AROUND`] around, then one from above.
pub const CAPTURES: usize = 9;
/// Captures around the tree, 360° / `AROUND` apart, at zero elevation.
pub const AROUND: usize = 8;
/// Texels per capture side.
pub const CAPTURE_SIZE: usize = 128;
/// Captures per atlas row (3 x 3 tiles, capture k at column k % 3, row k / 3).
pub const ATLAS_COLUMNS: usize = 3;
/// Atlas side in texels.
pub const ATLAS_SIZE: usize = ATLAS_COLUMNS * CAPTURE_SIZE;
/// Cells per side of the impostor's camera-facing grid.
pub const GRID: usize = 16;
/// Subsamples per texel side when capturing (coverage and colours average them).
const SUPERSAMPLE: usize = 2;
/// The top capture fades in between these elevations (radians: 20°, 70°;
/// 0°..60° measured better for the rosewood at 30° and worse for the larch).
pub const TOP_FADE: [f32; 2] = [0.349_065_85, 1.221_730_5];

/// Direction from the tree toward the camera of capture `k`.
pub fn capture_dir(k: usize) -> Vec3 {
    if k >= AROUND {
        return Vec3::Y;
    }
    let a = k as f32 * (TAU / AROUND as f32);
    Vec3::new(a.sin(), 0.0, a.cos())
}

/// (right, up, toward the camera) of an orthographic view looking along
/// `-dir` (unit): right = Y x dir (X when looking straight down), up = dir x right.
pub fn view_basis(dir: Vec3) -> [Vec3; 3] {
    let right = if dir.y.abs() > 0.999 {
        Vec3::X
    } else {
        Vec3::Y.cross(dir).normalize()
    };
    [right, dir.cross(right), dir]
}

/// Which captures a view along `-dir` blends, and their weights (sum 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    /// The two nearest captures around (by azimuth), then the top one.
    pub captures: [usize; 3],
    /// Weights of `captures`.
    pub weights: [f32; 3],
}

/// The blend of view direction `dir` (unit, toward the camera): linear in
/// azimuth between the two nearest captures around, the top capture by a
/// smoothstep of the elevation between [`TOP_FADE`]'s angles.
pub fn blend(dir: Vec3) -> Blend {
    let step = TAU / AROUND as f32;
    let s = dir.x.atan2(dir.z).rem_euclid(TAU) / step;
    let k0 = s.floor();
    let f = s - k0;
    let k0 = (k0 as usize) % AROUND;
    let e = dir.y.clamp(-1.0, 1.0).asin();
    let t = ((e - TOP_FADE[0]) / (TOP_FADE[1] - TOP_FADE[0])).clamp(0.0, 1.0);
    let top = t * t * (3.0 - 2.0 * t);
    Blend {
        captures: [k0, (k0 + 1) % AROUND, AROUND],
        weights: [(1.0 - f) * (1.0 - top), f * (1.0 - top), top],
    }
}

/// Continuous atlas texel coordinates (texel centres at +0.5) of the point
/// `p` (centre-relative, units of R) in capture `k`, clamped to the
/// capture's outer texel centres so no tap leaves its tile.
pub fn atlas_coord(k: usize, p: Vec3) -> Vec2 {
    let [r, u, _] = view_basis(capture_dir(k));
    let n = CAPTURE_SIZE as f32;
    let local = Vec2::new((p.dot(r) * 0.5 + 0.5) * n, (0.5 - p.dot(u) * 0.5) * n)
        .clamp(Vec2::splat(0.5), Vec2::splat(n - 0.5));
    let tile = Vec2::new((k % ATLAS_COLUMNS) as f32, (k / ATLAS_COLUMNS) as f32) * n;
    tile + local
}

/// The four texels of a bilinear tap at atlas coordinate `c` (row-major
/// indices: (x0, y0), (x1, y0), (x0, y1), (x1, y1)) and the fraction.
pub fn bilinear_taps(c: Vec2) -> ([usize; 4], Vec2) {
    let b = (c - 0.5).floor();
    let f = c - 0.5 - b;
    let (x, y) = (b.x as usize, b.y as usize);
    // atlas_coord keeps c >= 0.5 inside its tile, so x + 1 only leaves the
    // tile when f is 0 (the clamp's edge): clamp to the tile's last texel.
    let last = |v: usize| (v / CAPTURE_SIZE) * CAPTURE_SIZE + CAPTURE_SIZE - 1;
    let (x1, y1) = ((x + 1).min(last(x)), (y + 1).min(last(y)));
    (
        [
            y * ATLAS_SIZE + x,
            y * ATLAS_SIZE + x1,
            y1 * ATLAS_SIZE + x,
            y1 * ATLAS_SIZE + x1,
        ],
        f,
    )
}

/// Bilinear mix of four taps (order of [`bilinear_taps`]).
pub fn bilinear(t: [f32; 4], f: Vec2) -> f32 {
    let top = t[0] + (t[1] - t[0]) * f.x;
    let bottom = t[2] + (t[3] - t[2]) * f.x;
    top + (bottom - top) * f.y
}

/// The grid point (i, j) of the camera-facing quad, `i` right, `j` down,
/// in [-1, 1]²: x = 2 i / GRID - 1, y = 1 - 2 j / GRID.
pub fn grid_point(i: usize, j: usize) -> Vec2 {
    let g = GRID as f32;
    Vec2::new(2.0 * i as f32 / g - 1.0, 1.0 - 2.0 * j as f32 / g)
}

/// Fixed-point steps of the depth reconstruction per capture.
pub const DEPTH_STEPS: usize = 3;
/// Fixed-point steps per pixel and capture (the fragment's refinement).
pub const PIXEL_STEPS: usize = 2;
/// Floor of `w · dir_k` in [`depth_step`] (captures that far off carry
/// little or no weight).
pub const MIN_COS: f32 = 0.2;

/// One step of the ray-depth intersection with capture `k` (direction
/// `dir_k`): the distance `t` along the camera direction `w` from the quad's
/// point `q` at which the ray reaches the depth `d` capture `k` stores
/// where it sees the previous step's point `q + t w`:
/// `t = (d - q·dir_k) / max(w·dir_k, MIN_COS)`.
pub fn depth_step(dir_k: Vec3, q: Vec3, w: Vec3, d: f32) -> f32 {
    (d - q.dot(dir_k)) / w.dot(dir_k).max(MIN_COS)
}

/// The depth reconstruction: grid point `xy` of the quad with view basis
/// `basis` ([`view_basis`]) moved toward the camera `w = basis[2]` by the
/// blended `Σ w_k t_k`, `t_k` found by [`DEPTH_STEPS`] [`depth_step`]s from
/// 0 (where the camera ray through `q = x right + y up` meets capture k's
/// depth; exactly its depth at `q` when looking along the capture).
/// Centre-relative, units of R.
pub fn displace(imp: &Impostor, basis: [Vec3; 3], xy: Vec2) -> Vec3 {
    let (q, w) = (basis[0] * xy.x + basis[1] * xy.y, basis[2]);
    let b = blend(w);
    let mut d = 0.0;
    for (k, wk) in b.captures.into_iter().zip(b.weights) {
        if wk > 0.0 {
            let mut t = 0.0;
            for _ in 0..DEPTH_STEPS {
                let (taps, f) = bilinear_taps(atlas_coord(k, q + w * t));
                t = depth_step(
                    capture_dir(k),
                    q,
                    w,
                    bilinear(taps.map(|i| imp.depth_at(i)), f),
                );
            }
            d += wk * t;
        }
    }
    q + w * d
}

/// A tree's baked captures.
#[derive(Clone, Debug, PartialEq)]
pub struct Impostor {
    /// Capture centre (tree space, m): the middle of LOD0's bounding box.
    pub centre: Vec3,
    /// Bounding sphere radius about `centre` (m): every capture's half side.
    pub radius: f32,
    /// Per atlas texel: cluster tint t, leaf fraction, 1, coverage (unorm).
    pub color: Vec<[u8; 4]>,
    /// Per atlas texel: the tree-space normal * 0.5 + 0.5, 255 (unorm).
    pub normal: Vec<[u8; 4]>,
    /// Per atlas texel: the nearest surface's depth toward the camera,
    /// `d * 0.5 + 0.5` in unorm16, d in [-1, 1]; empty texels hold their
    /// covered neighbours' mean (dilated), so grid vertices at the
    /// silhouette stay on the crown.
    pub depth: Vec<u16>,
}

impl Impostor {
    /// Depth of atlas texel `i` in [-1, 1] (units of R, toward the camera).
    pub fn depth_at(&self, i: usize) -> f32 {
        f32::from(self.depth[i]) / 65535.0 * 2.0 - 1.0
    }
}

/// The LOD0 meshes the captures see: trunk (bark) and every cluster's
/// cards (vertex colour r = the cluster's tint t).
pub fn capture_meshes(model: &TreeModel) -> (Mesh, Mesh) {
    let material = MaterialDesc::default();
    let mut b = MeshBuilder::new(&material);
    let rig = super::rig::rig(model);
    for (limb, &hang) in model.limbs.iter().zip(&rig.limbs) {
        limb_mesh(&mut b, limb, 0, &rig, hang);
    }
    let trunk = b.finish("impostor-trunk".into());
    let mut b = MeshBuilder::new(&material);
    let all: Vec<usize> = (0..model.clusters.len()).collect();
    cards_mesh(&mut b, model, &all, 1.0, (Vec3::ZERO, Vec3::ONE), 1.0, &rig);
    (trunk, b.finish("impostor-leaves".into()))
}

/// One sample of an orthographic view: what the nearest surface is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Depth toward the camera (units of R); `f32::NEG_INFINITY`: empty.
    pub depth: f32,
    /// Cluster tint t (leaves).
    pub tint: f32,
    /// 1 leaf, 0 bark.
    pub leaf: f32,
    /// Tree-space unit normal.
    pub normal: Vec3,
}

const EMPTY: Sample = Sample {
    depth: f32::NEG_INFINITY,
    tint: 0.0,
    leaf: 0.0,
    normal: Vec3::ZERO,
};

/// Rasterises the LOD0 `meshes` orthographically along `-dir` into a
/// `size`² view of the square [-1, 1]² about `centre` (`radius` R): depth
/// test, leaf cards alpha-tested with the shader's pattern
/// (`vegetation::leaves_alpha`), one sample at each pixel centre (as the
/// G-buffer rasterises).
pub fn view(
    meshes: &(Mesh, Mesh),
    centre: Vec3,
    radius: f32,
    dir: Vec3,
    size: usize,
) -> Vec<Sample> {
    let basis = view_basis(dir);
    let mut out = vec![EMPTY; size * size];
    let n = size as f32;
    for (mesh, leaf) in [(&meshes.0, false), (&meshes.1, true)] {
        let screen: Vec<Vec3> = mesh
            .vertices
            .iter()
            .map(|v| {
                let p = (Vec3::from(v.position) - centre) / radius;
                Vec3::new(
                    (p.dot(basis[0]) * 0.5 + 0.5) * n,
                    (0.5 - p.dot(basis[1]) * 0.5) * n,
                    p.dot(basis[2]),
                )
            })
            .collect();
        for tri in mesh.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|i| tri[i] as usize);
            raster(size, [screen[a], screen[b], screen[c]], |px, w| {
                let at = |f: &dyn Fn(usize) -> f32| w[0] * f(a) + w[1] * f(b) + w[2] * f(c);
                let vx = &mesh.vertices;
                let z = at(&|i| screen[i].z);
                if z <= out[px].depth {
                    return;
                }
                if leaf {
                    let pattern = vx[a].uv[0].floor();
                    let u = (at(&|i| vx[i].uv[0]) - pattern).clamp(0.0, 0.9999);
                    let v = at(&|i| vx[i].uv[1]);
                    if crate::scene::vegetation::leaves_alpha([pattern + u, v]) < 0.5 {
                        return;
                    }
                }
                let normal = Vec3::new(
                    at(&|i| vx[i].normal[0]),
                    at(&|i| vx[i].normal[1]),
                    at(&|i| vx[i].normal[2]),
                )
                .normalize_or_zero();
                out[px] = Sample {
                    depth: z,
                    tint: if leaf { vx[a].color[0] } else { 0.0 },
                    leaf: if leaf { 1.0 } else { 0.0 },
                    normal,
                };
            });
        }
    }
    out
}

/// The capture frame of `model`: its LOD0 meshes, the bounding box centre
/// and the bounding sphere radius about it.
fn frame(model: &TreeModel) -> ((Mesh, Mesh), Vec3, f32) {
    let meshes = capture_meshes(model);
    let bounds = meshes.0.bounds.union(&meshes.1.bounds);
    let centre = bounds.center();
    let radius = meshes
        .0
        .vertices
        .iter()
        .chain(&meshes.1.vertices)
        .map(|v| Vec3::from(v.position).distance(centre))
        .fold(0.0f32, f32::max)
        .max(1e-3);
    (meshes, centre, radius)
}

/// Bakes `model`'s impostor: the nine captures ([`CAPTURE_SIZE`]² each,
/// [`SUPERSAMPLE`]² samples per texel averaged: coverage = the covered
/// fraction, the rest the covered samples' mean), captures spread over
/// threads (each independent: deterministic).
pub fn bake(model: &TreeModel) -> Impostor {
    let (meshes, centre, radius) = frame(model);
    let captures: Vec<Vec<Sample>> = std::thread::scope(|s| {
        let jobs: Vec<_> = (0..CAPTURES)
            .map(|k| {
                let meshes = &meshes;
                s.spawn(move || {
                    let dir = capture_dir(k);
                    view(meshes, centre, radius, dir, CAPTURE_SIZE * SUPERSAMPLE)
                })
            })
            .collect();
        jobs.into_iter()
            .map(|j| j.join().unwrap_or_default())
            .collect()
    });
    let texels = ATLAS_SIZE * ATLAS_SIZE;
    let mut imp = Impostor {
        centre,
        radius,
        color: vec![[0, 0, 255, 0]; texels],
        normal: vec![[128, 128, 128, 255]; texels],
        depth: vec![0; texels],
    };
    let unorm = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let m = CAPTURE_SIZE * SUPERSAMPLE;
    for (k, samples) in captures.iter().enumerate() {
        if samples.len() != m * m {
            continue;
        }
        let mut depth = vec![None; CAPTURE_SIZE * CAPTURE_SIZE];
        for ty in 0..CAPTURE_SIZE {
            for tx in 0..CAPTURE_SIZE {
                let (mut n, mut tint, mut leaf, mut d, mut normal) = (0, 0.0, 0.0, 0.0, Vec3::ZERO);
                for sy in 0..SUPERSAMPLE {
                    for sx in 0..SUPERSAMPLE {
                        let s = samples[(ty * SUPERSAMPLE + sy) * m + tx * SUPERSAMPLE + sx];
                        if s.depth > f32::NEG_INFINITY {
                            n += 1;
                            tint += s.tint;
                            leaf += s.leaf;
                            d += s.depth;
                            normal += s.normal;
                        }
                    }
                }
                let i = atlas_index(k, tx, ty);
                if n == 0 {
                    continue;
                }
                let c = n as f32;
                let cover = c / (SUPERSAMPLE * SUPERSAMPLE) as f32;
                imp.color[i] = [unorm(tint / c), unorm(leaf / c), 255, unorm(cover)];
                let nn = normal.normalize_or(Vec3::Y) * 0.5 + 0.5;
                imp.normal[i] = [unorm(nn.x), unorm(nn.y), unorm(nn.z), 255];
                depth[ty * CAPTURE_SIZE + tx] = Some(d / c);
            }
        }
        dilate(&mut depth);
        for ty in 0..CAPTURE_SIZE {
            for tx in 0..CAPTURE_SIZE {
                let d = depth[ty * CAPTURE_SIZE + tx].unwrap_or(0.0);
                imp.depth[atlas_index(k, tx, ty)] =
                    ((d * 0.5 + 0.5).clamp(0.0, 1.0) * 65535.0).round() as u16;
            }
        }
    }
    imp
}

/// Atlas index of texel (tx, ty) of capture `k`.
pub fn atlas_index(k: usize, tx: usize, ty: usize) -> usize {
    let (x0, y0) = (
        (k % ATLAS_COLUMNS) * CAPTURE_SIZE,
        (k / ATLAS_COLUMNS) * CAPTURE_SIZE,
    );
    (y0 + ty) * ATLAS_SIZE + x0 + tx
}

/// Fills empty texels ring by ring with the mean of their filled
/// 8-neighbours (a capture with nothing in it stays at the centre plane).
fn dilate(depth: &mut [Option<f32>]) {
    let n = CAPTURE_SIZE as isize;
    loop {
        let mut next = depth.to_vec();
        let mut changed = false;
        for y in 0..n {
            for x in 0..n {
                if depth[(y * n + x) as usize].is_some() {
                    continue;
                }
                let (mut s, mut c) = (0.0, 0);
                for (dx, dy) in [
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (xx, yy) = (x + dx, y + dy);
                    if (0..n).contains(&xx)
                        && (0..n).contains(&yy)
                        && let Some(d) = depth[(yy * n + xx) as usize]
                    {
                        s += d;
                        c += 1;
                    }
                }
                if c > 0 {
                    next[(y * n + x) as usize] = Some(s / c as f32);
                    changed = true;
                }
            }
        }
        depth.copy_from_slice(&next);
        if !changed {
            return;
        }
    }
}

/// The albedo of an atlas texel's parameters: bark where `leaf` is 0, the
/// leaf colour mixed toward the tint colour by `tint` where it is 1 (the
/// mesh's vertex colours, `cards_mesh`).
pub fn albedo(bark: Vec3, leaf_colour: Vec3, tint_colour: Vec3, tint: f32, leaf: f32) -> Vec3 {
    bark.lerp(leaf_colour.lerp(tint_colour, tint), leaf)
}

/// Materials and light of the CPU pictures ([`render_mesh`], [`render_impostor`]).
#[derive(Clone, Copy, Debug)]
pub struct Look {
    /// Bark, leaf and tint colours (linear).
    pub colours: [Vec3; 3],
    /// Unit direction toward the sun.
    pub sun: Vec3,
    /// Background (linear).
    pub sky: Vec3,
}

impl Default for Look {
    fn default() -> Self {
        let leaf = Vec3::new(0.05, 0.13, 0.02);
        Look {
            colours: [
                Vec3::new(0.09, 0.055, 0.033),
                leaf,
                leaf * Vec3::new(1.3, 1.15, 0.55),
            ],
            sun: Vec3::new(0.5, 0.7, 0.5).normalize(),
            sky: Vec3::new(0.35, 0.45, 0.6),
        }
    }
}

impl Look {
    /// Linear radiance of a surface (Lambert sun + constant sky).
    fn shade(&self, tint: f32, leaf: f32, normal: Vec3) -> Vec3 {
        let a = albedo(
            self.colours[0],
            self.colours[1],
            self.colours[2],
            tint,
            leaf,
        );
        a * (0.35 + 2.2 * normal.dot(self.sun).max(0.0))
    }
}

/// The `size`² sRGB picture of a linear one rendered at `ss` samples per
/// side: the box mean of each pixel's samples (what a resolved
/// anti-aliased frame converges to), encoded.
fn resolve(linear: &[Vec3], size: usize, ss: usize) -> Vec<[f32; 3]> {
    let m = size * ss;
    (0..size * size)
        .map(|i| {
            let (x, y) = (i % size, i / size);
            let mut c = Vec3::ZERO;
            for sy in 0..ss {
                for sx in 0..ss {
                    c += linear[(y * ss + sy) * m + x * ss + sx];
                }
            }
            encode_srgb(c / (ss * ss) as f32)
        })
        .collect()
}

/// sRGB encoding of a linear colour, clamped to [0, 1].
fn encode_srgb(c: Vec3) -> [f32; 3] {
    c.to_array().map(|v| {
        let v = v.clamp(0.0, 1.0);
        if v <= 0.003_130_8 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        }
    })
}

/// The full tree (LOD0) seen orthographically along `-dir`, `size`² pixels
/// over the impostor's square of `ss`² samples each, shaded by `look`
/// (sRGB, row-major).
pub fn render_mesh(
    model: &TreeModel,
    dir: Vec3,
    size: usize,
    ss: usize,
    look: &Look,
) -> Vec<[f32; 3]> {
    let (meshes, centre, radius) = frame(model);
    let linear: Vec<Vec3> = view(&meshes, centre, radius, dir, size * ss)
        .iter()
        .map(|s| {
            if s.depth > f32::NEG_INFINITY {
                look.shade(s.tint, s.leaf, s.normal)
            } else {
                look.sky
            }
        })
        .collect();
    resolve(&linear, size, ss)
}

/// An impostor pixel before its alpha test: the blended coverage and the
/// coverage-weighted sums of tint, leaf fraction and normal (divide by
/// `cover`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pixel {
    /// Blended coverage, `Σ w_k a_k` (alpha-tested at 0.5).
    pub cover: f32,
    /// `Σ w_k a_k t_k`.
    pub tint: f32,
    /// `Σ w_k a_k leaf_k`.
    pub leaf: f32,
    /// `Σ w_k a_k n_k` (tree space, not normalised).
    pub normal: Vec3,
}

/// The pixel at the grid's interpolated point `p` (centre-relative, units
/// of R) seen along `w` (toward the camera): per blended capture
/// [`PIXEL_STEPS`] ray-depth steps from the pixel's own `t = p·w`, so each
/// capture's texels are read where its own surface is, then its texels
/// bilinear and coverage-premultiplied. `impostor_pixel` in
/// `shaders/impostor_draw.wgsl` (`tests/impostor_wgsl.rs`).
pub fn pixel(imp: &Impostor, w: Vec3, p: Vec3) -> Pixel {
    let b = blend(w);
    let z = p.dot(w);
    let (mut cover, mut tint, mut leaf, mut normal) = (0.0, 0.0, 0.0, Vec3::ZERO);
    for (k, wk) in b.captures.into_iter().zip(b.weights) {
        if wk <= 0.0 {
            continue;
        }
        let q = p - w * z;
        let mut t = z;
        for _ in 0..PIXEL_STEPS {
            let (taps, f) = bilinear_taps(atlas_coord(k, q + w * t));
            let d = bilinear(taps.map(|i| imp.depth_at(i)), f);
            t = depth_step(capture_dir(k), q, w, d);
        }
        let (taps, f) = bilinear_taps(atlas_coord(k, q + w * t));
        let c = |ch: usize| bilinear(taps.map(|t| f32::from(imp.color[t][ch]) / 255.0), f);
        let a = |ch: usize| {
            bilinear(
                taps.map(|t| f32::from(imp.color[t][ch]) * f32::from(imp.color[t][3]) / 65025.0),
                f,
            )
        };
        let nm = |ch: usize| {
            bilinear(
                taps.map(|t| {
                    (f32::from(imp.normal[t][ch]) / 127.5 - 1.0) * f32::from(imp.color[t][3])
                        / 255.0
                }),
                f,
            )
        };
        cover += wk * c(3);
        tint += wk * a(0);
        leaf += wk * a(1);
        normal += wk * Vec3::new(nm(0), nm(1), nm(2));
    }
    Pixel {
        cover,
        tint,
        leaf,
        normal,
    }
}

/// The impostor seen orthographically along `-dir`: the displaced grid
/// ([`displace`]) rasterised, each pixel's point projected into the blended
/// captures (bilinear, coverage-weighted), alpha-tested at coverage 0.5,
/// `ss`² samples per pixel. What the G-buffer pass computes, on the CPU.
pub fn render_impostor(
    imp: &Impostor,
    dir: Vec3,
    size: usize,
    ss: usize,
    look: &Look,
) -> Vec<[f32; 3]> {
    let (out_size, size) = (size, size * ss);
    let basis = view_basis(dir);
    let g = GRID + 1;
    let points: Vec<Vec3> = (0..g * g)
        .map(|v| displace(imp, basis, grid_point(v % g, v / g)))
        .collect();
    let n = size as f32;
    let screen: Vec<Vec3> = points
        .iter()
        .map(|p| {
            Vec3::new(
                (p.dot(basis[0]) * 0.5 + 0.5) * n,
                (0.5 - p.dot(basis[1]) * 0.5) * n,
                p.dot(basis[2]),
            )
        })
        .collect();
    let mut depth = vec![f32::NEG_INFINITY; size * size];
    let mut out = vec![look.sky; size * size];
    for j in 0..GRID {
        for i in 0..GRID {
            let v = [
                j * g + i,
                j * g + i + 1,
                (j + 1) * g + i + 1,
                (j + 1) * g + i,
            ];
            for tri in [[v[0], v[1], v[2]], [v[0], v[2], v[3]]] {
                raster(size, tri.map(|t| screen[t]), |px, w| {
                    let p = points[tri[0]] * w[0] + points[tri[1]] * w[1] + points[tri[2]] * w[2];
                    let z = p.dot(basis[2]);
                    if z <= depth[px] {
                        return;
                    }
                    let Pixel {
                        cover,
                        tint,
                        leaf,
                        normal,
                    } = pixel(imp, basis[2], p);
                    if cover < 0.5 {
                        return;
                    }
                    depth[px] = z;
                    out[px] = look.shade(tint / cover, leaf / cover, normal.normalize_or(Vec3::Y));
                });
            }
        }
    }
    resolve(&out, out_size, ss)
}

const MAGIC: &[u8; 4] = b"HIMP";
const VERSION: u32 = 1;

/// The impostor file of tree (`species`, `seed`) under `dir`.
pub fn cache_file(dir: &Path, species: Species, seed: u32) -> PathBuf {
    dir.join("trees")
        .join(format!("{}-{seed}.himal-impostor", species.name()))
}

/// FNV-1a over the cards (V1's fingerprint) and the limbs.
pub fn fingerprint(model: &TreeModel) -> u64 {
    let mut h = super::bake::fingerprint(model);
    for limb in &model.limbs {
        for v in limb
            .points
            .iter()
            .flat_map(|p| p.to_array())
            .chain(limb.radii.iter().copied())
        {
            for b in v.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

/// File: magic `HIMP`, version, fingerprint, capture size, centre, radius,
/// then the atlas's colour, normal (RGBA8 each) and depth (u16) texels.
fn encode(model: &TreeModel, imp: &Impostor) -> Vec<u8> {
    let texels = imp.depth.len();
    let mut out = Vec::with_capacity(40 + 10 * texels);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&fingerprint(model).to_le_bytes());
    out.extend_from_slice(&(CAPTURE_SIZE as u32).to_le_bytes());
    for v in imp.centre.to_array().into_iter().chain([imp.radius]) {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend(imp.color.iter().flatten());
    out.extend(imp.normal.iter().flatten());
    for d in &imp.depth {
        out.extend_from_slice(&d.to_le_bytes());
    }
    out
}

/// The file's impostor, if it is whole and made for `model`.
fn decode(model: &TreeModel, bytes: &[u8]) -> Option<Impostor> {
    let word = |at: usize| -> Option<[u8; 4]> { bytes.get(at..at + 4)?.try_into().ok() };
    let texels = ATLAS_SIZE * ATLAS_SIZE;
    if bytes.get(..4)? != MAGIC
        || u32::from_le_bytes(word(4)?) != VERSION
        || u64::from_le_bytes(bytes.get(8..16)?.try_into().ok()?) != fingerprint(model)
        || u32::from_le_bytes(word(16)?) != CAPTURE_SIZE as u32
        || bytes.len() != 36 + 10 * texels
    {
        return None;
    }
    let f = |i: usize| word(20 + 4 * i).map(f32::from_le_bytes);
    let (centre, radius) = (Vec3::new(f(0)?, f(1)?, f(2)?), f(3)?);
    if !(centre.is_finite() && radius.is_finite() && radius > 0.0) {
        return None;
    }
    let rgba = |at: usize| -> Vec<[u8; 4]> {
        bytes[at..at + 4 * texels]
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    };
    let depth = bytes[36 + 8 * texels..]
        .chunks_exact(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    Some(Impostor {
        centre,
        radius,
        color: rgba(36),
        normal: rgba(36 + 4 * texels),
        depth,
    })
}

/// Reads tree (`model.species`, `seed`)'s impostor from `dir`, or bakes
/// and writes it; the flag is true when read from the cache.
pub fn load_or_bake_in(dir: &Path, model: &TreeModel, seed: u32) -> (Impostor, bool) {
    let path = cache_file(dir, model.species, seed);
    if let Some(imp) = std::fs::read(&path).ok().and_then(|b| decode(model, &b)) {
        return (imp, true);
    }
    let imp = bake(model);
    let written = std::fs::create_dir_all(path.parent().unwrap_or(dir))
        .and_then(|_| std::fs::write(&path, encode(model, &imp)));
    if let Err(e) = written {
        log::warn!("impostor cache {}: {e} (baked in memory)", path.display());
    }
    (imp, false)
}

#[cfg(test)]
mod tests {
    use super::super::generate;
    use super::*;

    #[test]
    fn blend_weights_follow_azimuth_and_elevation() {
        for k in 0..AROUND {
            let b = blend(capture_dir(k));
            assert_eq!(b.captures[0], k);
            assert!((b.weights[0] - 1.0).abs() < 1e-5, "{k}: {b:?}");
        }
        let a = TAU / 16.0;
        let b = blend(Vec3::new(a.sin(), 0.0, a.cos()));
        assert_eq!(b.captures, [0, 1, AROUND]);
        assert!((b.weights[0] - 0.5).abs() < 1e-5 && (b.weights[1] - 0.5).abs() < 1e-5);
        let top = blend(Vec3::Y);
        assert!((top.weights[2] - 1.0).abs() < 1e-6, "{top:?}");
        for d in [Vec3::new(0.3, 0.5, -0.8), Vec3::new(-1.0, 0.2, 0.1)] {
            let w = blend(d.normalize()).weights;
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn capture_round_trips_and_is_deterministic() {
        let model = generate(Species::Larch, 2, 0.1);
        let imp = bake(&model);
        assert_eq!(imp, bake(&model), "same model, same atlas");
        let covered = imp.color.iter().filter(|c| c[3] > 0).count();
        // Every capture sees the tree.
        for k in 0..CAPTURES {
            let n = (0..CAPTURE_SIZE * CAPTURE_SIZE)
                .filter(|&i| imp.color[atlas_index(k, i % CAPTURE_SIZE, i / CAPTURE_SIZE)][3] > 0)
                .count();
            assert!(n > 200, "capture {k}: {n} texels");
        }
        assert!(covered < ATLAS_SIZE * ATLAS_SIZE / 2);
        let bytes = encode(&model, &imp);
        assert_eq!(decode(&model, &bytes), Some(imp.clone()));
        assert_eq!(decode(&generate(Species::Larch, 3, 0.1), &bytes), None);
        assert_eq!(decode(&model, &bytes[..bytes.len() - 1]), None);
        let dir = std::env::temp_dir().join(format!("himal-impostor-cache-{}", std::process::id()));
        let (a, read) = load_or_bake_in(&dir, &model, 2);
        assert!(!read && a == imp);
        let (b, read) = load_or_bake_in(&dir, &model, 2);
        assert!(read && b == imp);
        let _ = std::fs::remove_dir_all(&dir);
    }
}

#[cfg(test)]
mod fidelity {
    use super::super::generate;
    use super::*;
    use himal_reference::flip::{DEFAULT_PIXELS_PER_DEGREE, flip_mean};

    /// Pixels across the impostor's square (2 R) at the transition
    /// distance: LOD2 -> impostor at 3 d_1 (E2's levels switch at l d_1),
    /// larch 222 m, rosewood 159 m at 1280 x 720, 60°: 2 R (larch seed 3
    /// 17.6 m, rosewood seed 5 16.8 m) spans about 49 and 66 px.
    const SIZE: usize = 64;
    /// Samples per pixel side: both pictures as a resolved (anti-aliased)
    /// frame shows them; one sample per pixel measures alpha-test aliasing.
    const SS: usize = 4;

    /// The views measured: the nine captures, the eight azimuths halfway
    /// between them, and those eight again from 30° above (name, dir).
    fn views() -> Vec<(String, Vec3)> {
        let at = |az: f32, el: f32| {
            let (a, e) = (az.to_radians(), el.to_radians());
            Vec3::new(a.sin() * e.cos(), e.sin(), a.cos() * e.cos())
        };
        let mut v: Vec<(String, Vec3)> = (0..CAPTURES)
            .map(|k| (format!("capture {k}"), capture_dir(k)))
            .collect();
        for el in [0.0, 30.0] {
            for k in 0..AROUND {
                let az = 22.5 + 45.0 * k as f32;
                v.push((format!("az {az:.1} el {el:.0}"), at(az, el)));
            }
        }
        v
    }

    /// Impostor vs full tree, FLIP mean over the 64² square, every species
    /// and view. `HIMAL_IMPOSTOR_PNG=dir` writes the worst view's pair.
    #[test]
    fn impostor_matches_the_full_tree() {
        let look = Look::default();
        let mut worsts = Vec::new();
        for species in Species::ALL {
            let model = generate(species, 3, 1.0);
            let imp = bake(&model);
            let mut worst = (String::new(), 0.0f32, Vec3::ZERO);
            let mut sum = 0.0;
            let views = views();
            let mut classes = [0.0f32; 3];
            for (i, (name, dir)) in views.iter().enumerate() {
                let reference = render_mesh(&model, *dir, SIZE, SS, &look);
                let test = render_impostor(&imp, *dir, SIZE, SS, &look);
                let e = flip_mean(&reference, &test, SIZE, SIZE, DEFAULT_PIXELS_PER_DEGREE)
                    .unwrap_or(1.0);
                let (r1, t1) = (
                    render_mesh(&model, *dir, SIZE, 1, &look),
                    render_impostor(&imp, *dir, SIZE, 1, &look),
                );
                let e1 = flip_mean(&r1, &t1, SIZE, SIZE, DEFAULT_PIXELS_PER_DEGREE).unwrap_or(1.0);
                println!(
                    "{} {name}: FLIP {e:.4} (1 sample per pixel: {e1:.4})",
                    species.name()
                );
                sum += e;
                let class = usize::from(i >= CAPTURES) + usize::from(i >= CAPTURES + AROUND);
                classes[class] = classes[class].max(e);
                if e > worst.1 {
                    worst = (name.clone(), e, *dir);
                }
            }
            println!(
                "{}: mean FLIP {:.4} over {} views, worst {:.4} at {}",
                species.name(),
                sum / views.len() as f32,
                views.len(),
                worst.1,
                worst.0
            );
            if let Some(dir) = std::env::var_os("HIMAL_IMPOSTOR_PNG") {
                let big = 4;
                // HIMAL_IMPOSTOR_PNG_VIEW=i: view i of `views()` instead of the worst.
                if let Some(i) = std::env::var("HIMAL_IMPOSTOR_PNG_VIEW")
                    .ok()
                    .and_then(|v| v.parse::<usize>().ok())
                    .filter(|&i| i < views.len())
                {
                    worst.2 = views[i].1;
                }
                // The atlas: shaded colour over the sky (left), depth (right).
                let n = ATLAS_SIZE;
                let mut atlas = vec![[0.0f32; 3]; 2 * n * n];
                for i in 0..n * n {
                    let (c, nm) = (imp.color[i], imp.normal[i]);
                    let a = f32::from(c[3]) / 255.0;
                    let normal = Vec3::from(
                        nm.map(|v| f32::from(v) / 127.5 - 1.0)[..3]
                            .try_into()
                            .unwrap_or([0.0; 3]),
                    );
                    let lit = look.shade(f32::from(c[0]) / 255.0, f32::from(c[1]) / 255.0, normal);
                    let (x, y) = (i % n, i / n);
                    atlas[y * 2 * n + x] = encode_srgb(look.sky.lerp(lit, a));
                    let d = imp.depth_at(i) * 0.5 + 0.5;
                    atlas[y * 2 * n + n + x] = [d, d, d];
                }
                let bytes: Vec<u8> = atlas
                    .iter()
                    .flat_map(|c| c.map(|v| (v * 255.0).round() as u8))
                    .collect();
                let path = Path::new(&dir).join(format!("V3-{}-atlas.png", species.name()));
                image::save_buffer(
                    &path,
                    &bytes,
                    2 * n as u32,
                    n as u32,
                    image::ColorType::Rgb8,
                )
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                for (kind, img) in [
                    ("mesh", render_mesh(&model, worst.2, SIZE * big, SS, &look)),
                    (
                        "impostor",
                        render_impostor(&imp, worst.2, SIZE * big, SS, &look),
                    ),
                ] {
                    let bytes: Vec<u8> = img
                        .iter()
                        .flat_map(|c| c.map(|v| (v * 255.0).round() as u8))
                        .collect();
                    let path = Path::new(&dir).join(format!("V3-{}-{kind}.png", species.name()));
                    let s = (SIZE * big) as u32;
                    image::save_buffer(&path, &bytes, s, s, image::ColorType::Rgb8)
                        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                }
            }
            worsts.push((species, worst, classes));
        }
        // Measured (4 x 4 samples, lavapipe-independent: all CPU), worst per
        // class, larch / rosewood: captures 0.042 / 0.019, halfway between
        // captures at 0° 0.108 / 0.065, at 30° elevation 0.123 / 0.159. The
        // issue's goal (0.05) holds at the capture angles only; the bounds
        // sit a little above the measurements to catch regressions.
        for (species, worst, classes) in worsts {
            let name = species.name();
            assert!(
                classes[0] <= 0.05,
                "{name}: captures {classes:?} (worst {worst:?})"
            );
            assert!(
                classes[1] <= 0.12,
                "{name}: between {classes:?} (worst {worst:?})"
            );
            assert!(
                classes[2] <= 0.17,
                "{name}: elevated {classes:?} (worst {worst:?})"
            );
        }
    }
}
