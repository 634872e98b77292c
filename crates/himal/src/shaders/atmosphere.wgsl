// L1 Bruneton & Neyret 2008 precomputed atmospheric scattering, following the
// structure and names of Bruneton's 2017 reference implementation
// (atmosphere/functions.glsl). Lengths in km, three wavelengths as straight
// RGB (680, 550, 440 nm), tables per unit extraterrestrial solar irradiance.
// Twin: crates/himal/src/passes/sky/bruneton/reference.rs.
#import math

// Twin of AtmosphereGpuParams (11 x vec4f = 176 bytes).
struct AtmosphereParams {
    // bottom radius, top radius (km), Mie g, mu_s_min
    shape: vec4f,
    // Rayleigh scattering = extinction (1/km); w: Rayleigh density exp scale (1/km)
    rayleigh_scattering: vec4f,
    // Mie scattering (1/km); w: Mie density exp scale (1/km)
    mie_scattering: vec4f,
    // Mie extinction (1/km); w: width of the lower ozone layer (km)
    mie_extinction: vec4f,
    // Ozone absorption extinction at peak density (1/km); w: sun angular radius (rad)
    absorption_extinction: vec4f,
    // Ozone tent: lower layer linear, constant; upper layer linear, constant
    ozone_density: vec4f,
    // Ground albedo; w: radiance scale (klux of the extraterrestrial sun)
    ground_albedo: vec4f,
    // Solar irradiance at the top in table units (1); w: viewer altitude (km)
    solar_irradiance: vec4f,
    // transmittance width, height; irradiance width, height
    sizes_2d: vec4f,
    // scattering r, mu, mu_s, nu sizes
    sizes_4d: vec4f,
    // Night sky radiance floor (linear RGB, kcd/m^2); w: ground blend width in -dir.y
    night_radiance: vec4f,
}

fn atmosphere_clamp_cosine(mu: f32) -> f32 {
    return clamp(mu, -1.0, 1.0);
}

fn atmosphere_clamp_radius(atm: AtmosphereParams, r: f32) -> f32 {
    return clamp(r, atm.shape.x, atm.shape.y);
}

fn atmosphere_safe_sqrt(a: f32) -> f32 {
    return sqrt(max(a, 0.0));
}

fn distance_to_top_atmosphere_boundary(atm: AtmosphereParams, r: f32, mu: f32) -> f32 {
    let discriminant = r * r * (mu * mu - 1.0) + atm.shape.y * atm.shape.y;
    return max(-r * mu + atmosphere_safe_sqrt(discriminant), 0.0);
}

fn distance_to_bottom_atmosphere_boundary(atm: AtmosphereParams, r: f32, mu: f32) -> f32 {
    let discriminant = r * r * (mu * mu - 1.0) + atm.shape.x * atm.shape.x;
    return max(-r * mu - atmosphere_safe_sqrt(discriminant), 0.0);
}

fn ray_intersects_ground(atm: AtmosphereParams, r: f32, mu: f32) -> bool {
    return mu < 0.0 && r * r * (mu * mu - 1.0) + atm.shape.x * atm.shape.x >= 0.0;
}

fn distance_to_nearest_atmosphere_boundary(atm: AtmosphereParams, r: f32, mu: f32, ground: bool) -> f32 {
    if (ground) {
        return distance_to_bottom_atmosphere_boundary(atm, r, mu);
    }
    return distance_to_top_atmosphere_boundary(atm, r, mu);
}

// Density profiles (0..1): exponential Rayleigh and Mie, ozone tent around 25 km.
fn rayleigh_density(atm: AtmosphereParams, altitude: f32) -> f32 {
    return clamp(exp(atm.rayleigh_scattering.w * altitude), 0.0, 1.0);
}

fn mie_density(atm: AtmosphereParams, altitude: f32) -> f32 {
    return clamp(exp(atm.mie_scattering.w * altitude), 0.0, 1.0);
}

fn ozone_density(atm: AtmosphereParams, altitude: f32) -> f32 {
    let o = atm.ozone_density;
    if (altitude < atm.mie_extinction.w) {
        return clamp(o.x * altitude + o.y, 0.0, 1.0);
    }
    return clamp(o.z * altitude + o.w, 0.0, 1.0);
}

