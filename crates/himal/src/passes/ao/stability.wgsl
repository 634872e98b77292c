// ao.stability: dilates the discontinuities of the continuity mask over 4x4 AO
// texels (TECHNIQUES O2, pass 2 of the talk): a pixel is stable only when all 16
// neighbours (offsets -2..+1) are continuous. Target: R8Unorm (1 = stable).
// Bindings: params, hbao_load (ao.hbao output). CPU twin: reference.rs `dilate_stability`.
#import view
#import ao
#import fullscreen

@group(0) @binding(0) var<uniform> params: AoParams;
@group(0) @binding(1) var hbao_load: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let q = vec2i(frag.xy);
    let last = vec2i(params.ao_size.xy) - 1;
    var stable = 1.0;
    for (var y = -2; y <= 1; y++) {
        for (var x = -2; x <= 1; x++) {
            stable = min(stable, textureLoad(hbao_load, clamp(q + vec2i(x, y), vec2i(0), last), 0).y);
        }
    }
    return vec4f(stable, 0.0, 0.0, 1.0);
}
