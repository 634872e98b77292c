// shadows.mask: full-screen sun occlusion before lighting (TECHNIQUES S1, S4).
// R = sun visibility from the cascade (or static map) of the pixel's view
// distance; fs_hero is drawn after it with a Min blend on R (= max of the
// occlusions), the hero map's tight fit over the rest. G, B, A: local lights
// (S3), each shadowed light in its channel, read from its atlas tile.
// Bindings: view, params (ShadowMaskParams), depth, gbuffer_frame (normal),
// cascades, static_map, hero_map, atlas (depth arrays), shadow_sampler
// (comparison), local_lights, light_tiles.
#import view
#import tangent_frame
#import shadow
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

// Visibility of `r` from local light `l` (channel > 0): the tile of its cube
// face (point) or its one tile (spot), normal offset and depth bias of 1.5
// and 2 texels at the receiver's distance, the same Poisson filter.
fn local_visibility(l: LocalLight, r: Receiver) -> f32 {
    let to_p = r.p - l.position_range.xyz;
    let d = length(to_p);
    if (d >= l.position_range.w) {
        return 1.0;
    }
    var tile = u32(l.params.z);
    if (l.color_kind.w < 0.5) {
        tile += shadow_cube_face(to_p);
    }
    let t = light_tiles[tile];
    let texel = t.info.x * d;
    let q = r.p + r.n * (1.5 * texel) - (to_p / d) * (2.0 * texel);
    let c = t.view_proj * vec4f(q, 1.0);
    if (c.w <= 0.0) {
        return 1.0;
    }
    let ndc = c.xyz / c.w;
    let uv_tile = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if (any(uv_tile < vec2f(0.0)) || any(uv_tile > vec2f(1.0)) || ndc.z > 1.0) {
        return 1.0;
    }
    let uv = t.rect.xy + uv_tile * t.rect.zw;
    let cell = floor(uv * vec2f(textureDimensions(atlas)));
    return shadow_poisson_visibility(atlas, shadow_sampler, 0, uv, ndc.z, params.filter_params.x,
                                     shadow_rotation_angle(cell));
}

struct Receiver {
    p: vec3f,
    n: vec3f,
    dist: f32,
}

fn receiver(frag: vec4f, d: f32) -> Receiver {
    let px = vec2i(frag.xy);
    var r: Receiver;
    r.p = world_at_fragment(view, frag.xy, d);
    r.n = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, px, 0)))[2];
    r.dist = dot(r.p - view.camera_position.xyz, params.camera_forward.xyz);
    return r;
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let d = textureLoad(depth, vec2i(frag.xy), 0);
    if (d <= 0.0) {
        return vec4f(1.0);
    }
    let r = receiver(frag, d);
    let vis = shadow_world_visibility(params, cascades, static_map, shadow_sampler, r.p, r.n, r.dist);
    var local = vec3f(1.0);
    for (var k = 0u; k < local_lights.count.x; k = k + 1u) {
        let l = local_lights.lights[k];
        let channel = u32(l.params.y);
        if (channel > 0u) {
            local[channel - 1u] = min(local[channel - 1u], local_visibility(l, r));
        }
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
