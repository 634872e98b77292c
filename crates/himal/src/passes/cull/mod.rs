//! V6 GPU culling (issue #17 item 5): per-instance frustum culling of the
//! opaque and vegetation objects for the camera and each sun cascade in one
//! compute node (`cull`, three dispatches, `cull.wgsl`), with each kept
//! object's E2 level chosen by its triangle size and distance, writing per
//! view an instance list and one indirect draw per batch and level; the
//! G-buffer and the cascades draw a whole list with one
//! `multi_draw_indexed_indirect` per pipeline. No per-object work is left
//! on the render thread.
//!
//! A batch is a run of consecutive objects of one mesh (the GPU order keeps
//! each static mesh's objects together, `gpu_scene::gpu_order`); chunks split
//! batches into 64 objects, one workgroup each. The layout is built once per
//! scene; the per-frame buffers have a fixed size ([`MAX_VIEWS`] views).
//! CPU twin: [`mod@reference`]. Adapters without indirect draws with a first
//! instance use the CPU path (`gpu_scene::SceneGpu::visible`, casters);
//! the streamed pool, which has no per-object lists, is then culled by the
//! twin and drawn directly ([`CullPath::Cpu`]).
//!
//! Optional Hi-Z occlusion ([`crate::settings::Occlusion::Hiz`], GPU path
//! only): the camera's view (view 0) also drops boxes hidden behind the
//! previous frame's depth pyramid ([`hiz`], built by `cull.hiz` after the
//! G-buffer and the terrain). Cascades, static tiles and the sky-occlusion
//! view are never occlusion-culled.

pub mod culled;
pub mod hiz;
pub mod reference;

pub use culled::{ALL, Culled, CulledArgs, FADING, SHADOW, STEADY, bind_instances};

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec4};
use wgpu::util::DeviceExt;

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, LodView, ObjectBounds, SceneGpu};
use crate::graph::{BufferDesc, Fallback, FrameGraph, TextureHandle};
use crate::scene::lod::MAX_LODS;

/// Views culled per frame at most: the camera and four cascades, and room
/// for three more (projectors, probe faces) without a new buffer size.
pub const MAX_VIEWS: usize = 8;
/// Objects per chunk (one workgroup; two 32-bit mask words).
pub const CHUNK: u32 = 64;
/// Bytes of one `DrawIndexedIndirectArgs`.
pub const ARGS_BYTES: u64 = 20;
/// Bytes of one `ChunkMask` (per view and chunk).
const MASK_BYTES: u64 = 8 * LISTS as u64 + 2 * 4 * LISTS as u64;
/// Lists per batch: kinds (steady, fading out, fading in) x levels.
pub const LISTS: usize = 3 * MAX_LODS;
/// Objects the instance entries can name (24 bits; 8 hold the fade code).
pub const MAX_OBJECTS: u32 = 1 << 24;

/// Which of an object's E2 lists: drawn whole, fading out of its level, or
/// fading into the next (complementary screen-door masks).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Drawn whole at its level.
    Steady = 0,
    /// Fading out of its level (screen-door dithered).
    FadeOut = 1,
    /// Fading into the next coarser level, drawn at that level with the complementary mask.
    FadeIn = 2,
}

/// Twin of `CullParams` in `cull.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
struct ParamsGpu {
    views: u32,
    chunks: u32,
    batches: u32,
    objects: u32,
    opaque_batches: u32,
    /// 1: Hi-Z occlusion of view 0 against the bound pyramid.
    occlusion: u32,
    _pad: [u32; 2],
    /// xyz the eye, w the E2 distance scale (0: LOD0).
    eye: [f32; 4],
    /// E2: x the transition band (a fraction of d1; 0: levels pop), y the
    /// focal length (px), z the largest geometric error (px; 0: no guard).
    lod: [f32; 4],
    /// The view-projection the Hi-Z pyramid's depth was rendered with.
    hiz_view_proj: [[f32; 4]; 4],
}

/// One culling view: six planes `n . p + w >= 0` (twin of `CullView`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CullView {
    /// The planes as (n, w): a point p is inside where `n . p + w >= 0` for all six.
    pub planes: [[f32; 4]; 6],
}

/// A plane that keeps everything.
const KEEP_ALL: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

impl CullView {
    /// A view that keeps everything (`--culling off`).
    pub const ALL: Self = Self {
        planes: [KEEP_ALL; 6],
    };

    /// The clip volume of `view_proj` (x, y in [-w, w], z in [0, w]): the
    /// camera (reverse-Z: z = 0 is the far plane). Same test as
    /// [`crate::scene::Aabb::outside_clip`].
    pub fn clip(view_proj: Mat4) -> Self {
        let r = |i: usize| view_proj.row(i);
        let planes = [
            r(3) + r(0),
            r(3) - r(0),
            r(3) + r(1),
            r(3) - r(1),
            r(2),
            r(3) - r(2),
        ];
        Self {
            planes: planes.map(|p: Vec4| p.to_array()),
        }
    }

