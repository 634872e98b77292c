//! A1 SMAA 1x (Jimenez et al. 2012): `aa.smaa.edges` (luma, depth
//! predicated), `aa.smaa.weights` (diagonal and orthogonal searches, corner
//! detection, area lookups with himal's own lookup textures, [`lut`]),
//! `aa.smaa.blend` (neighbourhood blending). CPU twins in [`mod@reference`].

pub mod lut;
pub mod reference;

use crate::gpu::pipeline::{Program, RenderSpec};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::target;

/// Edge texture format (RG: left, top edge).
pub const EDGES_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg8Unorm;
/// Blending-weight texture format (RG: top edge, BA: left edge).
pub const WEIGHTS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// The edge mask (#23, `FrameSettings::smaa_edge_mask`; the reference
/// implementation's stencil): `aa.smaa.edges` writes depth 0 where a pixel
/// has an edge (cleared to 1), and `aa.smaa.weights` tests 0 >= mask, so
/// only edge pixels run the searches. Both full-screen triangles are at
/// depth 0 (GreaterEqual, not Equal: no reliance on invariant positions).
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth16Unorm;

fn mask_state(write: bool) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: MASK_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(if write {
            wgpu::CompareFunction::Always
        } else {
            wgpu::CompareFunction::GreaterEqual
        }),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// What the SMAA chain reads.
#[derive(Clone, Copy)]
pub struct SmaaInputs {
    /// Tone-mapped colour (sRGB texture: samples are linear).
    pub color: TextureHandle,
    /// Device depth for predication (reverse-Z).
    pub depth: TextureHandle,
    /// G-buffer tangent frame (quaternion, Rgb10a2) for normal predication.
    pub normals: TextureHandle,
}

/// The three SMAA pipelines, lookup textures and samplers.
pub struct SmaaPass {
    edges_program: Program,
    weights_program: Program,
    blend_program: Program,
    edges: wgpu::RenderPipeline,
    /// `EDGE_MASK`: discards pixels without edges, writes the mask.
    edges_masked: wgpu::RenderPipeline,
    /// By area-table subsample index (0 = 1x; 1, 2 = T2x frames).
    weights: [wgpu::RenderPipeline; 3],
    /// The same, depth-tested against the edge mask.
    weights_masked: [wgpu::RenderPipeline; 3],
    blend: wgpu::RenderPipeline,
    area: wgpu::TextureView,
    search: wgpu::TextureView,
    linear: wgpu::Sampler,
    point: wgpu::Sampler,
}

fn lut_texture(
    ctx: &GpuContext,
    label: &str,
    size: (usize, usize),
    format: wgpu::TextureFormat,
    bytes: &[u8],
) -> wgpu::Texture {
    use wgpu::util::DeviceExt;
    ctx.device.create_texture_with_data(
        &ctx.queue,
        &wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size.0 as u32,
                height: size.1 as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytes,
    )
}

