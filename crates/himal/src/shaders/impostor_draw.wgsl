// V3 depth impostors in the frame (docs/techniques/V3.md "In the frame"):
// what the G-buffer and shadow pipelines' vegetation stages do with an
// impostor grid vertex (uv1.x < 0, packed by scene/tree/impostor_level.rs):
// face the viewer, displace by the captured depth, and per pixel read the
// blended captures. The atlas is read through three functions the
// importer defines (texel (x, y) of a layer, unorm values as stored):
//   impostor_depth_texel(layer: i32, x: u32, y: u32) -> f32  (depth * 0.5 + 0.5)
//   impostor_color_texel(layer: i32, x: u32, y: u32) -> vec4f
//   impostor_normal_texel(layer: i32, x: u32, y: u32) -> vec4f
// shaders/impostor_atlas.wgsl reads textures; tests/impostor_wgsl.rs reads
// buffers and compares with the CPU twins in scene/tree/impostor.rs
// (`displace`, `pixel`).
#import impostor

// The grid vertex's atlas layer, or -1 for any other vertex.
fn impostor_layer(uv1: vec2f) -> i32 {
    if (uv1.x < 0.0) {
        return i32(round(-1.0 - uv1.x));
    }
    return -1;
}

// Bilinear depth of capture k at p (the taps of impostor_taps).
fn impostor_depth_at(layer: i32, k: u32, p: vec3f) -> f32 {
    let t = impostor_taps(impostor_atlas_coord(k, p));
    let taps = vec4f(
        impostor_depth_texel(layer, t.x.x, t.y.x),
        impostor_depth_texel(layer, t.x.y, t.y.x),
        impostor_depth_texel(layer, t.x.x, t.y.y),
        impostor_depth_texel(layer, t.x.y, t.y.y));
    return impostor_bilinear(taps, t.f) * 2.0 - 1.0;
}

// The displaced grid point xy for a viewer along w (tree space, unit):
// centre-relative, units of R (`displace` on the CPU).
fn impostor_vertex(layer: i32, w: vec3f, xy: vec2f) -> vec3f {
    let basis = impostor_view_basis(w);
    let q = impostor_quad_point(basis, xy);
    let b = impostor_blend(basis[2]);
    var d = 0.0;
    for (var c = 0u; c < 3u; c++) {
        if (b.weights[c] > 0.0) {
            let k = b.captures[c];
            var s = 0.0;
            for (var i = 0u; i < IMPOSTOR_DEPTH_STEPS; i++) {
                s = impostor_depth_step(impostor_capture_dir(k), q, basis[2],
                    impostor_depth_at(layer, k, q + basis[2] * s));
            }
            d += b.weights[c] * s;
        }
    }
    return impostor_displace(basis, q, d);
}

// Per-pixel fixed-point steps (PIXEL_STEPS on the CPU).
const IMPOSTOR_PIXEL_STEPS: u32 = 2u;

struct ImpostorPixel {
    // blended coverage (alpha-tested at 0.5)
    cover: f32,
    // coverage-weighted means: cluster tint t, leaf fraction, material AO
    tint: f32,
    leaf: f32,
    ao: f32,
    // tree-space normal (not normalised)
    normal: vec3f,
}

