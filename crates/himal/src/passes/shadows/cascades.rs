//! S1 cascade fitting on the CPU: the practical split, one bounding sphere
//! per view-frustum slice, texel snapping, and the orthographic sun view that
//! every shadow map (cascades, static, hero) shares.

use glam::{Mat4, Vec3};

use crate::scene::{Aabb, Camera};

/// Sun cascades per frame.
pub const CASCADES: usize = 4;

/// An orthographic sun view: what is rendered and how it is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowFit {
    /// World to clip (xy in [-1, 1], z in [0, 1], 0 nearest the sun).
    pub light_view_proj: Mat4,
    /// World to light view (rotation only; the sun looks down -Z).
    pub light_rotation: Mat4,
    /// Light-view box covered: x, y extents and z from the far plane (min)
    /// to the near plane (max, toward the sun).
    pub min: Vec3,
    /// Max corner of that box (z at the near plane, toward the sun).
    pub max: Vec3,
    /// World size of one texel (m).
    pub texel_world: f32,
    /// Depth range of the projection (m).
    pub depth_range: f32,
}

impl ShadowFit {
    /// Could `bounds` (world) cast into this map? Overlaps the box in x, y
    /// and is not wholly beyond the far plane (all casters toward the sun count).
    pub fn may_cast(&self, bounds: &Aabb) -> bool {
        let b = bounds.transform(&self.light_rotation);
        b.max.x >= self.min.x
            && b.min.x <= self.max.x
            && b.max.y >= self.min.y
            && b.min.y <= self.max.y
            && b.max.z >= self.min.z
    }
}

/// Rotation from world to the sun's view (looking along -`sun_direction`);
/// independent of the camera, so texel grids stay put in the world.
pub fn light_rotation(sun_direction: Vec3) -> Mat4 {
    let d = sun_direction.normalize_or(Vec3::Y);
    let up = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    glam::camera::rh::view::look_to_mat4(Vec3::ZERO, -d, up)
}

/// Orthographic fit of the light-view rectangle centred on `center_ls`
/// (light-view x, y) with half size `half`, its near plane at `z_near` (toward
/// the sun) and far plane at `z_far`, for an `n`-texel map.
pub fn ortho_fit(
    rotation: Mat4,
    center_ls: Vec3,
    half: f32,
    z_near: f32,
    z_far: f32,
    n: u32,
) -> ShadowFit {
    let (cx, cy) = (center_ls.x, center_ls.y);
    // glam's "directx" convention is wgpu's clip space; distances along -Z.
    let proj = glam::camera::rh::proj::directx::orthographic(
        cx - half,
        cx + half,
        cy - half,
        cy + half,
        -z_near,
        -z_far,
    );
    ShadowFit {
        light_view_proj: proj * rotation,
        light_rotation: rotation,
        min: Vec3::new(cx - half, cy - half, z_far),
        max: Vec3::new(cx + half, cy + half, z_near),
        texel_world: 2.0 * half / n.max(1) as f32,
        depth_range: z_near - z_far,
    }
}

/// Highest light-view z of `bounds` (every caster lies below it), plus 1 m.
pub fn top_of(rotation: Mat4, bounds: &Aabb) -> f32 {
    if bounds.is_empty() {
        return 1.0;
    }
    bounds.transform(&rotation).max.z + 1.0
}

/// Practical split (Zhang et al.): d_i = λ·n·(f/n)^(i/N) + (1−λ)·(n + (f−n)·i/N),
/// i = 0..=N; λ = 1 is logarithmic (equal texel density ratio per cascade),
/// λ = 0 uniform.
pub fn practical_splits(near: f32, far: f32, lambda: f32) -> [f32; CASCADES + 1] {
    let mut d = [0.0; CASCADES + 1];
    for (i, di) in d.iter_mut().enumerate() {
        let s = i as f32 / CASCADES as f32;
        let log = near * (far / near).powf(s);
        let uniform = near + (far - near) * s;
        *di = lambda * log + (1.0 - lambda) * uniform;
    }
    d
}

/// R3 cinematic splits: fully logarithmic from the author's `near` to `far`
/// (d_i = near (far / near)^(i/N), i >= 1); the first cascade still starts
/// at the camera's near plane so nothing in view falls outside the maps.
pub fn cinematic_splits(camera_near: f32, near: f32, far: f32) -> [f32; CASCADES + 1] {
    let mut d = practical_splits(near, far, 1.0);
    d[0] = camera_near.min(near);
    d
}

