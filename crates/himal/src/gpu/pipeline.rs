//! Programs: a composed WGSL shader, its wgpu module and the bind-group
//! layouts reflected from it; bind groups are built by binding name.

use super::cache::{PipelineKey, fnv1a};
use super::{GpuContext, GpuError};
use crate::shader::{self, ComposedShader, ReflectedLayout};

/// A composed WGSL shader compiled into a wgpu module, with the bind-group
/// and pipeline layouts reflected from its bindings; pipelines are created from it.
pub struct Program {
    /// Shader path it was composed from (e.g. `passes/post/tonemap.wgsl`); labels the module and layouts.
    pub name: String,
    /// The compiled module holding every entry point.
    pub module: wgpu::ShaderModule,
    /// Bindings reflected from the WGSL, by group, with the stages that use them.
    pub layout: ReflectedLayout,
    /// One layout per bind group, in group order.
    pub bind_group_layouts: Vec<wgpu::BindGroupLayout>,
    /// Pipeline layout made of [`Self::bind_group_layouts`].
    pub pipeline_layout: wgpu::PipelineLayout,
    /// FNV-1a of the composed WGSL: part of every pipeline key (E1), so an
    /// edited shader never matches a cached pipeline.
    pub source_hash: u64,
}

/// Fixed-function state of a render pipeline; shaders and layout come from the program.
pub struct RenderSpec<'a> {
    /// Debug label of the pipeline (and part of its cache key).
    pub label: &'a str,
    /// Vertex entry point name.
    pub vertex_entry: &'a str,
    /// Fragment entry point name; `None` for a depth-only pipeline.
    pub fragment_entry: Option<&'a str>,
    /// Vertex buffer layouts, by slot (empty for generated full-screen triangles).
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// Colour targets: format, blend and write mask for each attachment.
    pub targets: &'a [Option<wgpu::ColorTargetState>],
    /// Depth test and write state; `None` without a depth attachment.
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// Topology, culling and winding.
    pub primitive: wgpu::PrimitiveState,
    /// WGSL `override` constants.
    pub constants: &'a [(&'a str, f64)],
}

impl<'a> RenderSpec<'a> {
    /// A full-screen triangle (`vs_main` draws 3 vertices) writing `targets`.
    pub fn fullscreen(label: &'a str, targets: &'a [Option<wgpu::ColorTargetState>]) -> Self {
        Self {
            label,
            vertex_entry: "vs_main",
            fragment_entry: Some("fs_main"),
            vertex_buffers: &[],
            targets,
            depth_stencil: None,
            primitive: wgpu::PrimitiveState::default(),
            constants: &[],
        }
    }
}

impl Program {
    /// Composes the embedded shader `path` and creates its module and layouts.
    pub fn new(ctx: &GpuContext, path: &str) -> Result<Self, GpuError> {
        Self::from_composed(ctx, shader::compose(path)?)
    }

    /// Same as [`Program::new`] for WGSL text (tests, generated kernels).
    pub fn from_source(ctx: &GpuContext, name: &str, text: &str) -> Result<Self, GpuError> {
        Self::from_composed(ctx, shader::compose_str(name, text)?)
    }

