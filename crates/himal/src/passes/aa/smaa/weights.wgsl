// aa.smaa.weights: SMAA blending weights, orthogonal patterns (Jimenez et al.
// 2012, SMAABlendingWeightCalculationPS without diagonal and corner detection,
// the reference's MEDIUM preset). For a pixel with a top (left) edge, search
// the edge line's ends left/right (up/down), 2 pixels per bilinear fetch, the
// last step finished by the search texture (the reference stops at a texture
// coordinate; an iteration count gives the same steps without float ties); read the crossing edges at both
// ends; look up the area texture at (crossing edges, sqrt distances).
// Output: RG = top edge weights, BA = left edge weights. CPU twin: smaa/reference.rs.
#import view

override MAX_SEARCH_STEPS: f32 = 8.0;
// Subsample indices of SMAA T2x (0 for 1x): area table for horizontal / vertical edges.
override SUBSAMPLE_H: f32 = 0.0;
override SUBSAMPLE_V: f32 = 0.0;
const AREATEX_MAX_DISTANCE: f32 = 16.0;
const AREATEX_PIXEL_SIZE: vec2f = vec2f(1.0 / 160.0, 1.0 / 560.0);
const AREATEX_SUBTEX_SIZE: f32 = 1.0 / 7.0;
const SEARCHTEX_SIZE: vec2f = vec2f(66.0, 33.0);
const SEARCHTEX_PACKED_SIZE: vec2f = vec2f(64.0, 16.0);

@group(0) @binding(0) var edges_tex: texture_2d<f32>;
@group(0) @binding(1) var area_tex: texture_2d<f32>;
@group(0) @binding(2) var search_tex: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;
@group(0) @binding(4) var point_sampler: sampler;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4f {
    return fullscreen_clip(i);
}

fn smaa_edges_at(tc: vec2f) -> vec2f {
    return textureSampleLevel(edges_tex, linear_sampler, tc, 0.0).rg;
}

// Extra length of the last search step from the bilinear edge value e.
fn smaa_search_length(e: vec2f, offset: f32) -> f32 {
    let scale = (SEARCHTEX_SIZE * vec2f(0.5, -1.0) + vec2f(-1.0, 1.0)) / SEARCHTEX_PACKED_SIZE;
    let bias = (SEARCHTEX_SIZE * vec2f(offset, 1.0) + vec2f(0.5, -0.5)) / SEARCHTEX_PACKED_SIZE;
    return textureSampleLevel(search_tex, point_sampler, scale * e + bias, 0.0).r;
}

fn smaa_search_x_left(start: vec2f, rt: vec4f) -> f32 {
    var tc = start;
    var e = vec2f(0.0, 1.0);
    for (var i = 0.0; i < MAX_SEARCH_STEPS && e.g > 0.8281 && e.r == 0.0; i += 1.0) {
        e = smaa_edges_at(tc);
        tc.x -= 2.0 * rt.x;
    }
    let offset = -(255.0 / 127.0) * smaa_search_length(e, 0.0) + 3.25;
    return rt.x * offset + tc.x;
}

fn smaa_search_x_right(start: vec2f, rt: vec4f) -> f32 {
    var tc = start;
    var e = vec2f(0.0, 1.0);
    for (var i = 0.0; i < MAX_SEARCH_STEPS && e.g > 0.8281 && e.r == 0.0; i += 1.0) {
        e = smaa_edges_at(tc);
        tc.x += 2.0 * rt.x;
    }
    let offset = -(255.0 / 127.0) * smaa_search_length(e, 0.5) + 3.25;
    return -rt.x * offset + tc.x;
}

fn smaa_search_y_up(start: vec2f, rt: vec4f) -> f32 {
    var tc = start;
    var e = vec2f(1.0, 0.0);
    for (var i = 0.0; i < MAX_SEARCH_STEPS && e.r > 0.8281 && e.g == 0.0; i += 1.0) {
        e = smaa_edges_at(tc);
        tc.y -= 2.0 * rt.y;
    }
    let offset = -(255.0 / 127.0) * smaa_search_length(e.gr, 0.0) + 3.25;
    return rt.y * offset + tc.y;
}

fn smaa_search_y_down(start: vec2f, rt: vec4f) -> f32 {
    var tc = start;
    var e = vec2f(1.0, 0.0);
    for (var i = 0.0; i < MAX_SEARCH_STEPS && e.r > 0.8281 && e.g == 0.0; i += 1.0) {
        e = smaa_edges_at(tc);
        tc.y += 2.0 * rt.y;
    }
    let offset = -(255.0 / 127.0) * smaa_search_length(e.gr, 0.5) + 3.25;
    return -rt.y * offset + tc.y;
}

// Area texture lookup: block (e1, e2) in quarters, texel sqrt distances.
fn smaa_area(sqrt_d: vec2f, e1: f32, e2: f32, subsample: f32) -> vec2f {
    var tc = AREATEX_MAX_DISTANCE * round(4.0 * vec2f(e1, e2)) + sqrt_d;
    tc = AREATEX_PIXEL_SIZE * tc + 0.5 * AREATEX_PIXEL_SIZE;
    tc.y += AREATEX_SUBTEX_SIZE * subsample;
    return textureSampleLevel(area_tex, linear_sampler, tc, 0.0).rg;
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let size = vec2f(textureDimensions(edges_tex));
    let rt = vec4f(1.0 / size, size);
    let tc = frag.xy * rt.xy;
    let off0 = rt.xyxy * vec4f(-0.25, -0.125, 1.25, -0.125) + tc.xyxy;
    let off1 = rt.xyxy * vec4f(-0.125, -0.25, -0.125, 1.25) + tc.xyxy;
    var weights = vec4f(0.0);
    let e = textureLoad(edges_tex, vec2i(frag.xy), 0).rg;
    if (e.g > 0.0) {
        let left = smaa_search_x_left(off0.xy, rt);
        let e1 = smaa_edges_at(vec2f(left, off1.y)).r;
        let right = smaa_search_x_right(off0.zw, rt);
        let e2 = smaa_edges_at(vec2f(right + rt.x, off1.y)).r;
        let d = abs(round(rt.zz * vec2f(left, right) - frag.xx));
        let a = smaa_area(sqrt(d), e1, e2, SUBSAMPLE_H);
        weights.x = a.x;
        weights.y = a.y;
    }
    if (e.r > 0.0) {
        let up = smaa_search_y_up(off1.xy, rt);
        let e1 = smaa_edges_at(vec2f(off0.x, up)).g;
        let down = smaa_search_y_down(off1.zw, rt);
        let e2 = smaa_edges_at(vec2f(off0.x, down + rt.y)).g;
        let d = abs(round(rt.ww * vec2f(up, down) - frag.yy));
        let a = smaa_area(sqrt(d), e1, e2, SUBSAMPLE_V);
        weights.z = a.x;
        weights.w = a.y;
    }
    return weights;
}
