// aa.smaa.weights: SMAA blending weights (Jimenez et al. 2012,
// SMAABlendingWeightCalculationPS with diagonal and corner detection, the
// reference's HIGH preset but 8 orthogonal steps).
// Diagonals first (a top edge starts both kinds): walk the two diagonals
// through the pixel up to MAX_SEARCH_STEPS_DIAG steps each way, one bilinear
// fetch per step (the second diagonal decodes two edges from one fetch);
// lines longer than 3 pixels read their crossing edges and look up the
// diagonal half of the area texture at (crossing edges, distances). A found
// diagonal takes the top weights and skips the orthogonal search.
// Orthogonal: for a pixel with a top (left) edge, search the edge line's ends
// left/right (up/down), 2 pixels per bilinear fetch, the last step finished
// by the search texture (the reference stops at a texture coordinate; an
// iteration count gives the same steps without float ties); read the crossing
// edges at both ends; look up the area texture at (crossing edges, sqrt
// distances); corner detection (CORNER_ROUNDING %) then keeps some aliasing
// where the line ends in a corner, so sharp corners stay sharp.
// Output: RG = top edge weights, BA = left edge weights. CPU twin: smaa/reference.rs.
#import view
#import fullscreen

override MAX_SEARCH_STEPS: f32 = 8.0;
// Subsample indices of SMAA T2x (0 for 1x): area table for horizontal / vertical edges.
override SUBSAMPLE_H: f32 = 0.0;
override SUBSAMPLE_V: f32 = 0.0;
// Diagonal search steps each way (0: no diagonal detection) and its area table
// (the second diagonal always uses table 0, as the reference's T2x indices).
override MAX_SEARCH_STEPS_DIAG: f32 = 8.0;
override SUBSAMPLE_DIAG: f32 = 0.0;
// Percent of a corner's blending kept (100: no corner detection).
override CORNER_ROUNDING: f32 = 25.0;
const AREATEX_MAX_DISTANCE: f32 = 16.0;
const AREATEX_MAX_DISTANCE_DIAG: f32 = 20.0;
const AREATEX_PIXEL_SIZE: vec2f = vec2f(1.0 / 160.0, 1.0 / 560.0);
const AREATEX_SUBTEX_SIZE: f32 = 1.0 / 7.0;
const SEARCHTEX_SIZE: vec2f = vec2f(66.0, 33.0);
const SEARCHTEX_PACKED_SIZE: vec2f = vec2f(64.0, 16.0);

@group(0) @binding(0) var edges_tex: texture_2d<f32>;
@group(0) @binding(1) var area_tex: texture_2d<f32>;
@group(0) @binding(2) var search_tex: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;
@group(0) @binding(4) var point_sampler: sampler;

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

// Two edges from one bilinear fetch a quarter pixel right of a texel centre:
// red reads 0.75 X + 0.25 (own, right), green the own texel's.
fn smaa_decode_diag_bilinear(e: vec4f) -> vec4f {
    var r = e;
    r.x = e.x * abs(5.0 * e.x - 3.75);
    r.z = e.z * abs(5.0 * e.z - 3.75);
    return round(r);
}

// Walks `dir` from tc while both edges of the step are on (mean > 0.9):
// returns (steps, mean of the last fetch); `e` gets the last edges. DECODE:
// the second diagonal's fetch (both edges from one bilinear sample).
fn smaa_search_diag(tc: vec2f, dir: vec2f, rt: vec4f, decode: bool, e: ptr<function, vec2f>) -> vec2f {
    var coord = vec4f(tc, -1.0, 1.0);
    if (decode) {
        coord.x += 0.25 * rt.x;
    }
    while (coord.z < MAX_SEARCH_STEPS_DIAG - 1.0 && coord.w > 0.9) {
        coord = vec4f(coord.xy + rt.xy * dir, coord.z + 1.0, coord.w);
        var f = smaa_edges_at(coord.xy);
        if (decode) {
            f = smaa_decode_diag_bilinear(vec4f(f, 0.0, 0.0)).xy;
        }
        *e = f;
        coord.w = dot(f, vec2f(0.5));
    }
    return coord.zw;
}

// Diagonal area lookup: block (crossing edges), texel distances, right half.
fn smaa_area_diag(dist: vec2f, e: vec2f, subsample: f32) -> vec2f {
    var tc = AREATEX_MAX_DISTANCE_DIAG * e + dist;
    tc = AREATEX_PIXEL_SIZE * tc + 0.5 * AREATEX_PIXEL_SIZE;
    tc.x += 0.5;
    tc.y += AREATEX_SUBTEX_SIZE * subsample;
    return textureSampleLevel(area_tex, linear_sampler, tc, 0.0).rg;
}

