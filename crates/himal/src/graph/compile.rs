//! Validation, ordering, culling, usage derivation and the pool plan.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, HashSet};

use super::GraphError;
use super::builder::{Backing, FrameGraph, PassFn, Resource, ResourceKind};
use super::resource::{ResourceAccess, ResourceUse, Usages};

/// A live pass in execution order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CompiledPass {
    /// Pass id as declared (with any view prefix), e.g. `ao.hbao`.
    pub id: String,
    /// Resource versions the pass reads.
    pub reads: Vec<ResourceUse>,
    /// Each write lists the new version it produces.
    pub writes: Vec<ResourceUse>,
    /// Whether the pass was declared with a side effect (never culled, e.g. readbacks).
    pub side_effect: bool,
}

/// Pool key of a transient texture: everything but the label.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct TextureKey {
    /// Width in texels of mip 0.
    pub width: u32,
    /// Height in texels of mip 0.
    pub height: u32,
    /// Depth (3D) or array layers (2D); 1 for a plain 2D texture.
    pub depth_or_layers: u32,
    /// Number of mip levels, at least 1.
    pub mip_levels: u32,
    /// Texel format.
    pub format: wgpu::TextureFormat,
    /// 1D, 2D or 3D.
    pub dimension: wgpu::TextureDimension,
    /// Union of the usages of every live access to the resource.
    pub usages: wgpu::TextureUsages,
}

impl TextureKey {
    pub(crate) fn desc(&self) -> super::TextureDesc {
        super::TextureDesc {
            label: None,
            width: self.width,
            height: self.height,
            depth_or_layers: self.depth_or_layers,
            mip_levels: self.mip_levels,
            format: self.format,
            dimension: self.dimension,
        }
    }
}

/// Pool key of a transient buffer: its size and derived usages.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct BufferKey {
    /// Size in bytes.
    pub size: u64,
    /// Union of the usages of every live access to the resource.
    pub usages: wgpu::BufferUsages,
}

/// One transient resource's slot and lifetime (execution positions, 0-based,
/// inclusive). Resources sharing a slot share one pooled object in a frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PoolAssignment {
    /// Name of the transient resource.
    pub resource: String,
    /// Index into [`PoolPlan::texture_slots`] or [`PoolPlan::buffer_slots`].
    pub slot: usize,
    /// Execution position of the first live pass that uses it.
    pub first_pass: usize,
    /// Execution position of the last live pass that uses it; the slot is free after it.
    pub last_pass: usize,
}

/// How transients map onto pooled textures and buffers within the frame:
/// a slot is freed after its resource's last use and handed to the next
/// transient with the identical key (lifetime reuse, no memory aliasing).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PoolPlan {
    /// Key of each pooled texture slot, indexed by slot.
    pub texture_slots: Vec<TextureKey>,
    /// Key of each pooled buffer slot, indexed by slot.
    pub buffer_slots: Vec<BufferKey>,
    /// Slot and lifetime of each live transient texture.
    pub textures: Vec<PoolAssignment>,
    /// Slot and lifetime of each live transient buffer.
    pub buffers: Vec<PoolAssignment>,
}

impl PoolPlan {
    /// Pool slot of the named transient texture; `None` if it is imported, culled or unknown.
    pub fn texture_slot(&self, name: &str) -> Option<usize> {
        self.textures
            .iter()
            .find(|a| a.resource == name)
            .map(|a| a.slot)
    }

    /// Pool slot of the named transient buffer; `None` if it is imported, culled or unknown.
    pub fn buffer_slot(&self, name: &str) -> Option<usize> {
        self.buffers
            .iter()
            .find(|a| a.resource == name)
            .map(|a| a.slot)
    }
}

/// A validated, ordered and culled graph, ready to execute once.
pub struct CompiledGraph<'a> {
    pub(crate) graph_id: u32,
    pub(crate) resources: Vec<Resource<'a>>,
    pub(crate) passes: Vec<CompiledPass>,
    /// Closures aligned with `passes`.
    pub(crate) closures: Vec<PassFn<'a>>,
    /// Resource indices each live pass declared (for `PassContext` checks).
    pub(crate) declared: Vec<Vec<u32>>,
    pub(crate) culled: Vec<String>,
    /// Derived usages per resource (empty when only culled passes use it).
    pub(crate) usages: Vec<Usages>,
    /// Pool slot per transient resource index.
    pub(crate) slot_of: Vec<Option<usize>>,
    pub(crate) plan: PoolPlan,
}

