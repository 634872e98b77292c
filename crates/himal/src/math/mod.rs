//! CPU math shared by passes, references and baking.

pub mod brdf;
pub mod quat_frame;
pub mod sampling;
pub mod sh;
