//! Recording: one command encoder, pooled transients, timestamps per pass.

use std::cell::{Cell, OnceCell};

use super::GraphError;
use super::builder::{Backing, ResourceKind};
use super::compile::CompiledGraph;
use super::pool::TexturePool;
use super::resource::{BufferHandle, TextureHandle};
use super::timer::{PassTimer, PassTiming, TimingMethod};

/// Each pass's wall time when submitted alone ([`CompiledGraph::execute_isolated`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IsolatedTimings {
    /// Each pass's submit-to-idle wall milliseconds less `empty_submit_ms`
    /// (clamped at 0), method [`TimingMethod::IsolatedWall`].
    pub passes: Vec<PassTiming>,
    /// Wall milliseconds of submitting an empty command buffer and waiting
    /// (the least of three), subtracted from each pass.
    pub empty_submit_ms: f64,
}

/// What a pass closure records with. Resources are looked up by handle;
/// any version of a resource the pass declared is accepted.
pub struct PassContext<'e> {
    /// The frame's command encoder; the pass records into it inside its debug group.
    pub encoder: &'e mut wgpu::CommandEncoder,
    /// The device, for bind groups and views the pass makes while recording.
    pub device: &'e wgpu::Device,
    pass_id: &'e str,
    declared: &'e [u32],
    graph_id: u32,
    names: &'e [&'e str],
    textures: &'e [Option<&'e wgpu::Texture>],
    views: &'e [OnceCell<wgpu::TextureView>],
    buffers: &'e [Option<&'e wgpu::Buffer>],
    fallbacks: &'e [&'e wgpu::TextureView],
    zero_buffer: &'e wgpu::Buffer,
    /// The pass-level query set and the pair this pass may write (taken
    /// once; a `Cell` of a plain index keeps the context covariant in 'e).
    pass_query_set: Option<&'e wgpu::QuerySet>,
    pass_pair: u32,
    pass_queries_taken: Cell<bool>,
}

impl<'e> PassContext<'e> {
    // Returned references live for the whole pass ('e), not the borrow of
    // `self`, so they can be used while `self.encoder` is borrowed mutably.
    /// The id of the running pass (with any view prefix).
    pub fn pass_id(&self) -> &'e str {
        self.pass_id
    }

    fn resolve(&self, graph: u32, index: u32) -> Result<usize, GraphError> {
        let name = self
            .names
            .get(index as usize)
            .filter(|_| graph == self.graph_id);
        let Some(name) = name else {
            return Err(GraphError::UnknownHandle {
                context: self.pass_id.to_string(),
            });
        };
        if self.declared.binary_search(&index).is_err() {
            return Err(GraphError::UndeclaredResource {
                pass: self.pass_id.to_string(),
                resource: name.to_string(),
            });
        }
        Ok(index as usize)
    }

    /// The texture behind `h`, or an error if this pass did not declare it.
    pub fn try_texture(&self, h: TextureHandle) -> Result<&'e wgpu::Texture, GraphError> {
        let i = self.resolve(h.graph, h.index)?;
        self.textures[i].ok_or_else(|| GraphError::UnknownHandle {
            context: self.pass_id.to_string(),
        })
    }

    /// Default view of the texture, created on first use and cached.
    pub fn try_view(&self, h: TextureHandle) -> Result<&'e wgpu::TextureView, GraphError> {
        let texture = self.try_texture(h)?;
        let i = h.index as usize;
        let (views, names) = (self.views, self.names);
        Ok(views[i].get_or_init(|| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some(names[i]),
                ..Default::default()
            })
        }))
    }

    /// The buffer behind `h`, or an error if this pass did not declare it.
    pub fn try_buffer(&self, h: BufferHandle) -> Result<&'e wgpu::Buffer, GraphError> {
        let i = self.resolve(h.graph, h.index)?;
        self.buffers[i].ok_or_else(|| GraphError::UnknownHandle {
            context: self.pass_id.to_string(),
        })
    }

    /// The graph's constant texture for an absent optional input.
    pub fn fallback(&self, f: super::Fallback) -> &'e wgpu::TextureView {
        self.fallbacks[f.index()]
    }

    /// The graph's buffer of zeros for an absent optional buffer input.
    pub fn zero_buffer(&self) -> &'e wgpu::Buffer {
        self.zero_buffer
    }

    /// Timestamp writes for this pass's first compute pass, when the graph
    /// is timed (`None` after the first call, or untimed): its GPU time
    /// then comes from them instead of the encoder timestamps around the
    /// pass, which lavapipe does not order against compute work.
    pub fn compute_timestamp_writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'e>> {
        let set = self.pass_query_set?;
        if self.pass_queries_taken.replace(true) {
            return None;
        }
        let pair = self.pass_pair;
        Some(wgpu::ComputePassTimestampWrites {
            query_set: set,
            beginning_of_pass_write_index: Some(2 * pair),
            end_of_pass_write_index: Some(2 * pair + 1),
        })
    }

    /// # Panics
    /// If this pass did not declare `h` (a bug in the pass code, like an
    /// out-of-bounds index); use [`Self::try_texture`] to handle it.
    pub fn texture(&self, h: TextureHandle) -> &'e wgpu::Texture {
        self.try_texture(h).unwrap_or_else(|e| panic!("{e}"))
    }

    /// # Panics
    /// As [`Self::texture`].
    pub fn view(&self, h: TextureHandle) -> &'e wgpu::TextureView {
        self.try_view(h).unwrap_or_else(|e| panic!("{e}"))
    }

    /// # Panics
    /// As [`Self::texture`].
    pub fn buffer(&self, h: BufferHandle) -> &'e wgpu::Buffer {
        self.try_buffer(h).unwrap_or_else(|e| panic!("{e}"))
    }
}

