//! Ambient occlusion, Battlefield 3's stable SSAO: HBAO (TECHNIQUES O1), the
//! selective temporal filter (O2) and the adaptive cross-bilateral blur (O3).
//!
//! ```text
//! depth ─> ao.hbao ─┬─> ao.stability ─────────────────────┐
//!   (AO res)        └─> ao.pack ─> ao.blur_x ─> ao.blur_y_stf ─> AO (full res, history)
//!                        (full res)      history (previous) ─┘
//! ```
//! With `--ao ssdo` (O4) the same nodes also carry the directional term
//! (two coefficients, their permutations `SSDO` / `fs_ssdo`) into a second
//! history ring, [`HISTORY_DIR`]. With `--ao-large-scale on` (O6)
//! `ao.large_scale` multiplies ao.hbao's output by the height field's
//! occlusion first ([`large_scale`]).
//! CPU twins: [`mod@reference`]. Math and measurements: `docs/techniques/O1.md`..`O4.md`.

pub mod bleed;
pub mod large_scale;
pub mod reference;
mod settings;

use wgpu::util::DeviceExt;

pub use settings::{AoMode, AoSettings, AoUniform, AoView, jitter_4x4};

use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{Fallback, FrameGraph, History, TextureAccess, TextureDesc, TextureHandle};
use crate::passes::common::{Step, clear_target, target, view_node};

/// ao.hbao output: (AO, continuity).
pub const RAW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// ao.stability output (AO resolution): 1 = stable (continuous over 4x4).
pub const STABILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;
/// ao.pack and ao.blur_x output: (AO, linear depth).
pub const PACKED_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;
/// ao.blur_x's output as a compute pass ([`AoSettings::compute_blur`], ao.pack merged in):
/// (AO, linear depth, c1, c2); Rg16Float is no core storage format.
pub const BLURRED_X_STORAGE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Pixels per `ao.blur_x` compute workgroup (`TILE` in blur_x_cs.wgsl).
const BLUR_TILE: u32 = 128;
/// ao.blur_y output and history: (AO, linear depth, N).
pub const HISTORY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// SSDO (O4): ao.hbao (AO, continuity, c1, c2), ao.pack / ao.blur_x (AO, Z, c1, c2).
pub const SSDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// SSDO (O4): the directional coefficients after ao.blur_y_stf, and their history.
pub const DIR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;

/// The temporal filter's history ring (AO, Z, N) in the graph's [`History`].
pub const HISTORY: &str = "ao.history";
/// O4: the directional coefficients' history ring (c1, c2).
pub const HISTORY_DIR: &str = "ao.history_dir";

/// Declares the history rings of a `size` frame with `mode` (before the graph is built).
pub fn declare_history(
    history: &mut History,
    device: &wgpu::Device,
    size: (u32, u32),
    mode: AoMode,
) {
    let desc = TextureDesc::new_2d(size.0, size.1, HISTORY_FORMAT);
    history.declare(device, HISTORY, &desc, 2);
    if mode.directional() {
        let desc = TextureDesc::new_2d(size.0, size.1, DIR_FORMAT);
        history.declare(device, HISTORY_DIR, &desc, 2);
    }
}

/// What the AO graph nodes read besides the depth buffer.
pub struct AoInputs<'a> {
    /// The frame's AO settings (mode, resolution, every parameter).
    pub settings: &'a AoSettings,
    /// The G-buffer's full-resolution device depth (reverse-Z, 0 = sky).
    pub depth: TextureHandle,
    /// Holds [`HISTORY`] (declared with [`declare_history`]).
    pub history: &'a History,
    /// O6: the height field and what locates a pixel in it (`None`: off).
    pub large_scale: Option<large_scale::LargeScaleInputs<'a>>,
}

/// Textures the AO nodes produce.
#[derive(Clone, Copy)]
pub struct AoTargets {
    /// Full resolution (AO, Z, N); lighting reads `.x`.
    pub ao: TextureHandle,
    /// O4 (`--ao ssdo`): full resolution (c1, c2), the directional term.
    pub dir: Option<TextureHandle>,
    /// ao.hbao's output at AO resolution, before blur and filter:
    /// (AO, continuity), with SSDO (AO, continuity, c1, c2).
    pub raw: TextureHandle,
    /// ao.stability's mask at AO resolution (1 = stable); `--view stability-mask` shows it.
    pub stability: TextureHandle,
}

/// The SSDO variants of the steps (O4).
struct SsdoSteps {
    hbao: Step,
    pack: Step,
    blur_x: Step,
    blur_y_stf: Step,
}

