// particles.sort (E4): each emitter's slots ordered far to near along the
// view direction, so premultiplied "over" composes back to front inside an
// emitter too. Key: view depth, dead slots last; ties by slot, a strict
// order (the CPU twin gives the same permutation). Two dispatches:
//   cs_chunks: one workgroup per CHUNK slots of a ring (workgroup x: chunk,
//     y: emitter) sorts them in workgroup memory (bitonic, padded to a
//     power of two) into `sorted`;
//   cs_merge: one thread per slot finds its rank in the whole ring, its
//     index in its chunk plus, per other chunk, how many of that chunk's
//     keys come before it (a binary search: the order is strict, so ranks
//     are unique), and writes order[first + rank] = the slot.
// O(n log CHUNK + n (n / CHUNK) log CHUNK) work, two dispatches at any ring
// length (rings hold at most 65536 slots). SORT false: ring order.
// CPU twin: passes/particles/reference.rs `draw_order`.
#import particles
#import view

override SORT: bool = true;

const CHUNK: u32 = 1024u;
const THREADS: u32 = 256u;
// Key of a dead slot: below every depth.
const DEAD: f32 = -3.0e38;

// A key and its ring index.
struct SortKey {
    k: f32,
    slot: u32,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> particles: array<Particle>;
@group(0) @binding(2) var<storage, read> emitters: array<ParticleEmitter>;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;
// Each chunk's keys sorted (cs_chunks), at the chunk's slots.
@group(0) @binding(4) var<storage, read_write> sorted: array<SortKey>;

var<workgroup> keys: array<f32, CHUNK>;
var<workgroup> slots: array<u32, CHUNK>;

// a before b: farther first, then the lower slot.
fn before(ka: f32, sa: u32, kb: f32, sb: u32) -> bool {
    return ka > kb || (ka == kb && sa < sb);
}

@compute @workgroup_size(256)
fn cs_chunks(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) t: u32) {
    let e = emitters[wg.y];
    let first = e.slots.x;
    let cap = e.slots.y;
    let start = wg.x * CHUNK;
    if (start >= cap) {
        return;
    }
    let len = min(CHUNK, cap - start);
    if (!SORT) {
        for (var i = t; i < len; i += THREADS) {
            order[first + start + i] = first + start + i;
        }
        return;
    }
    var n = 1u;
    while (n < len) {
        n *= 2u;
    }
    for (var i = t; i < n; i += THREADS) {
        // Padding sorts after every slot: dead, and a slot index past the chunk.
        var k = DEAD;
        let r = start + i;
        if (i < len) {
            let p = particles[first + r];
            if (p.vel_alive.w > 0.5) {
                k = dot(p.pos_age.xyz - view.camera_position.xyz, view.camera_forward.xyz);
            }
        }
        keys[i] = k;
        slots[i] = r;
    }
    workgroupBarrier();
    for (var size = 2u; size <= n; size *= 2u) {
        for (var stride = size / 2u; stride > 0u; stride /= 2u) {
            for (var i = t; i < n; i += THREADS) {
                let j = i ^ stride;
                if (j > i) {
                    // Blocks of `size` alternate direction; the last is ascending in `before`.
                    let forward = (i & size) == 0u;
                    let swap = before(keys[j], slots[j], keys[i], slots[i]) == forward;
                    if (swap) {
                        let k = keys[i];
                        keys[i] = keys[j];
                        keys[j] = k;
                        let s = slots[i];
                        slots[i] = slots[j];
                        slots[j] = s;
                    }
                }
            }
            workgroupBarrier();
        }
    }
    for (var i = t; i < len; i += THREADS) {
        sorted[first + start + i] = SortKey(keys[i], slots[i]);
    }
}

@compute @workgroup_size(256)
fn cs_merge(@builtin(global_invocation_id) id: vec3u) {
    let e = emitters[id.y];
    let first = e.slots.x;
    let cap = e.slots.y;
    let i = id.x;
    if (!SORT || i >= cap) {
        return;
    }
    let me = sorted[first + i];
    let own = i / CHUNK;
    var rank = i - own * CHUNK;
    for (var c = 0u; c * CHUNK < cap; c++) {
        if (c == own) {
            continue;
        }
        // Keys of chunk c before `me`: the first index that is not.
        var lo = c * CHUNK;
        var hi = min(lo + CHUNK, cap);
        let base = lo;
        while (lo < hi) {
            let mid = (lo + hi) / 2u;
            let x = sorted[first + mid];
            if (before(x.k, x.slot, me.k, me.slot)) {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        rank += lo - base;
    }
    order[first + rank] = first + me.slot;
}
