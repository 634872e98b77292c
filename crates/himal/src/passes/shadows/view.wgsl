// shadows.view: `--view shadow-mask` (VIEW 1: raw, the mask's RGBA as stored;
// displayed, R·(G, B, A): the sun in grey, local lights' shadows coloured) and
// `--view cascades` (VIEW 2: sun visibility tinted by the map the pixel reads:
// red, green, blue, yellow = cascades 0..3, magenta = static map, grey = none).
// DISPLAY = true writes viewable values (sRGB target), false raw (EXR).
// Bindings: view, params (ShadowMaskParams), depth, mask.
#import view
#import color
#import shadow
#import fullscreen

override VIEW: u32 = 1u;
override DISPLAY: bool = true;

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<uniform> params: ShadowMaskParams;
@group(0) @binding(2) var depth: texture_depth_2d;
@group(0) @binding(3) var mask: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let px = vec2i(frag.xy);
    let m = textureLoad(mask, px, 0);
    var c = m;
    if (VIEW == 1u && DISPLAY) {
        // Sun in grey; a local light's shadow (G, B, A) removes one primary.
        c = vec4f(m.r * m.gba, 1.0);
    }
    if (VIEW == 2u) {
        let d = textureLoad(depth, px, 0);
        var tint = vec3f(0.0);
        if (d > 0.0) {
            let p = world_at_fragment(view, frag.xy, d);
            let dist = dot(p - view.camera_position.xyz, params.camera_forward.xyz);
            switch shadow_map_index(params, dist) {
                case 0: { tint = vec3f(1.0, 0.25, 0.25); }
                case 1: { tint = vec3f(0.25, 1.0, 0.25); }
                case 2: { tint = vec3f(0.3, 0.45, 1.0); }
                case 3: { tint = vec3f(1.0, 1.0, 0.25); }
                case 4: { tint = vec3f(1.0, 0.3, 1.0); }
                default: { tint = vec3f(0.5); }
            }
        }
        // Shadowed pixels keep a third of the tint so the bands stay readable.
        c = vec4f(tint * (0.35 + 0.65 * m.r), 1.0);
    }
    if (DISPLAY) {
        return vec4f(srgb_to_linear(clamp(c.rgb, vec3f(0.0), vec3f(1.0))), 1.0);
    }
    return c;
}
