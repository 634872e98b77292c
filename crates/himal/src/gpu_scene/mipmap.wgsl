// renderer.mipmap: one mip level from the previous one (2x2 box via one
// bilinear tap at the texel corner shared by the four parents). sRGB
// levels are decoded by the sampler and re-encoded by the target view, so
// the average is taken in linear light.
#import view
#import fullscreen

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var source_sampler: sampler;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let uv = frag.xy / vec2f(textureDimensions(source, 0)) * 2.0;
    return textureSampleLevel(source, source_sampler, uv, 0.0);
}
