// sky.tables.transmittance (L1): T(r, mu) to the top of the atmosphere,
// 500-step trapezoid ray march per texel. Twin: reference.rs `transmittance_to_top`.
#import atmosphere

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var out_transmittance: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_transmittance(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_transmittance);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let r_mu = r_mu_from_transmittance_uv(atmosphere, (vec2f(id.xy) + 0.5) / vec2f(size));
    let t = compute_transmittance_to_top_atmosphere_boundary(atmosphere, r_mu.x, r_mu.y);
    textureStore(out_transmittance, id.xy, vec4f(t, 1.0));
}
