//! The scene's ambient lights (`[[ambient_light]]`) on the GPU: the twin of
//! `AmbientLights` in `shaders/ambient_lights.wgsl`, uploaded once per
//! scene; the count is rewritten per frame (0 with
//! `FrameSettings::ambient_lights` off). docs/ambient-lights.md.

use bytemuck::{Pod, Zeroable};

use crate::scene::{AmbientLightDesc, AmbientShape, MAX_AMBIENT_LIGHTS};

/// Twin of `AmbientLight`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AmbientLightGpu {
    /// xyz: world-space centre (m); w: shape, 0 = box, 1 = sphere.
    pub position_shape: [f32; 4],
    /// xyz: box half-extents (m), or the sphere's radius (m) in all three;
    /// w: falloff fraction in [0, 1] (0: hard edge).
    pub extent_falloff: [f32; 4],
    /// rgb: linear multiplier per channel, [0, 16]; w: 1 (unused).
    pub factor: [f32; 4],
    /// x: cos(yaw), y: sin(yaw) of the box's rotation about +Y; zw: 0.
    pub yaw: [f32; 4],
}

impl From<&AmbientLightDesc> for AmbientLightGpu {
    fn from(a: &AmbientLightDesc) -> Self {
        let p = a.position;
        let (extent, shape) = match a.shape {
            AmbientShape::Box(h) => (h.to_array(), 0.0),
            AmbientShape::Sphere(r) => ([r, r, r], 1.0),
        };
        let yaw = a.yaw_deg.to_radians();
        Self {
            position_shape: [p.x, p.y, p.z, shape],
            extent_falloff: [extent[0], extent[1], extent[2], a.falloff],
            factor: a.factor.extend(1.0).to_array(),
            yaw: [yaw.cos(), yaw.sin(), 0.0, 0.0],
        }
    }
}

/// Twin of `AmbientLights`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct AmbientLightsGpu {
    /// x: how many of `lights` are in use (0 turns them all off); yzw: 0.
    pub count: [u32; 4],
    /// The lights, `count[0]` of them from the start; the rest zeroed.
    pub lights: [AmbientLightGpu; MAX_AMBIENT_LIGHTS],
}

impl AmbientLightsGpu {
    /// The first [`MAX_AMBIENT_LIGHTS`] of `lights` (the scene file allows no more).
    pub fn new(lights: &[AmbientLightDesc]) -> Self {
        let mut out = Self::zeroed();
        for (slot, l) in out.lights.iter_mut().zip(lights) {
            *slot = l.into();
        }
        out.count[0] = lights.len().min(MAX_AMBIENT_LIGHTS) as u32;
        out
    }
}

/// The buffer and how many lights it holds.
pub struct AmbientLightBuffer {
    /// The storage buffer holding one [`AmbientLightsGpu`] (binding 20 of
    /// the shaders that import `ambient_lights.wgsl`); `COPY_DST` so
    /// [`enable`](Self::enable) can rewrite the count.
    pub buffer: wgpu::Buffer,
    /// The scene's light count, written back by `enable(.., true)`.
    pub count: u32,
}

impl AmbientLightBuffer {
    /// Uploads the scene's lights (at most [`MAX_AMBIENT_LIGHTS`]), enabled.
    pub fn new(device: &wgpu::Device, lights: &[AmbientLightDesc]) -> Self {
        use wgpu::util::DeviceExt;
        let data = AmbientLightsGpu::new(lights);
        Self {
            buffer: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("lighting.ambient_lights"),
                contents: bytemuck::bytes_of(&data),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            }),
            count: data.count[0],
        }
    }

    /// Turns the lights on (the scene's count) or off (0) for the next frame.
    pub fn enable(&self, queue: &wgpu::Queue, on: bool) {
        let count = [if on { self.count } else { 0 }, 0, 0, 0];
        queue.write_buffer(&self.buffer, 0, bytemuck::cast_slice(&count));
    }
}
