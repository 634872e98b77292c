//! This frame's culled lists as the passes draw them ([`Culled`]): one
//! multi-draw-indirect per list on the GPU path, direct draws of the CPU
//! twin's pool lists on the CPU path (`super::CullPath`).

use super::{ARGS_BYTES, CullLayout, LISTS, List};
use crate::graph::{BufferAccess, BufferHandle, Node, PassContext};
use crate::scene::lod::MAX_LODS;

/// This frame's culled lists in the graph ([`super::CullPass::add`]).
#[derive(Clone, Copy, Debug)]
pub struct Culled<'a> {
    /// Instance -> object: the identity at `0..objects` (draws recorded on
    /// the CPU in a culled pass), then per view `v` the lists at
    /// `(v + 1) * objects + batch.first_object ..`.
    pub instances: BufferHandle,
    /// Per view: one `DrawIndexedIndirectArgs` per batch, kind and level.
    pub args: CulledArgs<'a>,
    opaque: (u32, u32),
    vegetation: (u32, u32),
    /// The streamed regions' batches (first, count) inside the opaque and
    /// the vegetation list.
    pool: [(u32, u32); 2],
    batches: u32,
    /// Some batch has more than one level: fading lists may be non-empty.
    pub has_lods: bool,
}

/// Where the draw arguments of [`Culled`] are.
#[derive(Clone, Copy, Debug)]
pub enum CulledArgs<'a> {
    /// Written by the `cull` node: drawn with (multi-)indirect draws.
    Gpu(BufferHandle),
    /// Written by the CPU twin for the streamed pool alone (adapters
    /// without indirect draws, `--culling cpu`): drawn directly, the
    /// non-empty lists one instanced draw each (`instanced`) or one draw
    /// per instance (the per-object path).
    Cpu {
        /// The arguments, laid out as the GPU's (per view, batch, kind and level; scene batches
        /// empty).
        args: &'a [[u32; 5]],
        /// Each non-empty list is one instanced draw, else one draw per instance.
        instanced: bool,
    },
}

/// The kinds the G-buffer's opaque pipeline draws (no discard: early-Z).
pub const STEADY: std::ops::Range<u32> = 0..1;
/// The kinds the G-buffer's dithering pipeline draws.
pub const FADING: std::ops::Range<u32> = 1..3;
/// What shadow maps draw: steady and fading-out lists, undithered (a
/// transition shows in the shadow only when it ends).
pub const SHADOW: std::ops::Range<u32> = 0..2;
/// Every kind (vegetation, which tests its fade code anyway).
pub const ALL: std::ops::Range<u32> = 0..3;

/// Binds `instances` of `node`: the culled lists, their indirect arguments
/// declared too, or without `culled` the scene's identity `identity`.
pub fn bind_instances<'g, 'a>(
    node: Node<'g, 'a>,
    culled: Option<&Culled<'a>>,
    identity: &'a wgpu::Buffer,
) -> Node<'g, 'a> {
    let Some(c) = culled else {
        return node.uniform("instances", identity);
    };
    let node = node.read_buffer("instances", c.instances, BufferAccess::StorageRead);
    match c.args {
        CulledArgs::Gpu(args) => node.indirect(args),
        CulledArgs::Cpu { .. } => node,
    }
}

impl<'a> Culled<'a> {
    /// `layout`'s lists in the graph: `instances` and where their arguments are.
    pub(super) fn new(layout: &CullLayout, instances: BufferHandle, args: CulledArgs<'a>) -> Self {
        Culled {
            instances,
            args,
            opaque: layout.range(List::Opaque),
            vegetation: layout.range(List::Vegetation),
            pool: [
                layout.pool_range(List::Opaque),
                layout.pool_range(List::Vegetation),
            ],
            batches: layout.batches.len() as u32,
            has_lods: layout.has_lods(),
        }
    }

    /// Whether `list` has streamed regions (the world's pool).
    pub fn has_pool(&self, list: List) -> bool {
        self.pool[list as usize].1 > 0
    }

