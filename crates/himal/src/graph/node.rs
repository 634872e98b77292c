//! Declare-and-bind nodes (kajiya's `SimpleRenderPass`, Filament's
//! `addPass`): each WGSL binding is named once, to a graph handle, a
//! persistent resource or a uniform, and that one call both declares the
//! graph access and builds the bind group at record time. The program's
//! reflected layout is checked when the node is finished, so a binding the
//! shader does not have, or one it has and nobody gave, is a compile error
//! naming the pass and the binding.
//!
//! Three forms: [`FrameGraph::fullscreen`] (one triangle into colour
//! targets), [`FrameGraph::compute`] (dispatch) and [`FrameGraph::raster`]
//! (attachments and bind groups set up, draws recorded by a closure).
//! A binding a permutation does not read is given with
//! [`Node::optional`] and a [`Fallback`]; bindings named like a frame
//! constant ([`FrameGraph::set_frame_constants`]) bind themselves.

use super::builder::FrameGraph;
use super::execute::PassContext;
pub use super::fallback::{Fallback, ZERO_BUFFER_BYTES};
use super::resource::{BufferAccess, BufferHandle, TextureAccess, TextureHandle};
use super::{GraphError, PassBuilder};
use crate::gpu::GpuError;
use crate::gpu::pipeline::Program;
use crate::shader::BindingInfo;

/// What a binding is bound to.
enum Source<'a> {
    /// A graph texture, sampled (default view, or the given view).
    Texture(TextureHandle, Option<wgpu::TextureViewDescriptor<'static>>),
    /// A graph texture written as a storage texture (default view, or the given view).
    Storage(TextureHandle),
    StorageView(TextureHandle, wgpu::TextureViewDescriptor<'static>),
    /// A graph buffer.
    Buffer(BufferHandle),
    /// Owned outside the graph: uniforms, persistent views, samplers.
    External(wgpu::BindingResource<'a>),
    Fallback(Fallback),
    /// The graph's buffer of zeros ([`ZERO_BUFFER_BYTES`]) for an absent
    /// uniform or read-only storage input.
    ZeroBuffer,
}

impl Source<'_> {
    fn kind(&self) -> &'static str {
        match self {
            Source::Texture(..) => "a texture",
            Source::Fallback(Fallback::DepthFar) => "the depth-array fallback",
            Source::Fallback(Fallback::Black3d) => "the 3D fallback",
            Source::Fallback(Fallback::BlackArray) => "the black array fallback",
            Source::Fallback(_) => "a colour fallback",
            Source::ZeroBuffer => "the zero buffer",
            Source::Storage(_) | Source::StorageView(..) => "a storage texture",
            Source::Buffer(_) => "a buffer",
            Source::External(wgpu::BindingResource::Sampler(_)) => "a sampler",
            Source::External(wgpu::BindingResource::TextureView(_)) => "a texture",
            Source::External(_) => "a buffer",
        }
    }

    /// Whether this source can fill a binding of reflected type `ty`.
    fn fits(&self, ty: &wgpu::BindingType) -> bool {
        use wgpu::BindingType as B;
        match self {
            Source::Texture(..) => matches!(ty, B::Texture { .. }),
            Source::Fallback(f) => f.fits(ty),
            Source::Storage(_) | Source::StorageView(..) => {
                matches!(ty, B::StorageTexture { .. })
            }
            Source::Buffer(_) => matches!(ty, B::Buffer { .. }),
            Source::ZeroBuffer => match ty {
                B::Buffer {
                    ty: buffer,
                    min_binding_size,
                    ..
                } => {
                    let read_only = matches!(
                        buffer,
                        wgpu::BufferBindingType::Uniform
                            | wgpu::BufferBindingType::Storage { read_only: true }
                    );
                    read_only && min_binding_size.is_none_or(|n| n.get() <= ZERO_BUFFER_BYTES)
                }
                _ => false,
            },
            Source::External(r) => match r {
                wgpu::BindingResource::Sampler(_) => matches!(ty, B::Sampler(_)),
                wgpu::BindingResource::TextureView(_) => {
                    matches!(ty, B::Texture { .. } | B::StorageTexture { .. })
                }
                _ => matches!(ty, B::Buffer { .. }),
            },
        }
    }
}

