// shadows.mask: full-screen sun occlusion before lighting (TECHNIQUES S1, S4).
// R = sun visibility from the cascade (or static map) of the pixel's view
// distance; fs_hero is drawn after it with a Min blend on R (= max of the
// occlusions), the hero map's tight fit over the rest. G, B, A: local lights
// (S3), each shadowed light in its channel, read from its atlas tile.
// Bindings: view, params (ShadowMaskParams), depth, gbuffer_frame (normal),
// cascades, static_map, hero_map, atlas (depth arrays), shadow_sampler
// (comparison), local_lights, light_tiles, tile_states (TILES: the
// per-tile states of shadows.mask_tiles, #23: a map lit or shadowed over the
// whole tile costs no tap).
#import view
#import tangent_frame
#import shadow
#import shadow_receiver
#import fullscreen

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> params: ShadowMaskParams;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(4) var cascades: texture_depth_2d_array;
@group(0) @binding(5) var static_map: texture_depth_2d_array;
@group(0) @binding(6) var hero_map: texture_depth_2d_array;
@group(0) @binding(7) var shadow_sampler: sampler_comparison;
@group(0) @binding(8) var atlas: texture_depth_2d_array;
@group(0) @binding(9) var<storage, read> local_lights: LocalLights;
@group(0) @binding(10) var<storage, read> light_tiles: array<ShadowTile>;
@group(0) @binding(11) var<storage, read> tile_states: array<vec4u>;

override TILES: bool = false;

// 2-bit state of slot `slot` (0 sun, 1 + k local light k) in `states`;
// slots past 63 filter.
fn slot_state(states: vec4u, slot: u32) -> u32 {
    if (slot >= 64u) {
        return SHADOW_TILE_FILTER;
    }
    return (states[slot / 16u] >> (2u * (slot % 16u))) & 3u;
}

// Visibility of `r` from local light `l` (channel > 0): the tile of its cube
// face (point) or its one tile (spot), the same Poisson filter.
fn local_visibility(l: LocalLight, r: Receiver) -> f32 {
    let tile = shadow_local_tile(l, r.p);
    if (tile < 0) {
        return 1.0;
    }
    return shadow_local_visibility(l, light_tiles[tile], r.p, r.n, atlas, shadow_sampler, params.filter_params.x);
}

fn receiver(frag: vec4f, d: f32) -> Receiver {
    return shadow_receiver(view, params, frag.xy, d, textureLoad(gbuffer_frame, vec2i(frag.xy), 0));
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let d = textureLoad(depth, vec2i(frag.xy), 0);
    if (d <= 0.0) {
        return vec4f(1.0);
    }
    var states = vec4u(0u);
    if (TILES) {
        let t = vec2u(frag.xy) / SHADOW_TILE;
        let tiles_x = (textureDimensions(depth).x + SHADOW_TILE - 1u) / SHADOW_TILE;
        states = tile_states[t.y * tiles_x + t.x];
    }
    let r = receiver(frag, d);
    var vis = 1.0;
    let sun = slot_state(states, 0u);
    if (sun == SHADOW_TILE_SHADOWED) {
        vis = 0.0;
    } else if (sun == SHADOW_TILE_FILTER) {
        vis = shadow_world_visibility(params, cascades, static_map, shadow_sampler, r.p, r.n, r.dist);
    }
    var local = vec3f(1.0);
    for (var k = 0u; k < local_lights.count.x; k = k + 1u) {
        let l = local_lights.lights[k];
        let channel = u32(l.params.y);
        let state = slot_state(states, k + 1u);
        if (channel == 0u || state == SHADOW_TILE_LIT) {
            continue;
        }
        var v = 0.0;
        if (state == SHADOW_TILE_FILTER) {
            v = local_visibility(l, r);
        }
        local[channel - 1u] = min(local[channel - 1u], v);
    }
    return vec4f(vis, local);
}

// Hero map (S4), blended with Min into R.
@fragment
fn fs_hero(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let d = textureLoad(depth, vec2i(frag.xy), 0);
    if (d <= 0.0) {
        return vec4f(1.0);
    }
    let r = receiver(frag, d);
    let vis = shadow_map_visibility(hero_map, shadow_sampler, 0, params.hero, params.light_rotation, r.p, r.n,
                                    params.hero_info.y, params.hero_info.z, params.filter_params);
    return vec4f(vis, 1.0, 1.0, 1.0);
}
