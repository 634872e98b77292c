// aa.smaa.edges: SMAA luma edge detection (Jimenez et al. 2012, SMAALumaEdgeDetectionPS)
// with local contrast adaptation, predicated by depth and normals (TECHNIQUES A1):
//   delta = |L - L_left|, |L - L_top|        (L: Rec.709 luma of sRGB-encoded colour)
//   edge where delta >= threshold and 2 * delta >= the largest delta around it
//   predicated threshold = SCALE * THRESHOLD * (1 - STRENGTH * geometric_edge)
//   geometric_edge: relative depth step > PREDICATION_THRESHOLD, or (both
//   pixels geometry) normals from the quaternion G-buffer apart by more than
//   acos(NORMAL_COS)
// Output RG: edge on the left, edge on the top (0/1). CPU twin: smaa/reference.rs.
// EDGE_MASK (#23, the reference's stencil): pixels without an edge are
// discarded, so only edge pixels write the mask's depth and
// aa.smaa.weights (depth test GreaterEqual) shades only them.
#import view
#import color
#import tangent_frame
#import fullscreen

override THRESHOLD: f32 = 0.1;
override PREDICATION: bool = true;
// Relative step of linear depth that counts as a geometric edge.
override PREDICATION_THRESHOLD: f32 = 0.01;
override PREDICATION_SCALE: f32 = 2.0;
override PREDICATION_STRENGTH: f32 = 0.4;
override NORMAL_PREDICATION: bool = true;
// cos 25 degrees: creases sharper than that count as geometric edges.
override NORMAL_COS: f32 = 0.906;
override EDGE_MASK: bool = false;
const LOCAL_CONTRAST_ADAPTATION: f32 = 2.0;

@group(0) @binding(0) var color: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var gbuffer_frame: texture_2d<f32>;

fn smaa_clamp(p: vec2i) -> vec2i {
    return clamp(p, vec2i(0), vec2i(textureDimensions(color)) - 1);
}

// Luma of the gamma-encoded colour (SMAA thresholds are tuned for gamma space).
fn smaa_luma(p: vec2i) -> f32 {
    let c = clamp(textureLoad(color, smaa_clamp(p), 0).rgb, vec3f(0.0), vec3f(1.0));
    return dot(linear_to_srgb(c), vec3f(0.2126, 0.7152, 0.0722));
}

fn smaa_normal(p: vec2i) -> vec3f {
    return quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, smaa_clamp(p), 0)))[2];
}

// Relative step of linear depth between device depths a, b (reverse-Z: z ~ 1/d).
fn smaa_depth_step(a: f32, b: f32) -> f32 {
    return abs(a - b) / max(min(a, b), 1e-7);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let e = smaa_edges(vec2i(frag.xy));
    if (EDGE_MASK && e.x + e.y == 0.0) {
        discard;
    }
    return vec4f(e, 0.0, 0.0);
}

// (left, top) edges of pixel p.
fn smaa_edges(p: vec2i) -> vec2f {
    let l = smaa_luma(p);
    let l_left = smaa_luma(p + vec2i(-1, 0));
    let l_top = smaa_luma(p + vec2i(0, -1));
    var threshold = vec2f(THRESHOLD);
    if (PREDICATION) {
        let d = textureLoad(depth, p, 0);
        let d_left = textureLoad(depth, smaa_clamp(p + vec2i(-1, 0)), 0);
        let d_top = textureLoad(depth, smaa_clamp(p + vec2i(0, -1)), 0);
        let steps = vec2f(smaa_depth_step(d, d_left), smaa_depth_step(d, d_top));
        var geometric = step(vec2f(PREDICATION_THRESHOLD), steps);
        // Depth 0 is the sky (no G-buffer frame there).
        if (NORMAL_PREDICATION && d > 0.0) {
            let n = smaa_normal(p);
            let bent_left = d_left > 0.0 && dot(n, smaa_normal(p + vec2i(-1, 0))) < NORMAL_COS;
            let bent_top = d_top > 0.0 && dot(n, smaa_normal(p + vec2i(0, -1))) < NORMAL_COS;
            geometric = max(geometric, vec2f(f32(bent_left), f32(bent_top)));
        }
        threshold = PREDICATION_SCALE * THRESHOLD * (1.0 - PREDICATION_STRENGTH * geometric);
    }
    let delta = abs(vec2f(l) - vec2f(l_left, l_top));
    var edges = step(threshold, delta);
    if (edges.x + edges.y == 0.0) {
        return vec2f(0.0);
    }
    let l_right = smaa_luma(p + vec2i(1, 0));
    let l_bottom = smaa_luma(p + vec2i(0, 1));
    var max_delta = max(delta, abs(vec2f(l) - vec2f(l_right, l_bottom)));
    let l_left_left = smaa_luma(p + vec2i(-2, 0));
    let l_top_top = smaa_luma(p + vec2i(0, -2));
    max_delta = max(max_delta, abs(vec2f(l_left, l_top) - vec2f(l_left_left, l_top_top)));
    let final_delta = max(max_delta.x, max_delta.y);
    edges *= step(vec2f(final_delta), LOCAL_CONTRAST_ADAPTATION * delta);
    return edges;
}
