//! Copies GPU textures and buffers back to the CPU (tests, `--out`, EXR).

use super::{GpuContext, GpuError};

/// A texture's texels, rows tightly packed (no 256-byte padding).
#[derive(Clone, Debug)]
pub struct TextureData {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Texel format of the copied texture; [`Self::bytes`] is laid out in it.
    pub format: wgpu::TextureFormat,
    /// Texels row by row, top row first, `width * bytes_per_texel` bytes a row.
    pub bytes: Vec<u8>,
}

impl TextureData {
    /// Size of one texel in bytes (4 for a format without a copy size).
    pub fn bytes_per_texel(&self) -> u32 {
        self.format
            .block_copy_size(Some(wgpu::TextureAspect::All))
            .unwrap_or(4)
    }

    /// Texels as f32 RGBA, whatever the format (unorm, float16/32, 10:10:10:2).
    pub fn to_rgba_f32(&self) -> Result<Vec<[f32; 4]>, GpuError> {
        use wgpu::TextureFormat as F;
        let n = (self.width * self.height) as usize;
        let b = &self.bytes;
        let out = match self.format {
            F::Rgba8Unorm | F::Rgba8UnormSrgb => (0..n)
                .map(|i| std::array::from_fn(|c| b[i * 4 + c] as f32 / 255.0))
                .collect(),
            F::Bgra8Unorm | F::Bgra8UnormSrgb => (0..n)
                .map(|i| std::array::from_fn(|c| b[i * 4 + [2, 1, 0, 3][c]] as f32 / 255.0))
                .collect(),
            F::Rgba16Float => (0..n)
                .map(|i| {
                    std::array::from_fn(|c| {
                        let o = i * 8 + c * 2;
                        half::f16::from_le_bytes([b[o], b[o + 1]]).to_f32()
                    })
                })
                .collect(),
            F::Rg16Float => (0..n)
                .map(|i| {
                    let h = |o: usize| half::f16::from_le_bytes([b[o], b[o + 1]]).to_f32();
                    [h(i * 4), h(i * 4 + 2), 0.0, 1.0]
                })
                .collect(),
            F::Rgba32Float => bytemuck::cast_slice::<u8, f32>(b)
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]])
                .collect(),
            F::R32Float | F::Depth32Float => bytemuck::pod_collect_to_vec::<u8, f32>(b)
                .iter()
                .map(|&v| [v, v, v, 1.0])
                .collect(),
            F::Rgb10a2Unorm => bytemuck::pod_collect_to_vec::<u8, u32>(b)
                .iter()
                .map(|&v| {
                    [
                        (v & 1023) as f32 / 1023.0,
                        ((v >> 10) & 1023) as f32 / 1023.0,
                        ((v >> 20) & 1023) as f32 / 1023.0,
                        (v >> 30) as f32 / 3.0,
                    ]
                })
                .collect(),
            other => {
                return Err(GpuError::Readback(format!(
                    "no CPU conversion for {other:?}"
                )));
            }
        };
        Ok(out)
    }
}

/// Reads mip `mip` of layer `layer` of a 2D texture (depth formats: depth aspect).
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    mip: u32,
    layer: u32,
) -> Result<TextureData, GpuError> {
    let format = texture.format();
    let aspect = if format.is_depth_stencil_format() {
        wgpu::TextureAspect::DepthOnly
    } else {
        wgpu::TextureAspect::All
    };
    let texel = format
        .block_copy_size(Some(aspect))
        .ok_or_else(|| GpuError::Readback(format!("{format:?} cannot be copied")))?;
    let width = (texture.width() >> mip).max(1);
    let height = (texture.height() >> mip).max(1);
    let row = width * texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("himal.readback"),
        size: (padded * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: mip,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer,
            },
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    ctx.queue.submit([encoder.finish()]);
    let padded_bytes = map_read(ctx, &buffer)?;
    let mut bytes = Vec::with_capacity((row * height) as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        bytes.extend_from_slice(&padded_bytes[start..start + row as usize]);
    }
    Ok(TextureData {
        width,
        height,
        format,
        bytes,
    })
}

/// Copies `buffer` (needs COPY_SRC) to the CPU.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("himal.readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &staging)
}

fn map_read(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait("read-back")?;
    rx.recv()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| GpuError::Readback(e.to_string()))?
        .to_vec();
    buffer.unmap();
    Ok(data)
}
