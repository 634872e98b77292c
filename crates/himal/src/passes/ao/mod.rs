//! Ambient occlusion, Battlefield 3's stable SSAO: HBAO (TECHNIQUES O1), the
//! selective temporal filter (O2) and the adaptive cross-bilateral blur (O3).
//!
//! ```text
//! depth ─> ao.hbao ─┬─> ao.stability ─────────────────────┐
//!   (AO res)        └─> ao.pack ─> ao.blur_x ─> ao.blur_y_stf ─> AO (full res, history)
//!                        (full res)      history (previous) ─┘
//! ```
//! CPU twins: [`mod@reference`]. Math and measurements: `docs/techniques/O1.md`..`O3.md`.

pub mod bleed;
pub mod reference;
mod settings;

use wgpu::util::DeviceExt;

pub use settings::{AoMode, AoSettings, AoUniform, AoView, jitter_4x4};

use crate::gpu::pipeline::{Program, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{Fallback, FrameGraph, History, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{Step, clear_target, view_node};

/// ao.hbao output: (AO, continuity).
pub const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
pub const STABILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// ao.pack and ao.blur_x output: (AO, linear depth).
pub const PACKED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// ao.blur_y output and history: (AO, linear depth, N).
pub const HISTORY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The temporal filter's history ring (AO, Z, N) in the graph's [`History`].
pub const HISTORY: &str = "ao.history";

/// Declares the history ring of a `size` frame (before the graph is built).
pub fn declare_history(history: &mut History, device: &wgpu::Device, size: (u32, u32)) {
    let desc = TextureDesc::new_2d(size.0, size.1, HISTORY_FORMAT);
    history.declare(device, HISTORY, &desc, 2);
}

/// What the AO graph nodes read besides the depth buffer.
pub struct AoInputs<'a> {
    pub settings: &'a AoSettings,
    pub depth: TextureHandle,
    /// Holds [`HISTORY`] (declared with [`declare_history`]).
    pub history: &'a History,
}

/// Textures the AO nodes produce.
#[derive(Clone, Copy)]
pub struct AoTargets {
    /// Full resolution (AO, Z, N); lighting reads `.x`.
    pub ao: TextureHandle,
    pub raw: TextureHandle,
    pub stability: TextureHandle,
}

pub struct AoPass {
    hbao: Step,
    stability: Step,
    pack: Step,
    blur_x: Step,
    blur_y: Step,
    blur_y_stf: Step,
    view_program: Program,
    jitter: wgpu::Texture,
    linear_sampler: wgpu::Sampler,
    params: wgpu::Buffer,
}

impl AoPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let jitter = ctx.device.create_texture_with_data(
            &ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("ao.jitter"),
                size: wgpu::Extent3d {
                    width: 4,
                    height: 4,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&jitter_4x4()),
        );
        let linear_sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("ao.linear"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let stf_off = [("STF", 0.0)];
        Ok(Self {
            hbao: Step::new(ctx, "passes/ao/hbao.wgsl", "ao.hbao", RAW_FORMAT, &[])?,
            stability: Step::new(
                ctx,
                "passes/ao/stability.wgsl",
                "ao.stability",
                STABILITY_FORMAT,
                &[],
            )?,
            pack: Step::new(ctx, "passes/ao/pack.wgsl", "ao.pack", PACKED_FORMAT, &[])?,
            blur_x: Step::new(
                ctx,
                "passes/ao/blur_x.wgsl",
                "ao.blur_x",
                PACKED_FORMAT,
                &[],
            )?,
            blur_y: Step::new(
                ctx,
                "passes/ao/blur_y.wgsl",
                "ao.blur_y",
                HISTORY_FORMAT,
                &stf_off,
            )?,
            blur_y_stf: Step::new(
                ctx,
                "passes/ao/blur_y.wgsl",
                "ao.blur_y_stf",
                HISTORY_FORMAT,
                &[],
            )?,
            view_program: Program::new(ctx, "passes/ao/view.wgsl")?,
            jitter,
            linear_sampler,
            params: uniform_buffer(
                ctx,
                "ao.params",
                &<AoUniform as bytemuck::Zeroable>::zeroed(),
            ),
        })
    }

    /// Uploads this frame's parameters.
    pub fn update(&self, queue: &wgpu::Queue, uniform: &AoUniform) {
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(uniform));
    }

    /// The pipeline of AO debug view `view` into `format` (float = raw values).
    pub fn view_pipeline(
        &self,
        ctx: &GpuContext,
        view: AoView,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        crate::passes::common::view_pipeline(
            ctx,
            &self.view_program,
            "ao.view",
            view as u32,
            format,
        )
    }

    /// Adds the AO nodes for a `size` frame.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        inputs: AoInputs<'a>,
    ) -> AoTargets {
        let AoInputs {
            settings,
            depth,
            history,
        } = inputs;
        let ao_size = settings.ao_size(size);
        let (params, sampler) = (&self.params, &self.linear_sampler);
        let white = wgpu::LoadOp::Clear(wgpu::Color::WHITE);

        let raw = graph.create_texture(
            "ao.raw",
            TextureDesc::new_2d(ao_size.0, ao_size.1, RAW_FORMAT),
        );
        let jitter = graph.import_texture("ao.jitter", &self.jitter);
        let raw = self
            .hbao
            .node(graph, "ao.hbao")
            .uniform("params", params)
            .read("depth", depth)
            .read("jitter_load", jitter)
            .color(raw, white)
            .draw();
        let stability = graph.create_texture(
            "ao.stability",
            TextureDesc::new_2d(ao_size.0, ao_size.1, STABILITY_FORMAT),
        );
        let stability = self
            .stability
            .node(graph, "ao.stability")
            .uniform("params", params)
            .read("hbao_load", raw)
            .color(stability, white)
            .draw();
        let full = TextureDesc::new_2d(size.0, size.1, PACKED_FORMAT);
        let packed = graph.create_texture("ao.packed", full.clone());
        let packed = self
            .pack
            .node(graph, "ao.pack")
            .uniform("params", params)
            .read("depth", depth)
            .read("hbao", raw)
            .sampler("linear_sampler", sampler)
            .color(packed, white)
            .draw();
        let blurred_x = graph.create_texture("ao.blurred_x", full);
        let blurred_x = self
            .blur_x
            .node(graph, "ao.blur_x")
            .uniform("params", params)
            .read("packed", packed)
            .sampler("linear_sampler", sampler)
            .color(blurred_x, white)
            .draw();
        let ring = (settings.mode == AoMode::HbaoStf)
            .then(|| history.import(graph, HISTORY))
            .flatten();
        let ao = match ring {
            Some(ring) => {
                let mut previous = ring.previous[0];
                if ring.frames == 0 {
                    // The talk's clear values: (AO, Z) = (1, 0), N = 0.
                    let mut pass = graph.add_pass("ao.history_clear");
                    previous = pass.write(previous, TextureAccess::ColorAttachment);
                    pass.execute(move |ctx| {
                        let clear = wgpu::Color {
                            r: 1.0,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        };
                        clear_target(ctx, previous, clear)
                    });
                }
                let next = self
                    .blur_y_stf
                    .node(graph, "ao.blur_y_stf")
                    .uniform("params", params)
                    .read("blurred_x", blurred_x)
                    .read("depth", depth)
                    .read("stability_load", stability)
                    .read("history", previous)
                    .sampler("linear_sampler", sampler)
                    .color(ring.next, white)
                    .draw();
                // The history outlives the frame.
                graph.mark_output(next);
                next
            }
            None => {
                let out = graph.create_texture(
                    "ao.filtered",
                    TextureDesc::new_2d(size.0, size.1, HISTORY_FORMAT),
                );
                // Without the filter (STF = false) the shader reads neither.
                self.blur_y
                    .node(graph, "ao.blur_y")
                    .uniform("params", params)
                    .read("blurred_x", blurred_x)
                    .read("depth", depth)
                    .optional("stability_load", None, Fallback::White)
                    .optional("history", None, Fallback::Black)
                    .sampler("linear_sampler", sampler)
                    .color(out, white)
                    .draw()
            }
        };
        AoTargets { ao, raw, stability }
    }

    /// Draws AO debug view `kind` into `output`.
    pub fn add_view<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        kind: AoView,
        targets: AoTargets,
        output: TextureHandle,
    ) -> TextureHandle {
        let node = view_node(
            ctx,
            graph,
            &self.view_program,
            "ao.view",
            kind as u32,
            output,
        );
        let (ao, raw, stability) = match kind {
            // Bleed is drawn by passes/ao/bleed (frame.rs routes it there).
            AoView::Ao | AoView::Bleed => (Some(targets.ao), None, None),
            AoView::Raw => (None, Some(targets.raw), None),
            AoView::Stability => (None, None, Some(targets.stability)),
        };
        // The view reads one buffer; the others are unused by its permutation.
        node.uniform("params", &self.params)
            .optional("ao", ao, Fallback::Black)
            .optional("hbao_load", raw, Fallback::Black)
            .optional("stability_load", stability, Fallback::Black)
            .draw()
    }
}
