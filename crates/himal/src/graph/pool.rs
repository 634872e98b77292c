//! Transient texture and buffer pool, kept across frames outside the graph.

use std::collections::HashMap;

use super::Fallback;
use super::compile::{BufferKey, TextureKey};

struct Pooled<T> {
    object: T,
    bytes: u64,
    /// Frame (execute call) that last took it; taken objects are not handed
    /// out twice in one frame.
    last_frame: u64,
}

/// Pooled transient textures (and buffers), keyed by description plus
/// derived usages. A graph's `execute` takes one object per plan slot;
/// objects not taken for a while can be dropped with [`TexturePool::trim`].
#[derive(Default)]
pub struct TexturePool {
    textures: HashMap<TextureKey, Vec<Pooled<wgpu::Texture>>>,
    buffers: HashMap<BufferKey, Vec<Pooled<wgpu::Buffer>>>,
    frame: u64,
    /// Views of the 1x1 [`Fallback`] textures, in `Fallback::ALL` order.
    fallbacks: Vec<(wgpu::Texture, wgpu::TextureView)>,
    /// Set once a frame that recorded their clears finished recording; until
    /// then every execute records them (a failed frame is never submitted).
    fallbacks_cleared: std::cell::Cell<bool>,
    /// [`super::fallback::ZERO_BUFFER_BYTES`] of zeros (wgpu zero-initialises it).
    zero_buffer: std::cell::OnceCell<wgpu::Buffer>,
}

impl TexturePool {
    /// An empty pool; textures and buffers are created on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Bytes held by pooled textures and buffers (textures: theoretical
    /// size without driver padding).
    pub fn allocated_bytes(&self) -> u64 {
        let t: u64 = self.textures.values().flatten().map(|p| p.bytes).sum();
        let b: u64 = self.buffers.values().flatten().map(|p| p.bytes).sum();
        t + b
    }

    /// Number of pooled textures (all keys, free or in use).
    pub fn texture_count(&self) -> usize {
        self.textures.values().map(Vec::len).sum()
    }

    /// Number of pooled buffers (all keys, free or in use).
    pub fn buffer_count(&self) -> usize {
        self.buffers.values().map(Vec::len).sum()
    }

    /// Creates the [`Fallback`] textures on first use and records their clears.
    pub(crate) fn prepare_fallbacks(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) {
        if self.fallbacks_cleared.get() {
            return;
        }
        if self.fallbacks.is_empty() {
            self.fallbacks = Fallback::ALL.iter().map(|f| f.texture(device)).collect();
        }
        for (f, (texture, view)) in Fallback::ALL.iter().zip(&self.fallbacks) {
            if matches!(f, Fallback::Black3d | Fallback::BlackArray) {
                continue; // zero-initialised by wgpu
            }
            let depth = *f == Fallback::DepthFar;
            let attachment = depth.then(|| texture.create_view(&Default::default()));
            encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("himal.fallback.clear"),
                color_attachments: &[(!depth).then(|| wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(f.value()),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: attachment.as_ref().map(|view| {
                    wgpu::RenderPassDepthStencilAttachment {
                        view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        }
    }

    /// The buffer of zeros bound for absent optional buffers.
    pub(crate) fn zero_buffer(&self, device: &wgpu::Device) -> &wgpu::Buffer {
        self.zero_buffer.get_or_init(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("himal.fallback.zeros"),
                size: super::fallback::ZERO_BUFFER_BYTES,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        })
    }

    /// Views of the fallback textures, in `Fallback::ALL` order.
    pub(crate) fn fallback_views(&self) -> Vec<&wgpu::TextureView> {
        self.fallbacks.iter().map(|(_, v)| v).collect()
    }

    /// The frame that recorded the fallback clears finished recording.
    pub(crate) fn fallbacks_recorded(&self) {
        self.fallbacks_cleared.set(true);
    }

    /// Drops objects not used by the last `max_idle_frames` executes
    /// (e.g. after a resolution change).
    pub fn trim(&mut self, max_idle_frames: u64) {
        let frame = self.frame;
        let keep = |last: u64| frame.saturating_sub(last) <= max_idle_frames;
        for list in self.textures.values_mut() {
            list.retain(|p| keep(p.last_frame));
        }
        for list in self.buffers.values_mut() {
            list.retain(|p| keep(p.last_frame));
        }
        self.textures.retain(|_, l| !l.is_empty());
        self.buffers.retain(|_, l| !l.is_empty());
    }

    pub(crate) fn begin_frame(&mut self) {
        self.frame += 1;
    }

    /// Takes a texture not yet taken this frame, creating one if needed;
    /// returns its index within the key's list.
    pub(crate) fn take_texture(
        &mut self,
        device: &wgpu::Device,
        key: &TextureKey,
        label: &str,
    ) -> usize {
        let frame = self.frame;
        let list = self.textures.entry(key.clone()).or_default();
        if let Some(i) = list.iter().position(|p| p.last_frame != frame) {
            list[i].last_frame = frame;
            return i;
        }
        let desc = key.desc();
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: desc.size(),
            mip_level_count: desc.mip_levels,
            sample_count: 1,
            dimension: desc.dimension,
            format: desc.format,
            usage: key.usages,
            view_formats: &[],
        });
        list.push(Pooled {
            object: texture,
            bytes: desc.byte_size(),
            last_frame: frame,
        });
        list.len() - 1
    }

    pub(crate) fn take_buffer(
        &mut self,
        device: &wgpu::Device,
        key: &BufferKey,
        label: &str,
    ) -> usize {
        let frame = self.frame;
        let list = self.buffers.entry(key.clone()).or_default();
        if let Some(i) = list.iter().position(|p| p.last_frame != frame) {
            list[i].last_frame = frame;
            return i;
        }
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: key.size,
            usage: key.usages,
            mapped_at_creation: false,
        });
        list.push(Pooled {
            object: buffer,
            bytes: key.size,
            last_frame: frame,
        });
        list.len() - 1
    }

    pub(crate) fn texture(&self, key: &TextureKey, index: usize) -> Option<&wgpu::Texture> {
        self.textures.get(key)?.get(index).map(|p| &p.object)
    }

    pub(crate) fn buffer(&self, key: &BufferKey, index: usize) -> Option<&wgpu::Buffer> {
        self.buffers.get(key)?.get(index).map(|p| &p.object)
    }
}
