// terrain: the CDLOD patches into the G-buffer after the `gbuffer` node
// (targets loaded, depth test GreaterEqual, reverse-Z), encoded as
// gbuffer.wgsl encodes objects. One instanced draw: instance = patch
// (origin, level), vertex = grid point (index % 17, index / 17).
// Shading is independent of the mesh's level: the normal comes from the
// height data at the pixel (central differences over the data spacing or
// the pixel footprint), layers are weighted by that height and slope with
// noise on their borders, and each layer's detail (albedo + glossiness,
// normal) is sampled at two scales, triplanar where the slope is steep.
// E3: the detail normals' variance (their mips' alpha) widens roughness.
// Docs: docs/techniques/terrain.md, E3.md.
#import brdf
#import gbuffer_io
#import view
#import tangent_frame
#import terrain

// `--view lod`: albedo shows the patch's quadtree level.
override LOD_VIEW: bool = false;
// E3 (`--specular-aa`): widen roughness by the detail normals' variance.
override SPECULAR_AA: bool = true;

struct TerrainLayer {
    // rgb linear albedo, a glossiness
    albedo: vec4f,
    // min, max (m), blend width (m), jitter amplitude (m)
    height: vec4f,
    // min, max, blend width (degrees), detail normal strength
    slope: vec4f,
    // near scale (m per repeat), far scale, detail texture layer, unused
    detail: vec4f,
}

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> terrain: TerrainParams;
@group(0) @binding(2) var<storage, read> layers: array<TerrainLayer, 8>;
@group(0) @binding(3) var coarse_load: texture_2d<f32>;
@group(0) @binding(4) var fine_load: texture_2d_array<f32>;
@group(0) @binding(5) var pages: texture_2d<u32>;
// rgb albedo variation (mean 0.5), a glossiness variation (mean 0.5)
@group(0) @binding(6) var detail_albedo: texture_2d_array<f32>;
// xy tangent-space normal * 0.5 + 0.5
@group(0) @binding(7) var detail_normal: texture_2d_array<f32>;
@group(0) @binding(8) var detail_sampler: sampler;

struct VertexOut {
    @builtin(position) clip: vec4f,
    @location(0) world: vec3f,
    @location(1) curr_clip: vec4f,
    @location(2) prev_clip: vec4f,
    @location(3) @interpolate(flat) level: u32,
}

@vertex
fn vs_main(@location(0) origin: vec2f, @location(1) level: u32,
        @builtin(vertex_index) index: u32) -> VertexOut {
    let p = terrain;
    let w = terrain_vertex(coarse_load, fine_load, pages, p, origin, level, index);
    var out: VertexOut;
    out.world = w;
    out.curr_clip = view.view_proj * vec4f(w, 1.0);
    // Static ground: last frame's matrix on the same point (as objects do).
    out.prev_clip = view.prev_view_proj * vec4f(w, 1.0);
    out.clip = out.curr_clip;
    out.level = level;
    return out;
}

fn hash2(c: vec2i) -> f32 {
    var h = u32(c.x) * 0x8da6b343u ^ u32(c.y) * 0xd8163841u;
    h = (h ^ (h >> 15u)) * 0x2c1b3c6du;
    h = (h ^ (h >> 12u)) * 0x297a2d39u;
    return f32((h ^ (h >> 15u)) >> 8u) / 16777216.0;
}

// Value noise in [-1, 1], smooth (quintic), one cell per unit.
fn value_noise(x: vec2f) -> f32 {
    let i = vec2i(floor(x));
    let f = x - floor(x);
    let u = f * f * f * (f * (f * 6.0 - 15.0) + 10.0);
    let a = hash2(i);
    let b = hash2(i + vec2i(1, 0));
    let c = hash2(i + vec2i(0, 1));
    let d = hash2(i + vec2i(1, 1));
    return 2.0 * mix(mix(a, b, u.x), mix(c, d, u.x), u.y) - 1.0;
}

