//! Graph construction: resources, passes and their declared accesses.
//!
//! Nothing here needs a `wgpu::Device`. Misuse is recorded and reported by
//! [`FrameGraph::compile`], never by a panic while building.

use std::sync::atomic::{AtomicU32, Ordering};

use super::GraphError;
use super::compile::{CompiledGraph, compile};
use super::execute::PassContext;
use super::resource::{
    BufferAccess, BufferDesc, BufferHandle, ResourceAccess, TextureAccess, TextureDesc,
    TextureHandle,
};
use crate::gpu::GpuError;

/// Distinguishes graphs so a handle kept from last frame's graph is rejected.
static NEXT_GRAPH_ID: AtomicU32 = AtomicU32::new(1);

pub(crate) type PassFn<'a> =
    Box<dyn for<'e> FnOnce(&mut PassContext<'e>) -> Result<(), GpuError> + 'a>;

/// Where a resource's memory comes from.
pub(crate) enum Backing<'a, T> {
    /// Allocated from the [`super::TexturePool`] at execute.
    Transient,
    /// Owned outside the graph; `None` is a device-free placeholder
    /// (`import_*_desc`) that compiles but cannot execute.
    Imported(Option<&'a T>),
}

impl<T> Backing<'_, T> {
    pub(crate) fn is_imported(&self) -> bool {
        matches!(self, Self::Imported(_))
    }
}

pub(crate) enum ResourceKind<'a> {
    Texture {
        desc: TextureDesc,
        backing: Backing<'a, wgpu::Texture>,
    },
    Buffer {
        desc: BufferDesc,
        backing: Backing<'a, wgpu::Buffer>,
    },
}

pub(crate) struct Resource<'a> {
    pub(crate) name: String,
    pub(crate) kind: ResourceKind<'a>,
    /// Newest version handed out; 0 = initial content.
    pub(crate) latest: u32,
    pub(crate) output: bool,
}

impl Resource<'_> {
    pub(crate) fn is_imported(&self) -> bool {
        match &self.kind {
            ResourceKind::Texture { backing, .. } => backing.is_imported(),
            ResourceKind::Buffer { backing, .. } => backing.is_imported(),
        }
    }
}

pub(crate) struct ReadDecl {
    pub(crate) res: u32,
    pub(crate) version: u32,
    pub(crate) access: ResourceAccess,
}

pub(crate) struct WriteDecl {
    pub(crate) res: u32,
    /// Version the handle passed to `write` carried.
    pub(crate) from: u32,
    /// Newest version when `write` was called; `from != latest` is a fork.
    pub(crate) latest: u32,
    /// The new version returned.
    pub(crate) to: u32,
    pub(crate) access: ResourceAccess,
}

pub(crate) struct PassDecl<'a> {
    pub(crate) id: String,
    pub(crate) reads: Vec<ReadDecl>,
    pub(crate) writes: Vec<WriteDecl>,
    pub(crate) side_effect: bool,
    pub(crate) exec: Option<PassFn<'a>>,
    /// Misuse seen while declaring (unknown handles, wrong access kinds).
    pub(crate) errors: Vec<GraphError>,
}

/// A frame graph under construction. `'a` is what imported resources and
/// pass closures borrow (renderer state).
pub struct FrameGraph<'a> {
    pub(crate) id: u32,
    pub(crate) resources: Vec<Resource<'a>>,
    pub(crate) passes: Vec<PassDecl<'a>>,
    /// Misuse outside passes (e.g. `mark_output` with a foreign handle).
    pub(crate) errors: Vec<GraphError>,
    /// Prepended to pass ids while set (a pass reused for another view).
    prefix: Option<String>,
    /// Buffers nodes bind by name when they do not bind them ([`Self::set_frame_constants`]).
    pub(crate) frame_constants: Vec<(&'static str, &'a wgpu::Buffer)>,
}

impl Default for FrameGraph<'_> {
    fn default() -> Self {
        Self::new()
    }
}

impl<'a> FrameGraph<'a> {
    /// An empty graph with a fresh id; handles from other graphs are rejected by it.
    pub fn new() -> Self {
        Self {
            id: NEXT_GRAPH_ID.fetch_add(1, Ordering::Relaxed),
            resources: Vec::new(),
            passes: Vec::new(),
            errors: Vec::new(),
            prefix: None,
            frame_constants: Vec::new(),
        }
    }

    /// Until cleared with `None`, pass ids and resource names become
    /// `prefix.id`: lets a pass
    /// record again for another view (e.g. `envmap.probe0.face2.gbuffer`).
    pub fn set_pass_prefix(&mut self, prefix: Option<String>) {
        self.prefix = prefix;
    }

    fn push(&mut self, name: &str, kind: ResourceKind<'a>) -> u32 {
        let name = match &self.prefix {
            Some(p) => format!("{p}.{name}"),
            None => name.to_string(),
        };
        self.resources.push(Resource {
            name,
            kind,
            latest: 0,
            output: false,
        });
        (self.resources.len() - 1) as u32
    }