/// Smallest sphere around the view-frustum slice [d_near, d_far]: centre on
/// the view axis at t = (d_n + d_f)(1 + k²)/2 (clamped to d_f), k² =
/// tan²(fov/2)(1 + aspect²). Depends on the slice only, never on the camera's
/// position or orientation, so its size cannot change as the camera moves.
pub fn slice_sphere(camera: &Camera, aspect: f32, d_near: f32, d_far: f32) -> (Vec3, f32) {
    let forward = camera.forward.normalize_or(Vec3::NEG_Z);
    // Orthographic: the slice is a box of the view's half extents.
    if let Some(o) = camera.orthographic {
        let half = Vec3::new(
            o.half_height * aspect,
            o.half_height,
            0.5 * (d_far - d_near),
        );
        return (
            camera.position + forward * (0.5 * (d_near + d_far)),
            half.length(),
        );
    }
    let tan = (camera.fov_y_deg.to_radians() * 0.5).tan();
    let k2 = tan * tan * (1.0 + aspect * aspect);
    let t = ((d_near + d_far) * (1.0 + k2) * 0.5).min(d_far);
    let radius = ((t - d_near).powi(2) + d_near * d_near * k2)
        .sqrt()
        .max(((d_far - t).powi(2) + d_far * d_far * k2).sqrt());
    (camera.position + forward * t, radius)
}

/// Fits cascade `i` of `splits`: the slice's sphere seen from the sun, the
/// centre snapped to whole texels when `snap` (a camera move then shifts the
/// map by whole texels, so edges do not crawl), near plane above `scene`.
/// Two texels of margin per side cover the snap and the filter footprint.
#[allow(clippy::too_many_arguments)]
pub fn fit_cascade(
    camera: &Camera,
    aspect: f32,
    splits: &[f32; CASCADES + 1],
    i: usize,
    sun_direction: Vec3,
    scene: &Aabb,
    resolution: u32,
    snap: bool,
) -> ShadowFit {
    let (center, radius) = slice_sphere(camera, aspect, splits[i], splits[i + 1]);
    let rotation = light_rotation(sun_direction);
    let mut c = rotation.transform_point3(center);
    let n = resolution.max(8) as f32;
    let half = radius * n / (n - 4.0);
    if snap {
        let texel = 2.0 * half / n;
        c.x = (c.x / texel).round() * texel;
        c.y = (c.y / texel).round() * texel;
    }
    let z_near = top_of(rotation, scene).max(c.z + radius);
    ortho_fit(rotation, c, half, z_near, c.z - radius, resolution)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// R3: equal ratios between the author's splits (fully logarithmic),
    /// the last at `far`, the first cascade from the camera's near plane.
    #[test]
    fn cinematic_splits_are_logarithmic_from_the_author_near() {
        let d = cinematic_splits(0.1, 1.0, 12.0);
        assert_eq!(d[0], 0.1);
        assert!((d[CASCADES] - 12.0).abs() < 1e-5, "{d:?}");
        let ratio = 12.0f32.powf(1.0 / CASCADES as f32);
        assert!((d[1] - ratio).abs() < 1e-5, "{d:?}");
        for i in 1..CASCADES {
            assert!((d[i + 1] / d[i] - ratio).abs() < 1e-4, "{d:?}");
        }
        // A camera near beyond the author's: the author's near still starts.
        assert_eq!(cinematic_splits(2.0, 1.0, 12.0)[0], 1.0);
    }

    /// The slice sphere holds every corner of the view slice, for a
    /// perspective camera's frustum piece and an orthographic camera's box,
    /// and the box's sphere is the tight one (its corners on the surface).
    #[test]
    fn slice_spheres_hold_the_slice_for_both_projections() {
        let mut camera =
            Camera::look_at(Vec3::new(3.0, 2.0, 5.0), Vec3::new(-1.0, 0.5, -4.0), 50.0);
        let aspect = 1.6;
        for ortho in [
            None,
            Some(crate::scene::Orthographic {
                half_height: 7.0,
                far: 300.0,
            }),
        ] {
            camera.orthographic = ortho;
            let inv = camera.view_projection(aspect).inverse();
            let (d_n, d_f) = (4.0, 40.0);
            let (c, r) = slice_sphere(&camera, aspect, d_n, d_f);
            let mut farthest = 0.0f32;
            for d in [d_n, d_f] {
                // The depth of view distance d under this projection.
                let p = camera.position + camera.forward * d;
                let clip = camera.view_projection(aspect) * p.extend(1.0);
                let z = clip.z / clip.w;
                for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                    let q = inv * glam::Vec4::new(x, y, z, 1.0);
                    let corner = q.truncate() / q.w;
                    farthest = farthest.max(corner.distance(c));
                }
            }
            assert!(
                farthest <= r * (1.0 + 1e-4),
                "{ortho:?}: corner at {farthest}, radius {r}"
            );
            if ortho.is_some() {
                assert!((farthest - r).abs() < 1e-3 * r, "{farthest} vs {r}");
            }
        }
    }
}
