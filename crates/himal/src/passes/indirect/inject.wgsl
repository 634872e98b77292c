// probes.inject (L5): each texel of the camera-centred 32 x 32 x 5 clip
// map takes its probe: cascade c's texels are mip c's probes; where mip c's
// cell is not resident, the nearest probe of the next coarser (then finer)
// resident mip. Three textures hold the r, g, b channels' SH2.
// CPU twin: passes/indirect/reference.rs `ClipMap::inject`.
#import indirect

@group(0) @binding(0) var<storage, read> params: IndirectParams;
// Per-mip page tables, one byte per cell (255: not resident), packed in words.
@group(0) @binding(1) var<storage, read> tables: array<u32>;
@group(0) @binding(2) var<storage, read> sh_probes: array<vec4f>;
@group(0) @binding(3) var clip_r: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(4) var clip_g: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(5) var clip_b: texture_storage_2d_array<rgba16float, write>;

// The pool slot of the cell of mip m holding global probe index g (mip m's
// grid), or -1.
fn slot_of(m: i32, g: vec2i) -> i32 {
    let n = params.tables[m].x;
    let cell = vec2i(g.x >> 3u, g.y >> 3u);
    if (any(g < vec2i(0)) || any(cell >= vec2i(n))) {
        return -1;
    }
    let byte = u32(params.tables[m].y + cell.y * n + cell.x);
    let e = (tables[byte / 4u] >> ((byte % 4u) * 8u)) & 0xffu;
    return select(i32(e), -1, e == 0xffu);
}

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let c = i32(id.z);
    let t = vec2i(id.xy);
    if (any(t >= vec2i(INDIRECT_CLIP_RES)) || c >= INDIRECT_CASCADES) {
        return;
    }
    let g = params.base[c].xy + t;
    // The texel centre in metres from the grid origin.
    let x = (vec2f(g) + 0.5) * indirect_texel_size(c);
    var sh = array<vec4f, 3>(vec4f(0.0), vec4f(0.0), vec4f(0.0));
    for (var k = 0; k < INDIRECT_CASCADES; k++) {
        // Search order: c, c + 1, ..., 4, then c - 1, ..., 0.
        var m = c + k;
        if (m >= INDIRECT_CASCADES) {
            m = INDIRECT_CASCADES - 1 - k;
        }
        let gm = vec2i(floor(x / indirect_texel_size(m)));
        let slot = slot_of(m, gm);
        if (slot >= 0) {
            let probe = u32(slot) * 64u + u32((gm.y & 7) * 8 + (gm.x & 7));
            sh = array<vec4f, 3>(sh_probes[probe * 3u], sh_probes[probe * 3u + 1u], sh_probes[probe * 3u + 2u]);
            break;
        }
    }
    textureStore(clip_r, t, c, sh[0]);
    textureStore(clip_g, t, c, sh[1]);
    textureStore(clip_b, t, c, sh[2]);
}
