// shadows.mask_tiles (#23): for each 16 x 16 tile of the mask, the state of
// every map its pixels read (slot 0 the sun's cascade or static map, slot
// 1 + k shadowed local light k < 63): lit or shadowed over the whole tile
// (shadows.mask then takes no tap of it), else filter per pixel. Each map in
// turn: the tile's lookups (the mask's receiver and lookup functions) are
// binned by texel into a grid over the tile's footprint, each cell keeping
// the largest and smallest compare depth landing in it; both are spread
// over the taps' reach (shadow_tile_reach) and every texel compared with
// them: lit when each texel any tap of a pixel reads holds a depth at or
// behind that pixel's compare depth (so every tap passes; a thin occluder
// is such a texel and cannot be missed), shadowed when each is in front.
// CPU twin: passes/shadows/reference.rs `tile_state`.
#import view
#import tangent_frame
#import shadow
#import shadow_receiver

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> params: ShadowMaskParams;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(4) var cascades: texture_depth_2d_array;
@group(0) @binding(5) var static_map: texture_depth_2d_array;
@group(0) @binding(6) var atlas: texture_depth_2d_array;
@group(0) @binding(7) var<storage, read> local_lights: LocalLights;
@group(0) @binding(8) var<storage, read> light_tiles: array<ShadowTile>;
@group(0) @binding(9) var<storage, read_write> tile_states: array<vec4u>;

const GRID = SHADOW_TILE_MAX_TEXELS * SHADOW_TILE_MAX_TEXELS;

// Per map: lookups inside, pixels not sky, smallest and largest map index
// (cascade or atlas tile), the lookups' texel rectangle, texels failing
// lit / shadowed; per grid cell the largest (hi) and smallest (lo) compare
// depth as order-preserving keys, then spread along x.
var<workgroup> inside_n: atomic<u32>;
var<workgroup> valid_n: atomic<u32>;
var<workgroup> map_range: array<atomic<u32>, 2>;
var<workgroup> cells: array<atomic<i32>, 4>;
var<workgroup> fails: array<atomic<u32>, 2>;
var<workgroup> hi: array<atomic<u32>, GRID>;
var<workgroup> lo: array<atomic<u32>, GRID>;
var<workgroup> hi_x: array<u32, GRID>;
var<workgroup> lo_x: array<u32, GRID>;