/// A colour attachment of a node.
struct Color {
    target: TextureHandle,
    view: Option<wgpu::TextureViewDescriptor<'static>>,
    load: wgpu::LoadOp<wgpu::Color>,
}

/// The depth attachment of a node.
struct Depth {
    target: TextureHandle,
    view: Option<wgpu::TextureViewDescriptor<'static>>,
    /// `None`: read-only (depth test only).
    ops: Option<wgpu::Operations<f32>>,
}

enum Form {
    Fullscreen,
    Compute,
    Raster,
}

/// The recording closure of a raster node: the render pass has its
/// attachments and the node's bind groups set; the closure sets pipelines
/// and draws.
pub type RasterFn<'a> = Box<
    dyn for<'e> FnOnce(&PassContext<'e>, &mut wgpu::RenderPass<'static>) -> Result<(), GpuError>
        + 'a,
>;

/// The recording closure of a compute node with more than one dispatch.
pub type ComputeFn<'a> = Box<dyn FnOnce(&mut wgpu::ComputePass<'static>) + 'a>;

/// A pass under construction; see the module docs. Finish it with
/// [`Node::draw`], [`Node::dispatch`] or [`Node::record`].
pub struct Node<'g, 'a> {
    pass: PassBuilder<'g, 'a>,
    program: &'a Program,
    form: Form,
    bindings: Vec<(String, Source<'a>)>,
    /// Groups the closure binds itself (raster: per-material groups).
    external_groups: Vec<u32>,
    colors: Vec<Color>,
    depth: Option<Depth>,
    render: Option<Result<wgpu::RenderPipeline, GpuError>>,
    compute: Option<Result<wgpu::ComputePipeline, GpuError>>,
    errors: Vec<String>,
    frame_constants: Vec<(&'static str, &'a wgpu::Buffer)>,
}

impl<'a> FrameGraph<'a> {
    /// Buffers bound by name wherever a node's shader has a binding so
    /// named and the node does not bind it (view, lighting, sky).
    pub fn set_frame_constants(&mut self, constants: &[(&'static str, &'a wgpu::Buffer)]) {
        self.frame_constants = constants.to_vec();
    }

    /// The frame constants now in force.
    pub fn frame_constants(&self) -> Vec<(&'static str, &'a wgpu::Buffer)> {
        self.frame_constants.clone()
    }

    fn node(&mut self, id: &str, program: &'a Program, form: Form) -> Node<'_, 'a> {
        let frame_constants = self.frame_constants.clone();
        Node {
            pass: self.add_pass(id),
            program,
            form,
            bindings: Vec::new(),
            external_groups: Vec::new(),
            colors: Vec::new(),
            depth: None,
            render: None,
            compute: None,
            errors: Vec::new(),
            frame_constants,
        }
    }

    /// A full-screen triangle (`vs_main`, 3 vertices) into colour targets.
    pub fn fullscreen(&mut self, id: &str, program: &'a Program) -> Node<'_, 'a> {
        self.node(id, program, Form::Fullscreen)
    }

    /// A compute dispatch.
    pub fn compute(&mut self, id: &str, program: &'a Program) -> Node<'_, 'a> {
        self.node(id, program, Form::Compute)
    }

    /// A render pass whose draws a closure records.
    pub fn raster(&mut self, id: &str, program: &'a Program) -> Node<'_, 'a> {
        self.node(id, program, Form::Raster)
    }
}

impl<'g, 'a> Node<'g, 'a> {
    fn bind(mut self, name: &str, source: Source<'a>) -> Self {
        if self.bindings.iter().any(|(n, _)| n == name) {
            self.errors
                .push(format!("binding \"{name}\" is given twice"));
        }
        self.bindings.push((name.to_string(), source));
        self
    }