// Weights of the diagonal lines through the pixel (0 when none is found).
fn smaa_diag_weights(tc: vec2f, e: vec2f, rt: vec4f) -> vec2f {
    var weights = vec2f(0.0);
    var end = vec2f(0.0);
    // Down-left / up-right diagonal.
    var d = vec4f(0.0);
    if (e.r > 0.0) {
        let s = smaa_search_diag(tc, vec2f(-1.0, 1.0), rt, false, &end);
        d = vec4f(s.x + select(0.0, 1.0, end.y > 0.9), d.y, s.y, d.w);
    }
    let s1 = smaa_search_diag(tc, vec2f(1.0, -1.0), rt, false, &end);
    d = vec4f(d.x, s1.x, d.z, s1.y);
    if (d.x + d.y > 2.0) {
        let coords = vec4f(-d.x + 0.25, d.x, d.y, -d.y - 0.25) * rt.xyxy + tc.xyxy;
        let raw = vec4f(
            smaa_edges_at(coords.xy + vec2f(-1.0, 0.0) * rt.xy),
            smaa_edges_at(coords.zw + vec2f(1.0, 0.0) * rt.xy),
        );
        let c = smaa_decode_diag_bilinear(raw).yxwz;
        // Crossing edges of each end in one value; none where the search ran out.
        let cc = select(2.0 * c.xz + c.yw, vec2f(0.0), d.zw >= vec2f(0.9));
        weights += smaa_area_diag(d.xy, cc, SUBSAMPLE_DIAG);
    }
    // Up-left / down-right diagonal.
    let s2 = smaa_search_diag(tc, vec2f(-1.0, -1.0), rt, true, &end);
    d = vec4f(s2.x, 0.0, s2.y, 0.0);
    if (smaa_edges_at(tc + vec2f(rt.x, 0.0)).r > 0.0) {
        let s3 = smaa_search_diag(tc, vec2f(1.0, 1.0), rt, true, &end);
        d = vec4f(d.x, s3.x + select(0.0, 1.0, end.y > 0.9), d.z, s3.y);
    }
    if (d.x + d.y > 2.0) {
        let coords = vec4f(-d.x, -d.x, d.y, d.y) * rt.xyxy + tc.xyxy;
        let c = vec4f(
            smaa_edges_at(coords.xy + vec2f(-1.0, 0.0) * rt.xy).g,
            smaa_edges_at(coords.xy + vec2f(0.0, -1.0) * rt.xy).r,
            smaa_edges_at(coords.zw + vec2f(1.0, 0.0) * rt.xy).gr,
        );
        let cc = select(2.0 * c.xz + c.yw, vec2f(0.0), d.zw >= vec2f(0.9));
        weights += smaa_area_diag(d.xy, cc, 0.0).gr;
    }
    return weights;
}

// Corner detection: where an end of the line (`d`: pixels to the left/top and
// right/bottom end) meets a perpendicular edge one pixel beside it, keep only
// CORNER_ROUNDING % of that side's weight (split when both ends are as near).
fn smaa_corner(weights: vec2f, tc: vec2f, d: vec2f, horizontal: bool, rt: vec4f) -> vec2f {
    if (CORNER_ROUNDING >= 100.0) {
        return weights;
    }
    let left_right = step(d, d.yx);
    var rounding = (1.0 - CORNER_ROUNDING / 100.0) * left_right;
    rounding /= left_right.x + left_right.y;
    var factor = vec2f(1.0);
    if (horizontal) {
        let a = tc + vec2f(-d.x, 0.0) * rt.xy;
        let b = tc + vec2f(d.y, 0.0) * rt.xy;
        factor.x -= rounding.x * smaa_edges_at(a + vec2f(0.0, 1.0) * rt.xy).r;
        factor.x -= rounding.y * smaa_edges_at(b + vec2f(1.0, 1.0) * rt.xy).r;
        factor.y -= rounding.x * smaa_edges_at(a + vec2f(0.0, -2.0) * rt.xy).r;
        factor.y -= rounding.y * smaa_edges_at(b + vec2f(1.0, -2.0) * rt.xy).r;
    } else {
        let a = tc + vec2f(0.0, -d.x) * rt.xy;
        let b = tc + vec2f(0.0, d.y) * rt.xy;
        factor.x -= rounding.x * smaa_edges_at(a + vec2f(1.0, 0.0) * rt.xy).g;
        factor.x -= rounding.y * smaa_edges_at(b + vec2f(1.0, 1.0) * rt.xy).g;
        factor.y -= rounding.x * smaa_edges_at(a + vec2f(-2.0, 0.0) * rt.xy).g;
        factor.y -= rounding.y * smaa_edges_at(b + vec2f(-2.0, 1.0) * rt.xy).g;
    }
    return weights * saturate(factor);
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
    var e = textureLoad(edges_tex, vec2i(frag.xy), 0).rg;
    var diag = vec2f(0.0);
    if (e.g > 0.0 && MAX_SEARCH_STEPS_DIAG > 0.0) {
        diag = smaa_diag_weights(tc, e, rt);
    }
    if (diag.x + diag.y > 0.0) {
        // Diagonals have priority: no orthogonal search for this pixel.
        weights = vec4f(diag, 0.0, 0.0);
        e.r = 0.0;
    } else if (e.g > 0.0) {
        let left = smaa_search_x_left(off0.xy, rt);
        let e1 = smaa_edges_at(vec2f(left, off1.y)).r;
        let right = smaa_search_x_right(off0.zw, rt);
        let e2 = smaa_edges_at(vec2f(right + rt.x, off1.y)).r;
        let d = abs(round(rt.zz * vec2f(left, right) - frag.xx));
        let a = smaa_corner(smaa_area(sqrt(d), e1, e2, SUBSAMPLE_H), tc, d, true, rt);
        weights.x = a.x;
        weights.y = a.y;
    }
    if (e.r > 0.0) {
        let up = smaa_search_y_up(off1.xy, rt);
        let e1 = smaa_edges_at(vec2f(off0.x, up)).g;
        let down = smaa_search_y_down(off1.zw, rt);
        let e2 = smaa_edges_at(vec2f(off0.x, down + rt.y)).g;
        let d = abs(round(rt.ww * vec2f(up, down) - frag.yy));
        let a = smaa_corner(smaa_area(sqrt(d), e1, e2, SUBSAMPLE_V), tc, d, false, rt);
        weights.z = a.x;
        weights.w = a.y;
    }
    return weights;
}
