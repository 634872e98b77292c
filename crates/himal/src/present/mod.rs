//! Presentation of a rendered frame to a window: a full-screen pass that
//! copies [`crate::Renderer::output`] into a swapchain image (any 8-bit
//! RGBA/BGRA format, sRGB or not) and blends the HUD [`Overlay`] over it, so
//! the viewer needs no read-back. Shader `present/present.wgsl`, CPU twin
//! `present/reference.rs`.

mod overlay;
pub mod reference;

use std::collections::HashMap;

pub use overlay::{GLYPH, Hud, LINE, Overlay};

use crate::gpu::pipeline::target;
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PresentParams {
    overlay_origin: [u32; 2],
    overlay_size: [u32; 2],
    target_srgb: u32,
    pad: [u32; 3],
}

/// Copies a rendered frame into a window's swapchain image and blends the
/// HUD overlay over it; keeps one pipeline per swapchain format.
pub struct Presenter {
    program: Program,
    pipelines: HashMap<wgpu::TextureFormat, wgpu::RenderPipeline>,
    params: wgpu::Buffer,
    /// The overlay's texture and size; 1x1 transparent until one is given.
    overlay: (wgpu::Texture, [u32; 2]),
}

fn overlay_texture(ctx: &GpuContext, size: [u32; 2]) -> wgpu::Texture {
    crate::gpu::texture_2d(
        &ctx.device,
        "present.overlay",
        (size[0], size[1]),
        1,
        wgpu::TextureFormat::Rgba8Unorm,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    )
}

impl Presenter {
    /// Compiles the present shader; pipelines are made per target format on first use.
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let params = PresentParams {
            overlay_origin: [0; 2],
            overlay_size: [0; 2],
            target_srgb: 0,
            pad: [0; 3],
        };
        Ok(Self {
            program: Program::new(ctx, "present/present.wgsl")?,
            pipelines: HashMap::new(),
            params: uniform_buffer(ctx, "present.params", &params),
            overlay: (overlay_texture(ctx, [1, 1]), [1, 1]),
        })
    }

    /// Writes `frame` (an `Rgba8UnormSrgb` texture that allows an
    /// `Rgba8Unorm` view, as [`crate::Renderer::output`] does) into `target`
    /// of `target_format`, with `overlay` at `origin` blended over it, and
    /// submits.
    pub fn present(
        &mut self,
        ctx: &GpuContext,
        frame: &wgpu::Texture,
        overlay: Option<(&Overlay, [u32; 2])>,
        target_view: &wgpu::TextureView,
        target_format: wgpu::TextureFormat,
    ) -> Result<(), GpuError> {
        if !self.pipelines.contains_key(&target_format) {
            let targets = [target(target_format)];
            let spec = RenderSpec::fullscreen("present", &targets);
            let pipeline = self.program.render_pipeline(ctx, &spec)?;
            self.pipelines.insert(target_format, pipeline);
        }
        let (origin, size) = match overlay {
            Some((o, origin)) => {
                let size = [o.width, o.height];
                if self.overlay.1 != size {
                    self.overlay = (overlay_texture(ctx, size), size);
                }
                ctx.queue.write_texture(
                    self.overlay.0.as_image_copy(),
                    bytemuck::cast_slice(&o.rgba),
                    wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * o.width),
                        rows_per_image: None,
                    },
                    wgpu::Extent3d {
                        width: o.width,
                        height: o.height,
                        depth_or_array_layers: 1,
                    },
                );
                (origin, size)
            }
            None => ([0; 2], [0; 2]),
        };
        let params = PresentParams {
            overlay_origin: origin,
            overlay_size: size,
            target_srgb: u32::from(target_format.is_srgb()),
            pad: [0; 3],
        };
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let frame_view = frame.create_view(&wgpu::TextureViewDescriptor {
            format: Some(frame.format().remove_srgb_suffix()),
            ..Default::default()
        });
        let overlay_view = self.overlay.0.create_view(&Default::default());
        let bind_group = self.program.bind_group(
            ctx,
            0,
            &[
                ("params", self.params.as_entire_binding()),
                (
                    "frame_load",
                    wgpu::BindingResource::TextureView(&frame_view),
                ),
                (
                    "overlay_load",
                    wgpu::BindingResource::TextureView(&overlay_view),
                ),
            ],
        )?;
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("present"),
            });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipelines[&target_format]);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        ctx.queue.submit([encoder.finish()]);
        ctx.check("present")
    }
}