    /// The pipeline a full-screen or raster node draws with (raster nodes
    /// may instead set pipelines in their closure).
    pub fn pipeline(mut self, pipeline: Result<wgpu::RenderPipeline, GpuError>) -> Self {
        self.render = Some(pipeline);
        self
    }

    /// The pipeline a compute node dispatches with.
    pub fn compute_pipeline(mut self, pipeline: Result<wgpu::ComputePipeline, GpuError>) -> Self {
        self.compute = Some(pipeline);
        self
    }

    /// Samples graph texture `h` as `name` (default view).
    pub fn read(mut self, name: &str, h: TextureHandle) -> Self {
        self.pass.read(h, TextureAccess::Sampled);
        self.bind(name, Source::Texture(h, None))
    }

    /// Samples `h` through a view other than the default (cube, one layer, one mip).
    pub fn read_view(
        mut self,
        name: &str,
        h: TextureHandle,
        view: wgpu::TextureViewDescriptor<'static>,
    ) -> Self {
        self.pass.read(h, TextureAccess::Sampled);
        self.bind(name, Source::Texture(h, Some(view)))
    }

    /// Samples `h` as a cube (six layers).
    pub fn read_cube(self, name: &str, h: TextureHandle) -> Self {
        let view = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        };
        self.read_view(name, h, view)
    }