    fn from_composed(ctx: &GpuContext, composed: ComposedShader) -> Result<Self, GpuError> {
        let layout = composed.layout()?;
        let name = composed.name.clone();
        let source_hash = fnv1a(composed.source.as_bytes());
        ctx.scoped(&name, || {
            let module = ctx
                .device
                .create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(&name),
                    source: wgpu::ShaderSource::Wgsl(composed.wgsl()),
                });
            let bind_group_layouts: Vec<_> = (0..layout.groups.len())
                .map(|g| {
                    ctx.device
                        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                            label: Some(&format!("{name}.group{g}")),
                            entries: &layout.entries(g),
                        })
                })
                .collect();
            let refs: Vec<Option<&wgpu::BindGroupLayout>> =
                bind_group_layouts.iter().map(Some).collect();
            let pipeline_layout =
                ctx.device
                    .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some(&name),
                        bind_group_layouts: &refs,
                        immediate_size: 0,
                    });
            Program {
                name: name.clone(),
                module,
                layout,
                bind_group_layouts,
                pipeline_layout,
                source_hash,
            }
        })
    }

    /// Builds bind group `group` from resources named as in the WGSL.
    /// Every binding of the group must be given, and no unknown name.
    pub fn bind_group(
        &self,
        ctx: &GpuContext,
        group: u32,
        resources: &[(&str, wgpu::BindingResource<'_>)],
    ) -> Result<wgpu::BindGroup, GpuError> {
        ctx.scoped(&self.name, || self.bind(&ctx.device, group, resources))?
    }

    /// [`Program::bind_group`] without an error scope, for use while
    /// recording a frame (wgpu errors then reach the context's error log).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        group: u32,
        resources: &[(&str, wgpu::BindingResource<'_>)],
    ) -> Result<wgpu::BindGroup, GpuError> {
        let bindings = self
            .layout
            .groups
            .get(group as usize)
            .ok_or_else(|| GpuError::Other(format!("{}: no bind group {group}", self.name)))?;
        let mut entries = Vec::with_capacity(bindings.len());
        for b in bindings {
            let Some((_, res)) = resources.iter().find(|(n, _)| *n == b.name) else {
                return Err(GpuError::Other(format!(
                    "{}: binding \"{}\" (group {group}) was not given",
                    self.name, b.name
                )));
            };
            entries.push(wgpu::BindGroupEntry {
                binding: b.binding,
                resource: res.clone(),
            });
        }
        if let Some((n, _)) = resources
            .iter()
            .find(|(n, _)| !bindings.iter().any(|b| b.name == *n))
        {
            return Err(GpuError::Other(format!(
                "{}: group {group} has no binding \"{n}\"",
                self.name
            )));
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&format!("{}.group{group}", self.name)),
            layout: &self.bind_group_layouts[group as usize],
            entries: &entries,
        }))
    }

    /// The permutation key of a pipeline of this program: program and its
    /// hash, entry points, override constants (sorted) and, for render
    /// pipelines, a hash of the fixed-function state.
    pub fn key(
        &self,
        kind: &str,
        entries: &str,
        constants: &[(&str, f64)],
        state: u64,
    ) -> PipelineKey {
        let mut c: Vec<String> = constants.iter().map(|(n, v)| format!("{n}={v}")).collect();
        c.sort();
        PipelineKey(format!(
            "{kind}|{}|{entries}|{:016x}|{}|{state:016x}",
            self.name,
            self.source_hash,
            c.join(",")
        ))
    }

    /// The compute pipeline of `entry` with `constants`, through the
    /// context's pipeline cache (memory, disk, compile).
    pub fn compute_pipeline(
        &self,
        ctx: &GpuContext,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let key = self.key("compute", entry, constants, 0);
        ctx.pipelines.compute(key, |cache| {
            ctx.scoped(&format!("{}::{entry}", self.name), || {
                ctx.device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(&format!("{}::{entry}", self.name)),
                        layout: Some(&self.pipeline_layout),
                        module: &self.module,
                        entry_point: Some(entry),
                        compilation_options: wgpu::PipelineCompilationOptions {
                            constants,
                            ..Default::default()
                        },
                        cache,
                    })
            })
        })
    }

    /// The render pipeline of `spec`, through the context's pipeline cache.
    pub fn render_pipeline(
        &self,
        ctx: &GpuContext,
        spec: &RenderSpec<'_>,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        // wgpu's Debug output of the state is stable within a wgpu version,
        // which the cache file's identity pins.
        let state = format!(
            "{}|{:?}|{:?}|{:?}|{:?}",
            spec.label, spec.vertex_buffers, spec.targets, spec.depth_stencil, spec.primitive
        );
        let entries = format!(
            "{}+{}",
            spec.vertex_entry,
            spec.fragment_entry.unwrap_or("-")
        );
        let key = self.key("render", &entries, spec.constants, fnv1a(state.as_bytes()));
        let options = wgpu::PipelineCompilationOptions {
            constants: spec.constants,
            ..Default::default()
        };
        ctx.pipelines.render(key, |cache| {
            ctx.scoped(spec.label, || {
                ctx.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(spec.label),
                        layout: Some(&self.pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some(spec.vertex_entry),
                            compilation_options: options.clone(),
                            buffers: spec.vertex_buffers,
                        },
                        primitive: spec.primitive,
                        depth_stencil: spec.depth_stencil.clone(),
                        multisample: wgpu::MultisampleState::default(),
                        fragment: spec.fragment_entry.map(|e| wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some(e),
                            compilation_options: options.clone(),
                            targets: spec.targets,
                        }),
                        multiview_mask: None,
                        cache,
                    })
            })
        })
    }
}

/// A colour target state without blending.
pub fn target(format: wgpu::TextureFormat) -> Option<wgpu::ColorTargetState> {
    Some(wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })
}

/// A parameter buffer initialised with `data`, bindable as a uniform or as
/// a read-only storage buffer (shaders that branch on their parameters read
/// them as storage: see docs/reliability.md, the lavapipe recompile leak).
pub fn uniform_buffer<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &T) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(data),
            usage: wgpu::BufferUsages::UNIFORM
                | wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST,
        })
}