    /// The vertical prism over the xz rectangle `min..max` (L2's height
    /// fields: everything above or below the sectors being rendered).
    pub fn prism(min: glam::Vec2, max: glam::Vec2) -> Self {
        Self {
            planes: [
                [1.0, 0.0, 0.0, -min.x],
                [-1.0, 0.0, 0.0, max.x],
                [0.0, 0.0, 1.0, -min.y],
                [0.0, 0.0, -1.0, max.y],
                KEEP_ALL,
                KEEP_ALL,
            ],
        }
    }

    /// A sun map's volume without its near plane: casters between the sun
    /// and the map still cast (as `ShadowFit::may_cast`).
    pub fn caster(light_view_proj: Mat4) -> Self {
        let mut v = Self::clip(light_view_proj);
        v.planes[4] = KEEP_ALL;
        v
    }
}

/// Twin of `Chunk`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ChunkGpu {
    /// Index of the chunk's batch in [`CullLayout::batches`].
    pub batch: u32,
    /// First object of the chunk.
    pub first_object: u32,
    /// Objects in the chunk ([`CHUNK`] at most; 0 in a streamed region until it is filled).
    pub count: u32,
    _pad: u32,
}

/// Twin of `Batch`: consecutive objects of one mesh, and its levels'
/// index ranges (E2; unused levels are empty).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BatchGpu {
    /// First of the batch's chunks in [`CullLayout::chunks`].
    pub first_chunk: u32,
    /// Chunks of the batch.
    pub chunks: u32,
    /// First of the batch's consecutive objects.
    pub first_object: u32,
    /// Levels of the mesh in `lod` (1: LOD0 alone).
    pub lods: u32,
    /// Base vertex of the mesh in the scene's vertex buffer (all levels).
    pub base_vertex: i32,
    /// Culled beyond this distance from the LOD eye (m; 0: no limit).
    pub max_distance: f32,
    _pad: [u32; 2],
    /// Per level: first index, index count.
    pub lod: [[u32; 2]; MAX_LODS],
    /// Per level: geometric error (mesh units).
    pub error: [f32; MAX_LODS],
    _tail: u32,
}

// `Batch` in cull.wgsl: 8-byte aligned, 96 bytes.
const _: () = assert!(std::mem::size_of::<BatchGpu>() == 96);

/// Which pipeline a batch draws with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum List {
    /// The opaque batches: the scene's runs, then the opaque streamed regions.
    Opaque = 0,
    /// The vegetation batches: the scene's runs, then the vegetation streamed regions.
    Vegetation = 1,
}

/// The scene's batches and chunks: opaque batches first, then vegetation.
#[derive(Clone, Debug, Default)]
pub struct CullLayout {
    /// Every batch: the opaque ones, then vegetation.
    pub batches: Vec<BatchGpu>,
    /// Every batch's chunks, in batch order.
    pub chunks: Vec<ChunkGpu>,
    /// Culling bounds per object (the CPU copy of `cull.bounds`).
    pub bounds: Vec<ObjectBounds>,
    /// Opaque batches (opaque streamed regions included): the first in `batches`.
    pub opaque_batches: u32,
    /// Vegetation batches (vegetation streamed regions included), after the opaque ones.
    pub vegetation_batches: u32,
    /// Objects in the scene (the stride of the per-view instance lists).
    pub objects: u32,
    /// The batch of each streamed region (`SceneGpu::pool`): the opaque
    /// regions' after the opaque runs, the vegetation regions' after the
    /// vegetation runs ([`CullLayout::pool_range`]).
    pub pool_batches: Vec<u32>,
    /// The scene mesh each batch draws.
    pub batch_mesh: Vec<u32>,
    /// V3: the batches whose mesh ends in an impostor level.
    pub impostor_batches: Vec<u32>,
    /// Whether their `lods` count the impostor level ([`CullPass::set_impostors`]).
    pub impostors: bool,
    /// Per chunk: the box around its objects' boxes, `None` until
    /// [`CullLayout::refresh_chunk_boxes`] after they changed (the CPU
    /// path's early-out: a chunk whose box a view culls has every object culled).
    pub chunk_boxes: Vec<Option<ChunkBox>>,
}

/// The box around a chunk's objects' boxes, grown by [`ChunkBox::SLACK`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChunkBox {
    /// Centre in world space (metres).
    pub center: glam::Vec3,
    /// Half size per axis in metres, slack included.
    pub half_extent: glam::Vec3,
}

impl ChunkBox {
    /// Metres added to the half extent, so rounding in the plane and
    /// distance tests never makes the box culled where one of its objects is kept.
    pub const SLACK: f32 = 0.01;

