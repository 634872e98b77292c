// V3 depth impostors (docs/techniques/V3.md): the nine capture frames, the
// blend between captures by view direction, the atlas taps and the depth
// reconstruction of the 16 x 16 camera-facing grid. Units: centre-relative,
// in the bounding sphere radius R. CPU twin: scene/tree/impostor.rs
// (`capture_dir`, `view_basis`, `blend`, `atlas_coord`, `bilinear_taps`,
// `bilinear`, `grid_point`, `depth_step`, `displace`); tests/impostor_wgsl.rs.

const IMPOSTOR_AROUND: u32 = 8u;
const IMPOSTOR_CAPTURE_SIZE: u32 = 128u;
const IMPOSTOR_ATLAS_COLUMNS: u32 = 3u;
const IMPOSTOR_ATLAS_SIZE: u32 = 384u;
const IMPOSTOR_GRID: u32 = 16u;
const IMPOSTOR_TAU: f32 = 6.2831853;
// Fixed-point steps of the depth reconstruction, and the floor of w · dir_k.
const IMPOSTOR_DEPTH_STEPS: u32 = 3u;
const IMPOSTOR_MIN_COS: f32 = 0.2;
// The top capture fades in between these elevations (20°, 70°, radians).
const IMPOSTOR_TOP_FADE = vec2f(0.34906585, 1.2217305);

// Direction from the tree toward the camera of capture k (8 around, then top).
fn impostor_capture_dir(k: u32) -> vec3f {
    if (k >= IMPOSTOR_AROUND) {
        return vec3f(0.0, 1.0, 0.0);
    }
    let a = f32(k) * (IMPOSTOR_TAU / f32(IMPOSTOR_AROUND));
    return vec3f(sin(a), 0.0, cos(a));
}

// Columns (right, up, toward the camera) of an orthographic view along -dir.
fn impostor_view_basis(dir: vec3f) -> mat3x3f {
    var right = vec3f(1.0, 0.0, 0.0);
    if (abs(dir.y) <= 0.999) {
        right = normalize(cross(vec3f(0.0, 1.0, 0.0), dir));
    }
    return mat3x3f(right, cross(dir, right), dir);
}

struct ImpostorBlend {
    // the two nearest captures around, then the top one
    captures: vec3u,
    weights: vec3f,
}

// Linear in azimuth between the two nearest captures around; the top one
// by a smoothstep of the elevation.
fn impostor_blend(dir: vec3f) -> ImpostorBlend {
    let az = atan2(dir.x, dir.z);
    let s = select(az, az + IMPOSTOR_TAU, az < 0.0) / (IMPOSTOR_TAU / f32(IMPOSTOR_AROUND));
    let k0f = floor(s);
    let f = s - k0f;
    let k0 = u32(k0f) % IMPOSTOR_AROUND;
    let e = asin(clamp(dir.y, -1.0, 1.0));
    let t = clamp((e - IMPOSTOR_TOP_FADE.x) / (IMPOSTOR_TOP_FADE.y - IMPOSTOR_TOP_FADE.x), 0.0, 1.0);
    let top = t * t * (3.0 - 2.0 * t);
    var b: ImpostorBlend;
    b.captures = vec3u(k0, (k0 + 1u) % IMPOSTOR_AROUND, IMPOSTOR_AROUND);
    b.weights = vec3f((1.0 - f) * (1.0 - top), f * (1.0 - top), top);
    return b;
}

// Continuous atlas texel coordinates (centres at +0.5) of point p in
// capture k, clamped to the capture's outer texel centres.
fn impostor_atlas_coord(k: u32, p: vec3f) -> vec2f {
    let basis = impostor_view_basis(impostor_capture_dir(k));
    let n = f32(IMPOSTOR_CAPTURE_SIZE);
    let local = clamp(vec2f((dot(p, basis[0]) * 0.5 + 0.5) * n, (0.5 - dot(p, basis[1]) * 0.5) * n),
        vec2f(0.5), vec2f(n - 0.5));
    let tile = vec2f(f32(k % IMPOSTOR_ATLAS_COLUMNS), f32(k / IMPOSTOR_ATLAS_COLUMNS)) * n;
    return tile + local;
}

struct ImpostorTaps {
    // texel columns (x0, x1) and rows (y0, y1), inside the capture's tile
    x: vec2u,
    y: vec2u,
    f: vec2f,
}

// The four texels of a bilinear tap at atlas coordinate c (a manual tap,
// so vertex and fragment stages and the CPU agree bit for bit on the weights).
fn impostor_taps(c: vec2f) -> ImpostorTaps {
    let b = floor(c - 0.5);
    var t: ImpostorTaps;
    t.f = c - 0.5 - b;
    let base = vec2u(b);
    let last = (base / IMPOSTOR_CAPTURE_SIZE) * IMPOSTOR_CAPTURE_SIZE + IMPOSTOR_CAPTURE_SIZE - 1u;
    let next = min(base + 1u, last);
    t.x = vec2u(base.x, next.x);
    t.y = vec2u(base.y, next.y);
    return t;
}

// Bilinear mix of taps (x0 y0, x1 y0, x0 y1, x1 y1).
fn impostor_bilinear(t: vec4f, f: vec2f) -> f32 {
    let top = t.x + (t.y - t.x) * f.x;
    let bottom = t.z + (t.w - t.z) * f.x;
    return top + (bottom - top) * f.y;
}

// Grid point (i right, j down) of the quad in [-1, 1]².
fn impostor_grid_point(i: u32, j: u32) -> vec2f {
    let g = f32(IMPOSTOR_GRID);
    return vec2f(2.0 * f32(i) / g - 1.0, 1.0 - 2.0 * f32(j) / g);
}

// The quad's point q = x right + y up, and q moved toward the camera by the
// blended depth (the depth reconstruction).
fn impostor_quad_point(basis: mat3x3f, xy: vec2f) -> vec3f {
    return basis[0] * xy.x + basis[1] * xy.y;
}

fn impostor_displace(basis: mat3x3f, q: vec3f, depth: f32) -> vec3f {
    return q + basis[2] * depth;
}

// One step of the ray-depth intersection with the capture along dir_k: the
// distance along the camera direction w from q at which the ray reaches the
// depth d the capture stores where it sees the previous step's point.
fn impostor_depth_step(dir_k: vec3f, q: vec3f, w: vec3f, d: f32) -> f32 {
    return (d - dot(q, dir_k)) / max(dot(w, dir_k), IMPOSTOR_MIN_COS);
}
