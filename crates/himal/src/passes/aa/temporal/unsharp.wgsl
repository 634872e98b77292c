// aa.unsharp: 0.5-pixel unsharp mask after the resolve (TECHNIQUES A4; Far Cry
// 4 "high frequency recovery": 0.5 px box blur (FLIPQUAD resolve) + 0.5 px
// unsharp approximates a 4-tap sinc):
//   out = c + s * (c - blur(c)),  blur = [1 2 1]/4 x [1 2 1]/4 (0.5 px radius tent)
// CPU twin: temporal/reference.rs.
#import view
#import aa
#import fullscreen

// Read-only storage, not uniform: lavapipe 22.3 recompiles, per draw and
// without freeing, any shader whose branches or loop bounds read a uniform
// block (docs/reliability.md).
@group(0) @binding(0) var<storage, read> params: AaParams;
@group(0) @binding(1) var input: texture_2d<f32>;

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let p = vec2i(frag.xy);
    let dims = vec2i(textureDimensions(input)) - 1;
    let c = textureLoad(input, p, 0).rgb;
    var blur = vec3f(0.0);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let w = f32((2 - abs(i)) * (2 - abs(j))) / 16.0;
            blur += w * textureLoad(input, clamp(p + vec2i(i, j), vec2i(0), dims), 0).rgb;
        }
    }
    let s = params.tuning.z;
    return vec4f(max(c + s * (c - blur), vec3f(0.0)), 1.0);
}
