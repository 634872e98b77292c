//! Hybrid reconstruction anti-aliasing (TECHNIQUES A1–A5): SMAA, temporal
//! FLIPQUAD, TAA, unsharp recovery, and the sampling-pattern study.
//! Runs after tone mapping, on the display-referred image.

pub mod patterns;
pub mod settings;
pub mod smaa;

pub use settings::AaMode;
pub use smaa::{SmaaInputs, SmaaPass};
