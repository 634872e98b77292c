// envmap.dfg (TECHNIQUES L4, M1): the split-sum DFG table, computed on the GPU
// once. Texel (x, y): n.v = (x + 0.5) / W, perceptual roughness = (y + 0.5) / H.
//   A = 1/N sum (1 - Fc) G_vis,  B = 1/N sum Fc G_vis,  Fc = (1 - v.h)^5,
//   G_vis = 4 V(v, l) (n.l) (v.h) / (n.h)   (V: height-correlated Smith),
// over GGX-distributed half vectors. Twin: reference.rs `dfg`.
#import brdf
#import envmap

@group(0) @binding(0) var out_texture: texture_storage_2d<rgba16float, write>;

override DFG_SAMPLES: u32 = 512u;

@compute @workgroup_size(8, 8, 1)
fn cs_dfg(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_texture);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let n_o_v = (f32(id.x) + 0.5) / f32(size.x);
    let roughness = (f32(id.y) + 0.5) / f32(size.y);
    let alpha = max(roughness * roughness, BRDF_MIN_ALPHA);
    let v = vec3f(sqrt(1.0 - n_o_v * n_o_v), 0.0, n_o_v);
    var ab = vec2f(0.0);
    for (var i = 0u; i < DFG_SAMPLES; i++) {
        let h = envmap_sample_ggx(envmap_hammersley(i, DFG_SAMPLES), alpha);
        let v_o_h = dot(v, h);
        let l = 2.0 * v_o_h * h - v;
        let n_o_l = l.z;
        if (n_o_l > 0.0 && v_o_h > 0.0) {
            let vis = v_smith_ggx_correlated_aniso(n_o_v, n_o_l, v.x, 0.0, l.x, l.y, alpha, alpha);
            let g_vis = 4.0 * vis * n_o_l * v_o_h / h.z;
            let fc = pow(1.0 - v_o_h, 5.0);
            ab += vec2f(1.0 - fc, fc) * g_vis;
        }
    }
    textureStore(out_texture, id.xy, vec4f(ab / f32(DFG_SAMPLES), 0.0, 1.0));
}
