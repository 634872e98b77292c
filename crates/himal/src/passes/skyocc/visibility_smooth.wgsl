// skyocc.visibility (second dispatch): 5x5 binomial smoothing (1 4 6 4 1 / 16
// in x and y) of the SH2 visibility computed for the sector and a BORDER ring,
// written to the sector's pool layer. The per-texel rotation of the Poisson
// disk leaves about ±1/32 of noise per texel, which shows as streaks on walls
// where a 25 cm texel spans many pixels (TECHNIQUES L2).
// Twin: passes/skyocc/reference.rs `sector_visibility`.
#import sky_occlusion

override BORDER: i32 = 2;

@group(0) @binding(0) var vis_load: texture_2d_array<f32>;
@group(0) @binding(1) var<storage, read> jobs: array<SectorJob>;
@group(0) @binding(2) var vis_out: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_main(@builtin(global_invocation_id) id: vec3u) {
    let inner = vec2i(textureDimensions(vis_out));
    let u = vec2i(id.xy);
    if (u.x >= inner.x || u.y >= inner.y) {
        return;
    }
    let layer = i32(id.z);
    let w = array<f32, 5>(1.0 / 16.0, 4.0 / 16.0, 6.0 / 16.0, 4.0 / 16.0, 1.0 / 16.0);
    var s = vec4f(0.0);
    for (var j = 0; j < 5; j = j + 1) {
        for (var i = 0; i < 5; i = i + 1) {
            s += (w[i] * w[j]) * textureLoad(vis_load, u + vec2i(i, j) + vec2i(BORDER - 2), layer, 0);
        }
    }
    textureStore(vis_out, u, i32(jobs[id.z].layer.x), s);
}