// Extinction coefficient (1/km) at `altitude`.
fn atmosphere_extinction(atm: AtmosphereParams, altitude: f32) -> vec3f {
    return atm.rayleigh_scattering.xyz * rayleigh_density(atm, altitude)
        + atm.mie_extinction.xyz * mie_density(atm, altitude)
        + atm.absorption_extinction.xyz * ozone_density(atm, altitude);
}

// T(r, mu) to the top boundary: exp(-integral of extinction), trapezoid rule,
// 500 steps as in the reference.
fn compute_transmittance_to_top_atmosphere_boundary(atm: AtmosphereParams, r: f32, mu: f32) -> vec3f {
    let sample_count = 500;
    let dx = distance_to_top_atmosphere_boundary(atm, r, mu) / f32(sample_count);
    var optical_depth = vec3f(0.0);
    for (var i = 0; i <= sample_count; i++) {
        let d_i = f32(i) * dx;
        let r_i = sqrt(d_i * d_i + 2.0 * r * mu * d_i + r * r);
        let weight = select(1.0, 0.5, i == 0 || i == sample_count);
        optical_depth += atmosphere_extinction(atm, r_i - atm.shape.x) * (weight * dx);
    }
    return exp(-optical_depth);
}

fn texture_coord_from_unit_range(x: f32, size: f32) -> f32 {
    return 0.5 / size + x * (1.0 - 1.0 / size);
}

fn unit_range_from_texture_coord(u: f32, size: f32) -> f32 {
    return (u - 0.5 / size) / (1.0 - 1.0 / size);
}

fn transmittance_uv_from_r_mu(atm: AtmosphereParams, r: f32, mu: f32) -> vec2f {
    let bottom = atm.shape.x;
    let top = atm.shape.y;
    let h = sqrt(top * top - bottom * bottom);
    let rho = atmosphere_safe_sqrt(r * r - bottom * bottom);
    let d = distance_to_top_atmosphere_boundary(atm, r, mu);
    let d_min = top - r;
    let d_max = rho + h;
    let x_mu = (d - d_min) / (d_max - d_min);
    let x_r = rho / h;
    return vec2f(
        texture_coord_from_unit_range(x_mu, atm.sizes_2d.x),
        texture_coord_from_unit_range(x_r, atm.sizes_2d.y),
    );
}

fn r_mu_from_transmittance_uv(atm: AtmosphereParams, uv: vec2f) -> vec2f {
    let bottom = atm.shape.x;
    let top = atm.shape.y;
    let x_mu = unit_range_from_texture_coord(uv.x, atm.sizes_2d.x);
    let x_r = unit_range_from_texture_coord(uv.y, atm.sizes_2d.y);
    let h = sqrt(top * top - bottom * bottom);
    let rho = h * x_r;
    let r = sqrt(rho * rho + bottom * bottom);
    let d_min = top - r;
    let d_max = rho + h;
    let d = d_min + x_mu * (d_max - d_min);
    var mu = 1.0;
    if (d != 0.0) {
        mu = atmosphere_clamp_cosine((h * h - rho * rho - d * d) / (2.0 * r * d));
    }
    return vec2f(r, mu);
}

// Bilinear filtering by hand (clamp to edge): the transmittance table is
// Rgba32Float, which needs no FLOAT32_FILTERABLE this way. f32 because grazing
// rays reach T ~ 1e-5, where f16 loses the ratios transmittance_along_ray takes.
fn sample_bilinear_load(table: texture_2d<f32>, uv: vec2f) -> vec3f {
    let size = vec2f(textureDimensions(table));
    let x = uv * size - 0.5;
    let x0 = floor(x);
    let t = x - x0;
    let hi = vec2i(size) - 1;
    let i0 = clamp(vec2i(x0), vec2i(0), hi);
    let i1 = clamp(vec2i(x0) + 1, vec2i(0), hi);
    let a = mix(textureLoad(table, vec2i(i0.x, i0.y), 0).rgb, textureLoad(table, vec2i(i1.x, i0.y), 0).rgb, t.x);
    let b = mix(textureLoad(table, vec2i(i0.x, i1.y), 0).rgb, textureLoad(table, vec2i(i1.x, i1.y), 0).rgb, t.x);
    return mix(a, b, t.y);
}