// 1 inside [lo, hi], 0 outside, smoothstep edges `width` wide (as the
// scene's TerrainLayer::coverage).
fn band(x: f32, lo: f32, hi: f32, width: f32) -> f32 {
    let w = max(width, 1e-3) * 0.5;
    return smoothstep(lo - w, lo + w, x) * (1.0 - smoothstep(hi - w, hi + w, x));
}

struct Detail {
    albedo: vec4f,
    // world-space normal offset (UDN blend)
    offset: vec3f,
    // E3: the offset's normal variance at this pixel's mip levels
    variance: f32,
}

// One projection: near and far scale of layer `t`, `uv` in metres.
fn detail_sample(t: i32, uv: vec2f, du: vec2f, dv: vec2f, scales: vec2f) -> vec4f {
    let a = textureSampleGrad(detail_albedo, detail_sampler, uv / scales.x, t, du / scales.x, dv / scales.x);
    let b = textureSampleGrad(detail_albedo, detail_sampler, uv / scales.y, t, du / scales.y, dv / scales.y);
    return 0.5 * (a + b);
}

// xy: the offset a + b / 2 of the two scales; z: its normal variance (E3,
// alpha of the mips), the scales' independent variances added: s_a + s_b / 4.
fn detail_normal_sample(t: i32, uv: vec2f, du: vec2f, dv: vec2f, scales: vec2f) -> vec3f {
    let a = textureSampleGrad(detail_normal, detail_sampler, uv / scales.x, t, du / scales.x, dv / scales.x);
    let b = textureSampleGrad(detail_normal, detail_sampler, uv / scales.y, t, du / scales.y, dv / scales.y);
    let variance = normal_variance_decode(a.a) + 0.25 * normal_variance_decode(b.a);
    return vec3f((a.xy * 2.0 - 1.0) + 0.5 * (b.xy * 2.0 - 1.0), variance);
}

// Layer `layer`'s detail at world `w` with normal `n`: planar from above,
// triplanar (weights |n|^4) where the slope is steep.
fn layer_detail(layer: TerrainLayer, w: vec3f, dx: vec3f, dy: vec3f, n: vec3f) -> Detail {
    let t = i32(layer.detail.z);
    let scales = layer.detail.xy;
    var tw = pow(abs(n), vec3f(4.0));
    tw = tw / (tw.x + tw.y + tw.z);
    // Flat enough: the top projection alone (no side taps).
    if (tw.y > 0.95) {
        tw = vec3f(0.0, 1.0, 0.0);
    }
    var d: Detail;
    d.albedo = vec4f(0.0);
    d.offset = vec3f(0.0);
    d.variance = 0.0;
    if (tw.y > 0.0) {
        d.albedo += tw.y * detail_sample(t, w.xz, dx.xz, dy.xz, scales);
        let o = detail_normal_sample(t, w.xz, dx.xz, dy.xz, scales);
        d.offset += tw.y * vec3f(o.x, 0.0, o.y);
        d.variance += tw.y * o.z;
    }
    if (tw.x > 0.0) {
        d.albedo += tw.x * detail_sample(t, w.zy, dx.zy, dy.zy, scales);
        let o = detail_normal_sample(t, w.zy, dx.zy, dy.zy, scales);
        d.offset += tw.x * vec3f(0.0, o.y, o.x);
        d.variance += tw.x * o.z;
    }
    if (tw.z > 0.0) {
        d.albedo += tw.z * detail_sample(t, w.xy, dx.xy, dy.xy, scales);
        let o = detail_normal_sample(t, w.xy, dx.xy, dy.xy, scales);
        d.offset += tw.z * vec3f(o.x, o.y, 0.0);
        d.variance += tw.z * o.z;
    }
    d.offset *= layer.slope.w;
    // Strength scales the slopes, so their variance by its square.
    d.variance *= layer.slope.w * layer.slope.w;
    return d;
}

