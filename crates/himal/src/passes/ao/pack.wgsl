// ao.pack: full-resolution (AO, Z) for the blur (TECHNIQUES O3): AO upsampled
// bilinearly from the AO resolution, Z the linear view depth (m) of the pixel.
// SSDO (O4): Rgba16Float (AO, Z, c1, c2), the directional coefficients upsampled alike.
// Target: Rg16Float. Bindings: params, depth, hbao (ao.hbao output), linear_sampler.
// CPU twin: reference.rs `pack`.
#import view
#import ao
#import fullscreen

override SSDO: bool = false;

@group(0) @binding(0) var<uniform> params: AoParams;
@group(0) @binding(1) var depth: texture_depth_2d;
@group(0) @binding(2) var hbao: texture_2d<f32>;
@group(0) @binding(3) var linear_sampler: sampler;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let v = ao_pack(params, depth, hbao, linear_sampler, vec2i(frag.xy));
    if (SSDO) {
        return v;
    }
    return vec4f(v.xy, 0.0, 1.0);
}
