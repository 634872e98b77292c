// sky.tables.indirect_irradiance (L1): sky irradiance on a horizontal surface
// from scattering of order SCATTERING_ORDER (1: single, with phase functions),
// added to the running irradiance sum (ping-pong: previous -> out).
// Twin: reference.rs `indirect_irradiance`.
#import atmosphere
#import math

@group(0) @binding(0) var<uniform> atmosphere: AtmosphereParams;
@group(0) @binding(1) var single_rayleigh: texture_3d<f32>;
@group(0) @binding(2) var single_mie: texture_3d<f32>;
@group(0) @binding(3) var multiple: texture_3d<f32>;
@group(0) @binding(4) var previous_irradiance_load: texture_2d<f32>;
@group(0) @binding(5) var table_sampler: sampler;
@group(0) @binding(6) var out_delta_irradiance: texture_storage_2d<rgba16float, write>;
@group(0) @binding(7) var out_irradiance: texture_storage_2d<rgba16float, write>;

override SCATTERING_ORDER: u32 = 1u;

@compute @workgroup_size(8, 8, 1)
fn cs_indirect_irradiance(@builtin(global_invocation_id) id: vec3u) {
    let size = textureDimensions(out_irradiance);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let r_mu_s = r_mu_s_from_irradiance_uv(atmosphere, (vec2f(id.xy) + 0.5) / vec2f(size));
    let r = r_mu_s.x;
    let mu_s = r_mu_s.y;
    let n = 32u;
    let dphi = PI / f32(n);
    let dtheta = PI / f32(n);
    let omega_s = vec3f(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    var sum = vec3f(0.0);
    for (var j = 0u; j < n / 2u; j++) {
        let theta = (f32(j) + 0.5) * dtheta;
        for (var i = 0u; i < 2u * n; i++) {
            let phi = (f32(i) + 0.5) * dphi;
            let omega = vec3f(cos(phi) * sin(theta), sin(phi) * sin(theta), cos(theta));
            let domega = dtheta * dphi * sin(theta);
            let nu = dot(omega, omega_s);
            var l: vec3f;
            if (SCATTERING_ORDER == 1u) {
                let rayleigh = scattering_lookup(atmosphere, single_rayleigh, table_sampler, r, omega.z, mu_s, nu, false);
                let mie = scattering_lookup(atmosphere, single_mie, table_sampler, r, omega.z, mu_s, nu, false);
                l = rayleigh * rayleigh_phase_function(nu) + mie * mie_phase_function(atmosphere.shape.z, nu);
            } else {
                l = scattering_lookup(atmosphere, multiple, table_sampler, r, omega.z, mu_s, nu, false);
            }
            sum += l * omega.z * domega;
        }
    }
    let previous = textureLoad(previous_irradiance_load, id.xy, 0).rgb;
    textureStore(out_delta_irradiance, id.xy, vec4f(sum, 1.0));
    textureStore(out_irradiance, id.xy, vec4f(previous + sum, 1.0));
}
