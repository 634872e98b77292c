//! Table cache file (L1): the computed tables' texels, keyed by the
//! atmosphere parameters and the table shaders' sources, so that later
//! processes (CLI runs) load them instead of recomputing them (seconds on a
//! software rasteriser, milliseconds on a GPU).

use std::path::{Path, PathBuf};

use super::{
    AtmosphereConfig, BrunetonTables, TABLE_FORMAT, TRANSMITTANCE_FORMAT, table_texture_format,
};
use crate::gpu::cache::fnv1a;
use crate::gpu::pipeline::uniform_buffer;
use crate::gpu::{GpuContext, GpuError, read_texture};
use crate::graph::{PassTimer, PassTiming};

const MAGIC: &[u8; 8] = b"HIMALSKY";
/// 2: payload length and checksum in the header, exact size, finite texels.
const VERSION: u32 = 2;
/// Magic, version, key, payload length, payload checksum.
const HEADER: usize = 8 + 4 + 8 + 8 + 8;

/// The table shaders, whose change must invalidate a cached table; each is
/// hashed composed, so the modules they import (atmosphere, math) are part
/// of the key without being listed.
const SOURCES: [&str; 6] = [
    "passes/sky/bruneton/transmittance.wgsl",
    "passes/sky/bruneton/direct_irradiance.wgsl",
    "passes/sky/bruneton/single_scattering.wgsl",
    "passes/sky/bruneton/scattering_density.wgsl",
    "passes/sky/bruneton/indirect_irradiance.wgsl",
    "passes/sky/bruneton/multiple_scattering.wgsl",
];

fn key(config: &AtmosphereConfig) -> u64 {
    let mut bytes = bytemuck::bytes_of(&config.gpu_params()).to_vec();
    bytes.extend(config.sizes.density_samples.to_le_bytes());
    bytes.extend(VERSION.to_le_bytes());
    for s in SOURCES {
        let composed = crate::shader::compose(s).map(|c| c.source);
        bytes.extend(composed.unwrap_or_default().as_bytes());
    }
    fnv1a(&bytes)
}

/// The cache file of `config`'s tables in `dir`.
pub fn cache_file(dir: &Path, config: &AtmosphereConfig) -> PathBuf {
    dir.join(format!("bruneton-{:016x}.himal-sky", key(config)))
}

fn err(path: &Path, message: impl std::fmt::Display) -> GpuError {
    GpuError::Other(format!("{}: {message}", path.display()))
}

impl BrunetonTables {
    /// The final tables in `config` order: transmittance, irradiance,
    /// scattering, single Rayleigh, single Mie.
    fn kept(&self) -> [&wgpu::Texture; 5] {
        [
            &self.transmittance,
            &self.irradiance,
            &self.scattering,
            &self.single_rayleigh,
            &self.single_mie,
        ]
    }

