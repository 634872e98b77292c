// cull (V6): per-instance frustum culling on the GPU for the camera and each
// sun cascade, writing the instance lists and indirect draw arguments that
// the G-buffer and shadow passes draw with multi-draw-indirect.
// Each kept object draws at its E2 level (triangle size; docs/techniques/E2.md).
// Three dispatches in one node, deterministic (no atomic order reaches memory):
//   cs_test  (chunk, view): which of a chunk's <= 64 objects the view keeps, per level -> masks
//   cs_args  (batch, view): each chunk's offset per list in its batch (a scan), the draws' arguments
//   cs_write (chunk, view): each kept object at offset + rank -> instances
// A batch is the consecutive objects of one mesh; chunks split a batch in 64s.
// Near a transition (the last `band` of a level's distance interval) an
// object is in two lists: fading out at its level and fading in at the next,
// with complementary screen-door masks (lod_dither_keep, shaders/scene.wgsl).
// Lists per batch: kind (steady, fade-out, fade-in) x level; one draw each.
// Arguments per view: opaque batches' [kind][batch][level], then vegetation's,
// so a pipeline draws a range of kinds with one multi-draw.
// instances[0 .. objects] is the identity (the pass's CPU-recorded draws, glTF
// materials); view v's lists of batch b start at objects + v * 2 objects +
// 2 b.first_object (an object is in at most two). An entry is the object
// (bits 0-23) and its fade code (bits 24-31, 0 steady).
// With Hi-Z occlusion (params.occlusion) view 0, the camera, also drops
// boxes hidden behind the previous frame's depth pyramid (shaders/hiz.wgsl).
// Twin: reference.rs; the test: docs/techniques/V6.md.

#import hiz

struct CullParams {
    views: u32,
    chunks: u32,
    batches: u32,
    objects: u32,
    opaque_batches: u32,
    // 1: Hi-Z occlusion of view 0 against hiz_load
    occlusion: u32,
    _pad1: u32,
    _pad2: u32,
    // xyz: the camera (LOD distances for every view), w: E2 distance scale
    // f / sqrt(T) (0: LOD0 everywhere)
    eye: vec4f,
    // x: transition band, a fraction of d1 (0: levels pop); y: focal length
    // (px); z: largest geometric error a level may show (px; 0: no guard);
    // w: object-size metric f / R (E2 comparison; 0: triangle size)
    lod: vec4f,
    // the view-projection the pyramid's depth was rendered with
    hiz_view_proj: mat4x4f,
}

// Six planes (xyz . p + w >= 0 inside); a disabled plane is (0, 0, 0, 1).
struct CullView {
    planes: array<vec4f, 6>,
}

// w of center: the object's triangle size (m), sqrt of its geometric-mean
// area; w of half_extent: its linear scale
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

const MAX_LODS: u32 = 5u;
// Lists per batch: 3 kinds x MAX_LODS levels.
const LISTS: u32 = 15u;
const STEADY: u32 = 0u;
const FADE_OUT: u32 = 1u;
const FADE_IN: u32 = 2u;

struct Batch {
    first_chunk: u32,
    chunks: u32,
    first_object: u32,
    lods: u32,
    base_vertex: i32,
    // culled beyond this distance from the LOD eye (m; 0: no limit)
    max_distance: f32,
    _pad1: u32,
    _pad2: u32,
    // per level: first index, index count
    lod: array<vec2u, 5>,
    // per level: geometric error (mesh units)
    error: array<f32, 5>,
    _pad3: u32,
}

