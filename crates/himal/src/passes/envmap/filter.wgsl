// envmap.filter (TECHNIQUES L4): GGX filtered importance sampling per output
// mip (Colbert & Krivanek 2008; Lagarde & de Rousiers 2014), faces in z.
// Mip m holds perceptual roughness m / (levels - 1) (alpha = roughness^2),
// with n = v = r. Each GGX sample reads the box-filtered source at the lod
// whose texel solid angle matches the sample's:
//   lod = 0.5 log2(omega_s / omega_p),  omega_s = 1 / (N pdf),
//   pdf = D(h) / 4,  omega_p = 4 pi / (6 w^2).
// Colbert's +1 lod bias over-blurs rough mips (4.3% vs 1.5% error at
// alpha 0.64 in tests/envmap.rs), so none is added. The estimate is weighted
// by n.l (Karis 2013). Twin: reference.rs `filter_fis`.
#import brdf
#import envmap
#import math

struct FilterParams {
    // x: alpha, y: samples N, z: source face size w, w: source mip count
    p: vec4f,
}

@group(0) @binding(0) var<uniform> params: FilterParams;
@group(0) @binding(1) var source: texture_cube<f32>;
@group(0) @binding(2) var source_sampler: sampler;
@group(0) @binding(3) var out_texture: texture_storage_2d_array<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_filter(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_texture);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let uv = (vec2f(id.xy) + 0.5) / vec2f(size);
    let n = cube_face_direction(id.z, uv);
    let alpha = params.p.x;
    let count = u32(params.p.y);
    let w = params.p.z;
    let max_lod = params.p.w - 1.0;
    let basis = envmap_basis(n);
    let omega_p = 4.0 * PI / (6.0 * w * w);
    var sum = vec3f(0.0);
    var weight = 0.0;
    for (var i = 0u; i < count; i++) {
        let h_local = envmap_sample_ggx(envmap_hammersley(i, count), alpha);
        let h = basis * h_local;
        let l = 2.0 * dot(n, h) * h - n;
        let n_o_l = dot(n, l);
        if (n_o_l > 0.0) {
            let pdf = d_ggx(h_local.z, alpha) * 0.25;
            let omega_s = 1.0 / (f32(count) * pdf + 1e-6);
            let lod = clamp(0.5 * log2(omega_s / omega_p), 0.0, max_lod);
            sum += textureSampleLevel(source, source_sampler, l, lod).rgb * n_o_l;
            weight += n_o_l;
        }
    }
    textureStore(out_texture, id.xy, id.z, vec4f(sum / max(weight, 1e-6), 1.0));
}

// Mip 0 is the mirror: a copy of the source's level 0.
@compute @workgroup_size(8, 8, 1)
fn cs_copy(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_texture);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let uv = (vec2f(id.xy) + 0.5) / vec2f(size);
    let l = cube_face_direction(id.z, uv);
    textureStore(out_texture, id.xy, id.z, vec4f(textureSampleLevel(source, source_sampler, l, 0.0).rgb, 1.0));
}
