//! E2 LOD by triangle size, the offline half (Ryse, SIGGRAPH 2014,
//! `seeds/004_...`): each mesh's geometric-mean triangle area and its
//! chain of simplified index lists (meshoptimizer's edge-collapse
//! simplifier over the mesh's own vertices). The selection (transition
//! distances from the area, the view and `--lod-threshold`) runs per
//! instance in `passes/cull` and on the CPU path; math and figures in
//! `docs/techniques/E2.md`.

use super::{Mesh, Vertex};

/// Levels per mesh at most, LOD0 (the mesh) included: a simplified chain
/// has [`CHAIN_LODS`]; a tree's leaves have LOD0-2 and V3's two impostor
/// levels (`scene/tree/impostor_level.rs`).
pub const MAX_LODS: usize = 5;
/// Levels of a mesh's simplified chain ([`lod_chain`]), LOD0 included.
pub const CHAIN_LODS: usize = 4;
/// Meshes with fewer triangles keep one level: halving them saves nothing
/// a draw call does not cost anyway.
pub const MIN_TRIANGLES: usize = 96;
/// A level is kept only if it has at most this fraction of the previous
/// level's triangles (the simplifier stops early on locked topology).
const MIN_REDUCTION: f32 = 0.8;

/// Objects whose meshes extend further than this (m) are terrain-sized:
/// they are always near the camera somewhere, so they get no chain.
pub const MAX_EXTENT: f32 = 256.0;

/// `f / sqrt(T)`: the first transition distance per metre of an object's
/// triangle size. A triangle of world area `A` facing the camera at
/// distance `d` covers `A (f / d)^2` pixels, `f = height / (2 tan(fov/2))`
/// the focal length in pixels; it falls below `threshold_px` (T, pixels)
/// at `d_1 = f sqrt(A / T)`. Zero when LOD is off.
pub fn distance_scale(fov_y_deg: f32, height_px: u32, threshold_px: f32) -> f32 {
    if threshold_px <= 0.0 || !threshold_px.is_finite() {
        return 0.0;
    }
    focal_px(fov_y_deg, height_px) / threshold_px.sqrt()
}

/// The focal length in pixels, `f = H / (2 tan(fov_y / 2))`.
pub fn focal_px(fov_y_deg: f32, height_px: u32) -> f32 {
    height_px as f32 / (2.0 * (0.5 * fov_y_deg.to_radians()).tan())
}

/// How a frame selects levels (`gpu_scene::LodView` carries it with the eye).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Selection {
    /// [`distance_scale`] (0: LOD0 everywhere).
    pub scale: f32,
    /// [`focal_px`].
    pub focal_px: f32,
    /// Largest geometric error a level may show, in pixels (0: no guard).
    pub max_error_px: f32,
    /// Transition band, a fraction of `d_1` (0: levels pop).
    pub band: f32,
    /// The comparison metric (E2 measurements): object size instead of
    /// triangle size, `d_1 = r * object_scale` with `r` the bounds' half
    /// diagonal, `object_scale = f / R` for a first switch where the
    /// object's radius projects to `R` pixels (0: triangle size).
    pub object_scale: f32,
}

impl Selection {
    /// Whether levels are chosen at all (either metric).
    pub fn enabled(&self) -> bool {
        self.scale > 0.0 || self.object_scale > 0.0
    }
}

/// [`choice`] under `p`'s metric for an object of triangle size
/// `triangle_size` and bounding radius `radius` (`lod_choice` in
/// `passes/cull/cull.wgsl`).
pub fn choice_for(
    distance: f32,
    triangle_size: f32,
    radius: f32,
    object_scale: f32,
    errors: &[f32],
    p: &Selection,
) -> (u32, Option<f32>) {
    if p.object_scale > 0.0 {
        let by_object = Selection {
            scale: p.object_scale,
            ..*p
        };
        choice(distance, radius, object_scale, errors, &by_object)
    } else {
        choice(distance, triangle_size, object_scale, errors, p)
    }
}

/// Triangle areas of one mesh level in quarter-octave bins from 2^-32 to
/// 2^8 (mesh units squared), to count sub-pixel triangles of many
/// instances without projecting each triangle (E2 statistics).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AreaHistogram {
    counts: Vec<u32>,
}

const AREA_BINS: usize = 160;
const AREA_LOG2_MIN: f32 = -32.0;

