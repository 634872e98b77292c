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

#![warn(missing_docs)]

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
    /// Device, pipeline, validation or read-back failure.
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
    /// The frame graph was misused or failed to record.
    #[error("frame graph: {0}")]
    Graph(#[from] graph::GraphError),
    /// A scene file, glTF or world description could not be loaded.
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    /// A shader failed to compose, parse, validate or reflect.
    #[error(transparent)]
    Shader(#[from] shader::ShaderError),
    /// An output image could not be written.
    #[error("{path}: {message}")]
    Image {
        /// The output file.
        path: String,
        /// What went wrong (unsupported extension, encoder or I/O error).
        message: String,
    },
    /// A [`FrameSettings`] value is out of range or unknown (the text says which).
    #[error("{0}")]
    InvalidSettings(String),
}