    /// Samples `h` as a 2D array (all layers).
    pub fn read_array(self, name: &str, h: TextureHandle) -> Self {
        let view = wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        };
        self.read_view(name, h, view)
    }

    /// An input a permutation may not use: `None` binds the graph's `fallback`.
    pub fn optional(mut self, name: &str, h: Option<TextureHandle>, fallback: Fallback) -> Self {
        match h {
            Some(h) => {
                self.pass.read(h, TextureAccess::Sampled);
                self.bind(name, Source::Texture(h, None))
            }
            None => self.bind(name, Source::Fallback(fallback)),
        }
    }

    /// A texture owned outside the graph that a permutation may not read:
    /// `None` binds the graph's `fallback`.
    pub fn optional_external(
        self,
        name: &str,
        view: Option<&'a wgpu::TextureView>,
        fallback: Fallback,
    ) -> Self {
        match view {
            Some(v) => self.external(name, v),
            None => self.bind(name, Source::Fallback(fallback)),
        }
    }

    /// A uniform or read-only storage buffer owned outside the graph that a
    /// permutation may not read: `None` binds the graph's buffer of zeros.
    pub fn optional_buffer(self, name: &str, buffer: Option<&'a wgpu::Buffer>) -> Self {
        match buffer {
            Some(b) => self.uniform(name, b),
            None => self.bind(name, Source::ZeroBuffer),
        }
    }

    /// [`Node::optional`] for a 2D-array binding (shadow maps): `h` is
    /// bound as an array of all its layers.
    pub fn optional_array(
        mut self,
        name: &str,
        h: Option<TextureHandle>,
        fallback: Fallback,
    ) -> Self {
        match h {
            Some(h) => self.read_array(name, h),
            None => {
                self = self.bind(name, Source::Fallback(fallback));
                self
            }
        }
    }

    /// Orders this node after the writer of `h` without binding it (a
    /// persistent resource bound with [`Node::external`]).
    pub fn after(mut self, h: TextureHandle) -> Self {
        self.pass.read(h, TextureAccess::Sampled);
        self
    }

    /// Reads graph buffer `h` as indirect draw arguments (raster: the
    /// closure draws from it with `ctx.buffer(h)`; nothing is bound).
    pub fn indirect(mut self, h: BufferHandle) -> Self {
        self.pass.read_buffer(h, BufferAccess::Indirect);
        self
    }

    /// A buffer owned outside the graph (uniform or storage: object
    /// transforms, parameters).
    pub fn uniform(self, name: &str, buffer: &'a wgpu::Buffer) -> Self {
        self.bind(name, Source::External(buffer.as_entire_binding()))
    }

    /// A sampler owned outside the graph, bound as `name`.
    pub fn sampler(self, name: &str, sampler: &'a wgpu::Sampler) -> Self {
        self.bind(
            name,
            Source::External(wgpu::BindingResource::Sampler(sampler)),
        )
    }

    /// A persistent texture view owned outside the graph (lookup tables,
    /// pools); order it with [`Node::after`] when a graph pass writes it.
    pub fn external(self, name: &str, view: &'a wgpu::TextureView) -> Self {
        self.bind(
            name,
            Source::External(wgpu::BindingResource::TextureView(view)),
        )
    }

    /// Reads graph buffer `h`.
    pub fn read_buffer(mut self, name: &str, h: BufferHandle, access: BufferAccess) -> Self {
        self.pass.read_buffer(h, access);
        self.bind(name, Source::Buffer(h))
    }

    /// Writes graph buffer `h` (compute); the new version is returned by
    /// the finishing call's [`Written::buffer`].
    pub fn write_buffer(mut self, name: &str, h: BufferHandle) -> Self {
        let h = self.pass.write_buffer(h, BufferAccess::StorageWrite);
        self.bind(name, Source::Buffer(h))
    }

    /// Writes graph texture `h` as a storage texture (compute).
    pub fn storage(mut self, name: &str, h: TextureHandle) -> Self {
        let h = self.pass.write(h, TextureAccess::StorageWrite);
        self.bind(name, Source::Storage(h))
    }

    /// Writes `h` as a storage texture through a view (one mip, all layers).
    pub fn storage_view(
        mut self,
        name: &str,
        h: TextureHandle,
        view: wgpu::TextureViewDescriptor<'static>,
    ) -> Self {
        let h = self.pass.write(h, TextureAccess::StorageWrite);
        self.bind(name, Source::StorageView(h, view))
    }

    /// Buffers and views owned outside the graph, by binding name.
    pub fn externals<'r>(
        mut self,
        list: impl IntoIterator<Item = (&'r str, wgpu::BindingResource<'a>)>,
    ) -> Self {
        for (name, r) in list {
            self = self.bind(name, Source::External(r));
        }
        self
    }

    /// A colour attachment (default view).
    pub fn color(self, h: TextureHandle, load: wgpu::LoadOp<wgpu::Color>) -> Self {
        self.color_view(h, None, load)
    }

    /// A colour attachment through a view (one layer or mip).
    pub fn color_view(
        mut self,
        h: TextureHandle,
        view: Option<wgpu::TextureViewDescriptor<'static>>,
        load: wgpu::LoadOp<wgpu::Color>,
    ) -> Self {
        let target = self.pass.write(h, TextureAccess::ColorAttachment);
        self.colors.push(Color { target, view, load });
        self
    }

    /// A read-only depth attachment (depth test, no write).
    pub fn depth_test(mut self, h: TextureHandle) -> Self {
        let target = self.pass.read(h, TextureAccess::DepthRead);
        self.depth = Some(Depth {
            target,
            view: None,
            ops: None,
        });
        self
    }

    /// A written depth attachment.
    pub fn depth(
        mut self,
        h: TextureHandle,
        view: Option<wgpu::TextureViewDescriptor<'static>>,
        ops: wgpu::Operations<f32>,
    ) -> Self {
        let target = self.pass.write(h, TextureAccess::DepthAttachment);
        self.depth = Some(Depth {
            target,
            view,
            ops: Some(ops),
        });
        self
    }

    /// Bind group `group` is set by the raster closure (per-draw groups).
    pub fn external_group(mut self, group: u32) -> Self {
        self.external_groups.push(group);
        self
    }

    /// Never culled.
    pub fn side_effect(mut self) -> Self {
        self.pass.side_effect();
        self
    }

    /// Full-screen nodes: draws one triangle; returns the first colour
    /// target's new version.
    pub fn draw(self) -> TextureHandle {
        let first = self.colors.first().map(|c| c.target);
        let written = self.finish(None, None);
        first.map_or(written.fallback_handle(), |_| written.colors[0])
    }

    /// Full-screen nodes with several colour targets: returns their new versions.
    pub fn draw_targets(self) -> Written {
        self.finish(None, None)
    }

    /// Compute nodes: dispatches `groups` workgroups.
    pub fn dispatch(self, groups: [u32; 3]) -> Written {
        self.finish(
            None,
            Some(Box::new(move |cpass: &mut wgpu::ComputePass<'static>| {
                cpass.dispatch_workgroups(groups[0], groups[1], groups[2])
            })),
        )
    }

    /// Compute nodes: records the dispatches with `f` (the node's pipeline
    /// and bind groups are set; `f` may switch pipelines).
    pub fn dispatch_with(self, f: impl FnOnce(&mut wgpu::ComputePass<'static>) + 'a) -> Written {
        self.finish(None, Some(Box::new(f)))
    }

    /// Raster nodes: records the draws with `f`.
    pub fn record(
        self,
        f: impl for<'e> FnOnce(&PassContext<'e>, &mut wgpu::RenderPass<'static>) -> Result<(), GpuError>
        + 'a,
    ) -> Written {
        self.finish(Some(Box::new(f)), None)
    }

    /// Checks the bindings against the program's reflected layout.
    /// Returns the groups the node binds, each as (group, [(binding, source index)]).
    fn check(&mut self) -> Vec<(u32, Vec<(u32, usize)>)> {
        let layout = &self.program.layout;
        for (name, source) in &self.bindings {
            match layout.find(name) {
                None => self.errors.push(format!(
                    "shader {} has no binding \"{name}\"",
                    self.program.name
                )),
                Some(b) if !source.fits(&b.ty) => self.errors.push(format!(
                    "binding \"{name}\" of {} is {}, given {}",
                    self.program.name,
                    describe_type(&b.ty),
                    source.kind()
                )),
                Some(_) => {}
            }
        }
        // Frame constants fill what the node left unbound.
        for (name, buffer) in self.frame_constants.clone() {
            let wanted = layout.find(name).is_some_and(|b| {
                matches!(b.ty, wgpu::BindingType::Buffer { .. })
                    && !self.external_groups.contains(&b.group)
            });
            if wanted && !self.bindings.iter().any(|(n, _)| n == name) {
                self.bindings.push((
                    name.to_string(),
                    Source::External(buffer.as_entire_binding()),
                ));
            }
        }
        let mut groups = Vec::new();
        for (g, bindings) in layout.groups.iter().enumerate() {
            let g = g as u32;
            if self.external_groups.contains(&g) || bindings.is_empty() {
                continue;
            }
            let mut entries = Vec::with_capacity(bindings.len());
            for b in bindings {
                match self.bindings.iter().position(|(n, _)| *n == b.name) {
                    Some(i) => entries.push((b.binding, i)),
                    None => self.errors.push(unbound(self.program, b)),
                }
            }
            groups.push((g, entries));
        }
        groups
    }

    fn finish(mut self, raster: Option<RasterFn<'a>>, dispatch: Option<ComputeFn<'a>>) -> Written {
        let bind_groups = self.check();
        let pass_id = self.pass.id().to_string();
        let program = self.program;
        match self.form {
            Form::Fullscreen | Form::Raster if self.compute.is_some() => self
                .errors
                .push("a render node was given a compute pipeline".into()),
            Form::Compute if self.render.is_some() => self
                .errors
                .push("a compute node was given a render pipeline".into()),
            Form::Fullscreen if self.render.is_none() => {
                self.errors.push("no pipeline was given".into())
            }
            Form::Compute if self.compute.is_none() => {
                self.errors.push("no pipeline was given".into())
            }
            _ => {}
        }
        let written = Written {
            colors: self.colors.iter().map(|c| c.target).collect(),
            depth: self
                .depth
                .as_ref()
                .filter(|d| d.ops.is_some())
                .map(|d| d.target),
            storage: self
                .bindings
                .iter()
                .filter_map(|(_, s)| match s {
                    Source::Storage(h) | Source::StorageView(h, _) => Some(*h),
                    _ => None,
                })
                .collect(),
            buffers: self
                .bindings
                .iter()
                .filter_map(|(_, s)| match s {
                    Source::Buffer(h) => Some(*h),
                    _ => None,
                })
                .collect(),
        };
        for e in self.errors.drain(..) {
            self.pass.error(GraphError::Binding {
                pass: pass_id.clone(),
                message: e,
            });
        }
        let Node {
            pass,
            form,
            bindings,
            colors,
            depth,
            render,
            compute,
            ..
        } = self;
        pass.execute(move |ctx| {
            // Owned views first, so the entries can borrow them.
            let resolved = bindings
                .iter()
                .map(|(_, s)| resolve(ctx, s))
                .collect::<Result<Vec<_>, GpuError>>()?;
            let made: Vec<(u32, wgpu::BindGroup)> = bind_groups
                .iter()
                .map(|(g, entries)| {
                    let entries: Vec<wgpu::BindGroupEntry<'_>> = entries
                        .iter()
                        .map(|&(binding, i)| wgpu::BindGroupEntry {
                            binding,
                            resource: resolved[i].resource(),
                        })
                        .collect();
                    let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&format!("{}.group{g}", program.name)),
                        layout: &program.bind_group_layouts[*g as usize],
                        entries: &entries,
                    });
                    (*g, group)
                })
                .collect();
            let label = ctx.pass_id().to_string();
            if let Form::Compute = form {
                let pipeline = compute.ok_or_else(|| GpuError::Other("no pipeline".into()))??;
                let timestamp_writes = ctx.compute_timestamp_writes();
                let mut cpass = ctx
                    .encoder
                    .begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(&label),
                        timestamp_writes,
                    })
                    .forget_lifetime();
                cpass.set_pipeline(&pipeline);
                for (g, group) in &made {
                    cpass.set_bind_group(*g, group, &[]);
                }
                if let Some(f) = dispatch {
                    f(&mut cpass);
                }
                return Ok(());
            }
            let views: Vec<wgpu::TextureView> = colors
                .iter()
                .map(|c| attachment_view(ctx, c.target, c.view.as_ref()))
                .collect::<Result<_, _>>()?;
            let depth_view = depth
                .as_ref()
                .map(|d| attachment_view(ctx, d.target, d.view.as_ref()))
                .transpose()?;
            let color_attachments: Vec<Option<wgpu::RenderPassColorAttachment<'_>>> = colors
                .iter()
                .zip(&views)
                .map(|(c, view)| {
                    Some(wgpu::RenderPassColorAttachment {
                        view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: c.load,
                            store: wgpu::StoreOp::Store,
                        },
                    })
                })
                .collect();
            let pipeline = render.transpose()?;
            // The pass forgets the encoder borrow so the closure can read the context.
            let mut rpass = ctx
                .encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&label),
                    color_attachments: &color_attachments,
                    depth_stencil_attachment: depth.as_ref().zip(depth_view.as_ref()).map(
                        |(d, view)| wgpu::RenderPassDepthStencilAttachment {
                            view,
                            depth_ops: d.ops,
                            stencil_ops: None,
                        },
                    ),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            if let Some(p) = &pipeline {
                rpass.set_pipeline(p);
            }
            for (g, group) in &made {
                rpass.set_bind_group(*g, group, &[]);
            }
            match raster {
                Some(f) => f(ctx, &mut rpass),
                None => {
                    rpass.draw(0..3, 0..1);
                    Ok(())
                }
            }
        });
        written
    }
}

