// Sun shadow lookup shared by the shadow passes (TECHNIQUES S1, Ryse):
// per-pixel rotated Poisson-disk filtering of hardware-compared bilinear taps,
// the cascade choice, and the mask pass's parameters. CPU twin:
// passes/shadows/reference.rs (`poisson_visibility`, `rotation_angle`).
#import math

// 16-tap Poisson disk in the unit circle (minimum distance ~0.3); the first
// four are the outer ring, one per quadrant (early out, below).
const SHADOW_POISSON_16 = array<vec2f, 16>(
    vec2f(-0.94201624, -0.39906216), vec2f(0.94558609, -0.76890725),
    vec2f(0.97484398, 0.75648379), vec2f(-0.81409955, 0.91437590),
    vec2f(-0.09418410, -0.92938870), vec2f(0.34495938, 0.29387760),
    vec2f(-0.91588581, 0.45771432), vec2f(-0.81544232, -0.87912464),
    vec2f(-0.38277543, 0.27676845), vec2f(0.44323325, -0.97511554),
    vec2f(0.53742981, -0.47373420), vec2f(-0.26496911, -0.41893023),
    vec2f(0.79197514, 0.19090188), vec2f(-0.24188840, 0.99706507),
    vec2f(0.19984126, 0.78641367), vec2f(0.14383161, -0.14100790),
);

// Parameters of shadows.mask (twin: passes/shadows/mod.rs `MaskParamsGpu`).
struct ShadowMaskParams {
    // world -> clip of cascades 0..3
    cascades: array<mat4x4f, 4>,
    static_map: mat4x4f,
    hero: mat4x4f,
    // far view distance (along the camera axis) of cascades 0..3 (m)
    splits: vec4f,
    // world size of a texel of cascades 0..3 (m)
    texel: vec4f,
    // depth range of cascades 0..3 (m)
    depth_range: vec4f,
    // x: static map shown (1/0), y: its texel (m), z: its depth range (m),
    // w: first cascade it replaces
    static_info: vec4f,
    // x: hero map on (1/0), y: its texel (m), z: its depth range (m)
    hero_info: vec4f,
    // x: Poisson radius (texels), y: normal offset (texels), z: depth bias (texels),
    // w: number of cascades rendered
    filter_params: vec4f,
    // xyz: camera forward (unit)
    camera_forward: vec4f,
    // world -> light view (rotation only), shared by every map: anchors the
    // disk rotation to world texels
    light_rotation: mat4x4f,
}

// Rotation of the disk for one cell of the shadow map (interleaved gradient
// noise, Jimenez 2014). Keyed on the map's texel, not the screen pixel, so a
// snapped map gives the same pattern at the same world point every frame.
fn shadow_rotation_angle(cell: vec2f) -> f32 {
    return TAU * fract(52.9829189 * fract(dot(cell, vec2f(0.06711056, 0.00583715))));
}

// Visibility in [0,1] at `uv` of layer `layer`: the mean of 16 bilinear
// comparisons (stored >= depth_ref is lit) at Poisson offsets rotated by
// `angle`, scaled to `radius_texels`. When the outer four taps agree (fully
// lit or fully shadowed, most pixels) their mean is returned: a quarter of
// the cost, at the price of missing occluders thinner than the ring's gaps.
fn shadow_poisson_visibility(map: texture_depth_2d_array, cmp: sampler_comparison, layer: i32,
                             uv: vec2f, depth_ref: f32, radius_texels: f32, angle: f32) -> f32 {
    // Unrolled with constant indices: a dynamically indexed copy of the disk
    // was the largest cost of the pass on lavapipe.
    let scale = radius_texels / vec2f(textureDimensions(map));
    let cs = vec2f(cos(angle), sin(angle));
    let ring = shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[0])
        + shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[1])
        + shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[2])
        + shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[3]);
    if (ring == 0.0 || ring == 4.0) {
        return ring / 4.0;
    }
    var sum = ring;
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[4]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[5]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[6]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[7]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[8]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[9]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[10]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[11]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[12]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[13]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[14]);
    sum += shadow_poisson_tap(map, cmp, layer, uv, depth_ref, scale, cs, SHADOW_POISSON_16[15]);
    return sum / 16.0;
}

