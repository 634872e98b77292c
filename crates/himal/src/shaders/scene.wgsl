// Scene data shared by passes that draw meshes (twin: renderer/scene_gpu.rs `ObjectGpu`),
// and the vegetation functions those passes share: sway and alpha patterns
// (docs/techniques/vegetation.md; card conventions in scene/vegetation.rs).
#import math

struct Object {
    model: mat4x4f,
    // inverse transpose of model (for normals), 3x3 part used
    normal_matrix: mat4x4f,
    prev_model: mat4x4f,
    // x: alpha pattern (0 opaque, 1 grass, 2 leaves, 3 tinted opaque); y: sway
    // amplitude (m); zw: leaves' sway weight (local y of the bottom, 1 / height);
    // tinted: yzw the albedo tint
    params: vec4f,
}

const FOLIAGE_GRASS: u32 = 1u;
const FOLIAGE_LEAVES: u32 = 2u;

fn foliage_pattern(o: Object) -> u32 {
    return u32(o.params.x + 0.5);
}

// An opaque object whose albedo params.yzw multiplies (streamed world
// instances, gpu_scene OBJECT_TINTED).
const OBJECT_TINTED: u32 = 3u;

fn object_tint(o: Object) -> vec3f {
    if (foliage_pattern(o) == OBJECT_TINTED) {
        return o.params.yzw;
    }
    return vec3f(1.0);
}

// Sway weight: 0 at the root, 1 at the tip, quadratic (stiff base, supple tip).
fn foliage_sway_weight(o: Object, local: vec3f, uv: vec2f) -> f32 {
    var h = uv.y;
    if (foliage_pattern(o) == FOLIAGE_LEAVES) {
        h = clamp((local.y - o.params.z) * o.params.w, 0.0, 1.0);
    }
    return h * h;
}

// Horizontal world displacement at time t (s) of a vertex at rest at world
// xz `rest`: amplitude * weight * (two low frequencies, 0.4 and 1.1 Hz,
// phase from the position, so neighbouring clumps sway out of step). Each
// component stays within amplitude * weight.
fn foliage_sway(o: Object, local: vec3f, uv: vec2f, rest: vec2f, t: f32) -> vec3f {
    // Literals, not TAU: naga folds these abstract products in f64, and
    // TAU * 1.1 (f32) rounds differently, moving the cards.
    let w1 = 6.2831853 * 0.4;
    let w2 = 6.2831853 * 1.1;
    let phase = dot(rest, vec2f(0.9, 0.6));
    let s = vec2f(
        0.7 * sin(w1 * t + phase) + 0.3 * sin(w2 * t + 1.7 * phase + 1.0),
        0.7 * sin(w1 * t + phase + 1.9) + 0.3 * sin(w2 * t + 2.3 * phase),
    );
    let a = o.params.y * foliage_sway_weight(o, local, uv);
    return vec3f(s.x, 0.0, s.y) * a;
}

