//! Ambient occlusion, Battlefield 3's stable SSAO: HBAO (TECHNIQUES O1), the
//! selective temporal filter (O2) and the adaptive cross-bilateral blur (O3).
//!
//! ```text
//! depth ─> ao.hbao ─┬─> ao.stability ─────────────────────┐
//!   (AO res)        └─> ao.pack ─> ao.blur_x ─> ao.blur_y_stf ─> AO (full res, history)
//!                        (full res)      history (previous) ─┘
//! ```
//! CPU twins: [`reference`]. Math and measurements: `docs/techniques/O1.md`..`O3.md`.

pub mod reference;
mod settings;

use std::collections::HashMap;

use wgpu::util::DeviceExt;

pub use settings::{AoMode, AoSettings, AoUniform, AoView, jitter_4x4};

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, PassContext, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{draw_fullscreen, record_view, target, view_pipeline};

/// ao.hbao output: (AO, continuity).
pub const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
pub const STABILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// ao.pack and ao.blur_x output: (AO, linear depth).
pub const PACKED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// ao.blur_y output and history: (AO, linear depth, N).
pub const HISTORY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The ping-pong history (AO, Z, N) of the temporal filter, owned by the renderer.
pub struct AoHistory {
    textures: [wgpu::Texture; 2],
    pub size: (u32, u32),
    /// Index of the texture holding the previous frame.
    previous: usize,
    /// False on first use and after a camera cut: the previous texture is cleared to (1, 0, 0).
    valid: bool,
}

impl AoHistory {
    pub fn new(device: &wgpu::Device, size: (u32, u32)) -> Self {
        let make = |label| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: HISTORY_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        Self {
            textures: [make("ao.history.0"), make("ao.history.1")],
            size,
            previous: 0,
            valid: false,
        }
    }

    /// Forgets the history (camera cut).
    pub fn invalidate(&mut self) {
        self.valid = false;
    }

    /// (previous, next, previous must be cleared first).
    pub fn pair(&self) -> (&wgpu::Texture, &wgpu::Texture, bool) {
        (
            &self.textures[self.previous],
            &self.textures[1 - self.previous],
            !self.valid,
        )
    }

    /// After a frame was submitted: next becomes previous.
    pub fn advance(&mut self) {
        self.previous = 1 - self.previous;
        self.valid = true;
    }

    pub fn bytes(&self) -> u64 {
        2 * self.size.0 as u64 * self.size.1 as u64 * 8
    }
}

/// What the AO graph nodes read besides the depth buffer.
pub struct AoInputs<'a> {
    pub settings: &'a AoSettings,
    pub view: &'a wgpu::Buffer,
    pub depth: TextureHandle,
    pub history: &'a AoHistory,
}

/// Textures the AO nodes produce.
#[derive(Clone, Copy)]
pub struct AoTargets {
    /// Full resolution (AO, Z, N); lighting reads `.x`.
    pub ao: TextureHandle,
    pub raw: TextureHandle,
    pub stability: TextureHandle,
}

struct Step {
    program: Program,
    pipeline: wgpu::RenderPipeline,
}

impl Step {
    fn new(
        ctx: &GpuContext,
        path: &str,
        label: &str,
        format: wgpu::TextureFormat,
        constants: &[(&str, f64)],
    ) -> Result<Self, GpuError> {
        let program = Program::new(ctx, path)?;
        let targets = [target(format)];
        let mut spec = RenderSpec::fullscreen(label, &targets);
        spec.constants = constants;
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self { program, pipeline })
    }
}

pub struct AoPass {
    hbao: Step,
    stability: Step,
    pack: Step,
    blur_x: Step,
    blur_y: Step,
    blur_y_stf: Step,
    view_program: Program,
    views: HashMap<(AoView, wgpu::TextureFormat), wgpu::RenderPipeline>,
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
            views: HashMap::new(),
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

