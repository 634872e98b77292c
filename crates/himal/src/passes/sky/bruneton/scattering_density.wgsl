// sky.tables.density (L1): radiance scattered towards the view direction at
// each 4D texel by light of scattering order SCATTERING_ORDER - 1 (incl. the
// ground bounce of the previous order's irradiance), a DENSITY_SAMPLES x
// 2 DENSITY_SAMPLES sphere quadrature. Twin: reference.rs `scattering_density`.
#import atmosphere
#import math

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var transmittance_load: texture_2d<f32>;
@group(0) @binding(2) var single_rayleigh: texture_3d<f32>;
@group(0) @binding(3) var single_mie: texture_3d<f32>;
@group(0) @binding(4) var multiple: texture_3d<f32>;
@group(0) @binding(5) var delta_irradiance: texture_2d<f32>;
@group(0) @binding(6) var table_sampler: sampler;
@group(0) @binding(7) var out_density: texture_storage_3d<rgba16float, write>;

// Order of the scattering this density produces (2..): reads order - 1.
override SCATTERING_ORDER: u32 = 2u;
override DENSITY_SAMPLES: u32 = 16u;

fn incident_of_previous_order(r: f32, mu: f32, mu_s: f32, nu: f32, ground: bool) -> vec3f {
    if (SCATTERING_ORDER == 2u) {
        let rayleigh = scattering_lookup(atmosphere, single_rayleigh, table_sampler, r, mu, mu_s, nu, ground);
        let mie = scattering_lookup(atmosphere, single_mie, table_sampler, r, mu, mu_s, nu, ground);
        return rayleigh * rayleigh_phase_function(nu) + mie * mie_phase_function(atmosphere.shape.z, nu);
    }
    return scattering_lookup(atmosphere, multiple, table_sampler, r, mu, mu_s, nu, ground);
}

@compute @workgroup_size(8, 8, 1)
fn cs_scattering_density(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_density);
    if (id.x >= size.x || id.y >= size.y || id.z >= size.z) {
        return;
    }
    let c = scattering_coords_from_texel(atmosphere, vec3f(id) + 0.5);
    let bottom = atmosphere.shape.x;
    // Local frame: z = zenith, the view direction in the xz plane.
    let omega = vec3f(sqrt(max(1.0 - c.mu * c.mu, 0.0)), 0.0, c.mu);
    var sun_x = 0.0;
    if (omega.x != 0.0) {
        sun_x = (c.nu - c.mu * c.mu_s) / omega.x;
    }
    let sun_y = sqrt(max(1.0 - sun_x * sun_x - c.mu_s * c.mu_s, 0.0));
    let omega_s = vec3f(sun_x, sun_y, c.mu_s);
    let n = DENSITY_SAMPLES;
    let dphi = PI / f32(n);
    let dtheta = PI / f32(n);
    let rayleigh_k = atmosphere.rayleigh_scattering.xyz * rayleigh_density(atmosphere, c.r - bottom);
    let mie_k = atmosphere.mie_scattering.xyz * mie_density(atmosphere, c.r - bottom);
    var sum = vec3f(0.0);
    for (var l = 0u; l < n; l++) {
        let theta = (f32(l) + 0.5) * dtheta;
        let cos_theta = cos(theta);
        let sin_theta = sin(theta);
        let ground = ray_intersects_ground(atmosphere, c.r, cos_theta);
        var distance_to_ground = 0.0;
        var transmittance_to_ground = vec3f(0.0);
        if (ground) {
            distance_to_ground = distance_to_bottom_atmosphere_boundary(atmosphere, c.r, cos_theta);
            transmittance_to_ground = transmittance_along_ray(
                atmosphere, transmittance_load, table_sampler, c.r, cos_theta, distance_to_ground, true);
        }
        for (var m = 0u; m < 2u * n; m++) {
            let phi = (f32(m) + 0.5) * dphi;
            let omega_i = vec3f(cos(phi) * sin_theta, sin(phi) * sin_theta, cos_theta);
            let domega_i = dtheta * dphi * sin_theta;
            let nu1 = dot(omega_s, omega_i);
            var incident = incident_of_previous_order(c.r, omega_i.z, c.mu_s, nu1, ground);
            if (ground) {
                let ground_normal = normalize(vec3f(0.0, 0.0, c.r) + omega_i * distance_to_ground);
                let e = irradiance_lookup(atmosphere, delta_irradiance, table_sampler, bottom, dot(ground_normal, omega_s));
                incident += transmittance_to_ground * atmosphere.ground_albedo.xyz * (1.0 / PI) * e;
            }
            let nu2 = dot(omega, omega_i);
            sum += incident * (rayleigh_k * rayleigh_phase_function(nu2)
                + mie_k * mie_phase_function(atmosphere.shape.z, nu2)) * domega_i;
        }
    }
    textureStore(out_density, id, vec4f(sum, 1.0));
}
