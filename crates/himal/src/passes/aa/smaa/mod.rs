//! A1 SMAA 1x (Jimenez et al. 2012): `aa.smaa.edges` (luma, depth
//! predicated), `aa.smaa.weights` (orthogonal search and area lookups),
//! `aa.smaa.blend` (neighbourhood blending). CPU twins in `reference.rs`.

pub mod lut;
