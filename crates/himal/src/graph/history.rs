//! Named history: temporal textures kept across frames (AO, colour TAA,
//! buffer TAA, and every future one) through one mechanism.
//!
//! A technique declares a ring by name and description before the frame
//! ([`History::declare`]; a new size or format recreates it and forgets it),
//! imports it into the frame graph ([`History::import`]: the texture to
//! write and those of earlier frames, with how many earlier frames are
//! valid), and the renderer calls [`History::swap`] after submitting and
//! [`History::reset`] on camera cuts. A ring not written by a frame loses
//! its history at the swap. [`History::memory`] lists every ring's bytes.

use std::cell::Cell;

use super::builder::FrameGraph;
use super::resource::{TextureDesc, TextureHandle};

/// Usages every history texture gets: written as an attachment, sampled
/// next frame, copied for read-back in tests.
const USAGES: wgpu::TextureUsages = wgpu::TextureUsages::TEXTURE_BINDING
    .union(wgpu::TextureUsages::RENDER_ATTACHMENT)
    .union(wgpu::TextureUsages::COPY_SRC)
    .union(wgpu::TextureUsages::COPY_DST);

struct Ring {
    name: String,
    desc: TextureDesc,
    textures: Vec<wgpu::Texture>,
    /// Frames swapped since creation: `textures[frame % len]` is written next.
    frame: usize,
    /// Consecutive frames written since the last reset (0: no history).
    valid: u32,
    written: Cell<bool>,
}

impl Ring {
    fn slot(&self, frames_ago: usize) -> &wgpu::Texture {
        let n = self.textures.len();
        &self.textures[(self.frame + n - frames_ago % n) % n]
    }
}

/// One frame's view of a ring in the graph.
#[derive(Clone, Copy, Debug)]
pub struct HistoryFrame {
    /// Written this frame (marked as a graph output: it outlives the frame).
    pub next: TextureHandle,
    /// The frame before (`previous[0]`), and the one before that when the
    /// ring keeps three; unused entries repeat `previous[0]`.
    pub previous: [TextureHandle; 2],
    /// Earlier frames whose content is valid (0 after a cut or a resize).
    pub frames: u32,
}

/// Every temporal ring of a renderer, by name.
#[derive(Default)]
pub struct History {
    rings: Vec<Ring>,
}

impl History {
    /// No rings; [`Self::declare`] adds them.
    pub fn new() -> Self {
        Self::default()
    }

    /// Makes sure ring `name` holds `len` (2 or 3) textures of `desc`; a
    /// different description recreates it with no valid frames.
    pub fn declare(&mut self, device: &wgpu::Device, name: &str, desc: &TextureDesc, len: usize) {
        let len = len.clamp(2, 3);
        if let Some(r) = self.rings.iter().find(|r| r.name == name)
            && r.desc == *desc
            && r.textures.len() == len
        {
            return;
        }
        let textures = (0..len)
            .map(|i| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(&format!("{name}.{i}")),
                    size: desc.size(),
                    mip_level_count: desc.mip_levels,
                    sample_count: 1,
                    dimension: desc.dimension,
                    format: desc.format,
                    usage: USAGES,
                    view_formats: &[],
                })
            })
            .collect();
        let ring = Ring {
            name: name.to_string(),
            desc: desc.clone(),
            textures,
            frame: 0,
            valid: 0,
            written: Cell::new(false),
        };
        match self.rings.iter_mut().find(|r| r.name == name) {
            Some(r) => *r = ring,
            None => self.rings.push(ring),
        }
    }

    /// Whether ring `name` is declared with size `(w, h)`.
    pub fn has(&self, name: &str, size: (u32, u32)) -> bool {
        self.rings
            .iter()
            .any(|r| r.name == name && (r.desc.width, r.desc.height) == size)
    }

    /// Imports ring `name` into `graph` as `{name}.next`, `{name}.previous`
    /// (and `{name}.previous2`); `None` if it was never declared.
    pub fn import<'a>(&'a self, graph: &mut FrameGraph<'a>, name: &str) -> Option<HistoryFrame> {
        let r = self.rings.iter().find(|r| r.name == name)?;
        r.written.set(true);
        let next = graph.import_texture(&format!("{name}.next"), r.slot(0));
        let previous = graph.import_texture(&format!("{name}.previous"), r.slot(1));
        let previous2 = if r.textures.len() > 2 {
            graph.import_texture(&format!("{name}.previous2"), r.slot(2))
        } else {
            previous
        };
        Some(HistoryFrame {
            next,
            previous: [previous, previous2],
            frames: r.valid,
        })
    }

    /// Consecutive valid frames of ring `name` (0 if undeclared).
    pub fn frames(&self, name: &str) -> u32 {
        self.rings
            .iter()
            .find(|r| r.name == name)
            .map_or(0, |r| r.valid)
    }

    /// The texture ring `name` wrote `frames_ago` frames before the next
    /// one (1: the last frame written), for tests and tools.
    pub fn texture(&self, name: &str, frames_ago: usize) -> Option<&wgpu::Texture> {
        let r = self.rings.iter().find(|r| r.name == name)?;
        Some(r.slot(frames_ago))
    }

    /// After a frame was submitted: rings it imported advance (next becomes
    /// previous); the others lose their history.
    pub fn swap(&mut self) {
        for r in &mut self.rings {
            if r.written.replace(false) {
                r.frame += 1;
                r.valid = r.valid.saturating_add(1);
            } else {
                r.valid = 0;
            }
        }
    }

    /// After a frame that was not submitted (an error): nothing advances.
    pub fn discard(&mut self) {
        for r in &mut self.rings {
            r.written.set(false);
        }
    }

    /// Camera cut: every ring starts again.
    pub fn reset(&mut self) {
        for r in &mut self.rings {
            r.valid = 0;
        }
    }

    /// Ring `name` starts again (a technique's mode changed).
    pub fn reset_one(&mut self, name: &str) {
        if let Some(r) = self.rings.iter_mut().find(|r| r.name == name) {
            r.valid = 0;
        }
    }

    /// (name, bytes) of every ring, for the memory report.
    pub fn memory(&self) -> Vec<(String, u64)> {
        self.rings
            .iter()
            .map(|r| (r.name.clone(), r.desc.byte_size() * r.textures.len() as u64))
            .collect()
    }
}