    /// Records view `view`'s draws of `list`'s `kinds` ([`STEADY`],
    /// [`FADING`], [`SHADOW`], [`ALL`]; pipeline and geometry bound): one
    /// multi-draw, or none when the list is empty. Returns the calls
    /// recorded.
    pub fn draw(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        ctx: &PassContext<'_>,
        view: u32,
        list: List,
        kinds: std::ops::Range<u32>,
    ) -> u32 {
        let count = self.range(list).1;
        if count == 0 || kinds.is_empty() {
            return 0;
        }
        let start = self.args_at(view, list, kinds.start, 0, 0);
        let draws = (kinds.end - kinds.start) * count * MAX_LODS as u32;
        self.record(rp, ctx, start, draws)
    }

    /// [`Self::draw`] of the levels in `levels` alone: one multi-draw per
    /// kind (`--view lod`, a pipeline per level; V3's impostor levels in
    /// their own pass). Returns the calls recorded.
    pub fn draw_levels(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        ctx: &PassContext<'_>,
        view: u32,
        list: List,
        kinds: std::ops::Range<u32>,
        levels: std::ops::Range<u32>,
    ) -> u32 {
        let count = self.range(list).1;
        let levels = levels.start..levels.end.min(MAX_LODS as u32);
        if count == 0 || levels.is_empty() {
            return 0;
        }
        let draws = (levels.end - levels.start) * count;
        kinds
            .map(|kind| {
                let start = self.args_at(view, list, kind, 0, levels.start);
                self.record(rp, ctx, start, draws)
            })
            .sum()
    }

    /// View `view`'s draws of `list`'s streamed regions' batches alone
    /// (L2's height fields, shadow maps on the CPU path: static world
    /// instances, no scene objects): one multi-draw per kind and level in
    /// `kinds`. Returns the calls recorded.
    pub fn draw_pool(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        ctx: &PassContext<'_>,
        view: u32,
        list: List,
        kinds: std::ops::Range<u32>,
    ) -> u32 {
        let (first, count) = self.pool[list as usize];
        if count == 0 {
            return 0;
        }
        let mut calls = 0;
        for kind in kinds {
            for level in 0..MAX_LODS as u32 {
                let start = self.args_at(view, list, kind, first - self.range(list).0, level);
                calls += self.record(rp, ctx, start, count);
            }
        }
        calls
    }

    /// Draws the `count` argument records from `start`: one multi-draw
    /// (GPU), or each non-empty one directly (CPU twin).
    fn record(
        &self,
        rp: &mut wgpu::RenderPass<'_>,
        ctx: &PassContext<'_>,
        start: u64,
        count: u32,
    ) -> u32 {
        match self.args {
            CulledArgs::Gpu(args) => {
                rp.multi_draw_indexed_indirect(ctx.buffer(args), start * ARGS_BYTES, count);
                1
            }
            CulledArgs::Cpu { args, instanced } => {
                let at = start as usize;
                let records = args.get(at..at + count as usize).unwrap_or_default();
                let mut calls = 0;
                for &[indices, n, first, base, first_instance] in records {
                    let range = first..first + indices;
                    let instances = first_instance..first_instance + n;
                    if n == 0 {
                        continue;
                    } else if instanced {
                        rp.draw_indexed(range, base as i32, instances);
                        calls += 1;
                    } else {
                        for i in instances {
                            rp.draw_indexed(range.clone(), base as i32, i..i + 1);
                        }
                        calls += n;
                    }
                }
                calls
            }
        }
    }

    /// Index of the arguments of (view, list, kind, batch of the list,
    /// level): [view][opaque: kind, level, batch][vegetation: kind, level,
    /// batch] (`CullLayout::args_index`).
    fn args_at(&self, view: u32, list: List, kind: u32, batch: u32, level: u32) -> u64 {
        let (first, count) = self.range(list);
        let (lods, lists) = (MAX_LODS as u64, LISTS as u64);
        u64::from(view) * u64::from(self.batches) * lists
            + u64::from(first) * lists
            + (u64::from(kind) * lods + u64::from(level)) * u64::from(count)
            + u64::from(batch)
    }

    fn range(&self, list: List) -> (u32, u32) {
        match list {
            List::Opaque => self.opaque,
            List::Vegetation => self.vegetation,
        }
    }
}
