// ao.large_scale (O6): the screen-space AO times the large-scale AO of the
// height field around the pixel (shaders/ao_large_scale.wgsl), at AO
// resolution, between ao.hbao and the pack, so the blur and the temporal
// filter smooth the 4 interleaved samples. Other channels pass through
// (continuity; SSDO's coefficients). Pixels over no resident sector, and
// samples outside them, see no occlusion. One more lookup, at the pixel
// itself, tells whether it is under a roof.
// Bindings: params (AoParams), view, depth (full res), gbuffer_frame,
// jitter_load, raw (ao.hbao's output), skyocc_table, skyocc_heights_load.
// CPU twin: passes/ao/large_scale/reference.rs `large_scale_ao`.
#import view
#import ao
#import math
#import tangent_frame
#import sky_occlusion
#import ao_large_scale
#import fullscreen

@group(0) @binding(0) var<storage, read> params: AoParams;
@group(0) @binding(1) var<uniform> view: View;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var gbuffer_frame: texture_2d<f32>;
@group(0) @binding(4) var jitter_load: texture_2d<f32>;
@group(0) @binding(5) var raw: texture_2d<f32>;
@group(0) @binding(6) var skyocc_table: texture_2d<i32>;
@group(0) @binding(7) var skyocc_heights_load: texture_2d_array<f32>;

// The height field (fade height, m) at world xz; `fallback` where no sector is resident.
fn height_at(xz: vec2f, fallback: f32) -> f32 {
    let layer = sky_occlusion_layer(skyocc_table, xz);
    if (layer < 0) {
        return fallback;
    }
    return sky_occlusion_fade_height(skyocc_heights_load, layer, xz);
}

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let q = vec2i(frag.xy);
    let a = textureLoad(raw, q, 0);
    let full = min(q * i32(params.hbao_steps.z), vec2i(params.full_size.xy) - 1);
    let d = textureLoad(depth, full, 0);
    if (d <= 0.0) {
        return a;
    }
    let p = world_at_fragment(view, vec2f(full) + 0.5, d);
    let n = quat_to_frame(unpack_quat(textureLoad(gbuffer_frame, full, 0)))[2];
    let centre = p.xz + n.xz * SKYOCC_NORMAL_OFFSET;
    let j = textureLoad(jitter_load, q % 4, 0);
    let roof = ao_ls_roof(height_at(p.xz, p.y) - p.y);
    var sum = 0.0;
    var weights = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let s = ao_ls_sample(k, j.x, j.y);
        let w = ao_ls_weight(n, s.xy);
        let h = height_at(centre + s.xy * s.z, p.y);
        sum += w * ao_ls_visibility(h - p.y, s.z, roof);
        weights += w;
    }
    let ls = select(1.0, sum / weights, weights > 0.0);
    return vec4f(a.x * ls, a.yzw);
}
