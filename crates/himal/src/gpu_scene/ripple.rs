//! V2 grass ripple: the layout of the grid buffer around the camera
//! (`shaders/ripple.wgsl`), which the scene upload allocates and
//! `passes/vegetation` steps (the step and its CPU twin live there).

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};

/// Cells per side of the window (a scene with grass).
pub const RIPPLE_N: i32 = 128;
/// Cell size (m): the window covers 32 x 32 m.
pub const RIPPLE_CELL: f32 = 0.25;
/// Wave speed (m/s).
pub const RIPPLE_SPEED: f32 = 3.0;

/// Twin of `RippleHeader`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RippleHeader {
    /// Window origin (world cell x, z), the half this step reads, cells per side.
    pub window: [i32; 4],
    /// Cell size (m), step (s), wave speed (m/s), 0.
    pub params: [f32; 4],
}

/// Bytes of a ripple buffer of `n` cells per side: header, two halves of
/// heights, two of gradients.
pub fn ripple_bytes(n: i32) -> u64 {
    (std::mem::size_of::<RippleHeader>() + 4 * (n * n) as usize * 16) as u64
}

/// The header of a frame whose camera is at `camera`, reading `half`.
pub fn header(n: i32, camera: Vec3, half: i32, dt: f32) -> RippleHeader {
    let c = (Vec2::new(camera.x, camera.z) / RIPPLE_CELL).floor();
    RippleHeader {
        window: [c.x as i32 - n / 2, c.y as i32 - n / 2, half, n],
        params: [RIPPLE_CELL, dt, RIPPLE_SPEED, 0.0],
    }
}