impl AreaHistogram {
    /// Bins the triangles of a mesh by area (mesh units²) on a log2 scale, four bins per doubling.
    pub fn new(vertices: &[Vertex], indices: &[u32]) -> Self {
        let mut counts = vec![0u32; AREA_BINS];
        let p = |i: u32| {
            vertices
                .get(i as usize)
                .map(|v| glam::Vec3::from(v.position))
        };
        for t in indices.chunks_exact(3) {
            let (Some(a), Some(b), Some(c)) = (p(t[0]), p(t[1]), p(t[2])) else {
                continue;
            };
            let area = 0.5 * (b - a).cross(c - a).length();
            let x = ((area.max(1e-30).log2() - AREA_LOG2_MIN) * 4.0).floor();
            counts[(x.max(0.0) as usize).min(AREA_BINS - 1)] += 1;
        }
        Self { counts }
    }

    /// Number of triangles binned.
    pub fn triangles(&self) -> u64 {
        self.counts.iter().map(|&c| u64::from(c)).sum()
    }

    /// Expected triangles under one pixel when a triangle of area `a`
    /// covers `a k |cos t|` pixels (`k`: pixels per unit area facing the
    /// camera) with `|cos t|` uniform in [0, 1], as over a closed surface
    /// seen from anywhere: a triangle counts `min(1, 1 / (a k))` (each bin
    /// at its centre). Every triangle when `k` is 0 (infinitely far).
    pub fn below(&self, k: f32) -> f64 {
        if k.is_nan() || k <= 0.0 {
            return self.triangles() as f64;
        }
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, c)| **c > 0)
            .map(|(i, &c)| {
                let a = (AREA_LOG2_MIN as f64 + (i as f64 + 0.5) / 4.0).exp2();
                f64::from(c) * (1.0 / (a * f64::from(k))).min(1.0)
            })
            .sum()
    }
}

/// The level an object draws at and its fade (`lod_choice` in
/// `passes/cull/cull.wgsl`, the same steps). Level `l` takes over at
///
/// `S_l = max(l d_1, e_l s f / E)`:
///
/// the talk's multiples of the first distance `d_1 = size * scale`, and
/// himal's guard that the level's geometric error `e_l` (mesh units, times
/// the object's linear scale `s`) projects to at most `E` pixels. In the
/// last `band * d_1` before the next level's `S`, the fade `t` in [0, 1)
/// toward it (both draw with complementary screen-door masks); `None` when
/// steady. `errors` holds each level's error, LOD0's first (0).
pub fn choice(
    distance: f32,
    size: f32,
    object_scale: f32,
    errors: &[f32],
    p: &Selection,
) -> (u32, Option<f32>) {
    let d1 = size * p.scale;
    let levels = errors.len().min(MAX_LODS);
    if levels <= 1 || d1 <= 0.0 {
        return (0, None);
    }
    let switch = |l: usize| {
        let guard = if p.max_error_px > 0.0 {
            errors[l] * object_scale * p.focal_px / p.max_error_px
        } else {
            0.0
        };
        (l as f32 * d1).max(guard)
    };
    let mut l = 0;
    while l + 1 < levels && distance >= switch(l + 1) {
        l += 1;
    }
    let mut fade = None;
    if p.band > 0.0 && l + 1 < levels {
        let start = switch(l + 1) - p.band * d1;
        if distance > start {
            fade = Some((distance - start) / (p.band * d1));
        }
    }
    (l as u32, fade)
}

/// The fade step (0..=126) of `t`, as the instance entries carry it.
pub fn fade_step(t: f32) -> u32 {
    ((t * 127.0) as u32).min(126)
}

/// An object's triangle size (m): the square root of its mesh's
/// geometric-mean area scaled by the transform (`|det|^(2/3)`).
pub fn object_size(mean_area: f32, transform: &glam::Mat4) -> f32 {
    (mean_area * linear_scale(transform).powi(2)).sqrt()
}

/// The transform's mean linear scale, `|det|^(1/3)` (geometric errors).
pub fn linear_scale(transform: &glam::Mat4) -> f32 {
    glam::Mat3::from_mat4(*transform)
        .determinant()
        .abs()
        .powf(1.0 / 3.0)
}

/// A simplified level: its indices and its geometric error (mesh units,
/// accumulated over the chain).
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// Triangle list into the base mesh's vertices.
    pub indices: Vec<u32>,
    /// Geometric error of this level against the base mesh, in mesh units (accumulated over the chain).
    pub error: f32,
}

/// Distance from `p` to the box (0 inside).
pub fn distance_to_box(p: glam::Vec3, center: glam::Vec3, half_extent: glam::Vec3) -> f32 {
    ((p - center).abs() - half_extent)
        .max(glam::Vec3::ZERO)
        .length()
}

