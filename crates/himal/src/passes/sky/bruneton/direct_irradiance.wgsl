// sky.tables.direct_irradiance (L1): sun irradiance on a horizontal surface
// at (r, mu_s) through the transmittance table (ground bounce of order 2).
#import atmosphere

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var table_sampler: sampler;
@group(0) @binding(3) var out_delta_irradiance: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_direct_irradiance(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_delta_irradiance);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let r_mu_s = r_mu_s_from_irradiance_uv(atmosphere, (vec2f(id.xy) + 0.5) / vec2f(size));
    let e = compute_direct_irradiance(atmosphere, transmittance_load, table_sampler, r_mu_s.x, r_mu_s.y);
    textureStore(out_delta_irradiance, id.xy, vec4f(e, 1.0));
}
