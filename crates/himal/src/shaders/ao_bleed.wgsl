// O5 AO colour bleeding (Ryse, SIGGRAPH 2014): the occlusion term raised to
// a per-channel power that shrinks with the low-frequency albedo around the
// pixel, so occlusion next to a bright coloured surface darkens less in that
// surface's colour (a cheap stand-in for the light it bounces). CPU twin:
// passes/ao/bleed/reference.rs `bleed_occlusion`; docs/techniques/O5.md.

// Coverage-weighted mean albedo of a bleed texel: rgb holds the sum of the
// geometry's albedo over the texels averaged, a the fraction that was
// geometry (sky pixels add nothing).
fn ao_bleed_colour(texel: vec4f) -> vec3f {
    return texel.rgb / max(texel.a, 1e-4);
}

// occlColor = occl ^ (1 - min(3 bleed, 0.7)), per channel.
fn ao_bleed_occlusion(occl: f32, bleed: vec3f) -> vec3f {
    return pow(vec3f(max(occl, 0.0)), vec3f(1.0) - min(bleed * 3.0, vec3f(0.7)));
}
