//! CDLOD selection and planning: the per-view patch lists and the morph
//! parameters of a frame ([`TerrainPass::prepare`]).

use glam::{Mat4, Vec3};

use super::layout::ParamsGpu;
use super::reference::{MAX_LEVELS, Patch, Ranges, SelectStats, Selector};
use super::{MAX_PATCHES, MAX_VIEWS, PATCH_TRIANGLES, TerrainPass};
use crate::gpu::{GpuContext, GpuError};
use crate::passes::cull::CullView;

/// What the selection needs of a camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainView {
    /// The LOD eye (world).
    pub eye: Vec3,
    /// Culling volume (reverse-Z; jitter does no harm).
    pub view_proj: Mat4,
    /// `height / 2 / tan(fov_y / 2)`, pixels.
    pub focal_px: f32,
}

impl TerrainView {
    /// The view of `camera` rendering a frame of `size` (width, height; px).
    pub fn from_camera(camera: &crate::scene::Camera, size: (u32, u32)) -> Self {
        let (w, h) = (size.0.max(1) as f32, size.1.max(1) as f32);
        Self {
            eye: camera.position,
            view_proj: camera.view_projection(w / h),
            focal_px: h * 0.5 / (camera.fov_y_deg.to_radians() * 0.5).tan(),
        }
    }
}

/// One frame's selection.
#[derive(Clone, Debug, PartialEq)]
pub struct TerrainStats {
    /// The camera's per-level ranges and morph constants.
    pub ranges: Ranges,
    /// What the camera view's selection did.
    pub camera: SelectStats,
    /// Per shadow view.
    pub shadows: Vec<SelectStats>,
}

impl TerrainStats {
    /// Triangles the camera's draw submits.
    pub fn triangles(&self) -> u32 {
        self.camera.patches() * PATCH_TRIANGLES
    }
}

impl TerrainPass {
    /// The ranges this pass's settings give at focal length `focal_px`.
    pub fn ranges(&self, focal_px: f32) -> Ranges {
        Ranges::new(&self.geometry, &self.settings, focal_px)
    }

    /// Plans a frame: selects the camera's patches and, with the camera's
    /// levels and morph, those of each shadow view (`shadow_views`: light
    /// view-projections, at most `MAX_VIEWS - 1`), and uploads the lists and
    /// the morph parameters. O(selected nodes).
    pub fn prepare(
        &mut self,
        queue: &wgpu::Queue,
        camera: &TerrainView,
        shadow_views: &[Mat4],
    ) -> TerrainStats {
        let g = self.geometry;
        let ranges = self.ranges(camera.focal_px);
        let shadow_views = &shadow_views[..shadow_views.len().min(MAX_VIEWS - 1)];
        let cpu = self.cpu.get_mut().unwrap_or_else(|e| e.into_inner());
        let frustum = CullView::clip(camera.view_proj);
        let select = |frustum: &CullView, out: &mut Vec<Patch>| {
            Selector {
                geometry: &g,
                pyramid: &cpu.pyramid,
                ranges: &ranges,
                eye: camera.eye,
                frustum,
                capacity: MAX_PATCHES,
            }
            .select(out)
        };
        self.selection.clear();
        let stats = select(&frustum, &mut self.selection);
        let size = std::mem::size_of::<Patch>() as u64;
        let view_bytes = MAX_PATCHES as u64 * size;
        queue.write_buffer(&self.instances, 0, bytemuck::cast_slice(&self.selection));
        self.counts = [0; MAX_VIEWS];
        self.counts[0] = self.selection.len() as u32;
        let mut shadows = Vec::with_capacity(shadow_views.len());
        let mut list = Vec::new();
        for (i, light) in shadow_views.iter().enumerate() {
            list.clear();
            let caster = CullView::caster(*light);
            shadows.push(select(&caster, &mut list));
            queue.write_buffer(
                &self.instances,
                (i as u64 + 1) * view_bytes,
                bytemuck::cast_slice(&list),
            );
            self.counts[i + 1] = list.len() as u32;
        }
        let mut level = [[0.0; 4]; MAX_LEVELS];
        for (l, v) in level.iter_mut().enumerate().take(ranges.levels as usize) {
            let coarse = if g.coarse_only(l as u32) { 1.0 } else { 0.0 };
            *v = [
                ranges.morph_start[l],
                ranges.morph_scale[l],
                g.spacing(l as u32),
                coarse,
            ];
        }
        let params = ParamsGpu {
            origin: g.origin.to_array(),
            world_size: g.world_size,
            sector_size: g.sector_size,
            coarse_spacing: g.coarse_spacing,
            fine_spacing: g.fine_spacing,
            coarse_n: g.coarse_n,
            sectors: g.sectors,
            tile_res: g.tile_res,
            layers: self.layer_count,
            morph: u32::from(ranges.morph),
            levels: ranges.levels,
            eye: camera.eye.extend(0.0).to_array(),
            level,
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        TerrainStats {
            ranges,
            camera: stats,
            shadows,
        }
    }

    /// The camera's patches of the last [`Self::prepare`].
    pub fn selection(&self) -> &[Patch] {
        &self.selection
    }

    /// Patches of `view` (0 the camera, 1 + i shadow view i) this frame.
    pub fn count(&self, view: usize) -> u32 {
        self.counts.get(view).copied().unwrap_or(0)
    }

    /// Reads back the uploaded patch list of `view` (tests).
    pub fn read_patches(&self, ctx: &GpuContext, view: usize) -> Result<Vec<Patch>, GpuError> {
        let bytes = crate::gpu::read_buffer(ctx, &self.instances)?;
        let all: Vec<Patch> = bytemuck::pod_collect_to_vec(&bytes);
        let start = view * MAX_PATCHES;
        Ok(all
            .get(start..start + self.count(view) as usize)
            .unwrap_or_default()
            .to_vec())
    }
}
