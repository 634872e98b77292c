// ao.blur_x: horizontal cross-bilateral blur of (AO, Z) (TECHNIQUES O3).
// Target: Rg16Float (AO, Z), or Rgba16Float (AO, Z, c1, c2) with SSDO (O4: the
// directional coefficients take the AO's weights). Bindings: params, packed (ao.pack output), linear_sampler.
// Kernel: shaders/ao.wgsl `ao_cross_bilateral`. CPU twin: reference.rs `blur`.
#import view
#import ao
#import fullscreen

@group(0) @binding(0) var<uniform> params: AoParams;
@group(0) @binding(1) var packed: texture_2d<f32>;
@group(0) @binding(2) var linear_sampler: sampler;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let r = ao_cross_bilateral(packed, linear_sampler, vec2i(frag.xy), vec2i(1, 0), params);
    return r;
}