    fn texture_handle(&self, index: u32) -> TextureHandle {
        TextureHandle {
            graph: self.id,
            index,
            version: 0,
        }
    }

    fn buffer_handle(&self, index: u32) -> BufferHandle {
        BufferHandle {
            graph: self.id,
            index,
            version: 0,
        }
    }

    /// A transient texture, allocated from the pool only if a live pass uses it.
    pub fn create_texture(&mut self, name: &str, desc: TextureDesc) -> TextureHandle {
        let backing = Backing::Transient;
        let i = self.push(name, ResourceKind::Texture { desc, backing });
        self.texture_handle(i)
    }

    /// An external texture (history, output target); its description is
    /// read from the texture. Version 0 is its current content.
    pub fn import_texture(&mut self, name: &str, texture: &'a wgpu::Texture) -> TextureHandle {
        let desc = TextureDesc::from_texture(texture);
        let backing = Backing::Imported(Some(texture));
        let i = self.push(name, ResourceKind::Texture { desc, backing });
        self.texture_handle(i)
    }

    /// A device-free placeholder import: compiles and describes like
    /// [`Self::import_texture`], but `execute` fails with `UnboundImport`
    /// if a live pass uses it. For tests and `--graph` listings.
    pub fn import_texture_desc(&mut self, name: &str, desc: TextureDesc) -> TextureHandle {
        let backing = Backing::Imported(None);
        let i = self.push(name, ResourceKind::Texture { desc, backing });
        self.texture_handle(i)
    }

    /// A transient buffer.
    pub fn create_buffer(&mut self, name: &str, desc: BufferDesc) -> BufferHandle {
        let backing = Backing::Transient;
        let i = self.push(name, ResourceKind::Buffer { desc, backing });
        self.buffer_handle(i)
    }

    /// An external buffer (uniforms, scene data, readback target); its size and
    /// usages are read from the buffer. Version 0 is its current content.
    pub fn import_buffer(&mut self, name: &str, buffer: &'a wgpu::Buffer) -> BufferHandle {
        let desc = BufferDesc::from_buffer(buffer);
        let backing = Backing::Imported(Some(buffer));
        let i = self.push(name, ResourceKind::Buffer { desc, backing });
        self.buffer_handle(i)
    }

    /// Device-free placeholder buffer import; see [`Self::import_texture_desc`].
    pub fn import_buffer_desc(&mut self, name: &str, desc: BufferDesc) -> BufferHandle {
        let backing = Backing::Imported(None);
        let i = self.push(name, ResourceKind::Buffer { desc, backing });
        self.buffer_handle(i)
    }

    /// The resource's final version is an output: its writers survive culling.
    pub fn mark_output(&mut self, h: TextureHandle) {
        match self.check(h.graph, h.index, h.version, true) {
            Ok(i) => self.resources[i].output = true,
            Err(e) => self.errors.push(e.context("mark_output")),
        }
    }

    /// Buffer counterpart of [`Self::mark_output`]: the final version's writers survive culling.
    pub fn mark_buffer_output(&mut self, h: BufferHandle) {
        match self.check(h.graph, h.index, h.version, false) {
            Ok(i) => self.resources[i].output = true,
            Err(e) => self.errors.push(e.context("mark_buffer_output")),
        }
    }

    /// The description of a texture handle of this graph.
    pub fn texture_desc(&self, h: TextureHandle) -> Option<&TextureDesc> {
        let i = self.check(h.graph, h.index, h.version, true).ok()?;
        match &self.resources[i].kind {
            ResourceKind::Texture { desc, .. } => Some(desc),
            ResourceKind::Buffer { .. } => None,
        }
    }

    /// The description of a buffer handle of this graph (`None` for a texture or foreign handle).
    pub fn buffer_desc(&self, h: BufferHandle) -> Option<&BufferDesc> {
        let i = self.check(h.graph, h.index, h.version, false).ok()?;
        match &self.resources[i].kind {
            ResourceKind::Buffer { desc, .. } => Some(desc),
            ResourceKind::Texture { .. } => None,
        }
    }

    /// Starts a pass; `id` is dotted (`ao.hbao`) and unique in the graph.
    /// The pass is registered only by [`PassBuilder::execute`].
    pub fn add_pass(&mut self, id: &str) -> PassBuilder<'_, 'a> {
        let id = match &self.prefix {
            Some(p) => format!("{p}.{id}"),
            None => id.to_string(),
        };
        self.passes.push(PassDecl {
            id,
            reads: Vec::new(),
            writes: Vec::new(),
            side_effect: false,
            exec: None,
            errors: Vec::new(),
        });
        let pass = self.passes.len() - 1;
        PassBuilder { graph: self, pass }
    }

