// sky.tables.multiple_scattering (L1): scattering of one order >= 2 per 4D
// texel, the density integrated along the view ray (50-step trapezoid,
// transmittance from the table); added / Rayleigh phase to the running
// scattering sum (ping-pong: previous -> out). Twin: reference.rs `multiple_scattering`.
#import atmosphere

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var density: texture_3d<f32>;
@group(0) @binding(3) var previous_scattering_load: texture_3d<f32>;
@group(0) @binding(4) var table_sampler: sampler;
@group(0) @binding(5) var out_delta_multiple: texture_storage_3d<rgba16float, write>;
@group(0) @binding(6) var out_scattering: texture_storage_3d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_multiple_scattering(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_scattering);
    if (id.x >= size.x || id.y >= size.y || id.z >= size.z) {
        return;
    }
    let c = scattering_coords_from_texel(atmosphere, vec3f(id) + 0.5);
    let sample_count = 50;
    let dx = distance_to_nearest_atmosphere_boundary(atmosphere, c.r, c.mu, c.ground) / f32(sample_count);
    var sum = vec3f(0.0);
    for (var i = 0; i <= sample_count; i++) {
        let d = f32(i) * dx;
        let r_i = atmosphere_clamp_radius(atmosphere, sqrt(d * d + 2.0 * c.r * c.mu * d + c.r * c.r));
        let mu_i = atmosphere_clamp_cosine((c.r * c.mu + d) / r_i);
        let mu_s_i = atmosphere_clamp_cosine((c.r * c.mu_s + d * c.nu) / r_i);
        let j = scattering_lookup(atmosphere, density, table_sampler, r_i, mu_i, mu_s_i, c.nu, c.ground)
            * transmittance_along_ray(atmosphere, transmittance_load, table_sampler, c.r, c.mu, d, c.ground);
        let weight = select(1.0, 0.5, i == 0 || i == sample_count);
        sum += j * (weight * dx);
    }
    let previous = textureLoad(previous_scattering_load, id, 0).rgb;
    textureStore(out_delta_multiple, id, vec4f(sum, 1.0));
    textureStore(out_scattering, id, vec4f(previous + sum / rayleigh_phase_function(c.nu), 1.0));
}
