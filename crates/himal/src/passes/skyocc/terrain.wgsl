// skyocc.terrain: the streamed world's terrain into one sector's height
// images (TECHNIQUES L2): per texel centre the height data's bilinear
// sample (`terrain_height`: the resident tile, else the coarse grid) as
// world height in the raw and the ground image, and as depth in the
// sector's orthographic mapping, so the objects drawn after it
// (skyocc.ground, skyocc.heightfield, depth LessEqual) keep the highest
// surface. Texels outside the world are left at the cleared bottom.
#import terrain
#import fullscreen

struct SectorView {
    view_proj: mat4x4f,
    // xy world x, z of texel (0, 0)'s corner; z the texel size (m)
    origin: vec4f,
}

@group(0) @binding(0) var<uniform> sector: SectorView;
@group(0) @binding(1) var<storage, read> terrain: TerrainParams;
@group(0) @binding(2) var coarse_load: texture_2d<f32>;
@group(0) @binding(3) var fine_load: texture_2d_array<f32>;
@group(0) @binding(4) var pages: texture_2d<u32>;

struct TerrainOut {
    @location(0) raw: vec4f,
    @location(1) ground: vec4f,
    @builtin(frag_depth) depth: f32,
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> TerrainOut {
    let xz = sector.origin.xy + frag.xy * sector.origin.z;
    if (any(xz < terrain.origin) || any(xz > terrain.origin + vec2f(terrain.world_size))) {
        discard;
    }
    let h = terrain_height(coarse_load, fine_load, pages, terrain, xz, false);
    let clip = sector.view_proj * vec4f(xz.x, h, xz.y, 1.0);
    var out: TerrainOut;
    out.raw = vec4f(h, 0.0, 0.0, 1.0);
    out.ground = out.raw;
    out.depth = clamp(clip.z, 0.0, 1.0);
    return out;
}
