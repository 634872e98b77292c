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
    let px = vec2i(frag.xy);
    let z = ao_linear_depth(params, textureLoad(depth, px, 0));
    // AO texel q holds the full-res pixel q * scale, so pixel px sits at q = px / scale.
    let uv = (vec2f(px) / params.hbao_steps.z + 0.5) * params.ao_size.zw;
    let ao = textureSampleLevel(hbao, linear_sampler, uv, 0.0);
    if (SSDO) {
        return vec4f(ao.x, z, ao.zw);
    }
    return vec4f(ao.x, z, 0.0, 1.0);
}