/// The versions a finished node wrote, in declaration order.
pub struct Written {
    /// New versions of the colour attachments, in declaration order.
    pub colors: Vec<TextureHandle>,
    /// The written depth attachment's new version.
    pub depth: Option<TextureHandle>,
    /// New versions of the storage textures written, in declaration order.
    pub storage: Vec<TextureHandle>,
    /// Graph buffers the node binds, in declaration order: the new version
    /// of those it writes, the read version of the others.
    pub buffers: Vec<BufferHandle>,
}

impl Written {
    fn fallback_handle(&self) -> TextureHandle {
        self.storage.first().copied().unwrap_or(TextureHandle {
            graph: 0,
            index: u32::MAX,
            version: 0,
        })
    }

    /// The new version of buffer `h` written by this node (`h` itself if it did not write it).
    pub fn buffer(&self, h: BufferHandle) -> BufferHandle {
        self.buffers
            .iter()
            .copied()
            .filter(|b| b.graph == h.graph && b.index == h.index)
            .max_by_key(|b| b.version)
            .unwrap_or(h)
    }
}

/// A binding's resource at record time: borrowed from the context or the
/// node, or a view made for this pass.
enum Resolved<'r> {
    View(&'r wgpu::TextureView),
    Owned(wgpu::TextureView),
    Resource(wgpu::BindingResource<'r>),
}

impl Resolved<'_> {
    fn resource(&self) -> wgpu::BindingResource<'_> {
        match self {
            Resolved::View(v) => wgpu::BindingResource::TextureView(v),
            Resolved::Owned(v) => wgpu::BindingResource::TextureView(v),
            Resolved::Resource(r) => r.clone(),
        }
    }
}

