//! Writing frames: sRGB 8-bit PNG, or float EXR (linear values).

use std::path::Path;

use crate::Error;
use crate::gpu::TextureData;

fn image_error(path: &Path, message: impl std::fmt::Display) -> Error {
    Error::Image {
        path: path.display().to_string(),
        message: message.to_string(),
    }
}

/// Output kind chosen by the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    /// 8-bit sRGB PNG (`.png`).
    Png,
    /// Float EXR of linear values (`.exr`).
    Exr,
}

impl ImageKind {
    /// The kind named by the path's extension (case-insensitive); an error naming the path otherwise.
    pub fn from_path(path: &Path) -> Result<Self, Error> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("png") => Ok(ImageKind::Png),
            Some("exr") => Ok(ImageKind::Exr),
            _ => Err(image_error(
                path,
                "unsupported output extension (use .png or .exr)",
            )),
        }
    }
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Saves `image` to `path` (`.png` or `.exr`), creating parent folders.
pub fn save(path: &Path, image: &TextureData) -> Result<(), Error> {
    let kind = ImageKind::from_path(path)?;
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|e| image_error(path, format!("cannot create folder: {e}")))?;
    }
    match kind {
        ImageKind::Png => {
            let pixels: Vec<u8> = match image.format {
                wgpu::TextureFormat::Rgba8UnormSrgb | wgpu::TextureFormat::Rgba8Unorm => {
                    image.bytes.clone()
                }
                _ => image
                    .to_rgba_f32()?
                    .iter()
                    .flat_map(|p| p.map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8))
                    .collect(),
            };
            image::save_buffer(
                path,
                &pixels,
                image.width,
                image.height,
                image::ExtendedColorType::Rgba8,
            )
            .map_err(|e| image_error(path, e))
        }
        ImageKind::Exr => {
            let decode = image.format == wgpu::TextureFormat::Rgba8UnormSrgb;
            let texels = image.to_rgba_f32()?;
            let w = image.width as usize;
            exr::prelude::write_rgba_file(path, w, image.height as usize, |x, y| {
                let p = texels[y * w + x];
                if decode {
                    (
                        srgb_to_linear(p[0]),
                        srgb_to_linear(p[1]),
                        srgb_to_linear(p[2]),
                        p[3],
                    )
                } else {
                    (p[0], p[1], p[2], p[3])
                }
            })
            .map_err(|e| image_error(path, e))
        }
    }
}