impl SmaaPass {
    /// Builds the pipelines; `output_format` is the blend target's.
    pub fn new(ctx: &GpuContext, output_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let edges_program = Program::new(ctx, "passes/aa/smaa/edges.wgsl")?;
        let weights_program = Program::new(ctx, "passes/aa/smaa/weights.wgsl")?;
        let blend_program = Program::new(ctx, "passes/aa/smaa/blend.wgsl")?;
        let t = [target(EDGES_FORMAT)];
        let edges =
            edges_program.render_pipeline(ctx, &RenderSpec::fullscreen("aa.smaa.edges", &t))?;
        let mut spec = RenderSpec::fullscreen("aa.smaa.edges_masked", &t);
        spec.constants = &[("EDGE_MASK", 1.0)];
        spec.depth_stencil = Some(mask_state(true));
        let edges_masked = edges_program.render_pipeline(ctx, &spec)?;
        let t = [target(WEIGHTS_FORMAT)];
        let w = reference::WeightSettings::default();
        let weights_for = |index: u32, masked: bool| {
            let mut spec = RenderSpec::fullscreen("aa.smaa.weights", &t);
            spec.depth_stencil = masked.then(|| mask_state(false));
            // SMAA T2x's subsample indices: (i, i, i, 0).
            let constants = [
                ("SUBSAMPLE_H", index as f64),
                ("SUBSAMPLE_V", index as f64),
                ("SUBSAMPLE_DIAG", index as f64),
                ("MAX_SEARCH_STEPS", w.max_search_steps as f64),
                ("MAX_SEARCH_STEPS_DIAG", w.max_search_steps_diag as f64),
                ("CORNER_ROUNDING", w.corner_rounding as f64),
            ];
            spec.constants = &constants;
            weights_program.render_pipeline(ctx, &spec)
        };
        let weights = [
            weights_for(0, false)?,
            weights_for(1, false)?,
            weights_for(2, false)?,
        ];
        let weights_masked = [
            weights_for(0, true)?,
            weights_for(1, true)?,
            weights_for(2, true)?,
        ];
        let t = [target(output_format)];
        let blend =
            blend_program.render_pipeline(ctx, &RenderSpec::fullscreen("aa.smaa.blend", &t))?;
        let area = lut_texture(
            ctx,
            "aa.smaa.area",
            lut::AREA_SIZE,
            wgpu::TextureFormat::Rg8Unorm,
            &lut::area_texture(),
        )
        .create_view(&Default::default());
        let search = lut_texture(
            ctx,
            "aa.smaa.search",
            lut::SEARCH_SIZE,
            wgpu::TextureFormat::R8Unorm,
            &lut::search_texture(),
        )
        .create_view(&Default::default());
        let linear = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.smaa.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let point = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("aa.smaa.point"),
            ..Default::default()
        });
        Ok(Self {
            edges_program,
            weights_program,
            blend_program,
            edges,
            edges_masked,
            weights,
            weights_masked,
            blend,
            area,
            search,
            linear,
            point,
        })
    }

    /// `aa.smaa.edges` into `out` ([`EDGES_FORMAT`]) and, given one, the
    /// edge mask ([`MASK_FORMAT`]); returns their new versions.
    pub fn add_edges<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        inputs: SmaaInputs,
        out: TextureHandle,
        mask: Option<TextureHandle>,
    ) -> (TextureHandle, Option<TextureHandle>) {
        let pipeline = if mask.is_some() {
            &self.edges_masked
        } else {
            &self.edges
        };
        let mut node = graph
            .fullscreen("aa.smaa.edges", &self.edges_program)
            .pipeline(Ok(pipeline.clone()))
            .read("color", inputs.color)
            .read("depth", inputs.depth)
            .read("gbuffer_frame", inputs.normals)
            .color(out, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT));
        if let Some(m) = mask {
            let ops = wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            };
            node = node.depth(m, None, ops);
        }
        let written = node.draw_targets();
        (written.colors[0], written.depth)
    }

    /// `aa.smaa.weights` into `out` ([`WEIGHTS_FORMAT`]) with area-table
    /// `subsample` index (0 for 1x; T2x frames use 1 and 2), only where
    /// `mask` (from [`Self::add_edges`]) marks an edge when given; returns
    /// its new version (0 where masked off, as the unmasked pass writes there).
    pub fn add_weights<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        edges: TextureHandle,
        mask: Option<TextureHandle>,
        out: TextureHandle,
        subsample: u32,
    ) -> TextureHandle {
        let set = if mask.is_some() {
            &self.weights_masked
        } else {
            &self.weights
        };
        let pipeline = &set[(subsample as usize).min(2)];
        let node = graph
            .fullscreen("aa.smaa.weights", &self.weights_program)
            .pipeline(Ok(pipeline.clone()))
            .read("edges_tex", edges)
            .external("area_tex", &self.area)
            .external("search_tex", &self.search)
            .sampler("linear_sampler", &self.linear)
            .sampler("point_sampler", &self.point)
            .color(out, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT));
        match mask {
            Some(m) => node.depth_test(m).draw(),
            None => node.draw(),
        }
    }

    /// `aa.smaa.blend` into `output`; returns its new version.
    pub fn add_blend<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        color: TextureHandle,
        weights: TextureHandle,
        output: TextureHandle,
    ) -> TextureHandle {
        graph
            .fullscreen("aa.smaa.blend", &self.blend_program)
            .pipeline(Ok(self.blend.clone()))
            .read("color", color)
            .read("weights_tex", weights)
            .sampler("linear_sampler", &self.linear)
            .color(output, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .draw()
    }

    /// The whole chain: edges → weights (area table `subsample`; only on
    /// edge pixels with `edge_mask`) → blend into `output`.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        inputs: SmaaInputs,
        size: (u32, u32),
        subsample: u32,
        edge_mask: bool,
        output: TextureHandle,
    ) -> TextureHandle {
        let (w, h) = size;
        let edges = graph.create_texture("aa.smaa.edges", TextureDesc::new_2d(w, h, EDGES_FORMAT));
        let mask = edge_mask
            .then(|| graph.create_texture("aa.smaa.mask", TextureDesc::new_2d(w, h, MASK_FORMAT)));
        let (edges, mask) = self.add_edges(graph, inputs, edges, mask);
        let weights =
            graph.create_texture("aa.smaa.weights", TextureDesc::new_2d(w, h, WEIGHTS_FORMAT));
        let weights = self.add_weights(graph, edges, mask, weights, subsample);
        self.add_blend(graph, inputs.color, weights, output)
    }
}