fn transmittance_to_top_atmosphere_boundary(
    atm: AtmosphereParams, transmittance: texture_2d<f32>, table_sampler: sampler, r: f32, mu: f32,
) -> vec3f {
    return sample_bilinear_load(transmittance, transmittance_uv_from_r_mu(atm, r, mu));
}

// Transmittance between the point at (r, mu) and the point at distance d along the ray.
fn transmittance_along_ray(
    atm: AtmosphereParams, transmittance: texture_2d<f32>, table_sampler: sampler,
    r: f32, mu: f32, d: f32, ground: bool,
) -> vec3f {
    let r_d = atmosphere_clamp_radius(atm, sqrt(d * d + 2.0 * r * mu * d + r * r));
    let mu_d = atmosphere_clamp_cosine((r * mu + d) / r_d);
    if (ground) {
        return min(
            transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r_d, -mu_d)
                / transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r, -mu),
            vec3f(1.0),
        );
    }
    return min(
        transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r, mu)
            / transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r_d, mu_d),
        vec3f(1.0),
    );
}

// Transmittance to the sun, faded by the fraction of the sun disk above the horizon.
fn transmittance_to_sun(
    atm: AtmosphereParams, transmittance: texture_2d<f32>, table_sampler: sampler, r: f32, mu_s: f32,
) -> vec3f {
    let sin_theta_h = atm.shape.x / r;
    let cos_theta_h = -sqrt(max(1.0 - sin_theta_h * sin_theta_h, 0.0));
    let alpha = atm.absorption_extinction.w;
    return transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r, mu_s)
        * smoothstep(-sin_theta_h * alpha, sin_theta_h * alpha, mu_s - cos_theta_h);
}

fn rayleigh_phase_function(nu: f32) -> f32 {
    return 3.0 / (16.0 * PI) * (1.0 + nu * nu);
}

// Cornette-Shanks phase function, as the reference.
fn mie_phase_function(g: f32, nu: f32) -> f32 {
    let k = 3.0 / (8.0 * PI) * (1.0 - g * g) / (2.0 + g * g);
    return k * (1.0 + nu * nu) / pow(1.0 + g * g - 2.0 * g * nu, 1.5);
}

// 4D (r, mu, mu_s, nu) -> (u_nu, u_mu_s, u_mu, u_r), reference mapping.
fn scattering_uvwz_from_r_mu_mu_s_nu(
    atm: AtmosphereParams, r: f32, mu: f32, mu_s: f32, nu: f32, ground: bool,
) -> vec4f {
    let bottom = atm.shape.x;
    let top = atm.shape.y;
    let sizes = atm.sizes_4d;
    let h = sqrt(top * top - bottom * bottom);
    let rho = atmosphere_safe_sqrt(r * r - bottom * bottom);
    let u_r = texture_coord_from_unit_range(rho / h, sizes.x);
    let r_mu = r * mu;
    let discriminant = r_mu * r_mu - r * r + bottom * bottom;
    var u_mu: f32;
    if (ground) {
        let d = -r_mu - atmosphere_safe_sqrt(discriminant);
        let d_min = r - bottom;
        let d_max = rho;
        var x = 0.0;
        if (d_max != d_min) {
            x = (d - d_min) / (d_max - d_min);
        }
        u_mu = 0.5 - 0.5 * texture_coord_from_unit_range(x, sizes.y / 2.0);
    } else {
        let d = -r_mu + atmosphere_safe_sqrt(discriminant + h * h);
        let d_min = top - r;
        let d_max = rho + h;
        u_mu = 0.5 + 0.5 * texture_coord_from_unit_range((d - d_min) / (d_max - d_min), sizes.y / 2.0);
    }
    let d = distance_to_top_atmosphere_boundary(atm, bottom, mu_s);
    let d_min = top - bottom;
    let d_max = h;
    let a = (d - d_min) / (d_max - d_min);
    let big_d = distance_to_top_atmosphere_boundary(atm, bottom, atm.shape.w);
    let big_a = (big_d - d_min) / (d_max - d_min);
    let u_mu_s = texture_coord_from_unit_range(max(1.0 - a / big_a, 0.0) / (1.0 + a), sizes.z);
    let u_nu = (nu + 1.0) / 2.0;
    return vec4f(u_nu, u_mu_s, u_mu, u_r);
}

// Inverse of the mapping above; returns (r, mu, mu_s, nu), ground in the flag.
struct ScatteringCoords {
    r: f32,
    mu: f32,
    mu_s: f32,
    nu: f32,
    ground: bool,
}

