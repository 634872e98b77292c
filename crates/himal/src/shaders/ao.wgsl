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
    // O4 (SSDO): x: directional strength on lights (0 = off, 1 = full),
    // y: penumbra width (sine of elevation), z: extra width per unit roughness
    // (reflection occlusion), w: gain of the directional harmonic
    ssdo: vec4f,
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

// ao.pack at full-resolution pixel px: (AO upsampled bilinearly from the AO
// resolution, linear depth Z, the O4 coefficients c1, c2 alike; (0, 1) for
// a two-channel hbao). AO texel q holds full-res pixel q * scale, so px
// sits at q = px / scale. Twin: passes/ao/reference.rs `pack`.
fn ao_pack(p: AoParams, depth: texture_depth_2d, hbao: texture_2d<f32>, linear_sampler: sampler, px: vec2i) -> vec4f {
    let z = ao_linear_depth(p, textureLoad(depth, px, 0));
    let uv = (vec2f(px) / p.hbao_steps.z + 0.5) * p.ao_size.zw;
    let ao = textureSampleLevel(hbao, linear_sampler, uv, 0.0);
    return vec4f(ao.x, z, ao.zw);
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
// averages two texels. `v` is (AO, Z, c1, c2): the O4 directional
// coefficients (zw) take the same weights as AO; total is (sum AO w, sum w, sum c w).
fn ao_blur_tap(v: vec4f, r: f32, z0: f32, weight_scale: f32, p: AoParams, total: ptr<function, vec4f>) {
    let dz = (v.y - z0) * p.blur.z / z0;
    let w = weight_scale * exp2(-r * r * p.blur.y - dz * dz);
    *total += vec4f(v.x * w, w, v.zw * w);
}

// 1D cross-bilateral blur of (AO, Z[, c1, c2]) at pixel px along `step` (one pixel in x or y).
// Adaptive: inner half point taps with step 1, outer half bilinear taps with
// step 2 between texels r and r + 1; otherwise point taps at every r.
// Returns (AO, Z of the centre, c1, c2); zw are meaningless for two-channel textures.
fn ao_cross_bilateral(tex: texture_2d<f32>, linear_sampler: sampler, px: vec2i, step: vec2i, p: AoParams) -> vec4f {
    let size = vec2i(p.full_size.xy);
    let c = textureLoad(tex, px, 0);
    var total = vec4f(c.x, 1.0, c.zw);
    let radius = p.blur.x;
    var r = 1.0;
    let inner = select(radius, floor(radius * 0.5), p.blur.w > 0.5);
    for (; r <= inner; r += 1.0) {
        let o = step * i32(r);
        ao_blur_tap(textureLoad(tex, clamp(px + o, vec2i(0), size - 1), 0), r, c.y, 1.0, p, &total);
        ao_blur_tap(textureLoad(tex, clamp(px - o, vec2i(0), size - 1), 0), r, c.y, 1.0, p, &total);
    }
    let centre_uv = (vec2f(px) + 0.5) * p.full_size.zw;
    let duv = vec2f(step) * p.full_size.zw;
    for (; r <= radius; r += 2.0) {
        let o = duv * (r + 0.5);
        ao_blur_tap(textureSampleLevel(tex, linear_sampler, centre_uv + o, 0.0), r + 0.5, c.y, 2.0, p, &total);
        ao_blur_tap(textureSampleLevel(tex, linear_sampler, centre_uv - o, 0.0), r + 0.5, c.y, 2.0, p, &total);
    }
    return vec4f(total.x / total.y, c.y, total.zw / total.y);
}

// O4 directional visibility along unit direction l at view-space point p with
// view-space normal n. HBAO's per-slice occlusion (W-weighted rise of the
// horizon, in sine of elevation) over the slice angle phi (screen direction,
// y down) is kept as a constant (1 - AO, the ambient term) and a first
// harmonic c = (c1, c2). The directional part alone, gain * max(c1 cos phi +
// c2 sin phi, 0), is the horizon's rise toward phi: the harmonic of a
// half-plane occluder is 0 sideways and 2/pi of its rise toward it, and W
// lowers near-R occluders. l lies in the slice of its screen direction; it is
// visible when its elevation clears the tangent plane's plus the rise, with a
// penumbra of width `soft` below that horizon. Twin: passes/ao/reference.rs
// `ssdo_visibility`; docs/techniques/O4.md.
fn ssdo_visibility(p: vec3f, n: vec3f, l: vec3f, c: vec2f, gain: f32, soft: f32) -> f32 {
    let v = normalize(-p);
    // The screen direction p + e l moves along (as t in hbao.wgsl integrate_direction).
    let screen = l.xy * -p.z + p.xy * l.z;
    let len = length(screen);
    if (len <= 1e-6) {
        return 1.0;
    }
    let t3 = vec3f(screen / len, 0.0);
    let rise = gain * (c.x * t3.x - c.y * t3.y);
    if (rise <= 0.0) {
        return 1.0;
    }
    var sin_t = 0.0;
    var t = cross(n, cross(t3, v));
    let t_len = length(t);
    if (t_len > 1e-12) {
        t /= t_len;
        let st = t.xy * -p.z + p.xy * t.z;
        t = select(t, -t, dot(st, t3.xy) < 0.0);
        sin_t = dot(t, v);
    }
    let sin_l = dot(l, v);
    return clamp(1.0 + (sin_l - sin_t - rise) / soft, 0.0, 1.0);
}

// Specular occlusion from AO alone (Lagarde & de Rousiers 2014, "Moving
// Frostbite to PBR"): reflection occlusion without the directional term.
fn specular_occlusion_lagarde(n_o_v: f32, ao: f32, roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    return clamp(pow(n_o_v + ao, exp2(-16.0 * alpha - 1.0)) - 1.0 + ao, 0.0, 1.0);
}
