// Parameters and helpers shared by the AO passes (passes/ao, TECHNIQUES O1-O3).
// Twin: passes/ao/mod.rs `AoUniform`; CPU twins of the functions: passes/ao/reference.rs.

struct AoParams {
    // x: 1/P00, y: 1/P11 (inverse projection scale), z: near plane (m),
    // w: focal length in AO pixels (0.5 * AO height * P11)
    proj: vec4f,
    // AO-resolution width, height, 1/width, 1/height
    ao_size: vec4f,
    // full-resolution width, height, 1/width, 1/height
    full_size: vec4f,
    // x: radius R (m), y: 1/R^2, z: strength, w: angle bias (radians)
    hbao: vec4f,
    // x: directions D, y: steps S, z: full pixels per AO pixel (1 or 2), w: max radius (AO pixels)
    hbao_steps: vec4f,
    // x: kernel radius (pixels), y: falloff 1/(2 sigma^2), z: sharpness, w: 1 = adaptive sampling
    blur: vec4f,
    // x: epsilon, y: N_max, z: L (m), w: 1 = selective (filter only unstable pixels)
    stf: vec4f,
    // xy: this frame's sample offset (px, y down), zw: the previous frame's (both inside the view matrices)
    jitter: vec4f,
    // the projection's depth rows: P22, P23 (clip z), P32, P33 (clip w);
    // perspective (0, near, -1, 0), orthographic (1/(f-n), f/(f-n), 0, 1)
    depth: vec4f,
}

// Linear depth stored for pixels without geometry (fits Rg16Float).
const AO_SKY_DEPTH: f32 = 65000.0;

// Linear view depth z (m) of device depth d: d = (P22 z_v + P23) / (P32 z_v + P33)
// solved for z_v = -z (perspective: d = near / z; orthographic: linear in z).
// d = 0 is the cleared depth: infinity, or the orthographic far plane.
fn ao_linear_depth(p: AoParams, d: f32) -> f32 {
    if (d <= 0.0) {
        return AO_SKY_DEPTH;
    }
    let z_v = (p.depth.y - d * p.depth.w) / (d * p.depth.z - p.depth.x);
    return min(-z_v, AO_SKY_DEPTH);
}

// Clip w at linear depth z: z (perspective) or 1 (orthographic).
fn ao_clip_w(p: AoParams, z: f32) -> f32 {
    return p.depth.w - p.depth.z * z;
}

// View-space position (camera looks down -Z, y up) at full-resolution uv (y down), linear depth z.
fn ao_view_position(p: AoParams, uv: vec2f, z: f32) -> vec3f {
    let ndc = vec2f(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    return vec3f(ndc * p.proj.xy * ao_clip_w(p, z), -z);
}

// The view ray's direction through view-space point q (not normalised):
// q itself (perspective) or -Z (orthographic).
fn ao_ray(p: AoParams, q: vec3f) -> vec3f {
    return vec3f(q.xy * -p.depth.z, q.z);
}

// One tap of the cross-bilateral kernel: exp2(-r^2 falloff - dz^2), with dz the
// depth difference pre-scaled by sharpness / z0 (relative, so the blur is
// equally sharp near and far). `weight_scale` is 2 for a bilinear tap that
// averages two texels.
fn ao_blur_tap(ao_z: vec2f, r: f32, z0: f32, weight_scale: f32, p: AoParams, total: ptr<function, vec2f>) {
    let dz = (ao_z.y - z0) * p.blur.z / z0;
    let w = weight_scale * exp2(-r * r * p.blur.y - dz * dz);
    *total += vec2f(ao_z.x * w, w);
}

// 1D cross-bilateral blur of (AO, Z) at pixel px along `step` (one pixel in x or y).
// Adaptive: inner half point taps with step 1, outer half bilinear taps with
// step 2 between texels r and r + 1; otherwise point taps at every r.
// Returns (AO, Z of the centre).
fn ao_cross_bilateral(tex: texture_2d<f32>, linear_sampler: sampler, px: vec2i, step: vec2i, p: AoParams) -> vec2f {
    let size = vec2i(p.full_size.xy);
    let c = textureLoad(tex, px, 0).xy;
    var total = vec2f(c.x, 1.0);
    let radius = p.blur.x;
    var r = 1.0;
    let inner = select(radius, floor(radius * 0.5), p.blur.w > 0.5);
    for (; r <= inner; r += 1.0) {
        let o = step * i32(r);
        ao_blur_tap(textureLoad(tex, clamp(px + o, vec2i(0), size - 1), 0).xy, r, c.y, 1.0, p, &total);
        ao_blur_tap(textureLoad(tex, clamp(px - o, vec2i(0), size - 1), 0).xy, r, c.y, 1.0, p, &total);
    }
    let centre_uv = (vec2f(px) + 0.5) * p.full_size.zw;
    let duv = vec2f(step) * p.full_size.zw;
    for (; r <= radius; r += 2.0) {
        let o = duv * (r + 0.5);
        ao_blur_tap(textureSampleLevel(tex, linear_sampler, centre_uv + o, 0.0).xy, r + 0.5, c.y, 2.0, p, &total);
        ao_blur_tap(textureSampleLevel(tex, linear_sampler, centre_uv - o, 0.0).xy, r + 0.5, c.y, 2.0, p, &total);
    }
    return vec2f(total.x / total.y, c.y);
}