fn resolve<'r>(ctx: &PassContext<'r>, source: &'r Source<'_>) -> Result<Resolved<'r>, GpuError> {
    let err = |e: GraphError| GpuError::Other(e.to_string());
    Ok(match source {
        Source::Texture(h, None) | Source::Storage(h) => {
            Resolved::View(ctx.try_view(*h).map_err(err)?)
        }
        Source::Texture(h, Some(desc)) | Source::StorageView(h, desc) => {
            Resolved::Owned(ctx.try_texture(*h).map_err(err)?.create_view(desc))
        }
        Source::Buffer(h) => {
            Resolved::Resource(ctx.try_buffer(*h).map_err(err)?.as_entire_binding())
        }
        Source::External(r) => Resolved::Resource(r.clone()),
        Source::Fallback(f) => Resolved::View(ctx.fallback(*f)),
        Source::ZeroBuffer => Resolved::Resource(ctx.zero_buffer().as_entire_binding()),
    })
}

fn attachment_view(
    ctx: &PassContext<'_>,
    h: TextureHandle,
    desc: Option<&wgpu::TextureViewDescriptor<'static>>,
) -> Result<wgpu::TextureView, GpuError> {
    let texture = ctx
        .try_texture(h)
        .map_err(|e| GpuError::Other(e.to_string()))?;
    Ok(match desc {
        Some(d) => texture.create_view(d),
        None => ctx
            .try_view(h)
            .map_err(|e| GpuError::Other(e.to_string()))?
            .clone(),
    })
}

fn unbound(program: &Program, b: &BindingInfo) -> String {
    format!(
        "binding \"{}\" (group {}, {}) of {} is not bound",
        b.name,
        b.group,
        describe_type(&b.ty),
        program.name
    )
}

fn describe_type(ty: &wgpu::BindingType) -> &'static str {
    match ty {
        wgpu::BindingType::Buffer { .. } => "a buffer",
        wgpu::BindingType::Sampler(_) => "a sampler",
        wgpu::BindingType::Texture { .. } => "a texture",
        wgpu::BindingType::StorageTexture { .. } => "a storage texture",
        _ => "another kind",
    }
}