// Per (view, chunk) and list (kind * MAX_LODS + level): kept bits (0-31,
// 32-63), count, and offset in the batch's lists.
struct ChunkMask {
    bits: array<vec2u, 15>,
    count: array<u32, 15>,
    offset: array<u32, 15>,
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
// The previous frame's min-depth pyramid (a 1x1 fallback when occlusion is off).
@group(0) @binding(8) var hiz_load: texture_2d<f32>;

// Hi-Z occlusion: the camera's view only (cascades cast from what the
// camera cannot see; static tiles and sky occlusion are other views).
fn occluded(b: Bounds, view: u32) -> bool {
    return view == 0u && params.occlusion != 0u
        && hiz_occluded(hiz_load, params.hiz_view_proj, b.center.xyz, b.half_extent.xyz);
}

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

// E2 (scene/lod.rs `choice`, the same steps): x the level, y the fade t in
// [0, 1) toward the next level in the band before it, -1 steady. Level l
// takes over at S_l = max(l d1, e_l s f / E): multiples of d1 = size *
// scale, and no level whose error e_l (times the object's scale s) would
// show more than E pixels.
fn switch_distance(b: Bounds, batch: Batch, l: u32, d1: f32) -> f32 {
    var guard = 0.0;
    if (params.lod.z > 0.0) {
        guard = batch.error[l] * b.half_extent.w * params.lod.y / params.lod.z;
    }
    return max(f32(l) * d1, guard);
}

// The box's distance from the LOD eye (the camera, for every view).
fn eye_distance(b: Bounds) -> f32 {
    return length(max(abs(params.eye.xyz - b.center.xyz) - b.half_extent.xyz, vec3f(0.0)));
}

// Per-class distance culling: beyond the batch's max_distance.
fn too_far(b: Bounds, batch: Batch) -> bool {
    return batch.max_distance > 0.0 && eye_distance(b) > batch.max_distance;
}

fn lod_choice(b: Bounds, batch: Batch) -> vec2f {
    // d_1: triangle size x scale, or (E2 comparison) radius x object scale
    var d1 = b.center.w * params.eye.w;
    if (params.lod.w > 0.0) {
        d1 = length(b.half_extent.xyz) * params.lod.w;
    }
    let levels = min(batch.lods, MAX_LODS);
    if (levels <= 1u || d1 <= 0.0) {
        return vec2f(0.0, -1.0);
    }
    let d = eye_distance(b);
    var l = 0u;
    while (l + 1u < levels && d >= switch_distance(b, batch, l + 1u, d1)) {
        l += 1u;
    }
    let band = params.lod.x;
    if (band > 0.0 && l + 1u < levels) {
        let start = switch_distance(b, batch, l + 1u, d1) - band * d1;
        if (d > start) {
            return vec2f(f32(l), (d - start) / (band * d1));
        }
    }
    return vec2f(f32(l), -1.0);
}

// The fade step (0..126) of t: codes 1 + q (out) and 128 + q (in).
fn fade_step(t: f32) -> u32 {
    return min(u32(t * 127.0), 126u);
}

// Index of the arguments of (batch, kind, level) in view `view`: per view
// the opaque batches' then the vegetation batches', each [kind][level][batch],
// so one level (or a run of levels) of every batch is one multi-draw.
fn args_index(view: u32, batch: u32, kind: u32, level: u32) -> u32 {
    let opaque = params.opaque_batches;
    var i = (kind * MAX_LODS + level) * opaque + batch;
    if (batch >= opaque) {
        let vegetation = params.batches - opaque;
        i = LISTS * opaque + (kind * MAX_LODS + level) * vegetation + batch - opaque;
    }
    return view * params.batches * LISTS + i;
}

var<workgroup> kept: array<atomic<u32>, 30>;

@compute @workgroup_size(64)
fn cs_test(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) i: u32) {
    let chunk = chunks[wg.x];
    let view = wg.y;
    if (i < 2u * LISTS) {
        atomicStore(&kept[i], 0u);
    }
    workgroupBarrier();
    if (i < chunk.count) {
        let b = bounds[chunk.first_object + i];
        let batch = batches[chunk.batch];
        if (!outside(b, views[view]) && !too_far(b, batch) && !occluded(b, view)) {
            let c = lod_choice(b, batch);
            let l = u32(c.x);
            let bit = 1u << (i % 32u);
            if (c.y < 0.0) {
                atomicOr(&kept[(STEADY * MAX_LODS + l) * 2u + i / 32u], bit);
            } else {
                atomicOr(&kept[(FADE_OUT * MAX_LODS + l) * 2u + i / 32u], bit);
                atomicOr(&kept[(FADE_IN * MAX_LODS + l + 1u) * 2u + i / 32u], bit);
            }
        }
    }
    workgroupBarrier();
    if (i == 0u) {
        var m: ChunkMask;
        for (var k = 0u; k < LISTS; k++) {
            m.bits[k] = vec2u(atomicLoad(&kept[k * 2u]), atomicLoad(&kept[k * 2u + 1u]));
            m.count[k] = countOneBits(m.bits[k].x) + countOneBits(m.bits[k].y);
            m.offset[k] = 0u;
        }
        masks[view * params.chunks + wg.x] = m;
    }
}

