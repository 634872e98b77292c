//! V6 Hi-Z occlusion (issue #17 item 5): a min-depth pyramid of the frame's
//! depth after the G-buffer and the terrain (`cull.hiz`, then
//! `cull.hiz.mip1..`, one node per mip), kept to the next frame with the
//! view-projection it was rendered with. The next frame's `cull` node
//! reprojects each camera object's box with that matrix and drops it when
//! it lies behind every texel its screen rectangle touches
//! (`shaders/hiz.wgsl`). Reverse-Z: z = 0 is the far plane, so a coarser
//! texel keeps the minimum of its parents. CPU twin:
//! [`super::reference::hiz_build`], [`super::reference::hiz_occluded`].
//!
//! The pyramids are persistent (two, owned here, imported into the graph,
//! the last mip's write marked as an output); a new size, a camera cut
//! ([`HizPyramid::reset`]) or a frame that did not build one leaves none
//! valid, and the next frame culls without it.

use glam::Mat4;

use super::reference::HizMip;
use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureHandle};

/// The pyramid's format: depth as it was, min-reduced.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const WORKGROUP: u32 = 8;

/// Mips of a full chain for a `width` x `height` depth (down to 1 x 1).
pub fn mip_count(width: u32, height: u32) -> u32 {
    32 - width.max(height).max(1).leading_zeros()
}

fn mip_view(mip: u32) -> wgpu::TextureViewDescriptor<'static> {
    wgpu::TextureViewDescriptor {
        base_mip_level: mip,
        mip_level_count: Some(1),
        ..Default::default()
    }
}

/// The Hi-Z pyramids: pipelines, two persistent textures and what they
/// hold. A frame's `cull` reads the pyramid the previous frame wrote while
/// `cull.hiz` writes the other, so the one a frame culled against is still
/// there after it ([`crate::Renderer::count_drawn`] counts what the frame
/// drew).
pub struct HizPyramid {
    depth_program: Program,
    reduce_program: Program,
    copy: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    /// Two pyramids of the frame's size (none while occlusion is off).
    textures: Vec<wgpu::Texture>,
    /// Per pyramid, the (jittered) view-projection of the depth it holds;
    /// `None`: nothing valid (first frame, new size, camera cut).
    view_proj: [Option<Mat4>; 2],
    /// The pyramid the last frame wrote.
    latest: usize,
    /// The pyramid this (or the last drawn) frame's `cull` reads.
    read: Option<usize>,
    /// Whether this frame's graph builds a pyramid.
    building: bool,
}