    /// Around `bounds` (objects with an empty box, such as
    /// `ObjectBounds::NONE`, add nothing); `None` when none has a box.
    pub fn around(bounds: &[ObjectBounds]) -> Option<Self> {
        let (lo, hi) = bounds
            .iter()
            .filter(|b| b.half_extent().min_element() >= 0.0)
            .map(|b| (b.center() - b.half_extent(), b.center() + b.half_extent()))
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
        Some(Self {
            center: (lo + hi) * 0.5,
            half_extent: (hi - lo) * 0.5 + Self::SLACK,
        })
    }
}

impl CullLayout {
    /// Batches of `scene`'s opaque and vegetation lists (runs of one mesh
    /// over consecutive objects), split into chunks of [`CHUNK`].
    pub fn new(scene: &SceneGpu) -> Self {
        let mut layout = Self {
            bounds: scene.cull_bounds.clone(),
            objects: scene.cull_bounds.len() as u32,
            impostors: true,
            ..Self::default()
        };
        layout.pool_batches = vec![0; scene.pool.len()];
        layout.opaque_batches = layout.push_runs(scene, &scene.draws_opaque);
        // Streamed regions: one batch each, chunks empty until streaming
        // fills them; the opaque ones after the opaque runs, the vegetation
        // ones (trees' leaves) after the vegetation runs.
        layout.opaque_batches += layout.push_pool(scene, false);
        layout.vegetation_batches = layout.push_runs(scene, &scene.draws_vegetation);
        layout.vegetation_batches += layout.push_pool(scene, true);
        layout.chunk_boxes = vec![None; layout.chunks.len()];
        layout.refresh_chunk_boxes();
        layout
    }

    /// Recomputes the boxes of chunks whose objects changed.
    pub fn refresh_chunk_boxes(&mut self) {
        for (c, slot) in self.chunks.iter().zip(&mut self.chunk_boxes) {
            if slot.is_none() {
                let at = c.first_object as usize;
                *slot = (self.bounds.get(at..at + c.count as usize)).and_then(ChunkBox::around);
            }
        }
    }

    /// Forgets the boxes of the chunks of objects `first..first + n` (batches
    /// are consecutive objects, so their chunks are sorted by first object).
    pub fn invalidate_chunk_boxes(&mut self, first: u32, n: u32) {
        let end = first + n;
        let from = self
            .chunks
            .partition_point(|c| c.first_object + CHUNK <= first);
        for (c, slot) in self.chunks[from..]
            .iter()
            .zip(&mut self.chunk_boxes[from..])
        {
            if c.first_object >= end {
                break;
            }
            *slot = None;
        }
    }

    /// One empty batch per streamed region of `scene` that is vegetation
    /// (or not); returns the batches added.
    fn push_pool(&mut self, scene: &SceneGpu, vegetation: bool) -> u32 {
        let before = self.batches.len();
        for (i, r) in scene.pool.iter().enumerate() {
            if r.foliage.is_some() != vegetation {
                continue;
            }
            let Some(&(first_index, index_count, base_vertex)) =
                scene.mesh_ranges.get(r.mesh as usize)
            else {
                continue;
            };
            let d = Draw {
                first_index,
                index_count,
                base_vertex,
                object: r.first_object,
            };
            self.pool_batches[i] = self.batches.len() as u32;
            self.push_batch(scene, &d, r.capacity);
            let b = self.batches.len() - 1;
            self.batches[b].max_distance = r.max_distance;
            let first = self.batches[b].first_chunk as usize;
            for c in &mut self.chunks[first..] {
                c.count = 0;
            }
        }
        (self.batches.len() - before) as u32
    }

    /// The streamed regions' batches inside `list` (first, count; they are
    /// consecutive, after the list's own runs).
    pub fn pool_range(&self, list: List) -> (u32, u32) {
        let (first, count) = self.range(list);
        let inside = self
            .pool_batches
            .iter()
            .filter(|&&b| b >= first && b < first + count);
        let n = inside.clone().count() as u32;
        (inside.copied().min().unwrap_or(first + count), n)
    }

    fn push_runs(&mut self, scene: &SceneGpu, draws: &[Draw]) -> u32 {
        let before = self.batches.len();
        for (d, n) in crate::gpu_scene::runs(draws) {
            self.push_batch(scene, d, n);
        }
        (self.batches.len() - before) as u32
    }

