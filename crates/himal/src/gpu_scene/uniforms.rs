//! CPU twins of the uniform structs in `shaders/view.wgsl` and
//! `passes/lighting/deferred.wgsl` (layouts checked by a test).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3, Vec4};

use crate::math::sh::Sh9Gpu;

/// Per-view constants (`View` in `shaders/view.wgsl`): matrices, camera,
/// viewport, jitter and clocks. Matrices are column-major, world space is
/// Y-up in metres, clip depth is wgpu's \[0,1\].
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ViewUniform {
    /// World to clip, this frame (with the TAA jitter when it is on).
    pub view_proj: [[f32; 4]; 4],
    /// Clip to world: inverse of [`Self::view_proj`] (world positions from depth).
    pub inv_view_proj: [[f32; 4]; 4],
    /// The previous frame's world-to-clip matrix (motion vectors, reprojection).
    pub prev_view_proj: [[f32; 4]; 4],
    /// World to view space (right-handed, camera looking down -Z).
    pub view: [[f32; 4]; 4],
    /// xyz camera position, w near plane
    pub camera_position: [f32; 4],
    /// width, height, 1/width, 1/height
    pub viewport: [f32; 4],
    /// xy jitter (clip units), z frame index, w exposure bias (EV)
    pub jitter: [f32; 4],
    /// x animation time now (s), y animation time of the previous frame, zw 0
    pub time: [f32; 4],
    /// xyz unit view direction, w the far plane of an orthographic camera
    /// (parallel rays), 0 for a perspective one
    pub camera_forward: [f32; 4],
}

impl ViewUniform {
    /// Builds the uniform for camera `view` / `proj` at `position` (world, metres)
    /// with near plane `near` (metres) and a viewport of `size` pixels; the jitter's
    /// xy and the clocks stay 0 until [`Self::with_jitter`] / [`Self::with_times`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        view: Mat4,
        proj: Mat4,
        prev_view_proj: Mat4,
        position: Vec3,
        near: f32,
        size: (u32, u32),
        frame_index: u64,
        exposure_bias_ev: f32,
    ) -> Self {
        let view_proj = proj * view;
        let (w, h) = (size.0 as f32, size.1 as f32);
        Self {
            view_proj: view_proj.to_cols_array_2d(),
            inv_view_proj: view_proj.inverse().to_cols_array_2d(),
            prev_view_proj: prev_view_proj.to_cols_array_2d(),
            view: view.to_cols_array_2d(),
            camera_position: position.extend(near).to_array(),
            viewport: [w, h, 1.0 / w, 1.0 / h],
            jitter: [0.0, 0.0, frame_index as f32, exposure_bias_ev],
            time: [0.0; 4],
            // The view matrix's third row is the camera's back axis.
            camera_forward: (-view.row(2).truncate()).extend(0.0).to_array(),
        }
    }

    /// Marks the camera orthographic (parallel view rays) with far plane `far`.
    pub fn with_orthographic(mut self, far: Option<f32>) -> Self {
        self.camera_forward[3] = far.unwrap_or(0.0);
        self
    }

    /// Sets this frame's projection jitter in clip units (the matrices already carry it).
    pub fn with_jitter(mut self, x: f32, y: f32) -> Self {
        self.jitter[0] = x;
        self.jitter[1] = y;
        self
    }

    /// Sets the animation clock: `now` and the previous frame's time (s).
    pub fn with_times(mut self, now: f32, prev: f32) -> Self {
        self.time = [now, prev, 0.0, 0.0];
        self
    }
}

/// Constants of the deferred lighting pass (`Lighting` in `passes/lighting/deferred.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct LightingUniform {
    /// xyz unit vector towards the sun (world space); w 1 = V5 leaf shading
    /// (foliage pixels lit through and with a leaf's specular).
    pub sun_direction: [f32; 4],
    /// rgb sun illuminance at the ground in klux (zero when the sun is off);
    /// w 1 = R4, Burley's remapped roughness in analytic lights' visibility term.
    pub sun_illuminance: [f32; 4],
    /// Sky irradiance E(n) as SH9, in klux.
    pub sky_irradiance: Sh9Gpu,
    /// x extinction per metre, y aerial perspective amount (0 = off), z 1 = fog
    /// inscatter from the sky SH (Bruneton sky), w 1 = sky light along the bent normal (L2).
    pub fog: [f32; 4],
}

impl LightingUniform {
    /// Packs the sun, sky SH and fog parameters (see the fields) into the GPU layout.
    pub fn new(
        sun_direction: Vec3,
        sun_illuminance: Vec3,
        sky_irradiance: Sh9Gpu,
        fog: Vec4,
    ) -> Self {
        Self {
            sun_direction: sun_direction.extend(0.0).to_array(),
            sun_illuminance: sun_illuminance.extend(0.0).to_array(),
            sky_irradiance,
            fog: fog.to_array(),
        }
    }

    /// R4 on or off (`sun_illuminance.w`; see `FrameSettings::visibility_remap`).
    pub fn with_visibility_remap(mut self, on: bool) -> Self {
        self.sun_illuminance[3] = if on { 1.0 } else { 0.0 };
        self
    }

    /// V5 leaf shading on or off (`sun_direction.w`; see `FrameSettings::leaf_shading`).
    pub fn with_leaf_shading(mut self, on: bool) -> Self {
        self.sun_direction[3] = if on { 1.0 } else { 0.0 };
        self
    }
}
