// ao.bleed (STEP 0): the G-buffer albedo averaged over 4x4 pixel blocks,
// premultiplied by coverage (a = fraction of the block with geometry);
// ao.bleed_x / ao.bleed_y (STEP 1 / 2): a 9-tap Gaussian (sigma 2 texels) of
// all four channels along x / y at that resolution. Target Rgba16Float.
// Bindings: source (albedo, or the previous step), depth (STEP 0 only).
// CPU twin: passes/ao/bleed/reference.rs (`downsample`, `blur`); O5.md.
#import fullscreen

override STEP: u32 = 0u;

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var depth: texture_depth_2d;

// exp(-k^2 / 8) normalised; reference.rs `BLUR_WEIGHTS` holds the same numbers.
const BLEED_WEIGHTS = array<f32, 5>(0.20416, 0.18017, 0.12383, 0.06628, 0.02763);

@fragment
fn fs_main(@builtin(position) frag: vec4f) -> @location(0) vec4f {
    let q = vec2i(frag.xy);
    let size = vec2i(textureDimensions(source));
    if (STEP == 0u) {
        var sum = vec4f(0.0);
        for (var j = 0; j < 4; j++) {
            for (var i = 0; i < 4; i++) {
                let p = min(q * 4 + vec2i(i, j), size - 1);
                if (textureLoad(depth, p, 0) > 0.0) {
                    sum += vec4f(textureLoad(source, p, 0).rgb, 1.0);
                }
            }
        }
        return sum / 16.0;
    }
    let axis = select(vec2i(0, 1), vec2i(1, 0), STEP == 1u);
    // A function-local copy: dynamic indexing of a constant array.
    var w = BLEED_WEIGHTS;
    var sum = textureLoad(source, q, 0) * w[0];
    for (var k = 1; k < 5; k++) {
        sum += textureLoad(source, clamp(q + axis * k, vec2i(0), size - 1), 0) * w[k];
        sum += textureLoad(source, clamp(q - axis * k, vec2i(0), size - 1), 0) * w[k];
    }
    return sum;
}