    /// One batch of `n` consecutive objects from `d.object`, drawing `d`'s mesh.
    fn push_batch(&mut self, scene: &SceneGpu, d: &Draw, n: u32) {
        {
            let batch = self.batches.len() as u32;
            let first_chunk = self.chunks.len() as u32;
            for start in (0..n).step_by(CHUNK as usize) {
                self.chunks.push(ChunkGpu {
                    batch,
                    first_object: d.object + start,
                    count: (n - start).min(CHUNK),
                    _pad: 0,
                });
            }
            // The mesh's levels (E2); LOD0 is the draw's own range.
            let mesh = scene.object_mesh.get(d.object as usize);
            let levels = mesh.and_then(|&m| scene.lods.get(m as usize));
            let mut lod = [[0; 2]; MAX_LODS];
            let mut error = [0.0; MAX_LODS];
            lod[0] = [d.first_index, d.index_count];
            let mut lods = 1;
            for (l, r) in levels.into_iter().flatten().enumerate().skip(1) {
                if l < MAX_LODS {
                    lod[l] = [r.first_index, r.index_count];
                    error[l] = r.error;
                    lods = l as u32 + 1;
                }
            }
            let m = mesh.copied().unwrap_or(0);
            if lods > crate::scene::tree::impostor_level::LEVELS as u32
                && scene
                    .impostor_mesh
                    .get(m as usize)
                    .copied()
                    .unwrap_or(false)
            {
                self.impostor_batches.push(self.batches.len() as u32);
            }
            self.batch_mesh.push(m);
            self.batches.push(BatchGpu {
                first_chunk,
                chunks: self.chunks.len() as u32 - first_chunk,
                first_object: d.object,
                lods,
                base_vertex: d.base_vertex,
                max_distance: 0.0,
                _pad: [0; 2],
                lod,
                error,
                _tail: 0,
            });
        }
    }

    /// Whether some batch has more than one level (E2 fading lists exist).
    pub fn has_lods(&self) -> bool {
        self.batches.iter().any(|b| b.lods > 1)
    }

    /// Multi-draws one culled view records in the G-buffer (`true`: the
    /// opaque steady and fading lists; the vegetation's cards and, with
    /// impostors, their levels, one per kind each) or a shadow map (one
    /// per list).
    pub fn draw_calls(&self, gbuffer: bool) -> u32 {
        let fading = u32::from(gbuffer && self.has_lods() && self.opaque_batches > 0);
        let vegetation = match (self.vegetation_batches > 0, gbuffer) {
            (false, _) => 0,
            (true, false) => 1,
            (true, true) => {
                let impostors = self.impostors && !self.impostor_batches.is_empty();
                3 * (1 + u32::from(impostors))
            }
        };
        u32::from(self.opaque_batches > 0) + fading + vegetation
    }

    /// Index of the arguments of (`batch`, `kind`, `level`) in view `view`
    /// (`args_index` in `cull.wgsl`): per view the opaque batches' then the
    /// vegetation batches', each `[kind][level][batch]`.
    pub fn args_index(&self, view: usize, batch: usize, kind: usize, level: usize) -> usize {
        let (opaque, all) = (self.opaque_batches as usize, self.batches.len());
        let i = if batch < opaque {
            (kind * MAX_LODS + level) * opaque + batch
        } else {
            LISTS * opaque + (kind * MAX_LODS + level) * (all - opaque) + batch - opaque
        };
        view * all * LISTS + i
    }

    /// First batch and count of `list` (each batch has [`MAX_LODS`] draws).
    pub fn range(&self, list: List) -> (u32, u32) {
        match list {
            List::Opaque => (0, self.opaque_batches),
            List::Vegetation => (self.opaque_batches, self.vegetation_batches),
        }
    }
}

/// How [`CullPass::plan`] culls this frame's views.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CullPath {
    /// The `cull` node, where the adapter can draw its lists (else `Cpu`).
    Gpu,
    /// The streamed pool by the CPU twin ([`reference::cull_batch`]), its
    /// lists uploaded and drawn directly; scene objects are left to the
    /// passes' own CPU lists. `instanced`: one draw per list, else per
    /// instance.
    Cpu {
        /// One instanced draw per non-empty list, else one draw per instance.
        instanced: bool,
    },
}

/// V6 culling: the `cull` node's pipelines and buffers, the scene's layout and the CPU path's
/// lists.
pub struct CullPass {
    program: Program,
    test: wgpu::ComputePipeline,
    args: wgpu::ComputePipeline,
    write: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    views: wgpu::Buffer,
    bounds: wgpu::Buffer,
    chunks: wgpu::Buffer,
    batches: wgpu::Buffer,
    /// The identity, then [`MAX_VIEWS`] lists of `objects` entries (fixed).
    instances: wgpu::Buffer,
    /// The scene's batches and chunks (bounds follow the streamed regions).
    pub layout: CullLayout,
    /// Why the GPU path cannot run here (`None`: it can).
    unsupported: Option<String>,
    /// Views planned on the GPU this frame.
    planned: u32,
    /// Views whose pool lists the CPU twin wrote this frame ([`CullPath::Cpu`]),
    /// their arguments (laid out as the GPU's; scene batches empty), whether
    /// they draw instanced, and the lists' scratch (reused, never shrunk
    /// below the largest frame's).
    cpu: CpuLists,
    /// V6 Hi-Z: the previous frame's depth pyramid.
    pub hiz: hiz::HizPyramid,
    /// Per streamed region: its live objects ([`CullPass::set_live`]) and
    /// whether it is vegetation (hidden by [`CullPass::show_pool_vegetation`]).
    pool_live: Vec<(u32, bool)>,
    /// Whether the vegetation regions draw.
    pool_vegetation: bool,
    /// Whether view 0 is occlusion-culled this frame (the pyramid valid).
    occlusion: bool,
}