// Integer hash (PCG output permutation): a card's blades from its seed.
fn foliage_hash(n: u32) -> u32 {
    let state = n * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn foliage_unit(h: u32, shift: u32) -> f32 {
    return f32((h >> shift) & 255u) / 255.0;
}

// V5 leaf flutter: value noise over a leaf card (5 cells across), drifting
// with time t (s); each component in [-1, 1] (CPU twin
// passes/vegetation/reference.rs `leaf_flutter`).
fn leaf_flutter(uv: vec2f, t: f32) -> vec2f {
    let p = uv * 5.0 + vec2f(1.7, 1.3) * t;
    let i = floor(p);
    let f = fract(p);
    let s = f * f * (3.0 - 2.0 * f);
    var c: array<vec2f, 4>;
    for (var k = 0u; k < 4u; k++) {
        let q = vec2i(i) + vec2i(i32(k & 1u), i32(k >> 1u));
        let h = foliage_hash(bitcast<u32>(q.x) * 1973u + bitcast<u32>(q.y) * 9277u + 26699u);
        c[k] = vec2f(foliage_unit(h, 0u), foliage_unit(h, 8u)) * 2.0 - 1.0;
    }
    return mix(mix(c[0], c[1], s.x), mix(c[2], c[3], s.x), s.y);
}

// Largest tilt of a leaf's normal by the flutter, at 10 m/s of wind or more.
const LEAF_FLUTTER: f32 = 0.35;

// The leaf normal n (tangent t) tilted by the flutter at uv, time, in a
// wind of `speed` m/s.
fn leaf_flutter_normal(n: vec3f, t: vec3f, uv: vec2f, time: f32, speed: f32) -> vec3f {
    let f = leaf_flutter(uv, time) * (LEAF_FLUTTER * min(speed / 10.0, 1.0));
    let b = cross(n, t);
    return normalize(n + t * f.x + b * f.y);
}

// Grass card: four tapered blades of 55..100 % of the card's height,
// leaning a little; 1 inside a blade, 0 elsewhere. uv.x integer part = seed.
fn foliage_grass_alpha(uv: vec2f) -> f32 {
    let seed = u32(max(floor(uv.x), 0.0));
    let u = fract(uv.x);
    let v = uv.y;
    for (var i = 0u; i < 4u; i++) {
        let h = foliage_hash(seed * 16u + i);
        let top = 0.55 + 0.45 * foliage_unit(h, 0u);
        let centre = (f32(i) + 0.25 + 0.5 * foliage_unit(h, 8u)) / 4.0;
        let lean = (foliage_unit(h, 16u) - 0.5) * 0.25;
        let f = v / top;
        let half_width = 0.09 * (1.0 - f);
        if (f < 1.0 && abs(u - centre - lean * f * f) < half_width) {
            return 1.0;
        }
    }
    return 0.0;
}

// Leaf card: five ellipses (leaves) at random places and angles.
fn foliage_leaves_alpha(uv: vec2f) -> f32 {
    let seed = u32(max(floor(uv.x), 0.0));
    let p = vec2f(fract(uv.x), uv.y);
    for (var i = 0u; i < 5u; i++) {
        let h = foliage_hash(seed * 16u + i + 7u);
        let c = vec2f(0.22 + 0.56 * foliage_unit(h, 0u), 0.22 + 0.56 * foliage_unit(h, 8u));
        let a = PI * foliage_unit(h, 16u);
        let d = p - c;
        let q = vec2f(d.x * cos(a) + d.y * sin(a), -d.x * sin(a) + d.y * cos(a));
        let size = vec2f(0.27, 0.13) * (0.8 + 0.4 * foliage_unit(h, 24u));
        let e = q / size;
        if (dot(e, e) < 1.0) {
            return 1.0;
        }
    }
    return 0.0;
}

// Alpha of a vegetation card at uv for `pattern` (1 everywhere for 0).
fn foliage_alpha(pattern: u32, uv: vec2f) -> f32 {
    switch pattern {
        case 1u: { return foliage_grass_alpha(uv); }
        case 2u: { return foliage_leaves_alpha(uv); }
        default: { return 1.0; }
    }
}

// V6 / E2: an instance entry (passes/cull) is the object (bits 0-23) and
// its LOD fade code (bits 24-31; 0 steady, and always in the identity list).
fn instance_object(entry: u32) -> u32 {
    return entry & 0xffffffu;
}

fn instance_fade(entry: u32) -> u32 {
    return entry >> 24u;
}

// E2 dithered transitions: a 4x4 ordered (Bayer) threshold at `pixel`.
// Code 1 + q (fading out) keeps where the threshold is >= q / 126, code
// 128 + q (fading in) where it is below: one object's two levels cover
// complementary pixels, so the change spreads over the band, not one frame.
fn lod_dither_keep(code: u32, pixel: vec2f) -> bool {
    if (code == 0u) {
        return true;
    }
    let bayer = array<f32, 16>(0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0,
                               3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    let p = vec2u(pixel) % vec2u(4u);
    let threshold = (bayer[p.y * 4u + p.x] + 0.5) / 16.0;
    if (code < 128u) {
        return threshold >= f32(code - 1u) / 126.0;
    }
    return threshold < f32(code - 128u) / 126.0;
}
