//! Environment probes (TECHNIQUES L3): a G-buffer cube (albedo, tangent
//! frame, material, depth; 128² per face) captured once per probe with the
//! G-buffer pass, then relit by the deferred lighting pass (sun unshadowed,
//! sky SH unoccluded, no fog, no AO) and the sky pass whenever the time of
//! day changes, mirrored into the source cube and filtered like the sky
//! (L4). The probe nearest the camera is used, with hysteresis
//! ([`select_probe`]).

use glam::Vec3;

use crate::gpu::pipeline::{Program, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::uniforms::ViewUniform;
use crate::graph::{FrameGraph, TextureAccess, TextureHandle};
use crate::passes::gbuffer::{ALBEDO_FORMAT, DEPTH_FORMAT, FRAME_FORMAT, GBuffer, MATERIAL_FORMAT};
use crate::scene::Camera;

/// (forward, up) of the cube faces +X, -X, +Y, -Y, +Z, -Z (Vulkan convention).
pub const FACE_AXES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::NEG_Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// Near plane of the face cameras (metres).
pub const PROBE_NEAR: f32 = 0.05;

/// Hysteresis of the probe switch: another probe must be this fraction of
/// the current one's distance nearer (see [`ProbeSet::select`]).
pub const PROBE_SWITCH_MARGIN: f32 = 0.1;

/// The camera that renders face `face` of a probe at `position`.
pub fn face_camera(position: Vec3, face: usize) -> Camera {
    let (forward, up) = FACE_AXES[face];
    Camera {
        position,
        forward,
        up,
        fov_y_deg: 90.0,
        near: PROBE_NEAR,
        orthographic: None,
    }
}

/// The probe to use from `camera_position` while `current` is in use: the
/// nearest, but `current` is kept until another probe is nearer by
/// [`PROBE_SWITCH_MARGIN`] of its distance (at least 1 m), so a camera
/// hovering halfway does not relight and refilter every frame.
pub fn select_probe(
    positions: &[Vec3],
    camera_position: Vec3,
    current: Option<usize>,
) -> Option<usize> {
    let distance = |i: usize| positions[i].distance(camera_position);
    let nearest = (0..positions.len()).min_by(|&a, &b| distance(a).total_cmp(&distance(b)))?;
    match current.filter(|&c| c < positions.len() && c != nearest) {
        Some(c) => {
            let d = distance(c);
            let margin = (d * PROBE_SWITCH_MARGIN).max(1.0);
            Some(if distance(nearest) < d - margin {
                nearest
            } else {
                c
            })
        }
        None => Some(nearest),
    }
}

/// One face's persistent G-buffer and its view uniform.
pub struct ProbeFace {
    /// G-buffer albedo of the face ([`ALBEDO_FORMAT`]).
    pub albedo: wgpu::Texture,
    /// G-buffer tangent frame of the face ([`FRAME_FORMAT`]).
    pub frame: wgpu::Texture,
    /// G-buffer material parameters of the face ([`MATERIAL_FORMAT`]).
    pub material: wgpu::Texture,
    /// Depth of the face ([`DEPTH_FORMAT`], reverse-Z).
    pub depth: wgpu::Texture,
    /// The face camera's [`ViewUniform`] (90° field of view, near plane [`PROBE_NEAR`]).
    pub view: wgpu::Buffer,
}

/// One environment probe: a G-buffer cube captured at a fixed point.
pub struct Probe {
    /// Capture point in world space (metres).
    pub position: Vec3,
    /// The six faces in [`FACE_AXES`] order.
    pub faces: Vec<ProbeFace>,
    /// The G-buffer cube holds the scene (set after the capturing frame).
    pub captured: bool,
}

/// Probes of a scene and the mirror pipelines (one per face).
pub struct ProbeSet {
    /// One probe per position given to [`Self::new`], in that order.
    pub probes: Vec<Probe>,
    /// Face size in texels.
    pub size: u32,
    program: Program,
    mirror: Vec<wgpu::ComputePipeline>,
}

fn face_texture(
    ctx: &GpuContext,
    label: &str,
    size: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size,
            height: size,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        // Render attachment: the sky pass depth-tests against the stored depth.
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

impl ProbeSet {
    /// Creates a probe at each of `positions` with `size`² faces (not yet captured) and the mirror pipelines.
    pub fn new(ctx: &GpuContext, positions: &[Vec3], size: u32) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/envmap/face.wgsl")?;
        let mirror = (0..6)
            .map(|f| program.compute_pipeline(ctx, "cs_mirror", &[("FACE", f as f64)]))
            .collect::<Result<_, _>>()?;
        let probes = positions
            .iter()
            .enumerate()
            .map(|(p, &position)| {
                let faces = (0..6)
                    .map(|f| {
                        let label = format!("probe{p}.face{f}");
                        let camera = face_camera(position, f);
                        let proj = camera.projection(1.0);
                        let view = camera.view();
                        let uniform = ViewUniform::new(
                            view,
                            proj,
                            proj * view,
                            position,
                            PROBE_NEAR,
                            (size, size),
                            0,
                            0.0,
                        );
                        ProbeFace {
                            albedo: face_texture(ctx, &label, size, ALBEDO_FORMAT),
                            frame: face_texture(ctx, &label, size, FRAME_FORMAT),
                            material: face_texture(ctx, &label, size, MATERIAL_FORMAT),
                            depth: face_texture(ctx, &label, size, DEPTH_FORMAT),
                            view: uniform_buffer(ctx, &label, &uniform),
                        }
                    })
                    .collect();
                Probe {
                    position,
                    faces,
                    captured: false,
                }
            })
            .collect();
        Ok(Self {
            probes,
            size,
            program,
            mirror,
        })
    }

    /// The probe to use from `camera_position` while `current` is in use
    /// ([`select_probe`]).
    pub fn select(&self, camera_position: Vec3, current: Option<usize>) -> Option<usize> {
        let positions: Vec<Vec3> = self.probes.iter().map(|p| p.position).collect();
        select_probe(&positions, camera_position, current)
    }

    /// L3: relights probe `index`'s G-buffer cube face by face into level 0
    /// of the environment source, then mips and filters it; returns the
    /// filtered cube. `capture`: render the faces' G-buffer first (with
    /// `gbuffer`) and store it; `relight` lights one face's G-buffer
    /// (given the filtered cube of before, for ambient specular) into HDR.
    /// Each face's nodes run under the prefix `envmap.probe{index}.face{f}`
    /// with the face's camera as the `view` frame constant.
    pub fn add_relight<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        envmap: &'a super::EnvMapPass,
        (index, capture): (usize, bool),
        mut gbuffer: impl FnMut(&mut FrameGraph<'a>) -> GBuffer,
        mut relight: impl FnMut(&mut FrameGraph<'a>, GBuffer, TextureHandle) -> TextureHandle,
    ) -> TextureHandle {
        let constants = graph.frame_constants();
        let mut source = envmap.import_source(graph);
        let env_before = graph.import_texture("envmap.filtered.before", envmap.filtered());
        for face in 0..6 {
            graph.set_pass_prefix(Some(format!("envmap.probe{index}.face{face}")));
            let view = &self.probes[index].faces[face].view;
            let face_constants: Vec<_> = constants
                .iter()
                .map(|&(name, b)| (name, if name == "view" { view } else { b }))
                .collect();
            graph.set_frame_constants(&face_constants);
            let stored = if capture {
                let fresh = gbuffer(graph);
                self.add_store(graph, index, face, fresh)
            } else {
                self.import_face(graph, index, face)
            };
            let hdr = relight(graph, stored, env_before);
            source = self.add_mirror(graph, face, hdr, source);
        }
        graph.set_pass_prefix(None);
        graph.set_frame_constants(&constants);
        envmap.add_mips_and_filter(graph, source)
    }

    /// Copies a freshly rendered G-buffer face into the probe's textures;
    /// returns them (as the relight's input).
    pub fn add_store<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        probe: usize,
        face: usize,
        gbuffer: GBuffer,
    ) -> GBuffer {
        let f = &self.probes[probe].faces[face];
        let pairs = [
            (gbuffer.albedo, &f.albedo, "probe.albedo"),
            (gbuffer.frame, &f.frame, "probe.frame"),
            (gbuffer.material, &f.material, "probe.material"),
            (gbuffer.depth, &f.depth, "probe.depth"),
        ];
        let imported: Vec<(TextureHandle, TextureHandle, &'a wgpu::Texture)> = pairs
            .into_iter()
            .map(|(src, dst, name)| (src, graph.import_texture(name, dst), dst))
            .collect();
        let mut pass = graph.add_pass("store");
        let mut outputs = Vec::new();
        for (src, dst, _) in &imported {
            pass.read(*src, TextureAccess::CopySrc);
            outputs.push(pass.write(*dst, TextureAccess::CopyDst));
        }
        let size = self.size;
        pass.execute(move |ctx| {
            for (src, _, dst) in &imported {
                ctx.encoder.copy_texture_to_texture(
                    ctx.texture(*src).as_image_copy(),
                    dst.as_image_copy(),
                    wgpu::Extent3d {
                        width: size,
                        height: size,
                        depth_or_array_layers: 1,
                    },
                );
            }
            Ok(())
        });
        for o in &outputs {
            graph.mark_output(*o);
        }
        GBuffer {
            albedo: outputs[0],
            frame: outputs[1],
            material: outputs[2],
            motion: outputs[0],
            depth: outputs[3],
        }
    }

    /// The stored G-buffer of a probe face, imported for relighting.
    pub fn import_face<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        probe: usize,
        face: usize,
    ) -> GBuffer {
        let f = &self.probes[probe].faces[face];
        let albedo = graph.import_texture("probe.albedo", &f.albedo);
        GBuffer {
            albedo,
            frame: graph.import_texture("probe.frame", &f.frame),
            material: graph.import_texture("probe.material", &f.material),
            // Lighting does not read motion.
            motion: albedo,
            depth: graph.import_texture("probe.depth", &f.depth),
        }
    }

    /// Writes relit face `hdr` (camera layout) into layer `face` of level 0 of `source`.
    pub fn add_mirror<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        face: usize,
        hdr: TextureHandle,
        source: TextureHandle,
    ) -> TextureHandle {
        let level0 = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            base_mip_level: 0,
            mip_level_count: Some(1),
            ..Default::default()
        };
        let n = self.size.div_ceil(8);
        graph
            .compute("mirror", &self.program)
            .compute_pipeline(Ok(self.mirror[face].clone()))
            .read("face_hdr", hdr)
            .storage_view("out_texture", source, level0)
            .dispatch([n, n, 1])
            .storage[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probe_switch_has_hysteresis() {
        let probes = [Vec3::ZERO, Vec3::new(20.0, 0.0, 0.0)];
        let at = |x: f32| Vec3::new(x, 2.0, 0.0);
        // No probe in use: the nearest.
        assert_eq!(select_probe(&probes, at(9.0), None), Some(0));
        assert_eq!(select_probe(&probes, at(11.0), None), Some(1));
        // Just past halfway the first stays; 10 % of its distance nearer, the second wins.
        assert_eq!(select_probe(&probes, at(10.5), Some(0)), Some(0));
        assert_eq!(select_probe(&probes, at(11.5), Some(0)), Some(1));
        // And back: hovering around x = 10 never flips.
        for x in [9.6, 10.4, 9.7, 10.3] {
            assert_eq!(select_probe(&probes, at(x), Some(1)), Some(1), "x {x}");
            assert_eq!(select_probe(&probes, at(x), Some(0)), Some(0), "x {x}");
        }
        // A stale index (probes changed) falls back to the nearest.
        assert_eq!(select_probe(&probes, at(1.0), Some(7)), Some(0));
        assert_eq!(select_probe(&[], at(1.0), Some(0)), None);
    }
}
