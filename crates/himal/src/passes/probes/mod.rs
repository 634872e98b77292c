//! L5 indirect light for the whole world: radiance-transfer probes baked
//! offline, streamed in cells, turned into SH probes for the current sky
//! and sun every frame and injected into a camera-centred clip map that
//! deferred lighting samples (Far Cry 4, "Indirect lighting";
//! docs/techniques/L5.md).
//!
//! - [`cell`]: 8 x 8 probes per cell, mips 0..4, the file format.
//! - [`bake`]: the CPU ray-cast bake of one cell.
//! - [`pool`]: 16 cells per mip on the GPU, farthest-first eviction, page tables.
//! - [`reference`]: CPU twins of transfer, injection and clip-map sampling.

pub mod bake;
pub mod cell;
pub mod pool;
pub mod reference;

pub use bake::{BakeSettings, bake_cell, bake_probe, ground_height};
pub use cell::{Cell, CellKey, Transfer};
pub use pool::{Admit, CellPool};
