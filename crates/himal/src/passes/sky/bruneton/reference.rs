//! CPU twin of the Bruneton tables and sky (`shaders/atmosphere.wgsl`,
//! `passes/sky/bruneton/*.wgsl`): the integrals evaluated directly in f64 at
//! single points (transmittance by ray marching, single scattering with the
//! marched transmittance), the table parametrisations, and [`CpuTables`]:
//! lookups into read-back GPU tables with the sampler's bilinear filtering,
//! for the sky radiance and its SH projection.

use glam::{DVec3, Vec3};

use super::{AtmosphereConfig, BrunetonTables, OZONE_LAYER_WIDTH_KM, OZONE_TENT};
use crate::gpu::{GpuContext, GpuError, read_texture};
use crate::passes::sky::sun::SUN_ILLUMINANCE_KLUX;

fn dv(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// Distance (km) from radius `r` along zenith cosine `mu` to the top of the atmosphere.
pub fn distance_to_top(c: &AtmosphereConfig, r: f64, mu: f64) -> f64 {
    let top = f64::from(c.top_radius_km);
    let disc = r * r * (mu * mu - 1.0) + top * top;
    (-r * mu + disc.max(0.0).sqrt()).max(0.0)
}

/// Distance (km) from (r, mu) to the ground sphere, where [`ray_intersects_ground`] holds.
pub fn distance_to_bottom(c: &AtmosphereConfig, r: f64, mu: f64) -> f64 {
    let bottom = f64::from(c.bottom_radius_km);
    let disc = r * r * (mu * mu - 1.0) + bottom * bottom;
    (-r * mu - disc.max(0.0).sqrt()).max(0.0)
}

/// Whether the ray from radius `r` with zenith cosine `mu` hits the ground sphere.
pub fn ray_intersects_ground(c: &AtmosphereConfig, r: f64, mu: f64) -> bool {
    let bottom = f64::from(c.bottom_radius_km);
    mu < 0.0 && r * r * (mu * mu - 1.0) + bottom * bottom >= 0.0
}

/// Extinction (1/km) at `altitude` km: Rayleigh + Mie + ozone.
pub fn extinction(c: &AtmosphereConfig, altitude: f64) -> DVec3 {
    let rayleigh = (-altitude / f64::from(c.rayleigh_scale_height_km))
        .exp()
        .min(1.0);
    let mie = (-altitude / f64::from(c.mie_scale_height_km))
        .exp()
        .min(1.0);
    let o = OZONE_TENT.map(f64::from);
    let ozone = if altitude < f64::from(OZONE_LAYER_WIDTH_KM) {
        o[0] * altitude + o[1]
    } else {
        o[2] * altitude + o[3]
    }
    .clamp(0.0, 1.0);
    dv(c.rayleigh_scattering) * rayleigh
        + dv(c.mie_extinction) * mie
        + dv(c.absorption_extinction) * ozone
}

fn densities(c: &AtmosphereConfig, altitude: f64) -> (f64, f64) {
    (
        (-altitude / f64::from(c.rayleigh_scale_height_km))
            .exp()
            .min(1.0),
        (-altitude / f64::from(c.mie_scale_height_km))
            .exp()
            .min(1.0),
    )
}

/// Transmittance over `length` km from (r, mu), midpoint rule with `steps` steps.
pub fn transmittance_segment(
    c: &AtmosphereConfig,
    r: f64,
    mu: f64,
    length: f64,
    steps: u32,
) -> DVec3 {
    let dx = length / f64::from(steps);
    let bottom = f64::from(c.bottom_radius_km);
    let mut depth = DVec3::ZERO;
    for i in 0..steps {
        let d = (f64::from(i) + 0.5) * dx;
        let r_i = (d * d + 2.0 * r * mu * d + r * r).sqrt();
        depth += extinction(c, r_i - bottom) * dx;
    }
    (-depth).exp()
}

/// T(r, mu) to the top of the atmosphere, ray-marched with `steps` steps.
pub fn transmittance_to_top(c: &AtmosphereConfig, r: f64, mu: f64, steps: u32) -> DVec3 {
    transmittance_segment(c, r, mu, distance_to_top(c, r, mu), steps)
}

/// Rayleigh phase function at scattering-angle cosine `nu` (1/sr).
pub fn rayleigh_phase(nu: f64) -> f64 {
    3.0 / (16.0 * std::f64::consts::PI) * (1.0 + nu * nu)
}

/// Cornette-Shanks Mie phase function of asymmetry `g` at scattering-angle cosine `nu` (1/sr).
pub fn mie_phase(g: f64, nu: f64) -> f64 {
    let k = 3.0 / (8.0 * std::f64::consts::PI) * (1.0 - g * g) / (2.0 + g * g);
    k * (1.0 + nu * nu) / (1.0 + g * g - 2.0 * g * nu).powf(1.5)
}

/// Single (Rayleigh, Mie) scattering without phase functions, per unit solar
/// irradiance, at (r, mu, mu_s, nu): `steps` midpoint steps along the ray to
/// the nearest boundary with the view transmittance accumulated on the way,
/// the sun's ray-marched (no tables, no sun-disk fade).
pub fn single_scattering(
    c: &AtmosphereConfig,
    r: f64,
    mu: f64,
    mu_s: f64,
    nu: f64,
    steps: u32,
) -> (DVec3, DVec3) {
    let ground = ray_intersects_ground(c, r, mu);
    let length = if ground {
        distance_to_bottom(c, r, mu)
    } else {
        distance_to_top(c, r, mu)
    };
    let bottom = f64::from(c.bottom_radius_km);
    let dx = length / f64::from(steps);
    let (mut rayleigh, mut mie) = (DVec3::ZERO, DVec3::ZERO);
    let mut depth = DVec3::ZERO;
    let radius = |d: f64| (d * d + 2.0 * r * mu * d + r * r).sqrt();
    for i in 0..steps {
        let d = (f64::from(i) + 0.5) * dx;
        // Optical depth from the start to d: the previous sample's plus two half steps.
        let d_prev = (d - dx).max(0.0);
        depth += extinction(c, radius(0.5 * (d_prev + d)) - bottom) * (d - d_prev);
        let r_d = radius(d);
        let mu_s_d = ((r * mu_s + d * nu) / r_d).clamp(-1.0, 1.0);
        let t = if ray_intersects_ground(c, r_d, mu_s_d) {
            DVec3::ZERO
        } else {
            (-depth).exp() * transmittance_to_top(c, r_d, mu_s_d, 500)
        };
        let (rho_r, rho_m) = densities(c, r_d - bottom);
        rayleigh += t * rho_r * dx;
        mie += t * rho_m * dx;
    }
    (
        rayleigh * dv(c.rayleigh_scattering),
        mie * dv(c.mie_scattering),
    )
}

fn tex_coord(x: f64, size: f64) -> f64 {
    0.5 / size + x * (1.0 - 1.0 / size)
}

fn unit_range(u: f64, size: f64) -> f64 {
    (u - 0.5 / size) / (1.0 - 1.0 / size)
}

/// (r, mu) of the centre of transmittance texel (i, j).
pub fn transmittance_texel_r_mu(c: &AtmosphereConfig, i: u32, j: u32) -> (f64, f64) {
    let (w, h) = c.sizes.transmittance;
    let x_mu = unit_range((f64::from(i) + 0.5) / f64::from(w), f64::from(w));
    let x_r = unit_range((f64::from(j) + 0.5) / f64::from(h), f64::from(h));
    let (bottom, top) = (f64::from(c.bottom_radius_km), f64::from(c.top_radius_km));
    let big_h = (top * top - bottom * bottom).sqrt();
    let rho = big_h * x_r;
    let r = (rho * rho + bottom * bottom).sqrt();
    let (d_min, d_max) = (top - r, rho + big_h);
    let d = d_min + x_mu * (d_max - d_min);
    let mu = if d == 0.0 {
        1.0
    } else {
        ((big_h * big_h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
    };
    (r, mu)
}

/// Transmittance table uv of (r, mu).
pub fn transmittance_uv(c: &AtmosphereConfig, r: f64, mu: f64) -> (f64, f64) {
    let (w, h) = c.sizes.transmittance;
    let (bottom, top) = (f64::from(c.bottom_radius_km), f64::from(c.top_radius_km));
    let big_h = (top * top - bottom * bottom).sqrt();
    let rho = (r * r - bottom * bottom).max(0.0).sqrt();
    let d = distance_to_top(c, r, mu);
    let (d_min, d_max) = (top - r, rho + big_h);
    (
        tex_coord((d - d_min) / (d_max - d_min), f64::from(w)),
        tex_coord(rho / big_h, f64::from(h)),
    )
}

/// (r, mu, mu_s, nu, ground) of the centre of scattering texel (x, y, z).
pub fn scattering_texel_coords(
    c: &AtmosphereConfig,
    x: u32,
    y: u32,
    z: u32,
) -> (f64, f64, f64, f64, bool) {
    let s = c.sizes;
    let (size_r, size_mu, size_mu_s, size_nu) = (
        f64::from(s.r),
        f64::from(s.mu),
        f64::from(s.mu_s),
        f64::from(s.nu),
    );
    let fx = f64::from(x) + 0.5;
    let frag_nu = (fx / size_mu_s).floor();
    let frag_mu_s = fx - frag_nu * size_mu_s;
    let (u_nu, u_mu_s) = (frag_nu / (size_nu - 1.0), frag_mu_s / size_mu_s);
    let u_mu = (f64::from(y) + 0.5) / size_mu;
    let u_r = (f64::from(z) + 0.5) / size_r;
    let (bottom, top) = (f64::from(c.bottom_radius_km), f64::from(c.top_radius_km));
    let big_h = (top * top - bottom * bottom).sqrt();
    let rho = big_h * unit_range(u_r, size_r);
    let r = (rho * rho + bottom * bottom).sqrt();
    let (mu, ground) = if u_mu < 0.5 {
        let (d_min, d_max) = (r - bottom, rho);
        let d = d_min + (d_max - d_min) * unit_range(1.0 - 2.0 * u_mu, size_mu / 2.0);
        let mu = if d == 0.0 {
            -1.0
        } else {
            (-(rho * rho + d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
        };
        (mu, true)
    } else {
        let (d_min, d_max) = (top - r, rho + big_h);
        let d = d_min + (d_max - d_min) * unit_range(2.0 * u_mu - 1.0, size_mu / 2.0);
        let mu = if d == 0.0 {
            1.0
        } else {
            ((big_h * big_h - rho * rho - d * d) / (2.0 * r * d)).clamp(-1.0, 1.0)
        };
        (mu, false)
    };
    let x_mu_s = unit_range(u_mu_s, size_mu_s);
    let (d_min, d_max) = (top - bottom, big_h);
    let big_d = distance_to_top(c, bottom, f64::from(c.mu_s_min));
    let big_a = (big_d - d_min) / (d_max - d_min);
    let a = (big_a - x_mu_s * big_a) / (1.0 + x_mu_s * big_a);
    let d = d_min + a.min(big_a) * (d_max - d_min);
    let mu_s = if d == 0.0 {
        1.0
    } else {
        ((big_h * big_h - d * d) / (2.0 * bottom * d)).clamp(-1.0, 1.0)
    };
    let nu = (u_nu * 2.0 - 1.0).clamp(-1.0, 1.0);
    let sq = ((1.0 - mu * mu) * (1.0 - mu_s * mu_s)).sqrt();
    (
        r,
        mu,
        mu_s,
        nu.clamp(mu * mu_s - sq, mu * mu_s + sq),
        ground,
    )
}

/// (u_nu, u_mu_s, u_mu, u_r) of (r, mu, mu_s, nu).
pub fn scattering_uvwz(
    c: &AtmosphereConfig,
    r: f64,
    mu: f64,
    mu_s: f64,
    nu: f64,
    ground: bool,
) -> [f64; 4] {
    let s = c.sizes;
    let (bottom, top) = (f64::from(c.bottom_radius_km), f64::from(c.top_radius_km));
    let big_h = (top * top - bottom * bottom).sqrt();
    let rho = (r * r - bottom * bottom).max(0.0).sqrt();
    let u_r = tex_coord(rho / big_h, f64::from(s.r));
    let r_mu = r * mu;
    let disc = r_mu * r_mu - r * r + bottom * bottom;
    let half_mu = f64::from(s.mu) / 2.0;
    let u_mu = if ground {
        let d = -r_mu - disc.max(0.0).sqrt();
        let (d_min, d_max) = (r - bottom, rho);
        let x = if d_max == d_min {
            0.0
        } else {
            (d - d_min) / (d_max - d_min)
        };
        0.5 - 0.5 * tex_coord(x, half_mu)
    } else {
        let d = -r_mu + (disc + big_h * big_h).max(0.0).sqrt();
        let (d_min, d_max) = (top - r, rho + big_h);
        0.5 + 0.5 * tex_coord((d - d_min) / (d_max - d_min), half_mu)
    };
    let d = distance_to_top(c, bottom, mu_s);
    let (d_min, d_max) = (top - bottom, big_h);
    let a = (d - d_min) / (d_max - d_min);
    let big_d = distance_to_top(c, bottom, f64::from(c.mu_s_min));
    let big_a = (big_d - d_min) / (d_max - d_min);
    let u_mu_s = tex_coord((1.0 - a / big_a).max(0.0) / (1.0 + a), f64::from(s.mu_s));
    [(nu + 1.0) / 2.0, u_mu_s, u_mu, u_r]
}

/// A read-back RGBA table with the GPU sampler's filtering (linear, clamp to edge).
pub struct CpuTable {
    /// Width, height and depth in texels (depth 1 for the 2D tables).
    pub size: (u32, u32, u32),
    /// RGBA texels, row-major, slice after slice.
    pub texels: Vec<[f32; 4]>,
}

fn linear_axis(u: f64, n: u32) -> (usize, usize, f64) {
    let x = u * f64::from(n) - 0.5;
    let i0 = x.floor();
    let t = x - i0;
    let clamp = |i: f64| i.clamp(0.0, f64::from(n - 1)) as usize;
    (clamp(i0), clamp(i0 + 1.0), t)
}

impl CpuTable {
    /// RGB of texel (x, y, z), unfiltered.
    pub fn texel(&self, x: u32, y: u32, z: u32) -> Vec3 {
        let (w, h, _) = self.size;
        let t = self.texels[((z * h + y) * w + x) as usize];
        Vec3::new(t[0], t[1], t[2])
    }

    /// Trilinear (bilinear where depth is 1) sample at normalised (u, v, w).
    pub fn sample(&self, u: f64, v: f64, w: f64) -> DVec3 {
        let (x0, x1, tx) = linear_axis(u, self.size.0);
        let (y0, y1, ty) = linear_axis(v, self.size.1);
        let (z0, z1, tz) = linear_axis(w, self.size.2);
        let at = |x: usize, y: usize, z: usize| self.texel(x as u32, y as u32, z as u32).as_dvec3();
        let lerp = |a: DVec3, b: DVec3, t: f64| a + (b - a) * t;
        let plane = |z: usize| {
            lerp(
                lerp(at(x0, y0, z), at(x1, y0, z), tx),
                lerp(at(x0, y1, z), at(x1, y1, z), tx),
                ty,
            )
        };
        lerp(plane(z0), plane(z1), tz)
    }

    /// Reads `texture` back from the GPU, every depth slice.
    pub fn read(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Self, GpuError> {
        let depth = texture.depth_or_array_layers();
        let mut texels = Vec::new();
        for z in 0..depth {
            texels.extend(read_texture(ctx, texture, 0, z)?.to_rgba_f32()?);
        }
        Ok(CpuTable {
            size: (texture.width(), texture.height(), depth),
            texels,
        })
    }
}

/// Read-back tables and the CPU twin of `bruneton_sky_radiance`.
pub struct CpuTables {
    /// The atmosphere the tables were computed for (their parametrisation).
    pub config: AtmosphereConfig,
    /// Read-back [`BrunetonTables::transmittance`].
    pub transmittance: CpuTable,
    /// Read-back [`BrunetonTables::scattering`].
    pub scattering: CpuTable,
    /// Read-back [`BrunetonTables::single_rayleigh`].
    pub single_rayleigh: CpuTable,
    /// Read-back [`BrunetonTables::single_mie`].
    pub single_mie: CpuTable,
    /// Read-back [`BrunetonTables::irradiance`].
    pub irradiance: CpuTable,
}

impl CpuTables {
    /// Reads every table of `tables` back from the GPU.
    pub fn read(ctx: &GpuContext, tables: &BrunetonTables) -> Result<Self, GpuError> {
        Ok(CpuTables {
            config: tables.config.clone(),
            transmittance: CpuTable::read(ctx, &tables.transmittance)?,
            scattering: CpuTable::read(ctx, &tables.scattering)?,
            single_rayleigh: CpuTable::read(ctx, &tables.single_rayleigh)?,
            single_mie: CpuTable::read(ctx, &tables.single_mie)?,
            irradiance: CpuTable::read(ctx, &tables.irradiance)?,
        })
    }

    /// T(r, mu) to the top of the atmosphere, looked up in the table as the shaders do.
    pub fn transmittance_to_top(&self, r: f64, mu: f64) -> DVec3 {
        let (u, v) = transmittance_uv(&self.config, r, mu);
        self.transmittance.sample(u, v, 0.5)
    }

    /// 4D lookup: two samples lerped in nu, as `scattering_lookup`.
    pub fn scattering_lookup(
        &self,
        table: &CpuTable,
        r: f64,
        mu: f64,
        mu_s: f64,
        nu: f64,
        ground: bool,
    ) -> DVec3 {
        let [u_nu, u_mu_s, u_mu, u_r] = scattering_uvwz(&self.config, r, mu, mu_s, nu, ground);
        let nu_size = f64::from(self.config.sizes.nu);
        let x = u_nu * (nu_size - 1.0);
        let x0 = x.floor();
        let t = x - x0;
        table.sample((x0 + u_mu_s) / nu_size, u_mu, u_r) * (1.0 - t)
            + table.sample((x0 + 1.0 + u_mu_s) / nu_size, u_mu, u_r) * t
    }

    fn irradiance_lookup(&self, r: f64, mu_s: f64) -> DVec3 {
        let c = &self.config;
        let (w, h) = c.sizes.irradiance;
        let x_r =
            (r - f64::from(c.bottom_radius_km)) / f64::from(c.top_radius_km - c.bottom_radius_km);
        self.irradiance.sample(
            tex_coord(mu_s * 0.5 + 0.5, f64::from(w)),
            tex_coord(x_r, f64::from(h)),
            0.5,
        )
    }

    fn direct_irradiance(&self, r: f64, mu_s: f64) -> DVec3 {
        let alpha = f64::from(self.config.sun_angular_radius);
        let cosine = if mu_s < -alpha {
            0.0
        } else if mu_s <= alpha {
            (mu_s + alpha) * (mu_s + alpha) / (4.0 * alpha)
        } else {
            mu_s
        };
        self.transmittance_to_top(r, mu_s) * cosine
    }

    /// Sky radiance (kcd/m^2, linear RGB) along unit `dir` for a sun towards
    /// unit `sun`; twin of `bruneton_sky_radiance` (no sun disk).
    pub fn sky_radiance(&self, dir: Vec3, sun: Vec3) -> Vec3 {
        let c = &self.config;
        let r = f64::from(c.bottom_radius_km + c.view_altitude_km);
        let mu_s = f64::from(sun.y);
        let view = if dir.y < 0.0 {
            Vec3::new(dir.x, 0.0, dir.z)
                .try_normalize()
                .unwrap_or(Vec3::X)
        } else {
            dir
        };
        let mu = f64::from(view.y);
        let nu = f64::from(view.dot(sun).clamp(-1.0, 1.0));
        let ground = ray_intersects_ground(c, r, mu);
        let multiple = self.scattering_lookup(&self.scattering, r, mu, mu_s, nu, ground);
        let mie = self.scattering_lookup(&self.single_mie, r, mu, mu_s, nu, ground);
        let scale = f64::from(SUN_ILLUMINANCE_KLUX);
        let night = dv(c.night_radiance);
        let sky = (multiple * rayleigh_phase(nu) + mie * mie_phase(f64::from(c.mie_g), nu)) * scale
            + night;
        if dir.y >= 0.0 {
            return sky.as_vec3();
        }
        let e = self.direct_irradiance(r, mu_s) + self.irradiance_lookup(r, mu_s);
        let ground_l = dv(c.ground_albedo) * (e * scale / std::f64::consts::PI + night);
        let blend = smoothstep(0.0, f64::from(super::GROUND_BLEND_Y), -f64::from(dir.y));
        (sky + (ground_l - sky) * blend).as_vec3()
    }
}

fn smoothstep(e0: f64, e1: f64, x: f64) -> f64 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
