// Sky occlusion (TECHNIQUES L2): SH2 visibility of a spherical cap, bent
// normal, fade with height above the terrain, and the sector lookup.
// Twin: crates/himal/src/passes/skyocc/reference.rs (constants there too).
// SH2 layout: [L00, L1-1 (y), L10 (z), L11 (x)], the first four of sh.wgsl.

// SH2SphericalCap constants: sqrt(pi) and pi * Y1 / 2 (reference.rs).
const SKYOCC_CAP_C0: f32 = 1.7724539;
const SKYOCC_CAP_C2: f32 = 0.767495;
const SKYOCC_Y0: f32 = 0.282095;
const SKYOCC_Y1: f32 = 0.488603;
// Sector edge (m), texels per edge, sector table edge (passes/skyocc/pool.rs).
const SKYOCC_SECTOR_SIZE: f32 = 64.0;
const SKYOCC_SECTOR_TEXELS: i32 = 256;
const SKYOCC_TABLE_SIZE: i32 = 32;
// The lookup point moves this far (m) along the normal, off walls onto the
// ground in front of them, beyond the demo's 0.6 m eaves.
const SKYOCC_NORMAL_OFFSET: f32 = 0.75;

// Zonal cap of half angle A about the axis: (L0, axial L1), as in the talk.
fn sh2_spherical_cap(cos_a: f32) -> vec2f {
    let cos_2a = 2.0 * cos_a * cos_a - 1.0;
    return vec2f(SKYOCC_CAP_C0 * (1.0 - cos_a), SKYOCC_CAP_C2 * (1.0 - cos_2a));
}

// Cap of solid angle 2 pi f (cos A = 1 - f) rotated from +Y to the mean
// visible direction: the L1 band is a vector along d.
fn sh2_from_visibility(f: f32, sum: vec3f) -> vec4f {
    var d = vec3f(0.0, 1.0, 0.0);
    if (dot(sum, sum) > 0.0) {
        d = normalize(sum);
    }
    let cap = sh2_spherical_cap(1.0 - clamp(f, 0.0, 1.0));
    return vec4f(cap.x, cap.y * d.y, cap.y * d.z, cap.y * d.x);
}

fn sh2_open_sky() -> vec4f {
    return sh2_from_visibility(1.0, vec3f(0.0, 1.0, 0.0));
}

// Unoccluded: the whole sphere (cos A = -1): visibility 1 along every
// normal, no bending. "Fully visible" of the fade and of absent sectors.
fn sh2_unoccluded() -> vec4f {
    return vec4f(2.0 * SKYOCC_CAP_C0, 0.0, 0.0, 0.0);
}

fn sh2_primary_direction(sh: vec4f) -> vec3f {
    let d = vec3f(sh.w, sh.y, sh.z);
    if (dot(d, d) > 0.0) {
        return normalize(d);
    }
    return vec3f(0.0, 1.0, 0.0);
}

fn bent_normal_from_sh_visibility(n: vec3f, sh: vec4f) -> vec3f {
    let factor = saturate(1.0 - sh.x / SKYOCC_CAP_C0);
    return normalize(n + sh2_primary_direction(sh) * factor);
}

// Cosine-convolved SH2 (bands x 1, 2/3) at n, clamped: diffuse sky visibility.
fn sh2_visibility_cosine(sh: vec4f, n: vec3f) -> f32 {
    let v = sh.x * SKYOCC_Y0 + (2.0 / 3.0) * SKYOCC_Y1 * (sh.y * n.y + sh.z * n.z + sh.w * n.x);
    return clamp(v, 0.0, 1.0);
}

// Full occlusion at the terrain height, none at the fade (blurred) height.
fn sky_occlusion_fade(sh: vec4f, y: f32, h_terrain: f32, h_blurred: f32) -> vec4f {
    let t = saturate((y - h_terrain) / max(h_blurred - h_terrain, 0.1));
    return mix(sh, sh2_unoccluded(), t);
}

// The pool layer of the sector holding world xz, -1 where none is resident.
fn sky_occlusion_layer(table: texture_2d<i32>, xz: vec2f) -> i32 {
    let sector = vec2i(floor(xz / SKYOCC_SECTOR_SIZE));
    let slot = ((sector % SKYOCC_TABLE_SIZE) + SKYOCC_TABLE_SIZE) % SKYOCC_TABLE_SIZE;
    let entry = textureLoad(table, slot, 0);
    if (entry.w == 0 || entry.x != sector.x || entry.y != sector.y) {
        return -1;
    }
    return entry.z;
}

// The fade height (the blurred height field, m) at world xz in pool layer
// `layer`, nearest texel (O6 samples it over metres).
fn sky_occlusion_fade_height(heights: texture_2d_array<f32>, layer: i32, xz: vec2f) -> f32 {
    let local = xz / SKYOCC_SECTOR_SIZE - floor(xz / SKYOCC_SECTOR_SIZE);
    let last = vec2i(SKYOCC_SECTOR_TEXELS - 1);
    let t = clamp(vec2i(floor(local * f32(SKYOCC_SECTOR_TEXELS))), vec2i(0), last);
    return textureLoad(heights, t, layer, 0).y;
}

// SH2 visibility at world point p with normal n: sector table -> pool layer,
// bilinear SH and (terrain, fade) heights, faded; unoccluded where no sector is resident.
fn sky_occlusion_lookup(
    table: texture_2d<i32>,
    vis: texture_2d_array<f32>,
    heights: texture_2d_array<f32>,
    bilinear: sampler,
    p: vec3f,
    n: vec3f,
) -> vec4f {
    let xz = p.xz + n.xz * SKYOCC_NORMAL_OFFSET;
    let layer = sky_occlusion_layer(table, xz);
    if (layer < 0) {
        return sh2_unoccluded();
    }
    let local = xz / SKYOCC_SECTOR_SIZE - floor(xz / SKYOCC_SECTOR_SIZE);
    let sh = textureSampleLevel(vis, bilinear, local, layer, 0.0);
    // Heights bilinear by hand (Rg32Float is not filterable); nearest texels
    // step every 25 cm, which streaks walls.
    let tc = local * f32(SKYOCC_SECTOR_TEXELS) - 0.5;
    let t0 = floor(tc);
    let f = tc - t0;
    let last = vec2i(SKYOCC_SECTOR_TEXELS - 1);
    let i0 = clamp(vec2i(t0), vec2i(0), last);
    let i1 = clamp(vec2i(t0) + 1, vec2i(0), last);
    let h00 = textureLoad(heights, i0, layer, 0).xy;
    let h10 = textureLoad(heights, vec2i(i1.x, i0.y), layer, 0).xy;
    let h01 = textureLoad(heights, vec2i(i0.x, i1.y), layer, 0).xy;
    let h11 = textureLoad(heights, i1, layer, 0).xy;
    let h = mix(mix(h00, h10, f.x), mix(h01, h11, f.x), f.y);
    return sky_occlusion_fade(sh, p.y, h.x, h.y);
}

// One sector rendered this frame (passes/skyocc resources.rs `JobGpu`).
struct SectorJob {
    // xy: world x, z of the rendered image's corner (texel (0, 0) min)
    origin: vec4f,
    // x: pool layer written
    layer: vec4u,
}
