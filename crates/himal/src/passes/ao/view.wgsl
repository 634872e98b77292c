// ao.view: the AO debug views (`himal render --view ao|ao-raw|stability-mask`).
// VIEW: 1 = ao (filtered; raw values: AO, Z, N), 2 = ao-raw (HBAO before blur and
// filter; raw: AO, continuity[, c1, c2 with SSDO]), 3 = stability-mask (1 = stable: temporal filter off),
// 4 = ssdo (O4 directional term, filtered; raw: AO, c1, c2; shown as
// 0.5 + c1, 0.5 + c2, AO: red/green where the horizon rises toward screen +x/+y).
// DISPLAY = true writes viewable grey levels, false raw values (EXR).
// Bindings: params, ao (filtered, full res), hbao_load, stability_load (AO resolution).
#import view
#import color
#import ao
#import fullscreen

override VIEW: u32 = 1u;
override DISPLAY: bool = true;

@group(0) @binding(0) var<uniform> params: AoParams;
@group(0) @binding(1) var ao: texture_2d<f32>;
@group(0) @binding(2) var hbao_load: texture_2d<f32>;
@group(0) @binding(3) var stability_load: texture_2d<f32>;
@group(0) @binding(4) var ao_dir: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let q = min(px / i32(params.hbao_steps.z), vec2i(params.ao_size.xy) - 1);
    var raw: vec4f;
    switch VIEW {
        // Two-channel textures read (AO, continuity, 0, 1); SSDO adds (c1, c2).
        case 2u: { raw = textureLoad(hbao_load, q, 0); }
        case 3u: { raw = vec4f(textureLoad(stability_load, q, 0).x, 0.0, 0.0, 1.0); }
        case 4u: { raw = vec4f(textureLoad(ao, px, 0).x, textureLoad(ao_dir, px, 0).xy, 1.0); }
        default: { raw = vec4f(textureLoad(ao, px, 0).xyz, 1.0); }
    }
    if (!DISPLAY) {
        return raw;
    }
    if (VIEW == 4u) {
        return vec4f(srgb_to_linear(clamp(vec3f(0.5 + raw.y, 0.5 + raw.z, raw.x), vec3f(0.0), vec3f(1.0))), 1.0);
    }
    // The sRGB target encodes; store the grey level as linear so the PNG shows it as is.
    return vec4f(srgb_to_linear(vec3f(clamp(raw.x, 0.0, 1.0))), 1.0);
}