// The captures blended at the grid's interpolated point p (centre-relative,
// units of R) seen along w: each capture's own ray-depth hit from p, then
// its texels bilinear and coverage-premultiplied (`render_impostor`).
fn impostor_pixel(layer: i32, w: vec3f, p: vec3f) -> ImpostorPixel {
    let b = impostor_blend(w);
    let z = dot(p, w);
    let q = p - w * z;
    var out: ImpostorPixel;
    out.cover = 0.0;
    out.tint = 0.0;
    out.leaf = 0.0;
    out.ao = 0.0;
    out.normal = vec3f(0.0);
    for (var c = 0u; c < 3u; c++) {
        let wk = b.weights[c];
        if (wk <= 0.0) {
            continue;
        }
        let k = b.captures[c];
        var t = z;
        for (var i = 0u; i < IMPOSTOR_PIXEL_STEPS; i++) {
            t = impostor_depth_step(impostor_capture_dir(k), q, w, impostor_depth_at(layer, k, q + w * t));
        }
        let tap = impostor_taps(impostor_atlas_coord(k, q + w * t));
        let c00 = impostor_color_texel(layer, tap.x.x, tap.y.x);
        let c10 = impostor_color_texel(layer, tap.x.y, tap.y.x);
        let c01 = impostor_color_texel(layer, tap.x.x, tap.y.y);
        let c11 = impostor_color_texel(layer, tap.x.y, tap.y.y);
        let n00 = (impostor_normal_texel(layer, tap.x.x, tap.y.x).xyz * 2.0 - 1.0) * c00.a;
        let n10 = (impostor_normal_texel(layer, tap.x.y, tap.y.x).xyz * 2.0 - 1.0) * c10.a;
        let n01 = (impostor_normal_texel(layer, tap.x.x, tap.y.y).xyz * 2.0 - 1.0) * c01.a;
        let n11 = (impostor_normal_texel(layer, tap.x.y, tap.y.y).xyz * 2.0 - 1.0) * c11.a;
        let pre = vec4f(c00.a, c10.a, c01.a, c11.a);
        out.cover += wk * impostor_bilinear(pre, tap.f);
        out.tint += wk * impostor_bilinear(vec4f(c00.r, c10.r, c01.r, c11.r) * pre, tap.f);
        out.leaf += wk * impostor_bilinear(vec4f(c00.g, c10.g, c01.g, c11.g) * pre, tap.f);
        out.ao += wk * impostor_bilinear(vec4f(c00.b, c10.b, c01.b, c11.b) * pre, tap.f);
        let top = mix(n00, n10, tap.f.x);
        let bottom = mix(n01, n11, tap.f.x);
        out.normal += wk * mix(top, bottom, tap.f.y);
    }
    return out;
}

// Direction toward the viewer of a shadow map's light_view_proj (standard
// depth, 0 near): from the light's position for a perspective projection
// (clip x = y = w = 0 there), or against the orthographic view axis.
fn impostor_toward_light(m: mat4x4f, centre: vec3f) -> vec3f {
    let r0 = vec4f(m[0][0], m[1][0], m[2][0], m[3][0]);
    let r1 = vec4f(m[0][1], m[1][1], m[2][1], m[3][1]);
    let r2 = vec4f(m[0][2], m[1][2], m[2][2], m[3][2]);
    let r3 = vec4f(m[0][3], m[1][3], m[2][3], m[3][3]);
    if (dot(r3.xyz, r3.xyz) < 1e-12) {
        let d = cross(r0.xyz, r1.xyz);
        return normalize(select(d, -d, dot(d, r2.xyz) > 0.0));
    }
    // Cramer's rule for the point where rows 0, 1 and 3 vanish.
    let bc = cross(r1.xyz, r3.xyz);
    let det = dot(r0.xyz, bc);
    let eye = -(r0.w * bc + r1.w * cross(r3.xyz, r0.xyz) + r3.w * cross(r0.xyz, r1.xyz)) / det;
    return normalize(eye - centre);
}

struct ImpostorObjectVertex {
    // object space (m): centre + R * p
    local: vec3f,
    // centre-relative, units of R (the fragment stage's p)
    p: vec3f,
    // toward the viewer, tree space, unit
    w: vec3f,
}

// An impostor grid vertex of object `model` / `normal_matrix` (tree space ->
// world) for a viewer whose world direction from the tree's centre is
// `toward` (world); position = centre, tangent.w = R, uv = grid point.
fn impostor_object_vertex(normal_matrix: mat4x4f, layer: i32, centre: vec3f, radius: f32,
        xy: vec2f, toward: vec3f) -> ImpostorObjectVertex {
    // World -> tree space for directions: the transpose of the normal
    // matrix (the model's inverse); normalised against scale.
    let n = mat3x3f(normal_matrix[0].xyz, normal_matrix[1].xyz, normal_matrix[2].xyz);
    var v: ImpostorObjectVertex;
    v.w = normalize(transpose(n) * toward);
    v.p = impostor_vertex(layer, v.w, xy);
    v.local = centre + radius * v.p;
    return v;
}
