// probes.inject (L5): each texel of the camera-centred 32 x 32 x 5 clip
// map takes its probe through the combined page table (the talk's): the
// finest resident cell over the texel centre's sector, and in it the probe
// nearest the centre. Cascade c's texels are mip c's probes, so where mip c
// is the finest resident this is a copy. Three textures hold the r, g, b
// channels' SH2; a texel with no cell takes the flat ground's SH2. CPU twin: passes/indirect/reference.rs `ClipMap::inject`.
#import indirect

@group(0) @binding(0) var<storage, read> params: IndirectParams;
// The combined page table: one byte per sector (slot, 255: none), packed in words.
@group(0) @binding(1) var<storage, read> table: array<u32>;
@group(0) @binding(2) var<storage, read> sh_probes: array<vec4f>;
@group(0) @binding(3) var clip_r: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(4) var clip_g: texture_storage_2d_array<rgba16float, write>;
@group(0) @binding(5) var clip_b: texture_storage_2d_array<rgba16float, write>;

// The pool slot of the finest resident cell over sector s, or -1.
fn slot_of(s: vec2i) -> i32 {
    let n = params.grid.x;
    if (any(s < vec2i(0)) || any(s >= vec2i(n))) {
        return -1;
    }
    let byte = u32(s.y * n + s.x);
    let e = (table[byte / 4u] >> ((byte % 4u) * 8u)) & 0xffu;
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
    // No baked cell: the flat ground bounce, as before L5.
    var sh = params.fallback;
    let slot = slot_of(vec2i(floor(x / (INDIRECT_SPACING * 8.0))));
    if (slot >= 0) {
        // Slots are per mip, 16 each: the slot names the cell's mip.
        let m = slot / 16;
        let gm = vec2i(floor(x / indirect_texel_size(m)));
        let probe = u32(slot) * 64u + u32((gm.y & 7) * 8 + (gm.x & 7));
        sh = array<vec4f, 3>(sh_probes[probe * 3u], sh_probes[probe * 3u + 1u], sh_probes[probe * 3u + 2u]);
    }
    textureStore(clip_r, t, c, sh[0]);
    textureStore(clip_g, t, c, sh[1]);
    textureStore(clip_b, t, c, sh[2]);
}