/// The AO passes (O1-O4): the pipelines of each step, the 4x4 jitter
/// texture, a linear sampler and the `AoParams` uniform buffer they share.
pub struct AoPass {
    hbao: Step,
    stability: Step,
    pack: Step,
    blur_x: Step,
    /// `ao.pack` + `ao.blur_x` as one compute pass (both AO modes: it
    /// reads and writes four channels).
    blur_x_cs: (Program, wgpu::ComputePipeline),
    blur_y: Step,
    blur_y_stf: Step,
    /// Compiled on the first SSDO frame.
    ssdo: std::sync::OnceLock<SsdoSteps>,
    view_program: Program,
    large_scale: large_scale::LargeScalePass,
    jitter: wgpu::Texture,
    linear_sampler: wgpu::Sampler,
    params: wgpu::Buffer,
}

impl AoPass {
    /// Compiles the HBAO, stability, pack and blur pipelines (the SSDO
    /// variants wait for the first SSDO frame or [`Self::prewarm_ssdo`]) and
    /// uploads the jitter texture; the parameters start zeroed until [`Self::update`].
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
        let blur_x_cs = Program::new(ctx, "passes/ao/blur_x_cs.wgsl")?;
        let blur_x_cs_pipeline = blur_x_cs.compute_pipeline(ctx, "cs_main", &[])?;
        Ok(Self {
            blur_x_cs: (blur_x_cs, blur_x_cs_pipeline),
            large_scale: large_scale::LargeScalePass::new(ctx)?,
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
            ssdo: std::sync::OnceLock::new(),
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

    /// The parameters' buffer (`AoParams`; lighting reads the O4 fields).
    pub fn params(&self) -> &wgpu::Buffer {
        &self.params
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

    /// Compiles the SSDO steps now (`Renderer::prewarm`).
    pub fn prewarm_ssdo(&self, ctx: &GpuContext) -> Result<(), GpuError> {
        self.ssdo_steps(ctx).map(|_| ())
    }

    fn ssdo_steps(&self, ctx: &GpuContext) -> Result<&SsdoSteps, GpuError> {
        if let Some(s) = self.ssdo.get() {
            return Ok(s);
        }
        let steps = SsdoSteps::new(ctx)?;
        Ok(self.ssdo.get_or_init(|| steps))
    }

    /// Adds the AO nodes for a `size` frame.
    pub fn add<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        size: (u32, u32),
        inputs: AoInputs<'a>,
    ) -> Result<AoTargets, GpuError> {
        let AoInputs {
            settings,
            depth,
            history,
            large_scale,
        } = inputs;
        let ao_size = settings.ao_size(size);
        let (params, sampler) = (&self.params, &self.linear_sampler);
        let white = wgpu::LoadOp::Clear(wgpu::Color::WHITE);

        let ssdo = settings.mode.directional();
        let ssdo_steps = if ssdo {
            Some(self.ssdo_steps(ctx)?)
        } else {
            None
        };
        let (hbao, pack, blur_x, raw_format, packed_format) = if let Some(s) = ssdo_steps {
            (&s.hbao, &s.pack, &s.blur_x, SSDO_FORMAT, SSDO_FORMAT)
        } else {
            (
                &self.hbao,
                &self.pack,
                &self.blur_x,
                RAW_FORMAT,
                PACKED_FORMAT,
            )
        };
        let raw = graph.create_texture(
            "ao.raw",
            TextureDesc::new_2d(ao_size.0, ao_size.1, raw_format),
        );
        let jitter = graph.import_texture("ao.jitter", &self.jitter);
        let raw = hbao
            .node(graph, "ao.hbao")
            .uniform("params", params)
            .read("depth", depth)
            .read("jitter_load", jitter)
            .color(raw, white)
            .draw();
        let raw = match large_scale {
            Some(ls) => (self.large_scale).add(graph, ao_size, ssdo, params, jitter, raw, ls),
            None => raw,
        };
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
        let blurred_x = if settings.compute_blur {
            // ao.pack runs inside the compute blur's tile loads.
            let desc = TextureDesc::new_2d(size.0, size.1, BLURRED_X_STORAGE_FORMAT);
            let out = graph.create_texture("ao.blurred_x", desc);
            let (program, pipeline) = &self.blur_x_cs;
            let written = graph
                .compute("ao.blur_x", program)
                .compute_pipeline(Ok(pipeline.clone()))
                .uniform("params", params)
                .read("depth", depth)
                .read("hbao", raw)
                .sampler("linear_sampler", sampler)
                .storage("blurred", out)
                .dispatch([size.0.div_ceil(BLUR_TILE), size.1, 1]);
            written.storage.first().copied().unwrap_or(out)
        } else {
            let full = TextureDesc::new_2d(size.0, size.1, packed_format);
            let packed = graph.create_texture("ao.packed", full.clone());
            let packed = pack
                .node(graph, "ao.pack")
                .uniform("params", params)
                .read("depth", depth)
                .read("hbao", raw)
                .sampler("linear_sampler", sampler)
                .color(packed, white)
                .draw();
            let blurred_x = graph.create_texture("ao.blurred_x", full);
            blur_x
                .node(graph, "ao.blur_x")
                .uniform("params", params)
                .read("packed", packed)
                .sampler("linear_sampler", sampler)
                .color(blurred_x, white)
                .draw()
        };
        let ring = (settings.mode.temporal())
            .then(|| history.import(graph, HISTORY))
            .flatten();
        let ring_dir = ssdo.then(|| history.import(graph, HISTORY_DIR)).flatten();
        let (ao, dir) = match ring {
            Some(ring) => {
                let mut previous = ring.previous[0];
                let mut previous_dir = ring_dir.map(|r| r.previous[0]);
                if ring.frames == 0 {
                    if let Some(p) = previous_dir.as_mut() {
                        // No directional occlusion in the cleared history.
                        let mut pass = graph.add_pass("ao.history_dir_clear");
                        *p = pass.write(*p, TextureAccess::ColorAttachment);
                        let target = *p;
                        pass.execute(move |ctx| clear_target(ctx, target, wgpu::Color::BLACK));
                    }
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
                let step = match ssdo_steps {
                    Some(s) if ring_dir.is_some() => &s.blur_y_stf,
                    _ => &self.blur_y_stf,
                };
                let node = step
                    .node(graph, "ao.blur_y_stf")
                    .uniform("params", params)
                    .read("blurred_x", blurred_x)
                    .read("depth", depth)
                    .read("stability_load", stability)
                    .read("history", previous)
                    .optional("history_dir", previous_dir, Fallback::Black)
                    .sampler("linear_sampler", sampler)
                    .color(ring.next, white);
                let (next, dir) = match ring_dir {
                    Some(r) => {
                        let written = node
                            .color(r.next, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
                            .draw_targets();
                        (written.colors[0], Some(written.colors[1]))
                    }
                    None => (node.draw(), None),
                };
                // The history outlives the frame.
                graph.mark_output(next);
                if let Some(d) = dir {
                    graph.mark_output(d);
                }
                (next, dir)
            }
            None => {
                let out = graph.create_texture(
                    "ao.filtered",
                    TextureDesc::new_2d(size.0, size.1, HISTORY_FORMAT),
                );
                // Without the filter (STF = false) the shader reads neither.
                let ao = self
                    .blur_y
                    .node(graph, "ao.blur_y")
                    .uniform("params", params)
                    .read("blurred_x", blurred_x)
                    .read("depth", depth)
                    .optional("stability_load", None, Fallback::White)
                    .optional("history", None, Fallback::Black)
                    .optional("history_dir", None, Fallback::Black)
                    .sampler("linear_sampler", sampler)
                    .color(out, white)
                    .draw();
                (ao, None)
            }
        };
        Ok(AoTargets {
            ao,
            dir,
            raw,
            stability,
        })
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
        let (ao, raw, stability, dir) = match kind {
            // Bleed is drawn by passes/ao/bleed (frame.rs routes it there).
            AoView::Ao | AoView::Bleed => (Some(targets.ao), None, None, None),
            AoView::Raw => (None, Some(targets.raw), None, None),
            AoView::Stability => (None, None, Some(targets.stability), None),
            // Without SSDO data the coefficients read 0 (no directional occlusion).
            AoView::Directional => (Some(targets.ao), None, None, targets.dir),
        };
        // The view reads one buffer; the others are unused by its permutation.
        node.uniform("params", &self.params)
            .optional("ao", ao, Fallback::Black)
            .optional("hbao_load", raw, Fallback::Black)
            .optional("stability_load", stability, Fallback::Black)
            .optional("ao_dir", dir, Fallback::Black)
            .draw()
    }
}

impl SsdoSteps {
    fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let on = [("SSDO", 1.0)];
        let program = Program::new(ctx, "passes/ao/blur_y.wgsl")?;
        let targets = [target(HISTORY_FORMAT), target(DIR_FORMAT)];
        let mut spec = RenderSpec::fullscreen("ao.blur_y_ssdo", &targets);
        spec.fragment_entry = Some("fs_ssdo");
        let pipeline = program.render_pipeline(ctx, &spec)?;
        Ok(Self {
            hbao: Step::new(ctx, "passes/ao/hbao.wgsl", "ao.hbao_ssdo", SSDO_FORMAT, &on)?,
            pack: Step::new(ctx, "passes/ao/pack.wgsl", "ao.pack_ssdo", SSDO_FORMAT, &on)?,
            blur_x: Step::new(
                ctx,
                "passes/ao/blur_x.wgsl",
                "ao.blur_x_ssdo",
                SSDO_FORMAT,
                &[],
            )?,
            blur_y_stf: Step { program, pipeline },
        })
    }
}