    /// Orders, validates and culls; see [`CompiledGraph`].
    pub fn compile(self) -> Result<CompiledGraph<'a>, GraphError> {
        compile(self)
    }

    /// Resolves a handle to a resource index, rejecting foreign or forged ones.
    fn check(
        &self,
        graph: u32,
        index: u32,
        version: u32,
        texture: bool,
    ) -> Result<usize, GraphError> {
        let unknown = || GraphError::UnknownHandle {
            context: String::new(),
        };
        if graph != self.id {
            return Err(unknown());
        }
        let r = self.resources.get(index as usize).ok_or_else(unknown)?;
        let kind_ok = matches!(
            (&r.kind, texture),
            (ResourceKind::Texture { .. }, true) | (ResourceKind::Buffer { .. }, false)
        );
        if !kind_ok || version > r.latest {
            return Err(unknown());
        }
        Ok(index as usize)
    }
}

/// Declares one pass's accesses; finish with [`PassBuilder::execute`].
pub struct PassBuilder<'g, 'a> {
    graph: &'g mut FrameGraph<'a>,
    pass: usize,
}

impl<'a> PassBuilder<'_, 'a> {
    fn record_read(&mut self, graph: u32, index: u32, version: u32, access: ResourceAccess) {
        let texture = matches!(access, ResourceAccess::Texture(_));
        let pass = &self.graph.passes[self.pass].id;
        match self.graph.check(graph, index, version, texture) {
            Err(e) => {
                let e = e.context(pass);
                self.graph.passes[self.pass].errors.push(e);
            }
            Ok(res) => {
                if access.is_write() {
                    let e = GraphError::InvalidAccess {
                        pass: pass.clone(),
                        resource: self.graph.resources[res].name.clone(),
                        access: access.to_string(),
                        declared_with: "read",
                    };
                    self.graph.passes[self.pass].errors.push(e);
                }
                self.graph.passes[self.pass].reads.push(ReadDecl {
                    res: index,
                    version,
                    access,
                });
            }
        }
    }

    /// Returns the new version, or `version` unchanged for an unknown handle.
    fn record_write(
        &mut self,
        graph: u32,
        index: u32,
        version: u32,
        access: ResourceAccess,
    ) -> u32 {
        let texture = matches!(access, ResourceAccess::Texture(_));
        let pass = &self.graph.passes[self.pass].id;
        match self.graph.check(graph, index, version, texture) {
            Err(e) => {
                let e = e.context(pass);
                self.graph.passes[self.pass].errors.push(e);
                version
            }
            Ok(res) => {
                if !access.is_write() {
                    let e = GraphError::InvalidAccess {
                        pass: pass.clone(),
                        resource: self.graph.resources[res].name.clone(),
                        access: access.to_string(),
                        declared_with: "write",
                    };
                    self.graph.passes[self.pass].errors.push(e);
                }
                let r = &mut self.graph.resources[res];
                let latest = r.latest;
                r.latest += 1;
                let to = r.latest;
                self.graph.passes[self.pass].writes.push(WriteDecl {
                    res: index,
                    from: version,
                    latest,
                    to,
                    access,
                });
                to
            }
        }
    }

    /// Declares a read of this version; returns the same handle.
    pub fn read(&mut self, h: TextureHandle, access: TextureAccess) -> TextureHandle {
        self.record_read(h.graph, h.index, h.version, ResourceAccess::Texture(access));
        h
    }

    /// Declares a write of the newest version; returns the new version.
    /// The previous content counts as consumed (a `Load` keeps it), so the
    /// writer of the previous version stays alive while this pass does.
    pub fn write(&mut self, h: TextureHandle, access: TextureAccess) -> TextureHandle {
        let access = ResourceAccess::Texture(access);
        let version = self.record_write(h.graph, h.index, h.version, access);
        TextureHandle { version, ..h }
    }

    /// Declares a read of this buffer version; returns the same handle.
    pub fn read_buffer(&mut self, h: BufferHandle, access: BufferAccess) -> BufferHandle {
        self.record_read(h.graph, h.index, h.version, ResourceAccess::Buffer(access));
        h
    }

    /// Declares a write of the newest buffer version; returns the new version
    /// (the previous content counts as consumed, as for [`Self::write`]).
    pub fn write_buffer(&mut self, h: BufferHandle, access: BufferAccess) -> BufferHandle {
        let access = ResourceAccess::Buffer(access);
        let version = self.record_write(h.graph, h.index, h.version, access);
        BufferHandle { version, ..h }
    }

    /// The pass id (with the graph's prefix).
    pub fn id(&self) -> &str {
        &self.graph.passes[self.pass].id
    }

    /// Records misuse found while declaring; `compile` reports it.
    pub(crate) fn error(&mut self, e: GraphError) {
        self.graph.passes[self.pass].errors.push(e);
    }

    /// Never culled (read-backs, presentation).
    pub fn side_effect(&mut self) {
        self.graph.passes[self.pass].side_effect = true;
    }

    /// Registers the pass with its recording closure; it runs at
    /// [`CompiledGraph::execute`] unless the pass is culled. The first
    /// error a closure returns ends the recording and is what `execute` returns.
    pub fn execute(self, f: impl FnOnce(&mut PassContext<'_>) -> Result<(), GpuError> + 'a) {
        self.graph.passes[self.pass].exec = Some(Box::new(f));
    }
}
