// terrain.shadow: the camera's CDLOD patches (morphed as the camera sees
// them, so shadows match the G-buffer) as depth into a sun map, drawn into
// a cascade layer by the shadow pass (standard depth, LessEqual, as
// passes/shadows/depth.wgsl). `shadow` is the cascade's ShadowView buffer;
// only its first member is read.
#import terrain

struct TerrainShadowView {
    light_view_proj: mat4x4f,
}

@group(0) @binding(0) var<uniform> shadow: TerrainShadowView;
@group(0) @binding(1) var<storage, read> terrain: TerrainParams;
@group(0) @binding(2) var coarse_load: texture_2d<f32>;
@group(0) @binding(3) var fine_load: texture_2d_array<f32>;
@group(0) @binding(4) var pages: texture_2d<u32>;

@vertex
fn vs_main(@location(0) origin: vec2f, @location(1) level: u32,
        @builtin(vertex_index) index: u32) -> @builtin(position) vec4f {
    let w = terrain_vertex(coarse_load, fine_load, pages, terrain, origin, level, index);
    return shadow.light_view_proj * vec4f(w, 1.0);
}
