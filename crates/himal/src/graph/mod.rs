//! Frame graph: typed versioned handles, compile (order, cull, usages, pool), execute with timestamps.
//!
//! Built every frame (Filament / kajiya style, small):
//! - Passes declare reads and writes by handle; [`PassBuilder::write`]
//!   returns the next version, so read-after-write is explicit. Writing also
//!   consumes the previous version (attachments may `Load` it).
//! - [`FrameGraph::compile`] validates (misuse is an error, never a panic),
//!   orders passes (declaration order where valid; a pass reading an old
//!   version is moved before the overwrite), culls passes that reach no
//!   output (resources marked with [`FrameGraph::mark_output`], whose
//!   final version counts) and no `side_effect` pass, derives
//!   `wgpu::TextureUsages` / `BufferUsages` from the live accesses, and
//!   plans pool slots: a transient's slot is free after its last use and
//!   reused by a later transient of identical key ([`PoolPlan`]).
//! - [`CompiledGraph::execute`] records one command buffer with transients
//!   from a [`TexturePool`] kept across frames and, given a [`PassTimer`],
//!   a timestamp pair around each pass.
//!
//! Nothing before `execute` needs a device. Imported resources borrow the
//! texture or buffer (`import_texture`); for device-free tests and
//! listings, `import_texture_desc` / `import_buffer_desc` import a
//! placeholder from a description, which `execute` rejects
//! ([`GraphError::UnboundImport`]) if a live pass uses it. Imported
//! resources are not outputs unless marked: mark history written for the
//! next frame as output.

mod builder;
mod compile;
mod describe;
mod execute;
mod fallback;
mod history;
mod node;
mod pool;
mod resource;
mod timer;

#[cfg(test)]
mod tests;

pub use builder::{FrameGraph, PassBuilder};
pub use compile::{BufferKey, CompiledGraph, CompiledPass, PoolAssignment, PoolPlan, TextureKey};
pub use execute::{IsolatedTimings, PassContext};
pub use history::{History, HistoryFrame};
pub use node::{Fallback, Node, RasterFn, Written};
pub use pool::TexturePool;
pub use resource::{
    BufferAccess, BufferDesc, BufferHandle, ResourceAccess, ResourceUse, TextureAccess,
    TextureDesc, TextureHandle,
};
pub use timer::{PassTimer, PassTiming, TimingMethod};

/// Frame graph misuse and device failures.
#[derive(thiserror::Error, Debug, Clone, PartialEq, Eq)]
pub enum GraphError {
    /// A pass reads a resource that no earlier pass wrote and that was not imported.
    #[error("pass '{pass}' reads '{resource}' before any pass wrote it")]
    ReadBeforeWrite {
        /// Id of the reading pass.
        pass: String,
        /// Name of the resource it reads.
        resource: String,
    },
    /// A pass writes a handle whose version was already overwritten by another pass.
    #[error(
        "pass '{pass}' writes '{resource}'@{used} but the newest version is @{latest} (two writers of one version)"
    )]
    StaleVersion {
        /// Id of the writing pass.
        pass: String,
        /// Name of the resource written.
        resource: String,
        /// Version of the handle the pass wrote through.
        used: u32,
        /// Newest version of the resource at that point of the declaration.
        latest: u32,
    },
    /// Two passes were declared with the same id.
    #[error("pass id '{0}' is used twice")]
    DuplicatePass(String),
    /// Two resources (created or imported) share a name.
    #[error("resource name '{0}' is used twice")]
    DuplicateResource(String),
    /// A pass (named by its id) was declared but never given a body.
    #[error("pass '{0}' was declared without execute()")]
    MissingExecute(String),
    /// A handle does not belong to this graph or names a resource of the other kind.
    #[error("{context}: handle of another graph, unknown resource or wrong kind")]
    UnknownHandle {
        /// Where the handle was used: a pass id or a builder call.
        context: String,
    },
    /// A pass declared an access that does not fit the declaring call (a write access through `read()`, say).
    #[error("pass '{pass}' declares {access} on '{resource}' with {declared_with}()")]
    InvalidAccess {
        /// Id of the declaring pass.
        pass: String,
        /// Name of the resource.
        resource: String,
        /// The access as text (e.g. `StorageWrite`).
        access: String,
        /// Name of the builder method used (`read`, `write`, ...).
        declared_with: &'static str,
    },
    /// A pass body touched a resource it did not declare.
    #[error("pass '{pass}' uses '{resource}' without declaring it")]
    UndeclaredResource {
        /// Id of the pass.
        pass: String,
        /// Name of the undeclared resource.
        resource: String,
    },
    /// The listed pass ids depend on each other in a loop, so no order exists.
    #[error("passes {0:?} form a cycle (a pass reads a version that one of its inputs overwrote)")]
    Cycle(Vec<String>),
    /// An imported texture or buffer lacks usage flags that its live accesses need.
    #[error("imported '{resource}' needs usages {needed} but was created with {available}")]
    ImportedUsage {
        /// Name of the imported resource.
        resource: String,
        /// Usage flags the live passes need.
        needed: String,
        /// Usage flags the resource was created with.
        available: String,
    },
    /// A live pass uses a placeholder import (`import_*_desc`, named here), which has nothing to bind.
    #[error("'{0}' was imported as a placeholder (import_*_desc) and cannot execute")]
    UnboundImport(String),
    /// The graph has more live passes than the [`PassTimer`] has timestamp pairs.
    #[error("{passes} passes but the pass timer holds {capacity}")]
    TimerCapacity {
        /// Number of live passes.
        passes: usize,
        /// Passes the timer can time (its query set holds twice this many timestamps).
        capacity: u32,
    },
    /// A wgpu error while recording or reading back that could not be pinned on one pass.
    #[error("device: {0}")]
    Device(String),
    /// A [`Node`] binding could not be resolved (missing or mistyped shader binding).
    #[error("pass '{pass}': {message}")]
    Binding {
        /// Id of the pass.
        pass: String,
        /// What was wrong with the binding.
        message: String,
    },
    /// A pass body returned an error, or wgpu validation named the pass.
    #[error("pass '{pass}': {message}")]
    Pass {
        /// Id of the pass.
        pass: String,
        /// The error's text.
        message: String,
    },
}

impl GraphError {
    /// Names where an unknown handle was used.
    pub(crate) fn context(self, where_: &str) -> Self {
        match self {
            Self::UnknownHandle { .. } => Self::UnknownHandle {
                context: where_.to_string(),
            },
            e => e,
        }
    }
}

/// Compiles, records (timed with `timer`) with a pool of its own, submits
/// and checks `graph` outside a frame (precomputation, tools, tests).
pub fn run(
    ctx: &crate::gpu::GpuContext,
    graph: FrameGraph<'_>,
    mut timer: Option<&mut PassTimer>,
    context: &str,
) -> Result<Vec<PassTiming>, crate::gpu::GpuError> {
    let graph_error = |e: GraphError| crate::gpu::GpuError::Other(format!("{context}: {e}"));
    let compiled = graph.compile().map_err(graph_error)?;
    let commands = compiled
        .execute(&ctx.device, &mut TexturePool::new(), timer.as_deref_mut())
        .map_err(graph_error)?;
    ctx.queue.submit([commands]);
    ctx.check(context)?;
    match timer {
        Some(t) => t.read_timings(&ctx.device).map_err(graph_error),
        None => Ok(Vec::new()),
    }
}
