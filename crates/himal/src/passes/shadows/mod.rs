//! Sun shadow map (foundation of TECHNIQUES S1): one orthographic depth map
//! fitted to the scene's bounds, sampled with a 3x3 tent of hardware
//! comparisons in the lighting pass (`shaders/shadow.wgsl`). Cascades, the
//! static far map, the atlas and the hero map (S1-S4) build on this pass.
//! Reference: [`reference`] and `tests/shadows.rs` (CPU ray casting).

pub mod reference;

use glam::{Mat4, Vec3};

use crate::frame::FrameErrors;
use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, TextureAccess, TextureDesc, TextureHandle};
use crate::renderer::scene_gpu::{SceneGpu, vertex_layout};
use crate::scene::Aabb;

pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Position and uv of [`crate::scene::Vertex`] (locations as in gbuffer.wgsl).
const VEGETATION_ATTRIBUTES: [wgpu::VertexAttribute; 2] = [
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: 0,
        shader_location: 0,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x2,
        offset: 40,
        shader_location: 3,
    },
];

/// Light-space fit of the sun shadow map; see [`reference::sun_shadow_fit`].
#[derive(Clone, Copy, Debug)]
pub struct ShadowFit {
    pub light_view_proj: Mat4,
    /// World size of one shadow texel (metres).
    pub texel_world: f32,
    /// Depth range of the orthographic projection (metres).
    pub depth_range: f32,
}

/// Twin of `ShadowView` in `sun.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadowViewGpu {
    light_view_proj: [[f32; 4]; 4],
    /// x animation time (s)
    time: [f32; 4],
}

pub struct SunShadowPass {
    program: Program,
    pipeline: wgpu::RenderPipeline,
    /// Alpha-tested, swaying vegetation: blades cast shadows, not cards.
    vegetation: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    /// Comparison sampler the lighting pass uses with the map.
    pub sampler: wgpu::Sampler,
}

impl SunShadowPass {
    pub fn new(ctx: &GpuContext) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/shadows/sun.wgsl")?;
        let mut layout = vertex_layout();
        layout.attributes = &layout.attributes[..1]; // position only
        let mut veg_layout = vertex_layout();
        veg_layout.attributes = &VEGETATION_ATTRIBUTES;
        let depth_stencil = wgpu::DepthStencilState {
            format: SHADOW_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::LessEqual),
            stencil: Default::default(),
            // Slope-scaled bias against acne on surfaces grazing the sun.
            bias: wgpu::DepthBiasState {
                constant: 0,
                slope_scale: 1.5,
                clamp: 0.0,
            },
        };
        let vegetation = program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "shadows.sun.vegetation",
                vertex_entry: "vs_vegetation",
                fragment_entry: Some("fs_vegetation"),
                vertex_buffers: &[Some(veg_layout)],
                targets: &[],
                depth_stencil: Some(depth_stencil.clone()),
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                constants: &[],
            },
        )?;
        let pipeline = program.render_pipeline(
            ctx,
            &RenderSpec {
                label: "shadows.sun",
                vertex_entry: "vs_main",
                fragment_entry: None,
                vertex_buffers: &[Some(layout)],
                targets: &[],
                depth_stencil: Some(depth_stencil),
                // Both faces cast: the terrain is single-sided.
                primitive: wgpu::PrimitiveState {
                    cull_mode: None,
                    ..Default::default()
                },
                constants: &[],
            },
        )?;
        let uniform = uniform_buffer(
            ctx,
            "shadows.sun.view",
            &ShadowViewGpu {
                light_view_proj: Mat4::IDENTITY.to_cols_array_2d(),
                time: [0.0; 4],
            },
        );
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadows.sun.compare"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        Ok(Self {
            program,
            pipeline,
            vegetation,
            uniform,
            sampler,
        })
    }

    /// Fits the map to `bounds` for `sun_direction` and uploads the matrix
    /// and the animation time `time_s` (vegetation sway).
    pub fn update(
        &self,
        queue: &wgpu::Queue,
        bounds: &Aabb,
        sun_direction: Vec3,
        resolution: u32,
        time_s: f32,
    ) -> ShadowFit {
        let fit = reference::sun_shadow_fit(bounds, sun_direction, resolution);
        let gpu = ShadowViewGpu {
            light_view_proj: fit.light_view_proj.to_cols_array_2d(),
            time: [time_s, 0.0, 0.0, 0.0],
        };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&gpu));
        fit
    }

    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        resolution: u32,
        scene: &'a SceneGpu,
        errors: &'a FrameErrors,
    ) -> TextureHandle {
        let map = graph.create_texture(
            "shadow.sun",
            TextureDesc::new_2d(resolution, resolution, SHADOW_FORMAT),
        );
        let mut pass = graph.add_pass("shadows.sun");
        let map = pass.write(map, TextureAccess::DepthAttachment);
        pass.execute(move |ctx| {
            let bind_group = self.program.bind(
                ctx.device,
                0,
                &[
                    ("shadow", self.uniform.as_entire_binding()),
                    ("objects", scene.objects.as_entire_binding()),
                ],
            );
            let Some(bg) = errors.record(bind_group) else {
                return;
            };
            let view = ctx.view(map);
            let mut rp = ctx.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shadows.sun"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            rp.set_pipeline(&self.pipeline);
            rp.set_bind_group(0, &bg, &[]);
            scene.draw_opaque(&mut rp);
            if !scene.draws_vegetation.is_empty() {
                rp.set_pipeline(&self.vegetation);
                SceneGpu::draw_list(&mut rp, &scene.draws_vegetation);
            }
        });
        map
    }
}