    /// Writes the tables to `path` (temporary file, then rename).
    pub fn save(&self, ctx: &GpuContext, path: &Path) -> Result<(), GpuError> {
        let mut payload = Vec::new();
        for texture in self.kept() {
            let mut bytes = Vec::new();
            for z in 0..texture.depth_or_array_layers() {
                bytes.extend(read_texture(ctx, texture, 0, z)?.bytes);
            }
            payload.extend((bytes.len() as u64).to_le_bytes());
            payload.extend(bytes);
        }
        let mut out = MAGIC.to_vec();
        out.extend(VERSION.to_le_bytes());
        out.extend(key(&self.config).to_le_bytes());
        out.extend((payload.len() as u64).to_le_bytes());
        out.extend(fnv1a(&payload).to_le_bytes());
        out.extend(payload);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| err(dir, e))?;
        }
        let tmp = path.with_extension(format!("tmp{}", std::process::id()));
        std::fs::write(&tmp, &out).map_err(|e| err(&tmp, e))?;
        std::fs::rename(&tmp, path).map_err(|e| err(path, e))
    }

    /// Reads tables for `config` written by [`BrunetonTables::save`]; fails,
    /// naming the file, on a missing, stale (other parameters, shaders or
    /// version), short, long, damaged (checksum) or non-finite file. Never
    /// reads more than the file of `config` can hold.
    pub fn load(ctx: &GpuContext, config: AtmosphereConfig, path: &Path) -> Result<Self, GpuError> {
        let s = config.sizes;
        let e = s.scattering_extent();
        let shapes = [
            (
                (s.transmittance.0, s.transmittance.1, 1),
                false,
                TRANSMITTANCE_FORMAT,
            ),
            ((s.irradiance.0, s.irradiance.1, 1), false, TABLE_FORMAT),
            (e, true, TABLE_FORMAT),
            (e, true, TABLE_FORMAT),
            (e, true, TABLE_FORMAT),
        ];
        let texel = |f: wgpu::TextureFormat| f.block_copy_size(None).unwrap_or(8) as u64;
        let sizes: Vec<u64> = shapes
            .iter()
            .map(|&((w, h, d), _, f)| u64::from(w) * u64::from(h) * u64::from(d) * texel(f))
            .collect();
        let payload_len: u64 = sizes.iter().map(|b| 8 + b).sum();
        let expected = HEADER as u64 + payload_len;
        let data = read_exact_file(path, expected)?;
        if &data[..8] != MAGIC {
            return Err(err(path, "not a himal sky table file"));
        }
        let word = |at: usize| u64::from_le_bytes(data[at..at + 8].try_into().unwrap_or([0; 8]));
        if u32::from_le_bytes(data[8..12].try_into().unwrap_or([0; 4])) != VERSION
            || word(12) != key(&config)
        {
            return Err(err(
                path,
                "stale sky tables (other parameters, shaders or file version)",
            ));
        }
        let payload = &data[HEADER..];
        if word(20) != payload_len || word(28) != fnv1a(payload) {
            return Err(err(path, "damaged sky table file (checksum mismatch)"));
        }
        let names = [
            "transmittance",
            "irradiance",
            "scattering",
            "single Rayleigh",
            "single Mie",
        ];
        let mut at = HEADER;
        let mut textures = Vec::new();
        for (((size, d3, format), bytes), name) in shapes.into_iter().zip(sizes).zip(names) {
            let bytes = bytes as usize;
            if word(at) as usize != bytes {
                return Err(err(path, format!("the {name} table has the wrong size")));
            }
            let texels = &data[at + 8..at + 8 + bytes];
            if !all_finite(texels, format) {
                return Err(err(
                    path,
                    format!("the {name} table holds NaN or infinite texels"),
                ));
            }
            let t = table_texture_format(ctx, "sky.table.cached", size, d3, format);
            ctx.queue.write_texture(
                t.as_image_copy(),
                texels,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size.0 * texel(format) as u32),
                    rows_per_image: Some(size.1),
                },
                wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: size.2,
                },
            );
            at += 8 + bytes;
            textures.push(t);
        }
        let mut it = textures.into_iter();
        let mut next = || it.next().ok_or_else(|| err(path, "missing table"));
        let (transmittance, irradiance, scattering, single_rayleigh, single_mie) =
            (next()?, next()?, next()?, next()?, next()?);
        let params = uniform_buffer(ctx, "sky.atmosphere", &config.gpu_params());
        ctx.check("sky.tables.load")?;
        Ok(BrunetonTables {
            config,
            params,
            transmittance,
            irradiance,
            scattering,
            single_rayleigh,
            single_mie,
            sampler: super::table_sampler(ctx),
        })
    }

    /// Loads the tables from `dir`'s cache file, else computes them (and
    /// writes the file; a failed write only warns). Timings: computed only.
    pub fn load_or_compute(
        ctx: &GpuContext,
        config: AtmosphereConfig,
        dir: Option<&Path>,
        timer: Option<&mut PassTimer>,
    ) -> Result<(Self, Vec<PassTiming>), GpuError> {
        let path = dir.map(|d| cache_file(d, &config));
        if let Some(p) = &path {
            match Self::load(ctx, config.clone(), p) {
                Ok(t) => return Ok((t, Vec::new())),
                Err(e) if !p.exists() => log::info!("sky tables not cached yet: {e}"),
                Err(e) => log::warn!("sky tables rebuilt: {e}"),
            }
        }
        let (tables, timings) = Self::compute_with(ctx, config, timer)?;
        if let Some(p) = &path
            && let Err(e) = tables.save(ctx, p)
        {
            log::warn!("sky tables not cached: {e}");
        }
        Ok((tables, timings))
    }
}

/// The whole of `path` when it is a regular file of exactly `expected`
/// bytes (a symlink to a device or an endless file is never read).
fn read_exact_file(path: &Path, expected: u64) -> Result<Vec<u8>, GpuError> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| err(path, e))?;
    if !meta.is_file() {
        return Err(err(path, "not a regular file"));
    }
    if meta.len() < expected {
        return Err(err(
            path,
            format!(
                "truncated sky table file ({} of {expected} bytes)",
                meta.len()
            ),
        ));
    }
    if meta.len() > expected {
        return Err(err(
            path,
            format!(
                "sky table file has {} trailing bytes",
                meta.len() - expected
            ),
        ));
    }
    let mut data = Vec::with_capacity(expected as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(expected + 1).read_to_end(&mut data))
        .map_err(|e| err(path, e))?;
    if data.len() as u64 != expected {
        return Err(err(path, "the file changed while it was read"));
    }
    Ok(data)
}

/// Whether every channel of `texels` (Rgba16Float or Rgba32Float) is finite.
fn all_finite(texels: &[u8], format: wgpu::TextureFormat) -> bool {
    match format {
        wgpu::TextureFormat::Rgba32Float => texels
            .chunks_exact(4)
            .all(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]).is_finite()),
        // binary16: exponent all ones is infinity or NaN
        _ => texels
            .chunks_exact(2)
            .all(|c| u16::from_le_bytes([c[0], c[1]]) & 0x7c00 != 0x7c00),
    }
}