fn r_mu_mu_s_nu_from_scattering_uvwz(atm: AtmosphereParams, uvwz: vec4f) -> ScatteringCoords {
    let bottom = atm.shape.x;
    let top = atm.shape.y;
    let sizes = atm.sizes_4d;
    var c: ScatteringCoords;
    let h = sqrt(top * top - bottom * bottom);
    let rho = h * unit_range_from_texture_coord(uvwz.w, sizes.x);
    c.r = sqrt(rho * rho + bottom * bottom);
    if (uvwz.z < 0.5) {
        let d_min = c.r - bottom;
        let d_max = rho;
        let d = d_min + (d_max - d_min) * unit_range_from_texture_coord(1.0 - 2.0 * uvwz.z, sizes.y / 2.0);
        c.mu = -1.0;
        if (d != 0.0) {
            c.mu = atmosphere_clamp_cosine(-(rho * rho + d * d) / (2.0 * c.r * d));
        }
        c.ground = true;
    } else {
        let d_min = top - c.r;
        let d_max = rho + h;
        let d = d_min + (d_max - d_min) * unit_range_from_texture_coord(2.0 * uvwz.z - 1.0, sizes.y / 2.0);
        c.mu = 1.0;
        if (d != 0.0) {
            c.mu = atmosphere_clamp_cosine((h * h - rho * rho - d * d) / (2.0 * c.r * d));
        }
        c.ground = false;
    }
    let x_mu_s = unit_range_from_texture_coord(uvwz.y, sizes.z);
    let d_min = top - bottom;
    let d_max = h;
    let big_d = distance_to_top_atmosphere_boundary(atm, bottom, atm.shape.w);
    let big_a = (big_d - d_min) / (d_max - d_min);
    let a = (big_a - x_mu_s * big_a) / (1.0 + x_mu_s * big_a);
    let d = d_min + min(a, big_a) * (d_max - d_min);
    c.mu_s = 1.0;
    if (d != 0.0) {
        c.mu_s = atmosphere_clamp_cosine((h * h - d * d) / (2.0 * bottom * d));
    }
    c.nu = atmosphere_clamp_cosine(uvwz.x * 2.0 - 1.0);
    return c;
}

// Texel centre `frag` (x = nu * mu_s_size + mu_s, y = mu, z = r) of the 3D table.
fn scattering_coords_from_texel(atm: AtmosphereParams, frag: vec3f) -> ScatteringCoords {
    let sizes = atm.sizes_4d;
    let frag_nu = floor(frag.x / sizes.z);
    let frag_mu_s = frag.x - frag_nu * sizes.z;
    let uvwz = vec4f(frag_nu / (sizes.w - 1.0), frag_mu_s / sizes.z, frag.y / sizes.y, frag.z / sizes.x);
    var c = r_mu_mu_s_nu_from_scattering_uvwz(atm, uvwz);
    // nu is bounded by mu and mu_s (the three directions must exist).
    let s = sqrt((1.0 - c.mu * c.mu) * (1.0 - c.mu_s * c.mu_s));
    c.nu = clamp(c.nu, c.mu * c.mu_s - s, c.mu * c.mu_s + s);
    return c;
}

// 4D lookup: two trilinear samples of the 3D texture, lerped in nu.
fn scattering_lookup(
    atm: AtmosphereParams, table: texture_3d<f32>, table_sampler: sampler,
    r: f32, mu: f32, mu_s: f32, nu: f32, ground: bool,
) -> vec3f {
    let uvwz = scattering_uvwz_from_r_mu_mu_s_nu(atm, r, mu, mu_s, nu, ground);
    let nu_size = atm.sizes_4d.w;
    let tex_coord_x = uvwz.x * (nu_size - 1.0);
    let tex_x = floor(tex_coord_x);
    let t = tex_coord_x - tex_x;
    let uvw0 = vec3f((tex_x + uvwz.y) / nu_size, uvwz.z, uvwz.w);
    let uvw1 = vec3f((tex_x + 1.0 + uvwz.y) / nu_size, uvwz.z, uvwz.w);
    return textureSampleLevel(table, table_sampler, uvw0, 0.0).rgb * (1.0 - t)
        + textureSampleLevel(table, table_sampler, uvw1, 0.0).rgb * t;
}

