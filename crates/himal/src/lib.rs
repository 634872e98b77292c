//! himal: an open-world real-time deferred renderer on wgpu.
//!
//! One frame (see [`frame`]) implements the techniques of the Far Cry 4,
//! Battlefield 3, Far Cry 1 and Ryse talks; every GPU pass has a CPU twin in
//! its folder's `reference.rs`. Start with `docs/architecture.md`.
//!
//! ```no_run
//! use himal::{gpu::{GpuContext, GpuOptions}, scene::Scene, FrameSettings, Renderer};
//! let scene = Scene::demo()?;
//! let mut renderer = Renderer::new(GpuContext::new(&GpuOptions::default())?, &scene)?;
//! let settings = FrameSettings::new(640, 360, scene.sun.clone());
//! let frame = renderer.render(scene.camera("valley")?, &settings)?;
//! himal::image_io::save(std::path::Path::new("out/valley.png"), &frame.image)?;
//! # Ok::<(), himal::Error>(())
//! ```

pub mod budget;
pub mod clock;
pub mod frame;
pub mod gpu;
pub mod gpu_scene;
pub mod graph;
pub mod image_io;
pub mod math;
pub mod passes;
pub mod present;
pub mod renderer;
pub mod scene;
pub mod settings;
pub mod shader;
pub mod soak;

pub use renderer::{
    DrawnCounts, DrawnFrame, FrameSettings, RenderedFrame, Renderer, ViewBuffer, WorldFrame,
};
pub use settings::{Culling, Occlusion};

/// Every error the library returns; each names what failed and where.
#[derive(thiserror::Error, Debug)]
pub enum Error {
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
    #[error("frame graph: {0}")]
    Graph(#[from] graph::GraphError),
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    #[error(transparent)]
    Shader(#[from] shader::ShaderError),
    #[error("{path}: {message}")]
    Image { path: String, message: String },
    #[error("{0}")]
    InvalidSettings(String),
}
