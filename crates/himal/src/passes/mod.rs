//! Frame passes, one folder per technique group: `mod.rs` (pipelines and
//! graph nodes), one `.wgsl` per step, and `reference.rs` (the CPU twin).

pub mod aa;
pub mod ao;
pub mod common;
pub mod cull;
pub mod debug;
pub mod envmap;
pub mod forward;
pub mod gbuffer;
pub mod indirect;
pub mod lighting;
pub mod particles;
pub mod post;
pub mod shadows;
pub mod skin;
pub mod sky;
pub mod skyocc;
pub mod terrain;
pub mod tree_ao;
pub mod vegetation;
pub mod wet;
