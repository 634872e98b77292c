// sky.tables.single_scattering (L1): single Rayleigh and Mie scattering
// (without phase functions) per 4D texel, trapezoid rule along the view ray
// with 150 steps (the reference's 50 leave Mie, scale height 1.2 km, 3-7% off:
// tests/sky_bruneton.rs); transmittance from the table. Twin: reference.rs
// `single_scattering`.
#import atmosphere

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var table_sampler: sampler;
@group(0) @binding(3) var out_rayleigh: texture_storage_3d<rgba16float, write>;
@group(0) @binding(4) var out_mie: texture_storage_3d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_single_scattering(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_rayleigh);
    if (id.x >= size.x || id.y >= size.y || id.z >= size.z) {
        return;
    }
    let c = scattering_coords_from_texel(atmosphere, vec3f(id) + 0.5);
    let bottom = atmosphere.shape.x;
    let sample_count = 150;
    let dx = distance_to_nearest_atmosphere_boundary(atmosphere, c.r, c.mu, c.ground) / f32(sample_count);
    var rayleigh_sum = vec3f(0.0);
    var mie_sum = vec3f(0.0);
    for (var i = 0; i <= sample_count; i++) {
        let d = f32(i) * dx;
        let r_d = atmosphere_clamp_radius(atmosphere, sqrt(d * d + 2.0 * c.r * c.mu * d + c.r * c.r));
        let mu_s_d = atmosphere_clamp_cosine((c.r * c.mu_s + d * c.nu) / r_d);
        let t = transmittance_along_ray(atmosphere, transmittance_load, table_sampler, c.r, c.mu, d, c.ground)
            * transmittance_to_sun(atmosphere, transmittance_load, table_sampler, r_d, mu_s_d);
        let weight = select(1.0, 0.5, i == 0 || i == sample_count);
        rayleigh_sum += t * (rayleigh_density(atmosphere, r_d - bottom) * weight);
        mie_sum += t * (mie_density(atmosphere, r_d - bottom) * weight);
    }
    let k = dx * atmosphere.solar_irradiance.xyz;
    textureStore(out_rayleigh, id, vec4f(rayleigh_sum * k * atmosphere.rayleigh_scattering.xyz, 1.0));
    textureStore(out_mie, id, vec4f(mie_sum * k * atmosphere.mie_scattering.xyz, 1.0));
}
