//! himal: an open-world real-time deferred renderer on wgpu.
//!
//! One frame (see [`frame`]) implements the techniques of the Far Cry 4,
//! Battlefield 3, Far Cry 1 and Ryse talks; every GPU pass has a CPU twin in
//! its folder's `reference.rs`. Start with `docs/architecture.md`.

pub mod gpu;
pub mod graph;
pub mod math;
pub mod passes;
pub mod scene;
pub mod shader;
