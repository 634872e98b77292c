// Colour helpers shared by lighting, post and debug views.

// Rec.709 relative luminance of linear RGB.
fn luminance(c: vec3f) -> f32 {
    return dot(c, vec3f(0.2126, 0.7152, 0.0722));
}

// IEC 61966-2-1 linear -> sRGB transfer (for EXR/debug paths that write unorm).
fn linear_to_srgb(c: vec3f) -> vec3f {
    let lo = c * 12.92;
    let hi = 1.055 * pow(max(c, vec3f(0.0)), vec3f(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3f(0.0031308));
}

// Inverse of linear_to_srgb: lets a debug view write a display value v into
// an sRGB target so that the stored byte is v itself.
fn srgb_to_linear(c: vec3f) -> vec3f {
    let lo = c / 12.92;
    let hi = pow((max(c, vec3f(0.0)) + 0.055) / 1.055, vec3f(2.4));
    return select(hi, lo, c <= vec3f(0.04045));
}