fn irradiance_uv_from_r_mu_s(atm: AtmosphereParams, r: f32, mu_s: f32) -> vec2f {
    let x_r = (r - atm.shape.x) / (atm.shape.y - atm.shape.x);
    let x_mu_s = mu_s * 0.5 + 0.5;
    return vec2f(
        texture_coord_from_unit_range(x_mu_s, atm.sizes_2d.z),
        texture_coord_from_unit_range(x_r, atm.sizes_2d.w),
    );
}

fn r_mu_s_from_irradiance_uv(atm: AtmosphereParams, uv: vec2f) -> vec2f {
    let x_mu_s = unit_range_from_texture_coord(uv.x, atm.sizes_2d.z);
    let x_r = unit_range_from_texture_coord(uv.y, atm.sizes_2d.w);
    return vec2f(atm.shape.x + x_r * (atm.shape.y - atm.shape.x), atmosphere_clamp_cosine(2.0 * x_mu_s - 1.0));
}

fn irradiance_lookup(
    atm: AtmosphereParams, irradiance: texture_2d<f32>, table_sampler: sampler, r: f32, mu_s: f32,
) -> vec3f {
    let uv = irradiance_uv_from_r_mu_s(atm, r, mu_s);
    return textureSampleLevel(irradiance, table_sampler, uv, 0.0).rgb;
}

// Direct sun irradiance on a horizontal surface at r (disk partly set: average cosine).
fn compute_direct_irradiance(
    atm: AtmosphereParams, transmittance: texture_2d<f32>, table_sampler: sampler, r: f32, mu_s: f32,
) -> vec3f {
    let alpha_s = atm.absorption_extinction.w;
    var average_cosine = mu_s;
    if (mu_s < -alpha_s) {
        average_cosine = 0.0;
    } else if (mu_s <= alpha_s) {
        average_cosine = (mu_s + alpha_s) * (mu_s + alpha_s) / (4.0 * alpha_s);
    }
    return atm.solar_irradiance.xyz
        * transmittance_to_top_atmosphere_boundary(atm, transmittance, table_sampler, r, mu_s) * average_cosine;
}

// Sky radiance seen from the viewer altitude along unit `dir` (y up) with the
// sun towards unit `sun` (kcd/m^2, linear RGB): single Rayleigh + Mie with
// their phase functions plus multiple scattering (stored / Rayleigh phase).
// Below the horizon: the horizon value at that azimuth blended into a
// Lambertian ground lit by the table's direct and sky irradiance. Night floor added.
fn bruneton_sky_radiance(
    atm: AtmosphereParams,
    transmittance: texture_2d<f32>,
    scattering: texture_3d<f32>,
    single_mie: texture_3d<f32>,
    irradiance: texture_2d<f32>,
    table_sampler: sampler,
    dir: vec3f,
    sun: vec3f,
) -> vec3f {
    let r = atm.shape.x + atm.solar_irradiance.w;
    let mu_s = sun.y;
    var view = dir;
    if (dir.y < 0.0) {
        let h = vec3f(dir.x, 0.0, dir.z);
        let h_len = length(h);
        view = select(vec3f(1.0, 0.0, 0.0), h / h_len, h_len > 0.0);
    }
    let mu = view.y;
    let nu = clamp(dot(view, sun), -1.0, 1.0);
    let ground = ray_intersects_ground(atm, r, mu);
    let multiple_and_rayleigh = scattering_lookup(atm, scattering, table_sampler, r, mu, mu_s, nu, ground);
    let mie = scattering_lookup(atm, single_mie, table_sampler, r, mu, mu_s, nu, ground);
    let sky = (multiple_and_rayleigh * rayleigh_phase_function(nu) + mie * mie_phase_function(atm.shape.z, nu))
        * atm.ground_albedo.w + atm.night_radiance.xyz;
    if (dir.y >= 0.0) {
        return sky;
    }
    let e_ground = compute_direct_irradiance(atm, transmittance, table_sampler, r, mu_s)
        + irradiance_lookup(atm, irradiance, table_sampler, r, mu_s);
    let l_ground = atm.ground_albedo.xyz * (e_ground * atm.ground_albedo.w / PI + atm.night_radiance.xyz);
    return mix(sky, l_ground, smoothstep(0.0, atm.night_radiance.w, -dir.y));
}
