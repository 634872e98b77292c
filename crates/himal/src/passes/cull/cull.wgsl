// cull (V6): per-instance frustum culling on the GPU for the camera and each
// sun cascade, writing the instance lists and indirect draw arguments that
// the G-buffer and shadow passes draw with multi-draw-indirect.
// Three dispatches in one node, deterministic (no atomic order reaches memory):
//   cs_test  (chunk, view): which of a chunk's <= 64 objects the view keeps -> masks
//   cs_args  (batch, view): each chunk's offset in its batch, the draw's arguments
//   cs_write (chunk, view): each kept object at offset + rank -> instances
// A batch is the consecutive objects of one mesh; chunks split a batch in 64s.
// instances[0 .. objects] is the identity (the pass's CPU-recorded draws, glTF
// materials); view v's list of batch b starts at (v + 1) * objects + b.first_object.
// Twin: reference.rs; the test: docs/techniques/V6.md.

struct CullParams {
    views: u32,
    chunks: u32,
    batches: u32,
    objects: u32,
}

// Six planes (xyz . p + w >= 0 inside); a disabled plane is (0, 0, 0, 1).
struct CullView {
    planes: array<vec4f, 6>,
}

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

struct Batch {
    first_chunk: u32,
    chunks: u32,
    first_object: u32,
    index_count: u32,
    first_index: u32,
    base_vertex: i32,
    _pad0: u32,
    _pad1: u32,
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
// Per (view, chunk): kept bits 0-31, 32-63, kept count, offset in the batch.
@group(0) @binding(5) var<storage, read_write> masks: array<vec4u>;
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

var<workgroup> kept: array<atomic<u32>, 2>;

@compute @workgroup_size(64)
fn cs_test(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) i: u32) {
    let chunk = chunks[wg.x];
    let view = wg.y;
    if (i < 2u) {
        atomicStore(&kept[i], 0u);
    }
    workgroupBarrier();
    if (i < chunk.count && !outside(bounds[chunk.first_object + i], views[view])) {
        atomicOr(&kept[i / 32u], 1u << (i % 32u));
    }
    workgroupBarrier();
    if (i == 0u) {
        let lo = atomicLoad(&kept[0]);
        let hi = atomicLoad(&kept[1]);
        masks[view * params.chunks + wg.x] = vec4u(lo, hi, countOneBits(lo) + countOneBits(hi), 0u);
    }
}

@compute @workgroup_size(64)
fn cs_args(@builtin(global_invocation_id) id: vec3u) {
    let view = id.y;
    if (id.x >= params.batches) {
        return;
    }
    let batch = batches[id.x];
    var offset = 0u;
    for (var k = 0u; k < batch.chunks; k++) {
        let m = view * params.chunks + batch.first_chunk + k;
        masks[m].w = offset;
        offset += masks[m].z;
    }
    var a: DrawArgs;
    a.index_count = batch.index_count;
    a.instance_count = offset;
    a.first_index = batch.first_index;
    a.base_vertex = batch.base_vertex;
    a.first_instance = (view + 1u) * params.objects + batch.first_object;
    args[view * params.batches + id.x] = a;
}

@compute @workgroup_size(64)
fn cs_write(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) i: u32) {
    let chunk = chunks[wg.x];
    let view = wg.y;
    let m = masks[view * params.chunks + wg.x];
    let word = select(m.x, m.y, i >= 32u);
    let bit = i % 32u;
    if (i >= chunk.count || ((word >> bit) & 1u) == 0u) {
        return;
    }
    // Rank among the kept objects of this chunk: the kept bits below i.
    var rank = countOneBits(word & ((1u << bit) - 1u));
    if (i >= 32u) {
        rank += countOneBits(m.x);
    }
    let batch = batches[chunk.batch];
    instances[(view + 1u) * params.objects + batch.first_object + m.w + rank] = chunk.first_object + i;
}