impl CompiledGraph<'_> {
    /// Records all live passes into one command buffer. Transients come
    /// from `pool`; with a `timer`, each pass is wrapped in a timestamp
    /// pair resolved at the end (read with [`PassTimer::read_timings`]
    /// after submitting). wgpu validation and out-of-memory errors raised
    /// while allocating or recording are returned as [`GraphError::Device`].
    pub fn execute(
        self,
        device: &wgpu::Device,
        pool: &mut TexturePool,
        timer: Option<&mut PassTimer>,
    ) -> Result<wgpu::CommandBuffer, GraphError> {
        self.record(device, None, pool, timer).map(|(c, _)| c)
    }

    /// As [`Self::execute`], but each pass is recorded into a command
    /// buffer of its own, submitted alone after the work before it has
    /// finished, and timed by the wall clock until the queue is idle: a
    /// measurement for passes whose timestamps are not credible (bench).
    /// The returned buffer holds only the timestamp resolve; the image is
    /// the same as `execute`'s.
    pub fn execute_isolated(
        self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pool: &mut TexturePool,
        timer: Option<&mut PassTimer>,
    ) -> Result<(wgpu::CommandBuffer, IsolatedTimings), GraphError> {
        self.record(device, Some(queue), pool, timer)
    }

    fn record(
        self,
        device: &wgpu::Device,
        isolate: Option<&wgpu::Queue>,
        pool: &mut TexturePool,
        timer: Option<&mut PassTimer>,
    ) -> Result<(wgpu::CommandBuffer, IsolatedTimings), GraphError> {
        if let Some(t) = &timer
            && self.passes.len() > t.capacity() as usize
        {
            return Err(GraphError::TimerCapacity {
                passes: self.passes.len(),
                capacity: t.capacity(),
            });
        }
        // Placeholder imports used by a live pass cannot execute.
        for (r, res) in self.resources.iter().enumerate() {
            let placeholder = matches!(
                &res.kind,
                ResourceKind::Texture {
                    backing: Backing::Imported(None),
                    ..
                } | ResourceKind::Buffer {
                    backing: Backing::Imported(None),
                    ..
                }
            );
            if placeholder && self.declared.iter().any(|d| d.contains(&(r as u32))) {
                return Err(GraphError::UnboundImport(res.name.clone()));
            }
        }

        // Scopes cover pool allocation and recording; errors become Err.
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        // Take every slot first (mutable pool), then borrow immutably.
        pool.begin_frame();
        let tex_index: Vec<usize> = (0..self.plan.texture_slots.len())
            .map(|s| {
                let label = slot_label(&self.plan.textures, s);
                pool.take_texture(device, &self.plan.texture_slots[s], &label)
            })
            .collect();
        let buf_index: Vec<usize> = (0..self.plan.buffer_slots.len())
            .map(|s| {
                let label = slot_label(&self.plan.buffers, s);
                pool.take_buffer(device, &self.plan.buffer_slots[s], &label)
            })
            .collect();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("himal.frame_graph"),
        });
        pool.prepare_fallbacks(device, &mut encoder);
        let pool = &*pool;

        let n = self.resources.len();
        let mut textures: Vec<Option<&wgpu::Texture>> = vec![None; n];
        let mut buffers: Vec<Option<&wgpu::Buffer>> = vec![None; n];
        for (i, r) in self.resources.iter().enumerate() {
            match &r.kind {
                ResourceKind::Texture {
                    backing: Backing::Imported(t),
                    ..
                } => textures[i] = *t,
                ResourceKind::Buffer {
                    backing: Backing::Imported(b),
                    ..
                } => buffers[i] = *b,
                ResourceKind::Texture { .. } => {
                    textures[i] = self.slot_of[i]
                        .and_then(|s| pool.texture(&self.plan.texture_slots[s], tex_index[s]));
                }
                ResourceKind::Buffer { .. } => {
                    buffers[i] = self.slot_of[i]
                        .and_then(|s| pool.buffer(&self.plan.buffer_slots[s], buf_index[s]));
                }
            }
        }
        let views: Vec<OnceCell<wgpu::TextureView>> = (0..n).map(|_| OnceCell::new()).collect();
        let names: Vec<&str> = self.resources.iter().map(|r| r.name.as_str()).collect();

        let fallbacks = pool.fallback_views();
        let zero_buffer = pool.zero_buffer(device);
        let query = timer.as_ref().map(|t| t.query_set());
        let pass_query = timer.as_ref().map(|t| t.pass_query_set());
        // Each pass's pass-level pair, if it wrote one.
        let mut pass_pairs: Vec<Option<u32>> = Vec::with_capacity(self.passes.len());
        let mut next_pair = 0u32;
        let mut isolated = IsolatedTimings::default();
        let wait = || -> Result<(), GraphError> {
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map(drop)
                .map_err(|e| GraphError::Device(format!("isolated pass: {e}")))
        };
        if let Some(queue) = isolate {
            let mut empty = f64::INFINITY;
            for _ in 0..3 {
                let t = std::time::Instant::now();
                queue.submit(std::iter::empty());
                wait()?;
                empty = empty.min(t.elapsed().as_secs_f64() * 1e3);
            }
            isolated.empty_submit_ms = empty;
        }
        for (i, (f, pass)) in self.closures.into_iter().zip(&self.passes).enumerate() {
            if let Some(queue) = isolate {
                // Everything before this pass runs to completion first.
                let before = std::mem::replace(
                    &mut encoder,
                    device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some(&pass.id),
                    }),
                );
                queue.submit([before.finish()]);
                wait()?;
            }
            if let Some(q) = query {
                encoder.write_timestamp(q, 2 * i as u32);
            }
            encoder.push_debug_group(&pass.id);
            let mut ctx = PassContext {
                encoder: &mut encoder,
                device,
                pass_id: &pass.id,
                declared: &self.declared[i],
                graph_id: self.graph_id,
                names: &names,
                textures: &textures,
                views: &views,
                buffers: &buffers,
                fallbacks: &fallbacks,
                zero_buffer,
                pass_query_set: pass_query,
                pass_pair: next_pair,
                pass_queries_taken: Cell::new(false),
            };
            let result = f(&mut ctx);
            if ctx.pass_queries_taken.get() {
                pass_pairs.push(Some(next_pair));
                next_pair += 1;
            } else {
                pass_pairs.push(None);
            }
            encoder.pop_debug_group();
            if let Err(e) = result {
                // Close the scopes before returning: the first error is the one reported.
                let _ = pollster::block_on(validation.pop());
                let _ = pollster::block_on(oom.pop());
                return Err(GraphError::Pass {
                    pass: pass.id.clone(),
                    message: e.to_string(),
                });
            }
            if let Some(q) = query {
                encoder.write_timestamp(q, 2 * i as u32 + 1);
            }
            if let Some(queue) = isolate {
                let alone = std::mem::replace(
                    &mut encoder,
                    device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                        label: Some("himal.frame_graph"),
                    }),
                );
                let commands = alone.finish();
                let t = std::time::Instant::now();
                queue.submit([commands]);
                wait()?;
                let wall = t.elapsed().as_secs_f64() * 1e3;
                isolated.passes.push(PassTiming {
                    id: pass.id.clone(),
                    gpu_ms: (wall - isolated.empty_submit_ms).max(0.0),
                    encoder_ms: 0.0,
                    method: TimingMethod::IsolatedWall,
                });
            }
        }
        if let Some(t) = timer {
            let ids = self
                .passes
                .iter()
                .map(|p| p.id.clone())
                .zip(pass_pairs)
                .collect();
            t.record_resolve(&mut encoder, ids);
        }
        let commands = encoder.finish();
        pool.fallbacks_recorded();
        let v = pollster::block_on(validation.pop());
        let o = pollster::block_on(oom.pop());
        match v.or(o) {
            // wgpu names the pass (its label is the pass id) in the message.
            Some(e) => {
                let message = e.to_string();
                let quoted = |id: &str| {
                    message.contains(&format!("'{id}'")) || message.contains(&format!("\"{id}\""))
                };
                Err(match self.passes.iter().find(|p| quoted(&p.id)) {
                    Some(p) => GraphError::Pass {
                        pass: p.id.clone(),
                        message,
                    },
                    None => GraphError::Device(format!("recording the frame graph: {message}")),
                })
            }
            None => Ok((commands, isolated)),
        }
    }
}

/// Pool object label: the first resource that uses the slot this frame.
fn slot_label(assignments: &[super::compile::PoolAssignment], slot: usize) -> String {
    let first = assignments.iter().find(|a| a.slot == slot);
    format!(
        "himal.pool.{}",
        first.map_or("unused", |a| a.resource.as_str())
    )
}
