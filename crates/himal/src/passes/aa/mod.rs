//! Hybrid reconstruction anti-aliasing (TECHNIQUES A1–A5): SMAA, temporal
//! FLIPQUAD, TAA, unsharp recovery, and the sampling-pattern study.

pub mod patterns;
pub mod smaa;
