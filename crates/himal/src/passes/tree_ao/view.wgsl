// vegetation.ao.view: `--view tree-ao`, the factor the trees' occlusion
// volumes put on the sky light (grey; white outside every box). DISPLAY =
// true writes viewable values (sRGB target), false the raw factor (EXR).
#import color
#import fullscreen

override DISPLAY: bool = true;

@group(0) @binding(0) var factor: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let a = textureLoad(factor, vec2i(frag.xy), 0).x;
    if (DISPLAY) {
        return vec4f(srgb_to_linear(vec3f(a)), 1.0);
    }
    return vec4f(vec3f(a), 1.0);
}