impl HizPyramid {
    /// The pipelines; no texture until a frame asks for one.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let depth_program = Program::new(ctx, "passes/cull/hiz_depth.wgsl")?;
        let reduce_program = Program::new(ctx, "passes/cull/hiz.wgsl")?;
        Ok(Self {
            copy: depth_program.compute_pipeline(ctx, "cs_depth", &[])?,
            reduce: reduce_program.compute_pipeline(ctx, "cs_reduce", &[])?,
            depth_program,
            reduce_program,
            textures: Vec::new(),
            view_proj: [None; 2],
            latest: 0,
            read: None,
            building: false,
        })
    }

    /// This frame builds a pyramid at `size` and culls against the last
    /// one (`on`), or neither: off frees both. A new size starts empty.
    pub fn prepare(&mut self, device: &wgpu::Device, size: (u32, u32), on: bool) {
        self.building = on;
        if !on {
            self.textures.clear();
            self.reset();
            return;
        }
        let (w, h) = (size.0.max(1), size.1.max(1));
        let sized = self.textures.first().map(|t| (t.width(), t.height()));
        if sized != Some((w, h)) {
            self.reset();
            self.textures = (0..2)
                .map(|_| {
                    device.create_texture(&wgpu::TextureDescriptor {
                        label: Some("cull.hiz"),
                        size: wgpu::Extent3d {
                            width: w,
                            height: h,
                            depth_or_array_layers: 1,
                        },
                        mip_level_count: mip_count(w, h),
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: FORMAT,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING
                            | wgpu::TextureUsages::STORAGE_BINDING
                            | wgpu::TextureUsages::COPY_SRC,
                        view_formats: &[],
                    })
                })
                .collect();
        }
        self.read = self.view_proj[self.latest].map(|_| self.latest);
    }

    /// Whether this frame's graph builds a pyramid.
    pub fn building(&self) -> bool {
        self.building && !self.textures.is_empty()
    }

    /// The view-projection of the pyramid `cull` reads, where one is valid.
    pub fn previous(&self) -> Option<Mat4> {
        self.read.and_then(|i| self.view_proj[i])
    }

    /// Camera cut (or a failed frame): no pyramid describes what the camera sees.
    pub fn reset(&mut self) {
        self.view_proj = [None; 2];
        self.read = None;
    }

    /// After the frame's submit: the pyramid it built holds the depth
    /// rendered with `view_proj` (a frame that built none leaves none valid).
    pub fn frame_done(&mut self, view_proj: Mat4) {
        if self.building() {
            self.latest = 1 - self.latest;
            self.view_proj[self.latest] = Some(view_proj);
        } else {
            self.reset();
        }
    }

    /// Bytes of both pyramids (all mips).
    pub fn bytes(&self) -> u64 {
        let texel = |t: &wgpu::Texture| {
            (0..t.mip_level_count())
                .map(|m| u64::from((t.width() >> m).max(1)) * u64::from((t.height() >> m).max(1)))
                .sum::<u64>()
        };
        self.textures.iter().map(|t| 4 * texel(t)).sum()
    }

    /// The pyramid `cull` reads in `graph` (`None`: nothing valid to read).
    pub fn import_read<'a>(&'a self, graph: &mut FrameGraph<'a>) -> Option<TextureHandle> {
        let t = self.textures.get(self.read?)?;
        Some(graph.import_texture("cull.hiz.previous", t))
    }

    /// `cull.hiz` (mip 0: `depth` copied) and `cull.hiz.mipK` (each the
    /// min of its parents) into the pyramid `cull` does not read; the last
    /// write outlives the frame. Nothing where this frame builds none.
    pub fn add<'a>(&'a self, graph: &mut FrameGraph<'a>, depth: TextureHandle) {
        let Some(t) = self.textures.get(1 - self.latest).filter(|_| self.building) else {
            return;
        };
        let groups = |mip: u32| {
            let (w, h) = ((t.width() >> mip).max(1), (t.height() >> mip).max(1));
            [w.div_ceil(WORKGROUP), h.div_ceil(WORKGROUP), 1]
        };
        let pyramid = graph.import_texture("cull.hiz", t);
        let written = graph
            .compute("cull.hiz", &self.depth_program)
            .compute_pipeline(Ok(self.copy.clone()))
            .read("depth", depth)
            .storage_view("child", pyramid, mip_view(0))
            .dispatch(groups(0));
        let mut pyramid = written.storage.first().copied().unwrap_or(pyramid);
        for mip in 1..t.mip_level_count() {
            let written = graph
                .compute(&format!("cull.hiz.mip{mip}"), &self.reduce_program)
                .compute_pipeline(Ok(self.reduce.clone()))
                .read_view("parent_load", pyramid, mip_view(mip - 1))
                .storage_view("child", pyramid, mip_view(mip))
                .dispatch(groups(mip));
            pyramid = written.storage.first().copied().unwrap_or(pyramid);
        }
        // The next frame's `cull` reads it.
        graph.mark_output(pyramid);
    }

    /// Builds the pyramid of `depth` (Depth32Float, TEXTURE_BINDING) alone
    /// and reads every mip back (tests: the GPU against the twin). Leaves
    /// no pyramid valid for culling.
    pub fn build_and_read(
        &mut self,
        ctx: &GpuContext,
        depth: &wgpu::Texture,
    ) -> Result<Vec<HizMip>, crate::Error> {
        self.prepare(&ctx.device, (depth.width(), depth.height()), true);
        {
            let mut graph = FrameGraph::new();
            let depth = graph.import_texture("depth", depth);
            self.add(&mut graph, depth);
            let mut pool = crate::graph::TexturePool::new();
            let commands = graph.compile()?.execute(&ctx.device, &mut pool, None)?;
            ctx.queue.submit([commands]);
        }
        let Some(t) = self.textures.get(1 - self.latest) else {
            return Ok(Vec::new());
        };
        let mips = (0..t.mip_level_count())
            .map(|mip| {
                let data = crate::gpu::read_texture(ctx, t, mip, 0)?;
                Ok(HizMip {
                    width: data.width,
                    height: data.height,
                    depth: bytemuck::pod_collect_to_vec(&data.bytes),
                })
            })
            .collect();
        self.reset();
        mips
    }
}