/// Geometric mean (log-average) of the mesh's non-degenerate triangle
/// areas in its own units squared: `exp(mean ln A_i)`. Many tiny triangles
/// pull it down, a few large ones barely raise it (the talk's choice).
/// Zero for a mesh without area.
pub fn geometric_mean_area(vertices: &[Vertex], indices: &[u32]) -> f32 {
    let p = |i: u32| {
        vertices
            .get(i as usize)
            .map(|v| glam::Vec3::from(v.position))
    };
    let (mut sum, mut n) = (0.0f64, 0u64);
    for t in indices.chunks_exact(3) {
        let (Some(a), Some(b), Some(c)) = (p(t[0]), p(t[1]), p(t[2])) else {
            continue;
        };
        let area = 0.5 * (b - a).cross(c - a).length();
        if area > 1e-12 {
            sum += f64::from(area).ln();
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).exp() as f32
    }
}

/// The mesh's LODs after LOD0: index lists over the same vertices, each
/// about a quarter of the previous level's triangles (its mean triangle
/// about four times larger: at the transition distances `k d_1` level `k`'s
/// triangles stay above the threshold up to `2 k d_1`), with the
/// simplifier's error bound growing per level (2 %, 4 %, 8 % of the mesh's
/// extent). Empty for small meshes or ones the simplifier cannot reduce.
pub fn lod_chain(mesh: &Mesh) -> Vec<Level> {
    let mut chain: Vec<Level> = Vec::new();
    if mesh.triangle_count() < MIN_TRIANGLES || mesh.vertices.is_empty() {
        return chain;
    }
    let bytes: &[u8] = bytemuck::cast_slice(&mesh.vertices);
    let Ok(adapter) = meshopt::VertexDataAdapter::new(bytes, std::mem::size_of::<Vertex>(), 0)
    else {
        return chain;
    };
    // meshoptimizer's errors are relative to this extent.
    let extent = meshopt::simplify_scale(&adapter);
    for level in 1..CHAIN_LODS {
        let (previous, previous_error) = chain
            .last()
            .map_or((&mesh.indices, 0.0), |l| (&l.indices, l.error));
        let target = (previous.len() / 12) * 3;
        let limit = 0.02 * (1u32 << (level - 1)) as f32;
        let mut error = 0.0f32;
        let indices = meshopt::simplify(
            previous,
            &adapter,
            target,
            limit,
            meshopt::SimplifyOptions::empty(),
            Some(&mut error),
        );
        let reduced = indices.len() as f32 <= MIN_REDUCTION * previous.len() as f32;
        if indices.len() < 3 || !reduced {
            break;
        }
        chain.push(Level {
            indices,
            error: previous_error + error * extent,
        });
    }
    chain
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::primitives;

    fn sphere(segments: u32, rings: u32) -> Mesh {
        let m = crate::scene::MaterialDesc::default();
        primitives::uv_sphere("s".into(), 1.0, segments, rings, &m)
    }

    #[test]
    fn geometric_mean_of_equal_triangles_is_their_area() {
        let v = |x: f32, y: f32| Vertex {
            position: [x, y, 0.0],
            ..bytemuck::Zeroable::zeroed()
        };
        let vertices = [v(0.0, 0.0), v(2.0, 0.0), v(0.0, 2.0), v(2.0, 2.0)];
        // Two right triangles of area 2, and a degenerate one ignored.
        let a = geometric_mean_area(&vertices, &[0, 1, 2, 1, 3, 2, 0, 0, 1]);
        assert!((a - 2.0).abs() < 1e-5, "{a}");
        // Areas 2 and 8: geometric mean 4 (the arithmetic mean would be 5).
        let big = [v(0.0, 0.0), v(4.0, 0.0), v(0.0, 4.0)];
        let all = [&vertices[..3], &big[..]].concat();
        let a = geometric_mean_area(&all, &[0, 1, 2, 3, 4, 5]);
        assert!((a - 4.0).abs() < 1e-4, "{a}");
        assert_eq!(geometric_mean_area(&vertices, &[]), 0.0);
    }

    #[test]
    fn levels_step_at_multiples_of_the_first_distance() {
        // f = 100 / (2 tan 45) = 50 px; T = 4 px: scale 25 per metre of size.
        let k = distance_scale(90.0, 100, 4.0);
        assert!((k - 25.0).abs() < 1e-4, "{k}");
        // Size 0.1 m: d_1 = 2.5 m; a 0.01 m^2 triangle at 2.5 m covers
        // 0.01 * (50 / 2.5)^2 = 4 px, the threshold.
        let errors = [0.0; 4];
        let pop = Selection {
            scale: k,
            focal_px: focal_px(90.0, 100),
            ..Selection::default()
        };
        let at = |d| choice(d, 0.1, 1.0, &errors, &pop).0;
        assert_eq!(
            [at(0.0), at(2.4), at(2.6), at(5.1), at(7.6), at(1e6)],
            [0, 0, 1, 2, 3, 3]
        );
        let off = Selection { scale: 0.0, ..pop };
        assert_eq!(choice(100.0, 0.1, 1.0, &errors, &off).0, 0, "LOD off");
        assert_eq!(choice(100.0, 0.1, 1.0, &[0.0], &pop).0, 0, "one level");
        assert_eq!(distance_scale(90.0, 100, 0.0), 0.0);
        // The error guard at 1 px: level 1's 0.01 m error is 1 px at
        // 0.01 * 50 / 1 = 0.5 m (before d_1), levels 2 and 3's 0.2 m at 10 m
        // (after 2 d_1 = 5 m and 3 d_1 = 7.5 m).
        let guarded = Selection {
            max_error_px: 1.0,
            ..pop
        };
        let guard = [0.0, 0.01, 0.2, 0.2];
        let g = |d| choice(d, 0.1, 1.0, &guard, &guarded).0;
        assert_eq!([g(2.6), g(5.1), g(9.9), g(10.1)], [1, 1, 1, 3]);
        // A twice larger object shows its error twice as large.
        assert_eq!(choice(10.1, 0.1, 2.0, &guard, &guarded).0, 1);
        // With a band of 0.2: fading from 0.8 d_1 to d_1, steady after.
        let band = Selection { band: 0.2, ..pop };
        let c = |d| choice(d, 0.1, 1.0, &errors, &band);
        assert_eq!(c(1.9), (0, None));
        let (l, t) = c(2.25);
        assert_eq!(l, 0);
        assert!((t.unwrap_or(-1.0) - 0.5).abs() < 1e-4);
        assert_eq!(c(2.6), (1, None));
        assert_eq!(c(1e6), (3, None), "no fade past the last");
        assert_eq!(
            choice(2.25, 0.1, 1.0, &errors, &pop),
            (0, None),
            "band 0 pops"
        );
        assert_eq!(
            [fade_step(0.0), fade_step(0.5), fade_step(0.999)],
            [0, 63, 126]
        );
        // A uniform scale s multiplies the size by s.
        let m = glam::Mat4::from_scale(glam::Vec3::splat(3.0));
        assert!((object_size(4.0, &m) - 6.0).abs() < 1e-4);
        assert!((linear_scale(&m) - 3.0).abs() < 1e-5);
        let c = glam::Vec3::ZERO;
        let e = glam::Vec3::ONE;
        assert_eq!(distance_to_box(glam::Vec3::new(0.5, 0.0, 0.0), c, e), 0.0);
        assert!((distance_to_box(glam::Vec3::new(4.0, 5.0, 0.0), c, e) - 5.0).abs() < 1e-5);
    }

    #[test]
    fn chains_quarter_the_triangles_and_keep_the_shape() {
        let mesh = sphere(64, 32);
        let chain = lod_chain(&mesh);
        assert!(chain.len() >= 2, "{} levels", chain.len());
        let mut previous = mesh.indices.len();
        let mut error = 0.0;
        for (l, level) in chain.iter().enumerate() {
            let lod = &level.indices;
            // Errors grow along the chain and stay small on a unit sphere.
            assert!(level.error >= error && level.error < 0.3, "{}", level.error);
            error = level.error;
            assert_eq!(lod.len() % 3, 0);
            assert!(lod.iter().all(|&i| (i as usize) < mesh.vertices.len()));
            assert!(
                lod.len() as f32 <= MIN_REDUCTION * previous as f32,
                "level {}",
                l + 1
            );
            // Every kept vertex is on the unit sphere: the shape stays.
            for &i in lod {
                let r = glam::Vec3::from(mesh.vertices[i as usize].position).length();
                assert!((r - 1.0).abs() < 1e-4);
            }
            previous = lod.len();
        }
        // A box has too few triangles for a chain.
        let m = crate::scene::MaterialDesc::default();
        let cube = primitives::cuboid("b".into(), glam::Vec3::ONE, &m);
        assert!(lod_chain(&cube).is_empty());
    }
}
