//! Tile streaming: fine tiles in and out of the pool ([`TerrainPass::upload_tile`],
//! [`TerrainPass::evict`]), with the page table, the coarse grid under each
//! tile and the min/max pyramid kept in step.

use super::{TerrainCpu, TerrainPass, other};
use crate::gpu::GpuError;

/// Writes `bytes` (rows of `size.0` texels of `texel` bytes) into mip
/// `mip` of `t` at `origin` (x, y, layer): the terrain's one upload path.
pub(super) fn write_region(
    queue: &wgpu::Queue,
    t: &wgpu::Texture,
    origin: (u32, u32, u32),
    size: (u32, u32),
    mip: u32,
    texel: u32,
    bytes: &[u8],
) {
    queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: t,
            mip_level: mip,
            origin: wgpu::Origin3d {
                x: origin.0,
                y: origin.1,
                z: origin.2,
            },
            aspect: wgpu::TextureAspect::All,
        },
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size.0 * texel),
            rows_per_image: Some(size.1),
        },
        wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: 1,
        },
    );
}

impl TerrainPass {
    fn write_page(&self, queue: &wgpu::Queue, cpu: &TerrainCpu, (sx, sz): (u32, u32)) {
        let page = cpu.heights.pages[(sz * self.geometry.sectors + sx) as usize];
        write_region(
            queue,
            &self.pages,
            (sx, sz, 0),
            (1, 1),
            0,
            4,
            bytemuck::bytes_of(&page),
        );
    }

    /// Makes `heights` (`tile_res^2`, row = z) the tile of sector
    /// (`sector_x`, `sector_z`) in `slot`, replacing what the slot or the
    /// sector held; the coarse points inside the sector take the tile's
    /// values there (so coarse and fine levels meet exactly). Bad slot,
    /// sector or size: an error, nothing changed.
    pub fn upload_tile(
        &self,
        queue: &wgpu::Queue,
        slot: u32,
        sector_x: u32,
        sector_z: u32,
        heights: &[f32],
    ) -> Result<(), GpuError> {
        let mut guard = self.lock();
        let cpu = &mut *guard;
        cpu.heights
            .check_tile(slot, sector_x, sector_z, heights)
            .map_err(other)?;
        let g = self.geometry;
        let before_slot = cpu.heights.slots[slot as usize];
        let (i0, j0, side) = cpu
            .heights
            .upload(slot, sector_x, sector_z, heights)
            .map_err(other)?;
        write_region(
            queue,
            &self.fine,
            (0, 0, slot),
            (g.tile_res, g.tile_res),
            0,
            4,
            bytemuck::cast_slice(heights),
        );
        let n = g.coarse_n;
        let block: Vec<f32> = (0..side * side)
            .map(|k| cpu.heights.coarse[((j0 + k / side) * n + i0 + k % side) as usize])
            .collect();
        write_region(
            queue,
            &self.coarse,
            (i0, j0, 0),
            (side, side),
            0,
            4,
            bytemuck::cast_slice(&block),
        );
        self.write_page(queue, cpu, (sector_x, sector_z));
        if let Some(old) = before_slot.filter(|&s| s != (sector_x, sector_z)) {
            self.write_page(queue, cpu, old);
            cpu.pyramid.update_sector(&cpu.heights, old.0, old.1);
        }
        cpu.pyramid.update_sector(&cpu.heights, sector_x, sector_z);
        Ok(())
    }

    /// Frees `slot` (its sector falls back to the coarse grid). A slot out
    /// of range is an error; an empty one is left as it is.
    pub fn evict(&self, queue: &wgpu::Queue, slot: u32) -> Result<(), GpuError> {
        if slot >= self.geometry.fine_slots {
            return Err(other(format!(
                "terrain: slot {slot} is outside the pool of {}",
                self.geometry.fine_slots
            )));
        }
        let mut guard = self.lock();
        let cpu = &mut *guard;
        if let Some(sector) = cpu.heights.evict(slot) {
            self.write_page(queue, cpu, sector);
            cpu.pyramid.update_sector(&cpu.heights, sector.0, sector.1);
        }
        Ok(())
    }
}
