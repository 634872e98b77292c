// particles.sort (E4): each emitter's slots ordered far to near along the
// view direction, so premultiplied "over" composes back to front inside an
// emitter too. One workgroup per emitter, a bitonic sort in workgroup
// memory over the ring padded to a power of two (at most SORT_MAX slots;
// a larger ring keeps its ring order). Key: view depth, dead slots last;
// ties by slot, a strict order (the CPU twin gives the same permutation).
// Writes order[first + i] = the slot drawn i-th. SORT false: ring order.
// CPU twin: passes/particles/reference.rs `draw_order`.
#import particles
#import view

override SORT: bool = true;

const SORT_MAX: u32 = 1024u;
const THREADS: u32 = 256u;
// Key of a dead slot: below every depth.
const DEAD: f32 = -3.0e38;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> particles: array<Particle>;
@group(0) @binding(2) var<storage, read> emitters: array<ParticleEmitter>;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;

var<workgroup> keys: array<f32, SORT_MAX>;
var<workgroup> slots: array<u32, SORT_MAX>;

// a before b: farther first, then the lower slot.
fn before(ka: f32, sa: u32, kb: f32, sb: u32) -> bool {
    return ka > kb || (ka == kb && sa < sb);
}

@compute @workgroup_size(256)
fn cs_main(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_index) t: u32) {
    let e = emitters[wg.x];
    let first = e.slots.x;
    let cap = e.slots.y;
    if (!SORT || cap > SORT_MAX) {
        for (var i = t; i < cap; i += THREADS) {
            order[first + i] = first + i;
        }
        return;
    }
    var n = 1u;
    while (n < cap) {
        n *= 2u;
    }
    for (var i = t; i < n; i += THREADS) {
        var k = DEAD;
        if (i < cap) {
            let p = particles[first + i];
            if (p.vel_alive.w > 0.5) {
                k = dot(p.pos_age.xyz - view.camera_position.xyz, view.camera_forward.xyz);
            }
        }
        keys[i] = k;
        slots[i] = i;
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
    for (var i = t; i < cap; i += THREADS) {
        order[first + i] = first + slots[i];
    }
}