pub(crate) fn compile(graph: FrameGraph<'_>) -> Result<CompiledGraph<'_>, GraphError> {
    let FrameGraph {
        id: graph_id,
        resources,
        passes,
        errors,
        ..
    } = graph;
    if let Some(e) = errors.into_iter().next() {
        return Err(e);
    }
    validate(&resources, &passes)?;

    // Producer of each (resource, version) > 0.
    let mut producer: HashMap<(u32, u32), usize> = HashMap::new();
    // Consumers (reads, and the writer that continues it) of each version.
    let mut readers: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    let mut successor: HashMap<(u32, u32), usize> = HashMap::new();
    for (p, pass) in passes.iter().enumerate() {
        for w in &pass.writes {
            producer.insert((w.res, w.to), p);
            successor.insert((w.res, w.from), p);
        }
        for r in &pass.reads {
            readers.entry((r.res, r.version)).or_default().push(p);
        }
    }

    let order = topological_order(&passes, &producer, &readers, &successor)?;

    // Cull: walk back from outputs and side-effect passes.
    let mut needed: HashSet<(u32, u32)> = HashSet::new();
    for (i, r) in resources.iter().enumerate() {
        if r.output {
            needed.insert((i as u32, r.latest));
        }
    }
    let mut alive = vec![false; passes.len()];
    for &p in order.iter().rev() {
        let pass = &passes[p];
        let keep = pass.side_effect || pass.writes.iter().any(|w| needed.contains(&(w.res, w.to)));
        if keep {
            alive[p] = true;
            needed.extend(pass.reads.iter().map(|r| (r.res, r.version)));
            needed.extend(pass.writes.iter().map(|w| (w.res, w.from)));
        }
    }

    // Derived usages from live passes only.
    let mut usages: Vec<Usages> = resources
        .iter()
        .map(|r| match &r.kind {
            ResourceKind::Texture { .. } => Usages::Texture(wgpu::TextureUsages::empty()),
            ResourceKind::Buffer { .. } => Usages::Buffer(wgpu::BufferUsages::empty()),
        })
        .collect();
    for pass in passes
        .iter()
        .zip(&alive)
        .filter(|(_, a)| **a)
        .map(|(p, _)| p)
    {
        let uses = pass.reads.iter().map(|r| (r.res, r.access));
        for (res, access) in uses.chain(pass.writes.iter().map(|w| (w.res, w.access))) {
            match (&mut usages[res as usize], access) {
                (Usages::Texture(u), ResourceAccess::Texture(a)) => *u |= a.usage(),
                (Usages::Buffer(u), ResourceAccess::Buffer(a)) => *u |= a.usage(),
                _ => {} // kinds are checked when the access is declared
            }
        }
    }
    for (r, u) in resources.iter().zip(usages.iter_mut()) {
        if let (ResourceKind::Buffer { desc, .. }, Usages::Buffer(b)) = (&r.kind, &mut *u)
            && !b.is_empty()
        {
            *b |= desc.extra_usages;
        }
    }
    check_imported_usages(&resources, &usages)?;

    let mut compiled = Vec::new();
    let mut closures = Vec::new();
    let mut declared = Vec::new();
    let mut culled = Vec::new();
    let mut passes: Vec<_> = passes.into_iter().map(Some).collect();
    for &p in &order {
        let Some(pass) = passes[p].take() else {
            continue;
        };
        if !alive[p] {
            culled.push(pass.id);
            continue; // its closure is dropped unrun
        }
        let name = |res: u32| resources[res as usize].name.clone();
        let reads = pass.reads.iter().map(|r| ResourceUse {
            resource: name(r.res),
            version: r.version,
            access: r.access,
        });
        let writes = pass.writes.iter().map(|w| ResourceUse {
            resource: name(w.res),
            version: w.to,
            access: w.access,
        });
        let mut set: Vec<u32> = pass.reads.iter().map(|r| r.res).collect();
        set.extend(pass.writes.iter().map(|w| w.res));
        set.sort_unstable();
        set.dedup();
        compiled.push(CompiledPass {
            id: pass.id,
            reads: reads.collect(),
            writes: writes.collect(),
            side_effect: pass.side_effect,
        });
        declared.push(set);
        // Validation guarantees every pass has a closure.
        closures.extend(pass.exec);
    }

    let (plan, slot_of) = pool_plan(&resources, &usages, &declared);
    Ok(CompiledGraph {
        graph_id,
        resources,
        passes: compiled,
        closures,
        declared,
        culled,
        usages,
        slot_of,
        plan,
    })
}

/// Misuse checks, in declaration order.
fn validate(
    resources: &[Resource<'_>],
    passes: &[super::builder::PassDecl<'_>],
) -> Result<(), GraphError> {
    let mut ids = HashSet::new();
    for pass in passes {
        if !ids.insert(pass.id.as_str()) {
            return Err(GraphError::DuplicatePass(pass.id.clone()));
        }
        if pass.exec.is_none() {
            return Err(GraphError::MissingExecute(pass.id.clone()));
        }
        if let Some(e) = pass.errors.first() {
            return Err(e.clone());
        }
        for r in &pass.reads {
            let res = &resources[r.res as usize];
            if r.version == 0 && !res.is_imported() {
                return Err(GraphError::ReadBeforeWrite {
                    pass: pass.id.clone(),
                    resource: res.name.clone(),
                });
            }
        }
        for w in &pass.writes {
            if w.from != w.latest {
                return Err(GraphError::StaleVersion {
                    pass: pass.id.clone(),
                    resource: resources[w.res as usize].name.clone(),
                    used: w.from,
                    latest: w.latest,
                });
            }
        }
    }
    let mut names = HashSet::new();
    for r in resources {
        if !names.insert(r.name.as_str()) {
            return Err(GraphError::DuplicateResource(r.name.clone()));
        }
        if r.output && r.latest == 0 && !r.is_imported() {
            return Err(GraphError::ReadBeforeWrite {
                pass: "(output)".to_string(),
                resource: r.name.clone(),
            });
        }
    }
    Ok(())
}

/// Kahn's algorithm preferring declaration order. Edges: producer -> reader
/// (read after write) and reader -> next writer (write after read: a pass
/// reading an old version must run before that version is overwritten).
fn topological_order(
    passes: &[super::builder::PassDecl<'_>],
    producer: &HashMap<(u32, u32), usize>,
    readers: &HashMap<(u32, u32), Vec<usize>>,
    successor: &HashMap<(u32, u32), usize>,
) -> Result<Vec<usize>, GraphError> {
    let n = passes.len();
    let mut edges: Vec<HashSet<usize>> = vec![HashSet::new(); n];
    let add = |from: usize, to: usize, edges: &mut Vec<HashSet<usize>>| {
        if from != to {
            edges[from].insert(to);
        }
    };
    for (p, pass) in passes.iter().enumerate() {
        let inputs = pass.reads.iter().map(|r| (r.res, r.version));
        for key in inputs.chain(pass.writes.iter().map(|w| (w.res, w.from))) {
            if let Some(&q) = producer.get(&key) {
                add(q, p, &mut edges);
            }
        }
    }
    for (key, rs) in readers {
        if let Some(&w) = successor.get(key) {
            for &r in rs {
                add(r, w, &mut edges);
            }
        }
    }
    let mut indegree = vec![0usize; n];
    for e in &edges {
        for &t in e {
            indegree[t] += 1;
        }
    }
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..n).filter(|&p| indegree[p] == 0).map(Reverse).collect();
    let mut order = Vec::with_capacity(n);
    while let Some(Reverse(p)) = ready.pop() {
        order.push(p);
        for &t in &edges[p] {
            indegree[t] -= 1;
            if indegree[t] == 0 {
                ready.push(Reverse(t));
            }
        }
    }
    if order.len() != n {
        let stuck = (0..n)
            .filter(|p| indegree[*p] > 0)
            .map(|p| passes[p].id.clone());
        return Err(GraphError::Cycle(stuck.collect()));
    }
    Ok(order)
}

fn check_imported_usages(resources: &[Resource<'_>], usages: &[Usages]) -> Result<(), GraphError> {
    for (r, u) in resources.iter().zip(usages) {
        let (needed, available) = match (&r.kind, u) {
            (
                ResourceKind::Texture {
                    backing: Backing::Imported(Some(t)),
                    ..
                },
                Usages::Texture(u),
            ) => {
                if t.usage().contains(*u) {
                    continue;
                }
                (Usages::Texture(*u), Usages::Texture(t.usage()))
            }
            (
                ResourceKind::Buffer {
                    backing: Backing::Imported(Some(b)),
                    ..
                },
                Usages::Buffer(u),
            ) => {
                if b.usage().contains(*u) {
                    continue;
                }
                (Usages::Buffer(*u), Usages::Buffer(b.usage()))
            }
            _ => continue,
        };
        return Err(GraphError::ImportedUsage {
            resource: r.name.clone(),
            needed: needed.to_string(),
            available: available.to_string(),
        });
    }
    Ok(())
}

/// Lifetime-based slot assignment over execution positions.
fn pool_plan(
    resources: &[Resource<'_>],
    usages: &[Usages],
    declared: &[Vec<u32>],
) -> (PoolPlan, Vec<Option<usize>>) {
    let mut first = vec![usize::MAX; resources.len()];
    let mut last = vec![0usize; resources.len()];
    for (pos, set) in declared.iter().enumerate() {
        for &res in set {
            let res = res as usize;
            first[res] = first[res].min(pos);
            last[res] = pos;
        }
    }
    let end = declared.len();
    let mut plan = PoolPlan::default();
    let mut slot_of = vec![None; resources.len()];
    let mut free_tex: Vec<usize> = Vec::new();
    let mut free_buf: Vec<usize> = Vec::new();
    for pos in 0..end {
        for (i, r) in resources.iter().enumerate() {
            if first[i] != pos {
                continue;
            }
            let last_pass = if r.output { end - 1 } else { last[i] };
            match (&r.kind, usages[i]) {
                (
                    ResourceKind::Texture {
                        desc,
                        backing: Backing::Transient,
                    },
                    Usages::Texture(u),
                ) => {
                    let key = TextureKey {
                        width: desc.width,
                        height: desc.height,
                        depth_or_layers: desc.depth_or_layers,
                        mip_levels: desc.mip_levels,
                        format: desc.format,
                        dimension: desc.dimension,
                        usages: u,
                    };
                    let slot = take_slot(&mut free_tex, &mut plan.texture_slots, key);
                    slot_of[i] = Some(slot);
                    plan.textures.push(PoolAssignment {
                        resource: r.name.clone(),
                        slot,
                        first_pass: pos,
                        last_pass,
                    });
                }
                (
                    ResourceKind::Buffer {
                        desc,
                        backing: Backing::Transient,
                    },
                    Usages::Buffer(u),
                ) => {
                    let key = BufferKey {
                        size: desc.size,
                        usages: u,
                    };
                    let slot = take_slot(&mut free_buf, &mut plan.buffer_slots, key);
                    slot_of[i] = Some(slot);
                    plan.buffers.push(PoolAssignment {
                        resource: r.name.clone(),
                        slot,
                        first_pass: pos,
                        last_pass,
                    });
                }
                _ => {}
            }
        }
        // Release after the pass, so resources of one pass never share.
        for a in plan.textures.iter().filter(|a| a.last_pass == pos) {
            free_tex.push(a.slot);
        }
        for a in plan.buffers.iter().filter(|a| a.last_pass == pos) {
            free_buf.push(a.slot);
        }
    }
    (plan, slot_of)
}

/// Lowest free slot with this key, else a new slot.
fn take_slot<K: PartialEq>(free: &mut Vec<usize>, slots: &mut Vec<K>, key: K) -> usize {
    let best = free
        .iter()
        .enumerate()
        .filter(|(_, s)| slots[**s] == key)
        .min_by_key(|(_, s)| **s)
        .map(|(i, _)| i);
    match best {
        Some(i) => free.swap_remove(i),
        None => {
            slots.push(key);
            slots.len() - 1
        }
    }
}

impl CompiledGraph<'_> {
    /// Live passes in execution order.
    pub fn passes(&self) -> &[CompiledPass] {
        &self.passes
    }

    /// Ids of culled passes (their closures never run).
    pub fn culled(&self) -> &[String] {
        &self.culled
    }

    /// How the live transients map onto pool slots this frame.
    pub fn pool_plan(&self) -> &PoolPlan {
        &self.plan
    }

    fn usages_of(&self, name: &str) -> Option<Usages> {
        let i = self.resources.iter().position(|r| r.name == name)?;
        Some(self.usages[i])
    }

    /// Union of the live accesses to the named texture (empty if only
    /// culled passes use it); `None` for an unknown name or a buffer.
    pub fn texture_usages(&self, name: &str) -> Option<wgpu::TextureUsages> {
        match self.usages_of(name)? {
            Usages::Texture(u) => Some(u),
            Usages::Buffer(_) => None,
        }
    }

    /// Union of the live accesses to the named buffer (empty if only
    /// culled passes use it); `None` for an unknown name or a texture.
    pub fn buffer_usages(&self, name: &str) -> Option<wgpu::BufferUsages> {
        match self.usages_of(name)? {
            Usages::Buffer(u) => Some(u),
            Usages::Texture(_) => None,
        }
    }
}