@fragment
fn fs_main(in: VertexOut) -> GBufferOut {
    let p = terrain;
    let w = in.world;
    let dx = dpdx(w);
    let dy = dpdy(w);
    // Normal from the data, filtered to the pixel: central differences
    // over max(data spacing, footprint), so it does not follow the mesh.
    let footprint = max(length(dx), length(dy));
    let e = max(terrain_data_spacing(pages, p, w.xz), footprint);
    let hx0 = terrain_height(coarse_load, fine_load, pages, p, w.xz - vec2f(e, 0.0), false);
    let hx1 = terrain_height(coarse_load, fine_load, pages, p, w.xz + vec2f(e, 0.0), false);
    let hz0 = terrain_height(coarse_load, fine_load, pages, p, w.xz - vec2f(0.0, e), false);
    let hz1 = terrain_height(coarse_load, fine_load, pages, p, w.xz + vec2f(0.0, e), false);
    let grad = vec2f(hx1 - hx0, hz1 - hz0) / (2.0 * e);
    let n_geo = normalize(vec3f(-grad.x, 1.0, -grad.y));
    let height = 0.25 * (hx0 + hx1 + hz0 + hz1);
    let slope = degrees(acos(clamp(n_geo.y, -1.0, 1.0)));
    // Ragged borders: noise added to height and slope before the tests.
    let jitter = value_noise(w.xz / 23.0) * 0.6 + value_noise(w.xz / 5.7) * 0.4;

    // Layers paint over the ones before: w_i = c_i prod_{j > i} (1 - c_j).
    var weight: array<f32, 8>;
    let count = min(p.layers, 8u);
    for (var i = 0u; i < count; i++) {
        let l = layers[i];
        var c = band(height + l.height.w * jitter, l.height.x, l.height.y, l.height.z)
            * band(slope + 4.0 * jitter, l.slope.x, l.slope.y, l.slope.z);
        if (i == 0u) {
            c = 1.0;
        }
        for (var j = 0u; j < i; j++) {
            weight[j] *= 1.0 - c;
        }
        weight[i] = c;
    }
    var albedo = vec3f(0.0);
    var gloss = 0.0;
    var offset = vec3f(0.0);
    var variance = 0.0;
    for (var i = 0u; i < count; i++) {
        if (weight[i] > 0.004) {
            let l = layers[i];
            let d = layer_detail(l, w, dx, dy, n_geo);
            albedo += weight[i] * l.albedo.rgb * (2.0 * d.albedo.rgb);
            gloss += weight[i] * clamp(l.albedo.a + (d.albedo.a - 0.5) * 0.5, 0.0, 1.0);
            offset += weight[i] * d.offset;
            variance += weight[i] * d.variance;
        }
    }
    // Large-scale brightness variation against visible repetition.
    albedo *= 0.88 + 0.12 * value_noise(w.xz / 170.0);
    let n = normalize(n_geo + offset - n_geo * dot(offset, n_geo));
    // Tangent along +x on the surface; shading_frame makes it orthonormal.
    let tbn = shading_frame(n, vec4f(1.0, grad.x, 0.0, 1.0));
    var out: GBufferOut;
    out.albedo = vec4f(clamp(albedo, vec3f(0.0), vec3f(1.0)), 1.0);
    if (LOD_VIEW) {
        out.albedo = vec4f(lod_view_albedo(in.level, out.albedo.rgb), 1.0);
    }
    out.frame = pack_quat(frame_to_quat(tbn[0], tbn[1], tbn[2]));
    if (SPECULAR_AA) {
        gloss = 1.0 - toksvig_roughness(perceptual_roughness_from_glossiness(gloss), variance);
    }
    out.material = vec4f(gloss, 0.5, 0.0, 0.0);
    out.motion = gbuffer_motion(in.curr_clip, in.prev_clip);
    return out;
}
