// ao.bleed.view: `--view ao-bleed`, the O5 bleed colour (coverage-normalised
// low-frequency albedo) each pixel's ambient occlusion is tinted with,
// nearest texel (raw: rgb, coverage in a).
#import ao_bleed
#import fullscreen

override VIEW: u32 = 4u;
override DISPLAY: bool = true;

@group(0) @binding(0) var bleed: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let t = textureLoad(bleed, min(vec2i(frag.xy) / 4, vec2i(textureDimensions(bleed)) - 1), 0);
    if (!DISPLAY) {
        return t;
    }
    // Linear albedo into the sRGB target: shown as the surfaces' colours.
    return vec4f(clamp(ao_bleed_colour(t), vec3f(0.0), vec3f(1.0)), 1.0);
}
