// CDLOD terrain (passes/terrain): height sampling and the vertex morph,
// shared by the G-buffer and shadow-depth shaders. CPU twin:
// passes/terrain/reference.rs (same expressions, same order).
// Source: Strugar, "Continuous Distance-Dependent Level of Detail for
// Rendering Heightmaps", JGT 2009. Docs: docs/techniques/terrain.md.
// Textures: coarse_load (R32Float, the whole world), fine_load (R32Float
// array, one tile per layer), pages (R32Uint, sectors x sectors: slot or
// TERRAIN_NONE).

const TERRAIN_NONE: u32 = 0xffffffffu;
// Vertices per side of a drawn patch (16 x 16 quads, a quadrant of a node).
const TERRAIN_PATCH_VERTICES: u32 = 17u;

// Twin of ParamsGpu in passes/terrain/mod.rs.
struct TerrainParams {
    origin: vec2f,
    world_size: f32,
    sector_size: f32,
    coarse_spacing: f32,
    fine_spacing: f32,
    coarse_n: u32,
    sectors: u32,
    tile_res: u32,
    layers: u32,
    // 1: continuous morph; 0: k snaps at 1/2 (the popping comparison)
    morph: u32,
    levels: u32,
    // xyz the LOD eye (the camera; shadow views morph as the camera sees)
    eye: vec4f,
    // per level: x morph start, y 1 / (end - start), z vertex spacing, w 1 = coarse grid only
    level: array<vec4f, 16>,
}

// Lower sample and fraction of lattice coordinate u on n samples (clamped).
struct TerrainCell {
    i0: vec2f,
    t: vec2f,
}

fn terrain_cell(u: vec2f, n: u32) -> TerrainCell {
    let last = f32(n - 1u);
    let uc = clamp(u, vec2f(0.0), vec2f(last));
    let i0 = min(floor(uc), vec2f(last - 1.0));
    return TerrainCell(i0, uc - i0);
}

fn terrain_lerp(a: f32, b: f32, t: f32) -> f32 {
    return a * (1.0 - t) + b * t;
}

fn terrain_coarse_height(coarse_load: texture_2d<f32>, p: TerrainParams, xz: vec2f) -> f32 {
    let c = terrain_cell((xz - p.origin) / p.coarse_spacing, p.coarse_n);
    let i = vec2i(c.i0);
    let h00 = textureLoad(coarse_load, i, 0).x;
    let h10 = textureLoad(coarse_load, i + vec2i(1, 0), 0).x;
    let h01 = textureLoad(coarse_load, i + vec2i(0, 1), 0).x;
    let h11 = textureLoad(coarse_load, i + vec2i(1, 1), 0).x;
    return terrain_lerp(terrain_lerp(h00, h10, c.t.x), terrain_lerp(h01, h11, c.t.x), c.t.y);
}

// The resident tile's bilinear sample at xz, else the coarse grid;
// coarse_only for levels whose vertices lie on coarse points.
fn terrain_height(coarse_load: texture_2d<f32>, fine_load: texture_2d_array<f32>, pages: texture_2d<u32>,
        p: TerrainParams, xz: vec2f, coarse_only: bool) -> f32 {
    if (!coarse_only) {
        let last = f32(p.sectors - 1u);
        let s = clamp(floor((xz - p.origin) / p.sector_size), vec2f(0.0), vec2f(last));
        let slot = textureLoad(pages, vec2i(s), 0).x;
        if (slot != TERRAIN_NONE) {
            let corner = p.origin + s * p.sector_size;
            let c = terrain_cell((xz - corner) / p.fine_spacing, p.tile_res);
            let i = vec2i(c.i0);
            let l = i32(slot);
            let h00 = textureLoad(fine_load, i, l, 0).x;
            let h10 = textureLoad(fine_load, i + vec2i(1, 0), l, 0).x;
            let h01 = textureLoad(fine_load, i + vec2i(0, 1), l, 0).x;
            let h11 = textureLoad(fine_load, i + vec2i(1, 1), l, 0).x;
            return terrain_lerp(terrain_lerp(h00, h10, c.t.x), terrain_lerp(h01, h11, c.t.x), c.t.y);
        }
    }
    return terrain_coarse_height(coarse_load, p, xz);
}

// Spacing of the data at xz: fine where a tile is resident, else coarse.
fn terrain_data_spacing(pages: texture_2d<u32>, p: TerrainParams, xz: vec2f) -> f32 {
    let last = f32(p.sectors - 1u);
    let s = clamp(floor((xz - p.origin) / p.sector_size), vec2f(0.0), vec2f(last));
    return select(p.fine_spacing, p.coarse_spacing, textureLoad(pages, vec2i(s), 0).x == TERRAIN_NONE);
}

fn terrain_clamp(p: TerrainParams, xz: vec2f) -> vec2f {
    return clamp(xz, p.origin, p.origin + vec2f(p.world_size));
}

// k = clamp((d - start_l) / (end_l - start_l), 0, 1); snapped without morphing.
fn terrain_morph_k(p: TerrainParams, level: u32, d: f32) -> f32 {
    let lv = p.level[level];
    let k = clamp((d - lv.x) * lv.y, 0.0, 1.0);
    if (p.morph != 0u) {
        return k;
    }
    return select(0.0, 1.0, k >= 0.5);
}

// World position of vertex `index` of the patch at `origin`, `level`:
// odd grid lines slide onto even ones by k (Strugar's morphVertex), then
// the height is sampled at the morphed position.
fn terrain_vertex(coarse_load: texture_2d<f32>, fine_load: texture_2d_array<f32>, pages: texture_2d<u32>,
        p: TerrainParams, origin: vec2f, level: u32, index: u32) -> vec3f {
    let lv = p.level[level];
    let s = lv.z;
    let coarse_only = lv.w > 0.5;
    let g = vec2f(f32(index % TERRAIN_PATCH_VERTICES), f32(index / TERRAIN_PATCH_VERTICES));
    let xz0 = terrain_clamp(p, origin + g * s);
    let h0 = terrain_height(coarse_load, fine_load, pages, p, xz0, coarse_only);
    let d = length(p.eye.xyz - vec3f(xz0.x, h0, xz0.y));
    let k = terrain_morph_k(p, level, d);
    let odd = g - 2.0 * floor(g * 0.5);
    let xz = terrain_clamp(p, origin + (g - odd * k) * s);
    return vec3f(xz.x, terrain_height(coarse_load, fine_load, pages, p, xz, coarse_only), xz.y);
}
