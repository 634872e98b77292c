// cull (V6): per-instance frustum culling on the GPU for the camera and each
// sun cascade, writing the instance lists and indirect draw arguments that
// the G-buffer and shadow passes draw with multi-draw-indirect.
// Each kept object draws at its E2 level (triangle size; docs/techniques/E2.md).
// Three dispatches in one node, deterministic (no atomic order reaches memory):
//   cs_test  (chunk, view): which of a chunk's <= 64 objects the view keeps, per level -> masks
//   cs_args  (batch, view): each chunk's offset per level in its batch, the draws' arguments
//   cs_write (chunk, view): each kept object at offset + rank -> instances
// A batch is the consecutive objects of one mesh; chunks split a batch in 64s.
// A batch's list holds its levels one after the other; one draw per (batch, level).
// instances[0 .. objects] is the identity (the pass's CPU-recorded draws, glTF
// materials); view v's list of batch b starts at (v + 1) * objects + b.first_object.
// Twin: reference.rs; the test: docs/techniques/V6.md.

struct CullParams {
    views: u32,
    chunks: u32,
    batches: u32,
    objects: u32,
    // xyz: the camera (LOD distances for every view), w: E2 distance scale
    // f / sqrt(T) (0: LOD0 everywhere)
    eye: vec4f,
}

// Six planes (xyz . p + w >= 0 inside); a disabled plane is (0, 0, 0, 1).
struct CullView {
    planes: array<vec4f, 6>,
}

// w of center: the object's triangle size (m), sqrt of its geometric-mean area
struct Bounds {
    center: vec4f,
    half_extent: vec4f,
}

struct Chunk {
    batch: u32,
    first_object: u32,
    count: u32,
    _pad: u32,
}

const MAX_LODS: u32 = 4u;

struct Batch {
    first_chunk: u32,
    chunks: u32,
    first_object: u32,
    lods: u32,
    base_vertex: i32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
    // per level: first index, index count
    lod: array<vec2u, 4>,
}

// Per (view, chunk): kept bits per level (0-31, 32-63), count and offset in
// the batch's list per level.
struct ChunkMask {
    bits: array<vec2u, 4>,
    count: vec4u,
    offset: vec4u,
}

// wgpu::util::DrawIndexedIndirectArgs
struct DrawArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

@group(0) @binding(0) var<uniform> params: CullParams;
@group(0) @binding(1) var<storage, read> views: array<CullView>;
@group(0) @binding(2) var<storage, read> bounds: array<Bounds>;
@group(0) @binding(3) var<storage, read> chunks: array<Chunk>;
@group(0) @binding(4) var<storage, read> batches: array<Batch>;
@group(0) @binding(5) var<storage, read_write> masks: array<ChunkMask>;
@group(0) @binding(6) var<storage, read_write> args: array<DrawArgs>;
@group(0) @binding(7) var<storage, read_write> instances: array<u32>;

const CHUNK: u32 = 64u;

// The box is wholly outside a plane when even its farthest corner along the
// plane's normal is: dot(n, c) + w + dot(|n|, e) < 0 (exactly the eight-corner test).
fn outside(b: Bounds, v: CullView) -> bool {
    for (var i = 0u; i < 6u; i++) {
        let p = v.planes[i];
        if (dot(p.xyz, b.center.xyz) + p.w + dot(abs(p.xyz), b.half_extent.xyz) < 0.0) {
            return true;
        }
    }
    return false;
}

// E2: floor(d / d1), d1 = size * scale, clamped to the batch's levels
// (scene/lod.rs `level`); d from the eye to the box.
fn lod_level(b: Bounds, levels: u32) -> u32 {
    let d1 = b.center.w * params.eye.w;
    if (levels <= 1u || d1 <= 0.0) {
        return 0u;
    }
    let d = length(max(abs(params.eye.xyz - b.center.xyz) - b.half_extent.xyz, vec3f(0.0)));
    let l = floor(d / d1);
    if (l >= f32(levels - 1u)) {
        return levels - 1u;
    }
    return u32(max(l, 0.0));
}

var<workgroup> kept: array<atomic<u32>, 8>;

@compute @workgroup_size(64)
fn cs_test(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) i: u32) {
    let chunk = chunks[wg.x];
    let view = wg.y;
    if (i < 8u) {
        atomicStore(&kept[i], 0u);
    }
    workgroupBarrier();
    if (i < chunk.count) {
        let b = bounds[chunk.first_object + i];
        if (!outside(b, views[view])) {
            let l = lod_level(b, batches[chunk.batch].lods);
            atomicOr(&kept[l * 2u + i / 32u], 1u << (i % 32u));
        }
    }
    workgroupBarrier();
    if (i == 0u) {
        var m: ChunkMask;
        for (var l = 0u; l < MAX_LODS; l++) {
            m.bits[l] = vec2u(atomicLoad(&kept[l * 2u]), atomicLoad(&kept[l * 2u + 1u]));
            m.count[l] = countOneBits(m.bits[l].x) + countOneBits(m.bits[l].y);
        }
        masks[view * params.chunks + wg.x] = m;
    }
}

@compute @workgroup_size(64)
fn cs_args(@builtin(global_invocation_id) id: vec3u) {
    let view = id.y;
    if (id.x >= params.batches) {
        return;
    }
    let batch = batches[id.x];
    // Each level's total, then its place after the lower levels.
    var total = vec4u(0u);
    for (var k = 0u; k < batch.chunks; k++) {
        total += masks[view * params.chunks + batch.first_chunk + k].count;
    }
    let base = vec4u(0u, total.x, total.x + total.y, total.x + total.y + total.z);
    var offset = base;
    for (var k = 0u; k < batch.chunks; k++) {
        let m = view * params.chunks + batch.first_chunk + k;
        masks[m].offset = offset;
        offset += masks[m].count;
    }
    for (var l = 0u; l < MAX_LODS; l++) {
        var a: DrawArgs;
        a.index_count = batch.lod[l].y;
        a.instance_count = total[l];
        a.first_index = batch.lod[l].x;
        a.base_vertex = batch.base_vertex;
        a.first_instance = (view + 1u) * params.objects + batch.first_object + base[l];
        args[(view * params.batches + id.x) * MAX_LODS + l] = a;
    }
}

@compute @workgroup_size(64)
fn cs_write(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) i: u32) {
    let chunk = chunks[wg.x];
    let view = wg.y;
    if (i >= chunk.count) {
        return;
    }
    let m = masks[view * params.chunks + wg.x];
    let bit = i % 32u;
    for (var l = 0u; l < MAX_LODS; l++) {
        let word = select(m.bits[l].x, m.bits[l].y, i >= 32u);
        if (((word >> bit) & 1u) == 0u) {
            continue;
        }
        // Rank among the chunk's objects kept at this level: the bits below i.
        var rank = countOneBits(word & ((1u << bit) - 1u));
        if (i >= 32u) {
            rank += countOneBits(m.bits[l].x);
        }
        let batch = batches[chunk.batch];
        let slot = (view + 1u) * params.objects + batch.first_object + m.offset[l] + rank;
        instances[slot] = chunk.first_object + i;
    }
}
