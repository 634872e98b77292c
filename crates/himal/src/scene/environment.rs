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
    /// The `.hdr` or `.exr` file, or [`STUDIO`] for the generated studio
    /// (a scene file's relative path is joined to the scene's folder).
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
    /// The environment in `path` at intensity 1, unrotated, without the analytic sun.
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
    /// Width in texels: twice the height.
    pub width: usize,
    /// Height in texels (at least 2).
    pub height: usize,
    /// Radiance, row by row from the top, already scaled by the intensity and clamped to >= 0.
    pub texels: Vec<Vec3>,
    /// Rotation about +Y in radians.
    pub rotation: f32,
}

/// Widest environment image read (16K equirectangular).
const MAX_ENVIRONMENT_WIDTH: u64 = 16384;
/// Largest environment file read (a 16K float EXR, uncompressed, is 1.5 GiB).
const MAX_ENVIRONMENT_FILE_BYTES: u64 = 2 << 30;

/// The two formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EnvironmentFormat {
    /// Radiance RGBE.
    Hdr,
    /// OpenEXR (float or half).
    Exr,
}

impl EnvironmentFormat {
    /// By the file's extension.
    pub fn of(path: &Path) -> Result<Self, SceneError> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("hdr") => Ok(Self::Hdr),
            Some("exr") => Ok(Self::Exr),
            _ => Err(invalid(
                path,
                "unsupported environment image (use an equirectangular .hdr or .exr)",
            )),
        }
    }
}

/// Width and height from the header, before any texel is decoded.
fn header_size(
    path: &Path,
    bytes: &[u8],
    format: EnvironmentFormat,
) -> Result<(usize, usize), SceneError> {
    match format {
        EnvironmentFormat::Exr => {
            let m = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
                .map_err(|e| invalid(path, format!("cannot read the EXR header: {e}")))?;
            let header = m
                .headers
                .first()
                .ok_or_else(|| invalid(path, "the EXR file has no layer"))?;
            let size = header.layer_size;
            Ok((size.width(), size.height()))
        }
        EnvironmentFormat::Hdr => {
            image::ImageReader::with_format(std::io::Cursor::new(bytes), image::ImageFormat::Hdr)
                .into_dimensions()
                .map(|(w, h)| (w as usize, h as usize))
                .map_err(|e| invalid(path, format!("cannot read the HDR header: {e}")))
        }
    }
}