// One hardware-compared bilinear tap at disk point `o` rotated by (cos, sin) = `cs`.
fn shadow_poisson_tap(map: texture_depth_2d_array, cmp: sampler_comparison, layer: i32,
                      uv: vec2f, depth_ref: f32, scale: vec2f, cs: vec2f, o: vec2f) -> f32 {
    let r = vec2f(o.x * cs.x - o.y * cs.y, o.x * cs.y + o.y * cs.x);
    return textureSampleCompareLevel(map, cmp, uv + r * scale, layer, depth_ref);
}

// Where a receiver reads a map: `uv`, the compare depth and the disk's
// rotation; `inside` false where the map reads lit without a tap (off the
// map, beyond its far plane).
struct ShadowLookup {
    uv: vec2f,
    depth_ref: f32,
    angle: f32,
    inside: bool,
}

// `light_rotation`: world -> light view; the disk's rotation is keyed on the
// world texel (light-view xy / texel), the same cell whatever the map's offset.
fn shadow_map_lookup(light_view_proj: mat4x4f, light_rotation: mat4x4f, p: vec3f, n: vec3f,
                     texel_world: f32, depth_range: f32, filter_params: vec4f) -> ShadowLookup {
    var out: ShadowLookup;
    let q = vec4f(p + n * (filter_params.y * texel_world), 1.0);
    let c = light_view_proj * q;
    out.uv = vec2f(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
    out.inside = all(out.uv >= vec2f(0.0)) && all(out.uv <= vec2f(1.0)) && c.z <= 1.0;
    let cell = floor((light_rotation * q).xy / texel_world);
    out.depth_ref = c.z - filter_params.z * texel_world / depth_range;
    out.angle = shadow_rotation_angle(cell);
    return out;
}

fn shadow_map_visibility(map: texture_depth_2d_array, cmp: sampler_comparison, layer: i32,
                         light_view_proj: mat4x4f, light_rotation: mat4x4f, p: vec3f, n: vec3f,
                         texel_world: f32, depth_range: f32, filter_params: vec4f) -> f32 {
    let l = shadow_map_lookup(light_view_proj, light_rotation, p, n, texel_world, depth_range, filter_params);
    if (!l.inside) {
        return 1.0;
    }
    return shadow_poisson_visibility(map, cmp, layer, l.uv, l.depth_ref, filter_params.x, l.angle);
}

// The lookup of the map `i` (shadow_map_index: 0..3 cascades, 4 static).
fn shadow_world_lookup(params: ShadowMaskParams, i: i32, p: vec3f, n: vec3f) -> ShadowLookup {
    if (i == 4) {
        return shadow_map_lookup(params.static_map, params.light_rotation, p, n, params.static_info.y,
                                 params.static_info.z, params.filter_params);
    }
    return shadow_map_lookup(params.cascades[i], params.light_rotation, p, n, params.texel[i],
                             params.depth_range[i], params.filter_params);
}

// Map a point at view distance `dist` reads: 0..3 cascades, 4 static map, -1 none.
fn shadow_map_index(params: ShadowMaskParams, dist: f32) -> i32 {
    var i = -1;
    let rendered = i32(params.filter_params.w);
    for (var k = 3; k >= 0; k = k - 1) {
        if (dist <= params.splits[k]) {
            i = k;
        }
    }
    let static_on = params.static_info.x > 0.5;
    if (static_on && (i < 0 || i >= i32(params.static_info.w))) {
        return 4;
    }
    if (i >= rendered) {
        return -1;
    }
    return i;
}

// #23 tile classification (shadows.mask_tiles; CPU twins in
// passes/shadows/reference.rs `tile_reach`, `texel_verdict`, `tile_state`).
// A tile's state per map: filter per pixel, lit (every tap passes), shadowed
// (every tap fails).
const SHADOW_TILE_FILTER = 0u;
const SHADOW_TILE_LIT = 1u;
const SHADOW_TILE_SHADOWED = 2u;
// Screen tile edge (pixels), and the most texels per axis of a tile's
// footprint in a map (beyond: filter per pixel; 30² cells of 4 x 4 bytes
// keep the pass in 16 KiB of workgroup memory).
const SHADOW_TILE = 16u;
const SHADOW_TILE_MAX_TEXELS = 30;

// Texels from the one holding a lookup's uv to the farthest that any filter
// tap can read, per axis: a tap reads floor(st) and floor(st) + 1 at
// st = uv * size - 0.5 + offset, |offset| <= 1.03 radius (the disk).
fn shadow_tile_reach(radius_texels: f32) -> i32 {
    return i32(ceil(1.03 * radius_texels + 0.5));
}

// Verdict of one texel of depth z read by lookups with compare depths in
// [ref_min, ref_max]: bit 0 every comparison passes (lit), bit 1 every one
// fails (shadowed). `eps`: margin for rounding between this pass and the
// mask's own lookup, and for a 16-bit map (1/65535).
fn shadow_texel_verdict(z: f32, ref_min: f32, ref_max: f32) -> u32 {
    let eps = 3e-5;
    return select(0u, 1u, z >= ref_max + eps) | select(0u, 2u, z + eps < ref_min);
}

// The state of a map over a tile: `inside` of its `valid` pixels (not sky)
// read it; `read`: one map, footprint small enough; `lit`, `shadowed`:
// every texel's verdict agreed. Shadowed only when every pixel reads it
// (the others are lit).
fn shadow_tile_state(inside: u32, valid: u32, read: bool, lit: bool, shadowed: bool) -> u32 {
    if (inside == 0u) {
        return SHADOW_TILE_LIT;
    }
    if (!read) {
        return SHADOW_TILE_FILTER;
    }
    if (lit) {
        return SHADOW_TILE_LIT;
    }
    if (shadowed && inside == valid) {
        return SHADOW_TILE_SHADOWED;
    }
    return SHADOW_TILE_FILTER;
}

// A point or spot light (S3; twin: passes/shadows/local.rs `LocalLightGpu`).
struct LocalLight {
    // xyz: position, w: range (m)
    position_range: vec4f,
    // rgb: colour x intensity in klux at 1 m, w: 0 point, 1 spot
    color_kind: vec4f,
    // xyz: spot axis, w: cos of the outer half angle
    direction_cos_outer: vec4f,
    // x: cos of the inner half angle, y: shadow-mask channel (0 none, 1..3 = G, B, A),
    // z: first atlas tile, w: unused
    params: vec4f,
}

struct LocalLights {
    // x: number of lights
    count: vec4u,
    lights: array<LocalLight>,
}

// One projector's tile of the shadow atlas (twin: `ShadowTileGpu`).
struct ShadowTile {
    // world -> clip (perspective, depth 0 near .. 1 far)
    view_proj: mat4x4f,
    // xy: atlas uv of the tile's corner, zw: its uv size
    rect: vec4f,
    // x: world texel size per metre of distance
    info: vec4f,
}

// The atlas tile local light `l` (channel > 0) reads at p: its cube face's
// (point) or its one tile (spot); -1 beyond its range.
fn shadow_local_tile(l: LocalLight, p: vec3f) -> i32 {
    let to_p = p - l.position_range.xyz;
    if (length(to_p) >= l.position_range.w) {
        return -1;
    }
    var tile = u32(l.params.z);
    if (l.color_kind.w < 0.5) {
        tile += shadow_cube_face(to_p);
    }
    return i32(tile);
}

// Where p (normal n) reads local light `l`'s atlas tile `t` in an atlas of
// `atlas_size` texels: normal offset and depth bias of 1.5 and 2 texels at
// the receiver's distance.
fn shadow_local_lookup(l: LocalLight, t: ShadowTile, p: vec3f, n: vec3f, atlas_size: vec2f) -> ShadowLookup {
    var out: ShadowLookup;
    out.inside = false;
    let to_p = p - l.position_range.xyz;
    let d = length(to_p);
    let texel = t.info.x * d;
    let q = p + n * (1.5 * texel) - (to_p / d) * (2.0 * texel);
    let c = t.view_proj * vec4f(q, 1.0);
    if (c.w <= 0.0) {
        return out;
    }
    let ndc = c.xyz / c.w;
    let uv_tile = vec2f(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    out.inside = all(uv_tile >= vec2f(0.0)) && all(uv_tile <= vec2f(1.0)) && ndc.z <= 1.0;
    out.uv = t.rect.xy + uv_tile * t.rect.zw;
    out.depth_ref = ndc.z;
    out.angle = shadow_rotation_angle(floor(out.uv * atlas_size));
    return out;
}

// Visibility of surface point p (normal n) from local light `l` through
// its atlas tile `t` (from shadow_local_tile): S1's rotated Poisson filter
// of `radius` texels; 1 off the tile. shadows.mask per pixel, forward.blend
// per fragment.
fn shadow_local_visibility(l: LocalLight, t: ShadowTile, p: vec3f, n: vec3f,
                           atlas: texture_depth_2d_array, cmp: sampler_comparison, radius: f32) -> f32 {
    let k = shadow_local_lookup(l, t, p, n, vec2f(textureDimensions(atlas)));
    if (!k.inside) {
        return 1.0;
    }
    return shadow_poisson_visibility(atlas, cmp, 0, k.uv, k.depth_ref, radius, k.angle);
}

// Windowed inverse square: 1/d² · (1 − (d/range)⁴)², zero at the range
// (Karis 2013), d clamped to 1 cm.
fn local_light_falloff(d: f32, range: f32) -> f32 {
    let x = d / range;
    let window = clamp(1.0 - x * x * x * x, 0.0, 1.0);
    return window * window / max(d * d, 1e-4);
}

// Spot cone: 1 inside the inner angle, 0 outside the outer, smooth between.
fn spot_cone(cos_angle: f32, cos_outer: f32, cos_inner: f32) -> f32 {
    return smoothstep(cos_outer, cos_inner, cos_angle);
}

// A point without a normal (a particle, E4) seen by local light `l`
// through its atlas tile `t` (from shadow_local_tile): the 4 x 4 gather of
// the sun's particle shadow (R2), 1 off the tile. Twin:
// passes/shadows/reference.rs `local_point_visibility`.
fn shadow_local_point_visibility(l: LocalLight, t: ShadowTile, p: vec3f,
                                 atlas: texture_depth_2d_array, cmp: sampler_comparison) -> f32 {
    let k = shadow_local_lookup(l, t, p, vec3f(0.0), vec2f(textureDimensions(atlas)));
    if (!k.inside) {
        return 1.0;
    }
    return shadow_gather_4x4(atlas, cmp, 0, k.uv, k.depth_ref);
}

// Cube face of direction `d` (light to point): 0..5 = +X, -X, +Y, -Y, +Z, -Z.
fn shadow_cube_face(d: vec3f) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x > 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

// R2 (Ryse, particle shadows): the 4 x 4 texels around `uv`, each compared
// (stored >= depth_ref is lit), weighted per axis by a 3-tap binomial
// shifted bilinearly, (1 - f, 2 - f, 1 + f, f) / 4: a smooth Gaussian-like
// filter from four textureGatherCompare calls. CPU twin:
// passes/shadows/reference.rs `DepthMap::gather_4x4`.
fn shadow_gather_4x4(map: texture_depth_2d_array, cmp: sampler_comparison, layer: i32,
                     uv: vec2f, depth_ref: f32) -> f32 {
    let size = vec2f(textureDimensions(map));
    let st = uv * size - 0.5;
    let b = floor(st);
    let f = st - b;
    let wx = vec4f(1.0 - f.x, 2.0 - f.x, 1.0 + f.x, f.x) * 0.25;
    let wy = vec4f(1.0 - f.y, 2.0 - f.y, 1.0 + f.y, f.y) * 0.25;
    var v = 0.0;
    for (var j = 0; j < 2; j++) {
        for (var i = 0; i < 2; i++) {
            // The corner between texels b + 2i - 1 and b + 2i (per axis):
            // x = (0, 1), y = (1, 1), z = (1, 0), w = (0, 0) of that quad.
            let g = textureGatherCompare(map, cmp, (b + vec2f(f32(2 * i), f32(2 * j))) / size, layer, depth_ref);
            let x0 = 2 * i;
            let y0 = 2 * j;
            v += wx[x0] * wy[y0] * g.w + wx[x0 + 1] * wy[y0] * g.z
                + wx[x0] * wy[y0 + 1] * g.x + wx[x0 + 1] * wy[y0 + 1] * g.y;
        }
    }
    return v;
}

// The sun's visibility at a point without a surface (a particle, E4, Ryse
// "Particle Shadows"): the static map wherever S2 shows one and it covers
// the point (no cascades), else the cascade its view distance `dist`
// reads; no normal offset (no surface), the mask's depth bias, the 4 x 4
// gather filter (R2).
fn shadow_point_visibility(params: ShadowMaskParams, cascades: texture_depth_2d_array,
                           static_map: texture_depth_2d_array, cmp: sampler_comparison,
                           p: vec3f, dist: f32) -> f32 {
    if (params.static_info.x > 0.5) {
        let c = params.static_map * vec4f(p, 1.0);
        let uv = vec2f(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
        if (all(uv >= vec2f(0.0)) && all(uv <= vec2f(1.0)) && c.z <= 1.0) {
            let depth_ref = c.z - params.filter_params.z * params.static_info.y / params.static_info.z;
            return shadow_gather_4x4(static_map, cmp, 0, uv, depth_ref);
        }
    }
    let i = shadow_map_index(params, dist);
    if (i < 0 || i == 4) {
        return 1.0;
    }
    let c = params.cascades[i] * vec4f(p, 1.0);
    let uv = vec2f(c.x * 0.5 + 0.5, 0.5 - c.y * 0.5);
    if (any(uv < vec2f(0.0)) || any(uv > vec2f(1.0)) || c.z > 1.0) {
        return 1.0;
    }
    let depth_ref = c.z - params.filter_params.z * params.texel[i] / params.depth_range[i];
    return shadow_gather_4x4(cascades, cmp, i, uv, depth_ref);
}

// The world's sun visibility at p (normal n, view distance `dist`): the
// map shadow_map_index picks (cascade, else the static map beyond them),
// S1's rotated Poisson filter. shadows.mask per pixel; E4's per-pixel
// cascaded reference for particles (n = 0).
fn shadow_world_visibility(params: ShadowMaskParams, cascades: texture_depth_2d_array,
                           static_map: texture_depth_2d_array, cmp: sampler_comparison,
                           p: vec3f, n: vec3f, dist: f32) -> f32 {
    let i = shadow_map_index(params, dist);
    if (i < 0) {
        return 1.0;
    }
    let l = shadow_world_lookup(params, i, p, n);
    if (!l.inside) {
        return 1.0;
    }
    if (i == 4) {
        return shadow_poisson_visibility(static_map, cmp, 0, l.uv, l.depth_ref, params.filter_params.x, l.angle);
    }
    return shadow_poisson_visibility(cascades, cmp, i, l.uv, l.depth_ref, params.filter_params.x, l.angle);
}

// Illuminance (klux) at p from local light `l` and the unit direction to
// it; `lit` false outside its range (S3: windowed inverse square, spot cone).
struct LocalIlluminance {
    e: vec3f,
    dir: vec3f,
    lit: bool,
}

fn local_light_illuminance(l: LocalLight, p: vec3f) -> LocalIlluminance {
    var out: LocalIlluminance;
    out.lit = false;
    let to_l = l.position_range.xyz - p;
    let d = length(to_l);
    if (d >= l.position_range.w || d <= 0.0) {
        return out;
    }
    let dir = to_l / d;
    var e = l.color_kind.rgb * local_light_falloff(d, l.position_range.w);
    if (l.color_kind.w > 0.5) {
        e *= spot_cone(dot(-dir, l.direction_cos_outer.xyz), l.direction_cos_outer.w, l.params.x);
    }
    out.e = e;
    out.dir = dir;
    out.lit = true;
    return out;
}