    /// Builds the pipeline of an AO debug view into `format` (float = raw values).
    pub fn prepare_view(
        &mut self,
        ctx: &GpuContext,
        view: AoView,
        format: wgpu::TextureFormat,
    ) -> Result<(), GpuError> {
        if self.views.contains_key(&(view, format)) {
            return Ok(());
        }
        let pipeline = view_pipeline(ctx, &self.view_program, "ao.view", view as u32, format)?;
        self.views.insert((view, format), pipeline);
        Ok(())
    }

    /// Adds the AO nodes for a `size` frame.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        inputs: AoInputs<'a>,
        errors: &'a FrameErrors,
    ) -> AoTargets {
        let AoInputs {
            settings,
            view,
            depth,
            history,
        } = inputs;
        let ao_size = settings.ao_size(size);
        let params = &self.params;
        let sampler = &self.linear_sampler;

        let raw = graph.create_texture(
            "ao.raw",
            TextureDesc::new_2d(ao_size.0, ao_size.1, RAW_FORMAT),
        );
        let jitter = graph.import_texture("ao.jitter", &self.jitter);
        let raw = self.node(
            graph,
            "ao.hbao",
            &self.hbao,
            &[depth, jitter],
            raw,
            errors,
            move |ctx, program| {
                program.bind(
                    ctx.device,
                    0,
                    &[
                        ("params", params.as_entire_binding()),
                        ("depth", tv(ctx, depth)),
                        ("jitter_load", tv(ctx, jitter)),
                    ],
                )
            },
        );
        let stability = graph.create_texture(
            "ao.stability",
            TextureDesc::new_2d(ao_size.0, ao_size.1, STABILITY_FORMAT),
        );
        let stability = self.node(
            graph,
            "ao.stability",
            &self.stability,
            &[raw],
            stability,
            errors,
            move |ctx, program| {
                program.bind(
                    ctx.device,
                    0,
                    &[
                        ("params", params.as_entire_binding()),
                        ("hbao_load", tv(ctx, raw)),
                    ],
                )
            },
        );
        let full = TextureDesc::new_2d(size.0, size.1, PACKED_FORMAT);
        let packed = graph.create_texture("ao.packed", full.clone());
        let packed = self.node(
            graph,
            "ao.pack",
            &self.pack,
            &[depth, raw],
            packed,
            errors,
            move |ctx, program| {
                program.bind(
                    ctx.device,
                    0,
                    &[
                        ("params", params.as_entire_binding()),
                        ("depth", tv(ctx, depth)),
                        ("hbao", tv(ctx, raw)),
                        ("linear_sampler", wgpu::BindingResource::Sampler(sampler)),
                    ],
                )
            },
        );
        let blurred_x = graph.create_texture("ao.blurred_x", full);
        let blurred_x = self.node(
            graph,
            "ao.blur_x",
            &self.blur_x,
            &[packed],
            blurred_x,
            errors,
            move |ctx, program| {
                program.bind(
                    ctx.device,
                    0,
                    &[
                        ("params", params.as_entire_binding()),
                        ("packed", tv(ctx, packed)),
                        ("linear_sampler", wgpu::BindingResource::Sampler(sampler)),
                    ],
                )
            },
        );
        let ao = if settings.mode == AoMode::HbaoStf {
            let (previous, next, clear) = history.pair();
            let mut previous = graph.import_texture("ao.history.previous", previous);
            if clear {
                // The talk's clear values: (AO, Z) = (1, 0), N = 0.
                let mut pass = graph.add_pass("ao.history_clear");
                previous = pass.write(previous, TextureAccess::ColorAttachment);
                pass.execute(move |ctx| {
                    let label = ctx.pass_id().to_string();
                    ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some(&label),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: ctx.view(previous),
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(wgpu::Color {
                                    r: 1.0,
                                    g: 0.0,
                                    b: 0.0,
                                    a: 0.0,
                                }),
                                store: wgpu::StoreOp::Store,
                            },
                        })],
                        depth_stencil_attachment: None,
                        timestamp_writes: None,
                        occlusion_query_set: None,
                        multiview_mask: None,
                    });
                });
            }
            let next = graph.import_texture("ao.history.next", next);
            let next = self.node(
                graph,
                "ao.blur_y_stf",
                &self.blur_y_stf,
                &[blurred_x, depth, stability, previous],
                next,
                errors,
                move |ctx, program| {
                    program.bind(
                        ctx.device,
                        0,
                        &[
                            ("params", params.as_entire_binding()),
                            ("view", view.as_entire_binding()),
                            ("blurred_x", tv(ctx, blurred_x)),
                            ("depth", tv(ctx, depth)),
                            ("stability_load", tv(ctx, stability)),
                            ("history", tv(ctx, previous)),
                            ("linear_sampler", wgpu::BindingResource::Sampler(sampler)),
                        ],
                    )
                },
            );
            // The history outlives the frame.
            graph.mark_output(next);
            next
        } else {
            let out = graph.create_texture(
                "ao.filtered",
                TextureDesc::new_2d(size.0, size.1, HISTORY_FORMAT),
            );
            // Without the filter, the history and stability bindings are unused:
            // bind textures this pass reads anyway so no extra node runs.
            self.node(
                graph,
                "ao.blur_y",
                &self.blur_y,
                &[blurred_x, depth, raw],
                out,
                errors,
                move |ctx, program| {
                    program.bind(
                        ctx.device,
                        0,
                        &[
                            ("params", params.as_entire_binding()),
                            ("view", view.as_entire_binding()),
                            ("blurred_x", tv(ctx, blurred_x)),
                            ("depth", tv(ctx, depth)),
                            ("stability_load", tv(ctx, raw)),
                            ("history", tv(ctx, blurred_x)),
                            ("linear_sampler", wgpu::BindingResource::Sampler(sampler)),
                        ],
                    )
                },
            )
        };
        AoTargets { ao, raw, stability }
    }

    /// One full-screen node: reads `reads`, writes `output` with the bind group `bind` makes.
    #[allow(clippy::too_many_arguments)]
    fn node<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        id: &str,
        step: &'a Step,
        reads: &[TextureHandle],
        output: TextureHandle,
        errors: &'a FrameErrors,
        bind: impl for<'c> Fn(&PassContext<'c>, &Program) -> Result<wgpu::BindGroup, GpuError> + 'a,
    ) -> TextureHandle {
        let mut pass = graph.add_pass(id);
        for &t in reads {
            pass.read(t, TextureAccess::Sampled);
        }
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            if let Some(bg) = errors.record(bind(ctx, &step.program)) {
                let target = ctx.view(output);
                draw_fullscreen(
                    ctx,
                    &step.pipeline,
                    &bg,
                    target,
                    wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                    None,
                );
            }
        });
        output
    }

    /// Draws AO debug view `kind` into `output`.
    pub fn add_view<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        kind: AoView,
        targets: AoTargets,
        output: TextureHandle,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let format = graph.texture_desc(output).map(|d| d.format);
        let pipeline = format.and_then(|f| self.views.get(&(kind, f)));
        let mut pass = graph.add_pass("ao.view");
        let read = match kind {
            AoView::Ao => targets.ao,
            AoView::Raw => targets.raw,
            AoView::Stability => targets.stability,
        };
        pass.read(read, TextureAccess::Sampled);
        let output = pass.write(output, TextureAccess::ColorAttachment);
        pass.execute(move |ctx| {
            let what = || format!("AO view {kind:?}");
            record_view(ctx, pipeline, what, output, errors, |ctx| {
                // Bind the one texture this view reads in every slot: the others are unused.
                let t = tv(ctx, read);
                self.view_program.bind(
                    ctx.device,
                    0,
                    &[
                        ("params", self.params.as_entire_binding()),
                        ("ao", t.clone()),
                        ("hbao_load", t.clone()),
                        ("stability_load", t),
                    ],
                )
            });
        });
        output
    }
}

/// A sampled-texture binding of `h`.
fn tv<'c>(ctx: &PassContext<'c>, h: TextureHandle) -> wgpu::BindingResource<'c> {
    wgpu::BindingResource::TextureView(ctx.view(h))
}