#[derive(Default)]
struct CpuLists {
    views: u32,
    args: Vec<[u32; 5]>,
    instanced: bool,
    lists: [Vec<u32>; LISTS],
    entries: Vec<u32>,
}

impl CullPass {
    /// Pipelines and `scene`'s layout (bounds, chunks, batches; uploaded once).
    pub fn new(ctx: &GpuContext, scene: &SceneGpu) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/cull/cull.wgsl")?;
        let layout = CullLayout::new(scene);
        let storage = |label: &str, bytes: &[u8]| {
            let mut contents = bytes.to_vec();
            if contents.is_empty() {
                contents.resize(16, 0);
            }
            ctx.device
                .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents: &contents,
                    usage: wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                })
        };
        let features = ctx.device.features();
        let downlevel = ctx.adapter.get_downlevel_capabilities();
        let max_groups = ctx.device.limits().max_compute_workgroups_per_dimension;
        let unsupported = if !features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE) {
            Some("the adapter has no indirect draws with a first instance".to_string())
        } else if !downlevel
            .flags
            .contains(wgpu::DownlevelFlags::INDIRECT_EXECUTION)
        {
            Some("the adapter has no indirect execution".to_string())
        } else if layout.objects >= MAX_OBJECTS {
            Some(format!(
                "{} objects exceed the {MAX_OBJECTS} an instance entry can name",
                layout.objects
            ))
        } else if layout.chunks.len().max(layout.batches.len()) as u64 > u64::from(max_groups) {
            Some(format!(
                "{} chunks or {} batches exceed the adapter's {max_groups} workgroups per dimension",
                layout.chunks.len(),
                layout.batches.len()
            ))
        } else {
            None
        };
        let views = vec![CullView::zeroed(); MAX_VIEWS];
        let n = layout.objects.max(1) as usize;
        let mut instances: Vec<u32> = (0..n as u32).collect();
        instances.resize(n * (1 + 2 * MAX_VIEWS), 0);
        Ok(Self {
            test: program.compute_pipeline(ctx, "cs_test", &[])?,
            args: program.compute_pipeline(ctx, "cs_args", &[])?,
            write: program.compute_pipeline(ctx, "cs_write", &[])?,
            program,
            params: crate::gpu::pipeline::uniform_buffer(ctx, "cull.params", &ParamsGpu::default()),
            views: storage("cull.views", bytemuck::cast_slice(&views)),
            bounds: storage("cull.bounds", bytemuck::cast_slice(&layout.bounds)),
            chunks: storage("cull.chunks", bytemuck::cast_slice(&layout.chunks)),
            batches: storage("cull.batches", bytemuck::cast_slice(&layout.batches)),
            instances: storage("cull.instances", bytemuck::cast_slice(&instances)),
            layout,
            unsupported,
            planned: 0,
            cpu: CpuLists::default(),
            hiz: hiz::HizPyramid::new(ctx)?,
            occlusion: false,
            pool_live: scene.pool.iter().map(|r| (0, r.vegetation)).collect(),
            pool_vegetation: true,
        })
    }

    /// V3 `--impostors on|off`: off, the impostor batches' level count
    /// drops their two impostor levels (LOD2 stays to the end), on brings them back;
    /// rewrites those batches where the state changes.
    pub fn set_impostors(&mut self, queue: &wgpu::Queue, on: bool) {
        if self.layout.impostors == on {
            return;
        }
        self.layout.impostors = on;
        for &b in &self.layout.impostor_batches {
            let Some(batch) = self.layout.batches.get_mut(b as usize) else {
                continue;
            };
            let n = crate::scene::tree::impostor_level::LEVELS as u32;
            batch.lods = if on { batch.lods + n } else { batch.lods - n };
            let offset = b as u64 * std::mem::size_of::<BatchGpu>() as u64;
            queue.write_buffer(&self.batches, offset, bytemuck::bytes_of(&*batch));
        }
    }

    /// Writes the culling bounds of objects from `first_object` on
    /// (streamed regions; the CPU copy in `layout` follows).
    pub fn write_bounds(
        &mut self,
        queue: &wgpu::Queue,
        first_object: u32,
        bounds: &[ObjectBounds],
    ) {
        let at = first_object as usize;
        let Some(dst) = self.layout.bounds.get_mut(at..at + bounds.len()) else {
            return;
        };
        dst.copy_from_slice(bounds);
        (self.layout).invalidate_chunk_boxes(first_object, bounds.len() as u32);
        let offset = at as u64 * std::mem::size_of::<ObjectBounds>() as u64;
        queue.write_buffer(&self.bounds, offset, bytemuck::cast_slice(bounds));
    }

    /// Streamed region `region` holds `live` objects packed from its front:
    /// its chunks' counts cover them and no more (empty chunks cost a
    /// workgroup that exits at once); none while it is hidden vegetation.
    pub fn set_live(&mut self, queue: &wgpu::Queue, region: usize, live: u32) {
        let Some(r) = self.pool_live.get_mut(region) else {
            return;
        };
        r.0 = live;
        let shown = if r.1 && !self.pool_vegetation {
            0
        } else {
            live
        };
        self.write_counts(queue, region, shown);
    }

    /// `FrameSettings::vegetation` for the streamed regions: off, the
    /// vegetation regions (trees' trunks and leaves) list nothing on either
    /// culling path; on, their live objects again.
    pub fn show_pool_vegetation(&mut self, queue: &wgpu::Queue, on: bool) {
        if self.pool_vegetation == on {
            return;
        }
        self.pool_vegetation = on;
        for region in 0..self.pool_live.len() {
            let (live, vegetation) = self.pool_live[region];
            if vegetation {
                self.write_counts(queue, region, if on { live } else { 0 });
            }
        }
    }

    /// Sets region `region`'s chunk counts to cover `live` objects.
    fn write_counts(&mut self, queue: &wgpu::Queue, region: usize, live: u32) {
        let Some(&batch) = (self.layout.pool_batches.get(region))
            .and_then(|&b| self.layout.batches.get(b as usize))
        else {
            return;
        };
        let first = batch.first_chunk as usize;
        let chunks = &mut self.layout.chunks[first..first + batch.chunks as usize];
        let boxes = &mut self.layout.chunk_boxes[first..first + batch.chunks as usize];
        let mut changed = false;
        for (i, (c, b)) in chunks.iter_mut().zip(boxes).enumerate() {
            let count = live.saturating_sub(i as u32 * CHUNK).min(CHUNK);
            if c.count != count {
                changed = true;
                *b = None;
            }
            c.count = count;
        }
        if changed {
            let offset = first as u64 * std::mem::size_of::<ChunkGpu>() as u64;
            queue.write_buffer(&self.chunks, offset, bytemuck::cast_slice(chunks));
        }
    }

    /// Whether the GPU path runs on this adapter and scene; else why not.
    pub fn supported(&self) -> Result<(), &str> {
        self.unsupported.as_deref().map_or(Ok(()), Err)
    }

    /// Uploads this frame's views (the first [`MAX_VIEWS`]) and the LOD
    /// selection (every view draws at the levels seen from `lod.eye`, so
    /// shadows match the G-buffer); no views: the node is left out. Where
    /// `path` is [`CullPath::Cpu`] or the GPU path cannot run, the CPU twin
    /// culls the streamed pool for the views instead. Returns the views
    /// planned on the GPU.
    pub fn plan(
        &mut self,
        ctx: &GpuContext,
        views: &[CullView],
        lod: LodView,
        path: CullPath,
    ) -> u32 {
        let views = &views[..views.len().min(MAX_VIEWS)];
        let gpu = path == CullPath::Gpu && self.supported().is_ok();
        self.planned = if gpu { views.len() as u32 } else { 0 };
        // Hi-Z: only against a pyramid this frame's graph binds.
        let hiz = (gpu && self.hiz.building()).then(|| self.hiz.previous());
        let hiz = hiz.flatten();
        self.occlusion = hiz.is_some();
        self.cpu.views = 0;
        if !gpu {
            let instanced = !matches!(path, CullPath::Cpu { instanced: false });
            self.plan_cpu(&ctx.queue, views, &lod, instanced);
        }
        if self.planned > 0 {
            let l = &self.layout;
            let params = ParamsGpu {
                views: self.planned,
                chunks: l.chunks.len() as u32,
                batches: l.batches.len() as u32,
                objects: l.objects,
                opaque_batches: l.opaque_batches,
                occlusion: u32::from(self.occlusion),
                _pad: [0; 2],
                eye: lod.eye.extend(lod.selection.scale).to_array(),
                lod: [
                    lod.selection.band,
                    lod.selection.focal_px,
                    lod.selection.max_error_px,
                    lod.selection.object_scale,
                ],
                hiz_view_proj: hiz.unwrap_or(Mat4::IDENTITY).to_cols_array_2d(),
            };
            ctx.queue
                .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
            ctx.queue
                .write_buffer(&self.views, 0, bytemuck::cast_slice(views));
        }
        self.planned
    }

    /// The CPU path of the streamed pool: [`reference::cull_batch`] per view
    /// and pool batch, each batch's lists written where the GPU would write
    /// them (one upload per view and batch), the arguments kept for direct
    /// draws. Scene objects are not culled here (their passes' CPU lists
    /// draw them). Nothing to do without a pool, or with more objects than
    /// an entry can name (the fade code shares the word).
    fn plan_cpu(
        &mut self,
        queue: &wgpu::Queue,
        views: &[CullView],
        lod: &LodView,
        instanced: bool,
    ) {
        let l = &self.layout;
        if l.pool_batches.is_empty() || l.objects >= MAX_OBJECTS || views.is_empty() {
            return;
        }
        self.layout.refresh_chunk_boxes();
        let l = &self.layout;
        let cpu = &mut self.cpu;
        cpu.views = views.len() as u32;
        cpu.instanced = instanced;
        cpu.args.clear();
        cpu.args
            .resize(views.len() * l.batches.len() * LISTS, [0; 5]);
        for (v, view) in views.iter().enumerate() {
            for &b in &l.pool_batches {
                let batch = &l.batches[b as usize];
                let args = reference::cull_batch(l, v, view, batch, lod, &mut cpu.lists);
                cpu.entries.clear();
                for list in &cpu.lists {
                    cpu.entries.extend_from_slice(list);
                }
                for (j, a) in args.into_iter().enumerate() {
                    cpu.args[l.args_index(v, b as usize, j / MAX_LODS, j % MAX_LODS)] = a;
                }
                if !cpu.entries.is_empty() {
                    let offset = u64::from(reference::region(l, v, batch)) * 4;
                    queue.write_buffer(&self.instances, offset, bytemuck::cast_slice(&cpu.entries));
                }
            }
        }
    }

    /// Views planned on the GPU this frame.
    pub fn planned(&self) -> u32 {
        self.planned
    }

    /// Views whose pool lists the CPU twin culled this frame.
    pub fn cpu_planned(&self) -> u32 {
        self.cpu.views
    }

    /// Draw calls view `view`'s pool lists of `kinds` record this frame:
    /// one multi-draw per kind on the GPU path, the non-empty lists (or
    /// their instances, not instanced) on the CPU path.
    pub fn pool_calls(&self, view: u32, kinds: std::ops::Range<u32>) -> u32 {
        let l = &self.layout;
        if l.pool_batches.is_empty() {
            return 0;
        }
        if self.planned > view {
            return kinds.len() as u32;
        }
        if self.cpu.views <= view {
            return 0;
        }
        let mut calls = 0;
        for kind in kinds {
            for &b in &l.pool_batches {
                for level in 0..MAX_LODS {
                    let at = l.args_index(view as usize, b as usize, kind as usize, level);
                    let n = self.cpu.args.get(at).map_or(0, |a| a[1]);
                    calls += if self.cpu.instanced {
                        u32::from(n > 0)
                    } else {
                        n
                    };
                }
            }
        }
        calls
    }

    /// Whether the camera's view is occlusion-culled this frame.
    pub fn occlusion(&self) -> bool {
        self.occlusion
    }

    /// The `cull` node for the planned views; `None` when none are planned
    /// or the scene has no opaque or vegetation objects. `hiz`: last
    /// frame's pyramid as imported ([`hiz::HizPyramid::import_read`]).
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        hiz: Option<TextureHandle>,
    ) -> Option<Culled<'a>> {
        let l = &self.layout;
        if l.batches.is_empty() {
            return None;
        }
        let culled = |instances, args| Culled::new(l, instances, args);
        if self.planned == 0 {
            // The CPU twin's pool lists, already uploaded: no node.
            let instances = graph.import_buffer("cull.instances", &self.instances);
            let args = CulledArgs::Cpu {
                args: &self.cpu.args,
                instanced: self.cpu.instanced,
            };
            return (self.cpu.views > 0).then(|| culled(instances, args));
        }
        // Fixed sizes (MAX_VIEWS): the graph's pool reuses one allocation.
        let views = MAX_VIEWS as u64;
        let masks = graph.create_buffer(
            "cull.masks",
            BufferDesc::new(views * l.chunks.len() as u64 * MASK_BYTES),
        );
        let args = graph.create_buffer(
            "cull.args",
            BufferDesc::new(views * (l.batches.len() * LISTS) as u64 * ARGS_BYTES),
        );
        let instances = graph.import_buffer("cull.instances", &self.instances);
        let (chunks, batches, n) = (l.chunks.len() as u32, l.batches.len() as u32, self.planned);
        let (args_pipeline, write) = (&self.args, &self.write);
        let written = graph
            .compute("cull", &self.program)
            .compute_pipeline(Ok(self.test.clone()))
            .uniform("params", &self.params)
            .uniform("views", &self.views)
            .uniform("bounds", &self.bounds)
            .uniform("chunks", &self.chunks)
            .uniform("batches", &self.batches)
            .write_buffer("masks", masks)
            .write_buffer("args", args)
            .write_buffer("instances", instances)
            // Unread unless `occlusion` is set (then it is the pyramid).
            .optional("hiz_load", hiz, Fallback::Black)
            .dispatch_with(move |cp| {
                cp.dispatch_workgroups(chunks, n, 1);
                cp.set_pipeline(args_pipeline);
                cp.dispatch_workgroups(batches, n, 1);
                cp.set_pipeline(write);
                cp.dispatch_workgroups(chunks, n, 1);
            });
        Some(culled(
            written.buffer(instances),
            CulledArgs::Gpu(written.buffer(args)),
        ))
    }

    /// Runs the node for `views` alone and reads back each view's draw
    /// arguments and instance lists, per (view, batch, kind, level) as
    /// [`reference::cull`] orders them (tests, statistics). With Hi-Z on,
    /// view 0 is also tested against the pyramid the last frame culled
    /// against (occlusion is not in the twin's lists).
    pub fn read_back(
        &mut self,
        ctx: &GpuContext,
        views: &[CullView],
        lod: LodView,
    ) -> Result<reference::CullResult, crate::Error> {
        let n = self.plan(ctx, views, lod, CullPath::Gpu) as usize;
        let l = &self.layout;
        let draws = l.batches.len() * LISTS;
        let mut result = reference::CullResult {
            args: vec![[0; 5]; n * draws],
            instances: vec![Vec::new(); n * draws],
        };
        let copy = |label, size: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let args_size = (MAX_VIEWS * draws) as u64 * ARGS_BYTES;
        let inst_size = self.instances.size();
        let (args_copy, inst_copy) = (
            copy("cull.args.copy", args_size),
            copy("cull.instances.copy", inst_size),
        );
        {
            let mut graph = FrameGraph::new();
            // The pyramid the last frame culled against (view 0
            // occlusion-culled where `plan` found it valid).
            let hiz = self.hiz.import_read(&mut graph);
            let Some((culled, CulledArgs::Gpu(culled_args))) =
                self.add(&mut graph, hiz).map(|c| (c, c.args))
            else {
                return Ok(result);
            };
            let dst_args = graph.import_buffer("cull.args.copy", &args_copy);
            let dst_inst = graph.import_buffer("cull.instances.copy", &inst_copy);
            let mut pass = graph.add_pass("cull.read_back");
            let src_args = pass.read_buffer(culled_args, crate::graph::BufferAccess::CopySrc);
            let src_inst = pass.read_buffer(culled.instances, crate::graph::BufferAccess::CopySrc);
            let dst_args = pass.write_buffer(dst_args, crate::graph::BufferAccess::CopyDst);
            let dst_inst = pass.write_buffer(dst_inst, crate::graph::BufferAccess::CopyDst);
            pass.execute(move |pc| {
                let (a, i) = (pc.buffer(src_args), pc.buffer(src_inst));
                let (da, di) = (pc.buffer(dst_args), pc.buffer(dst_inst));
                pc.encoder.copy_buffer_to_buffer(a, 0, da, 0, args_size);
                pc.encoder.copy_buffer_to_buffer(i, 0, di, 0, inst_size);
                Ok(())
            });
            graph.mark_buffer_output(dst_args);
            graph.mark_buffer_output(dst_inst);
            let mut pool = crate::graph::TexturePool::new();
            let commands = graph.compile()?.execute(&ctx.device, &mut pool, None)?;
            ctx.queue.submit([commands]);
        }
        let args: Vec<u32> =
            bytemuck::pod_collect_to_vec(&crate::gpu::read_buffer(ctx, &args_copy)?);
        let inst: Vec<u32> =
            bytemuck::pod_collect_to_vec(&crate::gpu::read_buffer(ctx, &inst_copy)?);
        for v in 0..n {
            for (b, batch) in l.batches.iter().enumerate() {
                for list in 0..LISTS {
                    let (kind, lod) = (list / MAX_LODS, list % MAX_LODS);
                    let k = (v * l.batches.len() + b) * LISTS + list;
                    let at = l.args_index(v, b, kind, lod);
                    let a: [u32; 5] = std::array::from_fn(|j| args[at * 5 + j]);
                    let start = a[4] as usize;
                    let list = (a[4] >= reference::region(l, v, batch))
                        .then(|| inst.get(start..start + a[1] as usize))
                        .flatten()
                        .ok_or_else(|| {
                            GpuError::Other(format!(
                                "cull: view {v} batch {b} level {lod} has arguments {a:?}"
                            ))
                        })?;
                    result.instances[k] = list.to_vec();
                    result.args[k] = a;
                }
            }
        }
        Ok(result)
    }
}
