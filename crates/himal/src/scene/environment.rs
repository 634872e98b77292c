//! HDR environments (issue #8): an equirectangular `.hdr` or `.exr` image
//! lighting the scene instead of the physical sky. Diffuse light is its SH9
//! irradiance, specular light its cube map filtered by the L4 path, and the
//! background the image itself. Math and conventions: `docs/gltf.md`
//! ("HDR environments").

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::SceneError;
use crate::math::sh::Sh9Rgb;

/// An environment as the scene file or the CLI names it.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentDesc {
    pub path: PathBuf,
    /// Radiance scale (the file's values are relative).
    pub intensity: f32,
    /// Turn about +Y in degrees (moves the image's features around the horizon).
    pub rotation_deg: f32,
    /// Keep the analytic sun of the scene's time of day (shadows, highlights)
    /// on top of the image; off by default, as the image holds its own sun.
    pub sun: bool,
}

impl EnvironmentDesc {
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            intensity: 1.0,
            rotation_deg: 0.0,
            sun: false,
        }
    }
}

/// A loaded equirectangular image: linear RGB, rows top (+Y) to bottom.
#[derive(Clone, Debug)]
pub struct EnvironmentImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
    /// Rotation about +Y in radians.
    pub rotation: f32,
}

fn invalid(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        file: path.display().to_string(),
        message: message.into(),
    }
}

impl EnvironmentImage {
    /// Reads `.hdr` (Radiance RGBE) or `.exr`, scaled by the intensity.
    pub fn load(desc: &EnvironmentDesc) -> Result<Self, SceneError> {
        let path = &desc.path;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        let (width, height, mut texels) = match ext.as_deref() {
            Some("hdr") => {
                let img = image::open(path)
                    .map_err(|e| invalid(path, format!("cannot read the HDR image: {e}")))?
                    .into_rgb32f();
                let (w, h) = (img.width() as usize, img.height() as usize);
                let texels = img.pixels().map(|p| Vec3::from(p.0)).collect();
                (w, h, texels)
            }
            Some("exr") => {
                use exr::prelude::*;
                let img = read_first_rgba_layer_from_file(
                    path,
                    |size, _| (size.width(), vec![Vec3::ZERO; size.width() * size.height()]),
                    |(w, texels): &mut (usize, Vec<Vec3>),
                     pos,
                     (r, g, b, _a): (f32, f32, f32, f32)| {
                        texels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
                    },
                )
                .map_err(|e| invalid(path, format!("cannot read the EXR image: {e}")))?;
                let size = img.layer_data.size;
                (
                    size.width(),
                    size.height(),
                    img.layer_data.channel_data.pixels.1,
                )
            }
            _ => {
                return Err(invalid(
                    path,
                    "unsupported environment image (use an equirectangular .hdr or .exr)",
                ));
            }
        };
        if width < 2 || height < 2 || width != 2 * height {
            return Err(invalid(
                path,
                format!("{width}x{height}: an equirectangular image is twice as wide as high"),
            ));
        }
        if !desc.intensity.is_finite() || desc.intensity < 0.0 {
            return Err(invalid(
                path,
                format!("intensity {} must be >= 0", desc.intensity),
            ));
        }
        for t in &mut texels {
            // Non-finite texels (broken files) would poison the SH and the filter.
            *t = if t.is_finite() {
                t.max(Vec3::ZERO) * desc.intensity
            } else {
                Vec3::ZERO
            };
        }
        Ok(Self {
            width,
            height,
            texels,
            rotation: desc.rotation_deg.to_radians(),
        })
    }

    /// Image coordinates in [0,1]² of direction `d`: longitude from -Z
    /// toward +X (the image centre looks down -Z, the default camera
    /// forward), latitude from +Y at the top; turned by `rotation`.
    pub fn uv(&self, d: Vec3) -> Vec2 {
        let phi = d.x.atan2(-d.z) + self.rotation;
        let u = (phi / std::f32::consts::TAU + 0.5).rem_euclid(1.0);
        let v = d.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI;
        Vec2::new(u, v)
    }

    /// Bilinear radiance toward `d` (wraps in longitude, clamps at the poles).
    pub fn sample(&self, d: Vec3) -> Vec3 {
        let uv = self.uv(d);
        let p = uv * Vec2::new(self.width as f32, self.height as f32) - 0.5;
        let p0 = p.floor();
        let f = p - p0;
        let at = |x: f32, y: f32| {
            let x = (x as i64).rem_euclid(self.width as i64) as usize;
            let y = (y.max(0.0) as usize).min(self.height - 1);
            self.texels[y * self.width + x]
        };
        let top = at(p0.x, p0.y).lerp(at(p0.x + 1.0, p0.y), f.x);
        let bottom = at(p0.x, p0.y + 1.0).lerp(at(p0.x + 1.0, p0.y + 1.0), f.x);
        top.lerp(bottom, f.y)
    }

    /// Radiance SH9, projected by quadrature over the sphere.
    pub fn radiance_sh(&self) -> Sh9Rgb {
        // 64 nodes per axis: 32 Gauss-Legendre rows per hemisphere x 128 azimuths.
        Sh9Rgb::project(|d| self.sample(d), 64)
    }

    /// The six faces (+X, -X, +Y, -Y, +Z, -Z) of a `size`² cube, each texel
    /// the mean of 2x2 samples (for `EnvMapPass::filter_faces`).
    pub fn cube_faces(&self, size: usize) -> [Vec<[f32; 3]>; 6] {
        use crate::passes::envmap::reference::cube_face_direction;
        std::array::from_fn(|face| {
            (0..size * size)
                .map(|i| {
                    let corner = Vec2::new((i % size) as f32, (i / size) as f32);
                    let sum: Vec3 = [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
                        .iter()
                        .map(|&(dx, dy)| {
                            let uv = (corner + Vec2::new(dx, dy)) / size as f32;
                            self.sample(cube_face_direction(face, uv))
                        })
                        .sum();
                    (sum * 0.25).to_array()
                })
                .collect()
        })
    }
}
