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
const VERSION: u32 = 1;

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
        let mut out = MAGIC.to_vec();
        out.extend(VERSION.to_le_bytes());
        out.extend(key(&self.config).to_le_bytes());
        for texture in self.kept() {
            let mut bytes = Vec::new();
            for z in 0..texture.depth_or_array_layers() {
                bytes.extend(read_texture(ctx, texture, 0, z)?.bytes);
            }
            out.extend((bytes.len() as u64).to_le_bytes());
            out.extend(bytes);
        }
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| err(dir, e))?;
        }
        let tmp = path.with_extension(format!("tmp{}", std::process::id()));
        std::fs::write(&tmp, &out).map_err(|e| err(&tmp, e))?;
        std::fs::rename(&tmp, path).map_err(|e| err(path, e))
    }

    /// Reads tables for `config` written by [`BrunetonTables::save`]; fails
    /// on a missing, truncated or stale (other parameters or shaders) file.
    pub fn load(ctx: &GpuContext, config: AtmosphereConfig, path: &Path) -> Result<Self, GpuError> {
        let data = std::fs::read(path).map_err(|e| err(path, e))?;
        let header = 8 + 4 + 8;
        if data.len() < header || &data[..8] != MAGIC {
            return Err(err(path, "not a himal sky table file"));
        }
        let word = |at: usize| u64::from_le_bytes(data[at..at + 8].try_into().unwrap_or([0; 8]));
        if u32::from_le_bytes(data[8..12].try_into().unwrap_or([0; 4])) != VERSION
            || word(12) != key(&config)
        {
            return Err(err(path, "stale sky tables (other parameters or shaders)"));
        }
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
        let mut at = header;
        let mut textures = Vec::new();
        for (size, d3, format) in shapes {
            let texel = format.block_copy_size(None).unwrap_or(8);
            let expected = (size.0 * size.1 * size.2 * texel) as usize;
            if data.len() < at + 8
                || word(at) as usize != expected
                || data.len() < at + 8 + expected
            {
                return Err(err(path, "truncated sky table file"));
            }
            let t = table_texture_format(ctx, "sky.table.cached", size, d3, format);
            ctx.queue.write_texture(
                t.as_image_copy(),
                &data[at + 8..at + 8 + expected],
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(size.0 * texel),
                    rows_per_image: Some(size.1),
                },
                wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: size.2,
                },
            );
            at += 8 + expected;
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
                Err(e) => log::info!("sky tables not loaded: {e}"),
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