// Order-preserving u32 key of an f32 (atomicMin / atomicMax of any sign).
fn key(x: f32) -> u32 {
    let b = bitcast<u32>(x);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn unkey(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

@compute @workgroup_size(16, 16)
fn cs_main(@builtin(workgroup_id) wg: vec3u, @builtin(local_invocation_id) lid: vec3u,
           @builtin(local_invocation_index) li: u32) {
    let size = textureDimensions(depth);
    let px = wg.xy * SHADOW_TILE + lid.xy;
    var valid = false;
    var r: Receiver;
    if (all(px < size)) {
        let d = textureLoad(depth, vec2i(px), 0);
        if (d > 0.0) {
            valid = true;
            r = shadow_receiver(view, params, vec2f(px) + 0.5, d, textureLoad(gbuffer_frame, vec2i(px), 0));
        }
    }
    let atlas_size = vec2i(textureDimensions(atlas));
    let reach = shadow_tile_reach(params.filter_params.x);
    let n_lights = min(local_lights.count.x, 63u);
    var out = vec4u(0u);
    for (var slot = 0u; slot <= n_lights; slot = slot + 1u) {
        if (slot > 0u && u32(local_lights.lights[slot - 1u].params.y) == 0u) {
            continue;
        }
        if (li == 0u) {
            atomicStore(&inside_n, 0u);
            atomicStore(&valid_n, 0u);
            atomicStore(&map_range[0], 0xffffffffu);
            atomicStore(&map_range[1], 0u);
            atomicStore(&cells[0], 0x7fffffff);
            atomicStore(&cells[1], 0x7fffffff);
            atomicStore(&cells[2], -0x7fffffff);
            atomicStore(&cells[3], -0x7fffffff);
            atomicStore(&fails[0], 0u);
            atomicStore(&fails[1], 0u);
        }
        for (var i = li; i < u32(GRID); i += 256u) {
            atomicStore(&hi[i], 0u);
            atomicStore(&lo[i], 0xffffffffu);
        }
        workgroupBarrier();
        // This pixel's lookup and its texel (the one holding its uv).
        var l: ShadowLookup;
        l.inside = false;
        var map = -1;
        var dims = atlas_size;
        if (valid) {
            atomicAdd(&valid_n, 1u);
            if (slot == 0u) {
                map = shadow_map_index(params, r.dist);
                if (map >= 0) {
                    l = shadow_world_lookup(params, map, r.p, r.n);
                }
            } else {
                let light = local_lights.lights[slot - 1u];
                map = shadow_local_tile(light, r.p);
                if (map >= 0) {
                    l = shadow_local_lookup(light, light_tiles[map], r.p, r.n, vec2f(atlas_size));
                }
            }
        }
        if (slot == 0u) {
            dims = select(vec2i(textureDimensions(cascades)), vec2i(textureDimensions(static_map)), map == 4);
        }
        let mine = map >= 0 && l.inside;
        let cell = vec2i(floor(l.uv * vec2f(dims)));
        if (mine) {
            atomicAdd(&inside_n, 1u);
            atomicMin(&map_range[0], u32(map));
            atomicMax(&map_range[1], u32(map));
            atomicMin(&cells[0], cell.x);
            atomicMin(&cells[1], cell.y);
            atomicMax(&cells[2], cell.x);
            atomicMax(&cells[3], cell.y);
        }
        workgroupBarrier();
        let inside = atomicLoad(&inside_n);
        let one_map = atomicLoad(&map_range[0]) == atomicLoad(&map_range[1]);
        let c0 = vec2i(atomicLoad(&cells[0]), atomicLoad(&cells[1])) - reach;
        let c1 = vec2i(atomicLoad(&cells[2]), atomicLoad(&cells[3])) + reach;
        let extent = c1 - c0 + 1;
        let read = inside > 0u && one_map && all(extent <= vec2i(SHADOW_TILE_MAX_TEXELS));
        let map_index = atomicLoad(&map_range[0]);
        var map_dims = atlas_size;
        if (slot == 0u) {
            map_dims = select(vec2i(textureDimensions(cascades)), vec2i(textureDimensions(static_map)),
                              map_index == 4u);
        }
        if (read && mine) {
            let g = cell - c0;
            let i = g.y * SHADOW_TILE_MAX_TEXELS + g.x;
            atomicMax(&hi[i], key(l.depth_ref));
            atomicMin(&lo[i], key(l.depth_ref));
        }
        workgroupBarrier();
        // Spread along x, then along y while comparing each texel.
        let w = SHADOW_TILE_MAX_TEXELS;
        if (read) {
            for (var i = i32(li); i < extent.x * extent.y; i += 256) {
                let g = vec2i(i % extent.x, i / extent.x);
                var h = 0u;
                var m = 0xffffffffu;
                for (var dx = -reach; dx <= reach; dx++) {
                    let x = g.x + dx;
                    if (x >= 0 && x < extent.x) {
                        h = max(h, atomicLoad(&hi[g.y * w + x]));
                        m = min(m, atomicLoad(&lo[g.y * w + x]));
                    }
                }
                hi_x[g.y * w + g.x] = h;
                lo_x[g.y * w + g.x] = m;
            }
        }
        workgroupBarrier();
        if (read) {
            for (var i = i32(li); i < extent.x * extent.y; i += 256) {
                let g = vec2i(i % extent.x, i / extent.x);
                var h = 0u;
                var m = 0xffffffffu;
                for (var dy = -reach; dy <= reach; dy++) {
                    let y = g.y + dy;
                    if (y >= 0 && y < extent.y) {
                        h = max(h, hi_x[y * w + g.x]);
                        m = min(m, lo_x[y * w + g.x]);
                    }
                }
                if (h == 0u) {
                    continue;
                }
                let t = clamp(c0 + g, vec2i(0), map_dims - 1);
                var z: f32;
                if (slot > 0u) {
                    z = textureLoad(atlas, t, 0, 0);
                } else if (map_index == 4u) {
                    z = textureLoad(static_map, t, 0, 0);
                } else {
                    z = textureLoad(cascades, t, i32(map_index), 0);
                }
                let v = shadow_texel_verdict(z, unkey(m), unkey(h));
                if ((v & 1u) == 0u) {
                    atomicAdd(&fails[0], 1u);
                }
                if ((v & 2u) == 0u) {
                    atomicAdd(&fails[1], 1u);
                }
            }
        }
        workgroupBarrier();
        if (li == 0u) {
            let s = shadow_tile_state(inside, atomicLoad(&valid_n), read, atomicLoad(&fails[0]) == 0u,
                                      atomicLoad(&fails[1]) == 0u);
            out[slot / 16u] |= s << (2u * (slot % 16u));
        }
        workgroupBarrier();
    }
    if (li == 0u) {
        let tiles_x = (size.x + SHADOW_TILE - 1u) / SHADOW_TILE;
        tile_states[wg.y * tiles_x + wg.x] = out;
    }
}