// cs_args: one workgroup per (batch, view). The lists' offsets over the
// batch's chunks are a scan: totals first (strided sums, then a reduction),
// then blocks of 64 chunks, each an inclusive Hillis-Steele scan added to the
// running offsets, so a batch of 100,000 objects is not one thread's loop.
var<workgroup> scan: array<array<u32, 15>, 64>;
var<workgroup> totals: array<u32, 15>;
var<workgroup> base: array<u32, 15>;
var<workgroup> running: array<u32, 15>;
var<workgroup> batch_chunks: u32;

@compute @workgroup_size(64)
fn cs_args(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) t: u32) {
    let view = wg.y;
    let batch = batches[wg.x];
    let first = view * params.chunks + batch.first_chunk;
    if (t == 0u) {
        batch_chunks = batch.chunks;
    }
    let n = workgroupUniformLoad(&batch_chunks);
    // Each list's total.
    var sum: array<u32, 15>;
    for (var k = t; k < n; k += 64u) {
        let count = masks[first + k].count;
        for (var j = 0u; j < LISTS; j++) {
            sum[j] += count[j];
        }
    }
    scan[t] = sum;
    workgroupBarrier();
    if (t < LISTS) {
        var total = 0u;
        for (var i = 0u; i < 64u; i++) {
            total += scan[i][t];
        }
        totals[t] = total;
    }
    workgroupBarrier();
    // The lists one after the other in the batch's region.
    if (t == 0u) {
        var at = 0u;
        for (var j = 0u; j < LISTS; j++) {
            base[j] = at;
            running[j] = at;
            at += totals[j];
        }
    }
    workgroupBarrier();
    if (t < LISTS) {
        let level = t % MAX_LODS;
        let region = params.objects + view * 2u * params.objects + 2u * batch.first_object;
        var a: DrawArgs;
        a.index_count = batch.lod[level].y;
        a.instance_count = totals[t];
        a.first_index = batch.lod[level].x;
        a.base_vertex = batch.base_vertex;
        a.first_instance = region + base[t];
        args[args_index(view, wg.x, t / MAX_LODS, level)] = a;
    }
    // Each chunk's offset per list.
    for (var block = 0u; block < n; block += 64u) {
        let k = block + t;
        var own: array<u32, 15>;
        if (k < n) {
            own = masks[first + k].count;
        }
        scan[t] = own;
        workgroupBarrier();
        for (var step = 1u; step < 64u; step <<= 1u) {
            var v = scan[t];
            if (t >= step) {
                let o = scan[t - step];
                for (var j = 0u; j < LISTS; j++) {
                    v[j] += o[j];
                }
            }
            workgroupBarrier();
            scan[t] = v;
            workgroupBarrier();
        }
        if (k < n) {
            var offset: array<u32, 15>;
            for (var j = 0u; j < LISTS; j++) {
                offset[j] = running[j] + scan[t][j] - own[j];
            }
            masks[first + k].offset = offset;
        }
        workgroupBarrier();
        if (t < LISTS) {
            running[t] += scan[63][t];
        }
        workgroupBarrier();
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
    let batch = batches[chunk.batch];
    let region = params.objects + view * 2u * params.objects + 2u * batch.first_object;
    let bit = i % 32u;
    // The fade code, recomputed exactly as cs_test chose the lists.
    let c = lod_choice(bounds[chunk.first_object + i], batch);
    var q = 0u;
    if (c.y >= 0.0) {
        q = fade_step(c.y);
    }
    for (var k = 0u; k < LISTS; k++) {
        let word = select(m.bits[k].x, m.bits[k].y, i >= 32u);
        if (((word >> bit) & 1u) == 0u) {
            continue;
        }
        // Rank among the chunk's objects in this list: the bits below i.
        var rank = countOneBits(word & ((1u << bit) - 1u));
        if (i >= 32u) {
            rank += countOneBits(m.bits[k].x);
        }
        var code = 0u;
        if (k / MAX_LODS == FADE_OUT) {
            code = 1u + q;
        } else if (k / MAX_LODS == FADE_IN) {
            code = 128u + q;
        }
        instances[region + m.offset[k] + rank] = (chunk.first_object + i) | (code << 24u);
    }
}
