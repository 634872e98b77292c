//! L5 indirect light for the whole world: radiance-transfer probes baked
//! offline, streamed in cells, turned into SH probes for the current sky
//! and sun every frame and injected into a camera-centred clip map that
//! deferred lighting samples (Far Cry 4, "Indirect lighting";
//! docs/techniques/L5.md).
//!
//! - [`cell`]: 8 x 8 probes per cell, mips 0..4, the file format.
//! - [`bake`]: the CPU ray-cast bake of one cell.
//! - [`pass`]: the GPU pool and the `probes.transfer` / `probes.inject` nodes.
//! - [`pool`]: 16 cells per mip on the GPU, farthest-first eviction, page tables.
//! - [`store`]: a scene's cells of every mip, baked or read from the cache.
//! - [`world`]: the streamed world's cells, baked per block of sectors as the camera goes.
//! - [`reference`]: CPU twins of transfer, injection and clip-map sampling.

pub mod bake;
pub mod cell;
pub mod pass;
pub mod pool;
pub mod reference;
pub mod store;
pub mod world;

pub use bake::{BakeSettings, bake_cell, bake_probe, ground_height};
pub use cell::{Cell, CellKey, Transfer};
pub use pass::{IndirectFrame, IndirectLight, IndirectPass, IndirectStats};
pub use pool::{Admit, CellPool};
pub use store::{BakeReport, CellSource, ProbeStore};
pub use world::WorldProbes;