/// Decodes the texels (linear RGB, rows top to bottom).
fn decode(
    path: &Path,
    bytes: &[u8],
    format: EnvironmentFormat,
) -> Result<(usize, usize, Vec<Vec3>), SceneError> {
    match format {
        EnvironmentFormat::Hdr => {
            let img = image::ImageReader::with_format(
                std::io::Cursor::new(bytes),
                image::ImageFormat::Hdr,
            )
            .decode()
            .map_err(|e| invalid(path, format!("cannot read the HDR image: {e}")))?
            .into_rgb32f();
            let (w, h) = (img.width() as usize, img.height() as usize);
            Ok((w, h, img.pixels().map(|p| Vec3::from(p.0)).collect()))
        }
        EnvironmentFormat::Exr => {
            use exr::prelude::*;
            let img = read()
                .no_deep_data()
                .largest_resolution_level()
                .rgba_channels(
                    |size, _| (size.width(), vec![Vec3::ZERO; size.width() * size.height()]),
                    |(w, texels): &mut (usize, Vec<Vec3>),
                     pos,
                     (r, g, b, _a): (f32, f32, f32, f32)| {
                        texels[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(bytes))
                .map_err(|e| invalid(path, format!("cannot read the EXR image: {e}")))?;
            let size = img.layer_data.size;
            Ok((
                size.width(),
                size.height(),
                img.layer_data.channel_data.pixels.1,
            ))
        }
    }
}

/// The studio's radiance toward unit `d`: backdrop plus softboxes.
fn studio_radiance(boxes: &[Softbox], d: Vec3) -> f32 {
    let smooth = |e0: f32, e1: f32, x: f32| {
        let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    // Cyclorama: 0.35 at the floor, 0.5 at the horizon, 0.8 overhead.
    let mut l = if d.y >= 0.0 {
        0.5 + 0.3 * d.y
    } else {
        0.5 - 0.15 * smooth(0.0, 0.3, -d.y)
    };
    for b in boxes {
        // Angles from the box's centre along its horizontal and vertical axes.
        let right = Vec3::Y.cross(b.toward).normalize_or(Vec3::X);
        let up = b.toward.cross(right);
        let forward = d.dot(b.toward);
        if forward <= 0.0 {
            continue;
        }
        let (x, y) = (d.dot(right).atan2(forward), d.dot(up).atan2(forward));
        let feather = 0.04;
        let inside = (1.0 - smooth(b.half.x - feather, b.half.x + feather, x.abs()))
            * (1.0 - smooth(b.half.y - feather, b.half.y + feather, y.abs()));
        l += b.radiance * inside;
    }
    l
}

fn invalid(path: &Path, message: impl Into<String>) -> SceneError {
    SceneError::Invalid {
        file: path.display().to_string(),
        message: message.into(),
    }
}

/// The built-in studio environment's name (`--env studio`, the default
/// for a bare `--gltf`).
pub const STUDIO: &str = "builtin:studio";

/// A softbox of the studio: a rectangle of constant radiance, feathered.
struct Softbox {
    /// Unit direction to its centre.
    toward: Vec3,
    /// Half extents in radians (along the horizon, up).
    half: Vec2,
    radiance: f32,
}

impl EnvironmentImage {
    /// A neutral photo studio, generated: a grey cyclorama (brighter above,
    /// a darker floor) lit by a key softbox front-right, a larger dim fill
    /// front-left and a rim strip behind, all white (no tint to judge
    /// materials by). Radiance relative, like an image's.
    pub fn studio(desc: &EnvironmentDesc) -> Self {
        let (width, height) = (512usize, 256usize);
        let boxes = [
            Softbox {
                toward: Vec3::new(0.7, 0.55, 0.6).normalize(),
                half: Vec2::new(0.32, 0.22),
                radiance: 14.0,
            },
            Softbox {
                toward: Vec3::new(-0.8, 0.25, 0.55).normalize(),
                half: Vec2::new(0.5, 0.3),
                radiance: 3.0,
            },
            Softbox {
                toward: Vec3::new(0.0, 0.45, -1.0).normalize(),
                half: Vec2::new(0.6, 0.06),
                radiance: 9.0,
            },
        ];
        let mut texels = Vec::with_capacity(width * height);
        for j in 0..height {
            for i in 0..width {
                let theta = (j as f32 + 0.5) / height as f32 * std::f32::consts::PI;
                let phi = ((i as f32 + 0.5) / width as f32 - 0.5) * std::f32::consts::TAU;
                let d = Vec3::new(
                    theta.sin() * phi.sin(),
                    theta.cos(),
                    -theta.sin() * phi.cos(),
                );
                texels.push(Vec3::splat(
                    studio_radiance(&boxes, d) * desc.intensity.max(0.0),
                ));
            }
        }
        Self {
            width,
            height,
            texels,
            rotation: desc.rotation_deg.to_radians(),
        }
    }

    /// Reads `.hdr` (Radiance RGBE) or `.exr`, scaled by the intensity;
    /// [`STUDIO`] is generated.
    pub fn load(desc: &EnvironmentDesc) -> Result<Self, SceneError> {
        let path = &desc.path;
        if path.as_os_str() == STUDIO {
            if !desc.intensity.is_finite() || desc.intensity < 0.0 {
                return Err(invalid(
                    path,
                    format!("intensity {} must be >= 0", desc.intensity),
                ));
            }
            return Ok(Self::studio(desc));
        }
        let format = EnvironmentFormat::of(path)?;
        let meta =
            std::fs::metadata(path).map_err(|e| invalid(path, format!("cannot read: {e}")))?;
        // A directory, a device or an endless pipe is not read.
        if !meta.is_file() || meta.len() > MAX_ENVIRONMENT_FILE_BYTES {
            return Err(invalid(
                path,
                format!(
                    "not a regular file of at most {} GiB",
                    MAX_ENVIRONMENT_FILE_BYTES >> 30
                ),
            ));
        }
        let bytes = std::fs::read(path).map_err(|e| invalid(path, format!("cannot read: {e}")))?;
        Self::from_bytes(desc, &bytes, format)
    }

    /// [`EnvironmentImage::load`] for bytes already read; `desc.path` names
    /// them in messages.
    pub fn from_bytes(
        desc: &EnvironmentDesc,
        bytes: &[u8],
        format: EnvironmentFormat,
    ) -> Result<Self, SceneError> {
        let path = &desc.path;
        let (w, h) = header_size(path, bytes, format)?;
        if w as u64 > MAX_ENVIRONMENT_WIDTH || h as u64 > MAX_ENVIRONMENT_WIDTH / 2 {
            return Err(invalid(
                path,
                format!("{w}x{h}: at most {MAX_ENVIRONMENT_WIDTH} texels wide (16K) are read"),
            ));
        }
        // The decoded texels, the f32 copy, cube faces and SH projection.
        crate::budget::MemoryBudget::from_env()
            .and_then(|b| {
                b.check(
                    format!("a {w}x{h} environment image"),
                    w as u64 * h as u64 * 48,
                )
            })
            .map_err(|e| invalid(path, e))?;
        let (width, height, mut texels) = decode(path, bytes, format)?;
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
        // Non-finite texels (a damaged file) would poison the SH and the filter.
        let broken = texels.iter().filter(|t| !t.is_finite()).count();
        if broken > 0 {
            return Err(invalid(
                path,
                format!(
                    "{broken} of {} texels are NaN or infinite: a damaged image",
                    texels.len()
                ),
            ));
        }
        for t in &mut texels {
            *t = t.max(Vec3::ZERO) * desc.intensity;
        }
        Ok(Self {
            width,
            height,
            texels,
            rotation: desc.rotation_deg.to_radians(),
        })
    }

    /// Image coordinates in \[0,1\]² of direction `d`: longitude from -Z
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
