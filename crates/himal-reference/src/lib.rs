//! CPU ground truth for himal's tests.
//!
//! Nothing here depends on `himal` (himal dev-depends on this crate): the
//! integrators take the functions under test as closures, and the formulas
//! here are written independently of himal's, in another parameterisation,
//! so a shared mistake is unlikely.
//!
//! - [`ao`]: ray-traced ambient occlusion of analytic scenes (planes, spheres, boxes).
//! - [`bounce`]: one-bounce indirect irradiance by path tracing (L5's ground truth).
//! - [`flip`]: the LDR-FLIP perceptual error map between two images
//!   (Andersson et al. 2020).
//! - [`integrate`]: Monte Carlo (importance sampling, two-strategy MIS) and
//!   deterministic polar quadrature over the sphere.
//! - [`microfacet`]: isotropic GGX D and Smith terms in f64, written in
//!   theta form after Walter et al. 2007 and Heitz 2014.

pub mod ao;
pub mod bounce;
pub mod flip;
pub mod integrate;
pub mod microfacet;
