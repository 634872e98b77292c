// shadows.mask: full-screen sun occlusion before lighting (TECHNIQUES S1, S4).
// R = sun visibility from the cascade (or static map) of the pixel's view
// distance; fs_hero is drawn after it with a Min blend on R (= max of the
// occlusions), the hero map's tight fit over the rest. G, B, A: local lights (S3), 1 now.
// Bindings: view, params (ShadowMaskParams), depth, gbuffer_frame (normal),
// cascades, static_map, hero_map (depth arrays), shadow_sampler (comparison).
#import view
#import tangent_frame
#import shadow

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> params: ShadowMaskParams;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(4) var cascades: texture_depth_2d_array;
@group(0) @binding(5) var static_map: texture_depth_2d_array;
@group(0) @binding(6) var hero_map: texture_depth_2d_array;
@group(0) @binding(7) var shadow_sampler: sampler_comparison;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    return fullscreen_clip(i);
}

struct Receiver {
    p: vec3f,
    n: vec3f,
    dist: f32,
}

fn receiver(frag: vec4f, d: f32) -> Receiver {
    let px = vec2i(frag.xy);
    let uv = frag.xy * view.viewport.zw;
    var r: Receiver;
    r.p = world_from_depth(view, uv, d);
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
    let i = shadow_map_index(params, r.dist);
    var vis = 1.0;
    if (i == 4) {
        vis = shadow_map_visibility(static_map, shadow_sampler, 0, params.static_map, params.light_rotation, r.p, r.n,
                                    params.static_info.y, params.static_info.z, params.filter_params);
    } else if (i >= 0) {
        vis = shadow_map_visibility(cascades, shadow_sampler, i, params.cascades[i], params.light_rotation, r.p, r.n,
                                    params.texel[i], params.depth_range[i], params.filter_params);
    }
    return vec4f(vis, 1.0, 1.0, 1.0);
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
