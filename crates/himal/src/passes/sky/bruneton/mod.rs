//! L1: Bruneton & Neyret 2008 precomputed atmospheric scattering, structured
//! like Bruneton's 2017 reference implementation (transmittance, direct and
//! indirect irradiance, single Rayleigh + Mie and multiple scattering orders
//! 2..=4 in a 4D table packed into a 3D texture). Computed on the GPU once per
//! renderer; the sky pass draws from the tables (`SkyModel::Bruneton`) and
//! [`SkyShProjector`] turns them into the SH3 sky light. Shaders:
//! `shaders/atmosphere.wgsl`, `passes/sky/bruneton/*.wgsl`; CPU twin:
//! [`mod@reference`]. See `docs/techniques/L1.md`.

mod cache;
mod compute;
pub mod reference;
mod sh;

use glam::Vec3;

use crate::gpu::GpuContext;
use crate::passes::sky::reference::GROUND_ALBEDO;
use crate::passes::sky::sun::{SUN_ANGULAR_RADIUS_DEG, SUN_ILLUMINANCE_KLUX};

pub use cache::cache_file;
pub use compute::TableProgress;
pub use sh::{SKY_SH_SAMPLES, SkyShProjector};

/// Format of the irradiance and scattering tables: filterable,
/// storage-writable; f16 keeps ~3 significant digits (values per unit solar
/// irradiance, O(1e-4..1) where visible).
pub const TABLE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The transmittance table is f32: grazing rays reach T ~ 1e-5, where f16
/// loses the ratios T(r, mu) / T(r_d, mu_d) that single scattering takes
/// (measured 7% off at the ground's horizon). Filtered by hand (`_load`).
pub const TRANSMITTANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Table resolutions. The 4D scattering table (r, mu, mu_s, nu) is packed as
/// a 3D texture of (nu * mu_s) x mu x r.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableSizes {
    /// Transmittance table: width (mu) x height (r), texels.
    pub transmittance: (u32, u32),
    /// Irradiance table: width (mu_s) x height (r), texels.
    pub irradiance: (u32, u32),
    /// Scattering samples in r (altitude): the 3D texture's depth.
    pub r: u32,
    /// Scattering samples in mu (view zenith cosine): the 3D texture's height.
    pub mu: u32,
    /// Scattering samples in mu_s (sun zenith cosine), inner to nu in the width.
    pub mu_s: u32,
    /// Scattering samples in nu (cosine of the view-sun angle), outer in the width.
    pub nu: u32,
    /// Scattering-density quadrature: n polar x 2n azimuthal directions.
    pub density_samples: u32,
}

impl TableSizes {
    /// Bruneton 2017's sizes except r 32 -> 16 and mu 128 -> 64 (256x64x16
    /// scattering texels) and an 8 x 16 density quadrature (reference 16 x 32):
    /// the full sizes take minutes on a software rasteriser; the sky
    /// radiance changes by the amounts measured in docs/techniques/L1.md.
    pub const DEFAULT: TableSizes = TableSizes {
        transmittance: (256, 64),
        irradiance: (64, 16),
        r: 16,
        mu: 64,
        mu_s: 32,
        nu: 8,
        density_samples: 8,
    };
    /// Bruneton 2017's sizes (scattering 256 x 128 x 32, a 16 x 32 density
    /// quadrature): minutes on a software rasteriser, so baked ahead
    /// (`himal bake --tables reference`) and chosen with `--sky-tables`.
    pub const REFERENCE: TableSizes = TableSizes {
        transmittance: (256, 64),
        irradiance: (64, 16),
        r: 32,
        mu: 128,
        mu_s: 32,
        nu: 8,
        density_samples: 16,
    };
    /// Small scattering tables for tests (fast on lavapipe); the 2D tables
    /// at full size (cheap, and a coarse transmittance table misses the
    /// ground horizon by several percent).
    pub const TEST: TableSizes = TableSizes {
        transmittance: (256, 64),
        irradiance: (64, 16),
        r: 8,
        mu: 32,
        mu_s: 16,
        nu: 4,
        density_samples: 6,
    };

    /// Size of the 3D scattering texture.
    pub fn scattering_extent(&self) -> (u32, u32, u32) {
        (self.nu * self.mu_s, self.mu, self.r)
    }
}

/// Earth's atmosphere (Bruneton 2017 demo values) in km and 1/km, RGB at
/// 680, 550, 440 nm.
#[derive(Clone, Debug, PartialEq)]
pub struct AtmosphereConfig {
    /// Radius of the ground sphere (km).
    pub bottom_radius_km: f32,
    /// Radius of the top of the atmosphere (km).
    pub top_radius_km: f32,
    /// Rayleigh scattering (= extinction) at the ground (1/km).
    pub rayleigh_scattering: Vec3,
    /// Altitude over which the Rayleigh density falls by 1/e (km).
    pub rayleigh_scale_height_km: f32,
    /// Mie scattering at the ground (1/km).
    pub mie_scattering: Vec3,
    /// Mie extinction at the ground (1/km; scattering / 0.9 for Earth).
    pub mie_extinction: Vec3,
    /// Altitude over which the Mie density falls by 1/e (km).
    pub mie_scale_height_km: f32,
    /// Asymmetry of the Cornette-Shanks Mie phase function (> 0: forward).
    pub mie_g: f32,
    /// Ozone absorption at peak density; tent profile 0 at 10 and 40 km, 1 at 25 km.
    pub absorption_extinction: Vec3,
    /// Lambertian albedo of the ground sphere (linear RGB): light bounced into the sky.
    pub ground_albedo: Vec3,
    /// Angular radius of the sun disk (rad).
    pub sun_angular_radius: f32,
    /// Lowest sun cosine the tables cover (102 degrees: twilight).
    pub mu_s_min: f32,
    /// Altitude of the viewer the sky is drawn for (km above the ground sphere).
    pub view_altitude_km: f32,
    /// Night floor added to the sky radiance (kcd/m^2, linear RGB).
    pub night_radiance: Vec3,
    /// Resolutions of the precomputed tables.
    pub sizes: TableSizes,
}

/// Night sky floor: 1e-3 kcd/m^2 (1 cd/m^2: bright moonlit sky) with a cool
/// (blue) tint, ~1e-3 of the noon sky's zenith; it keeps night dark but not black.
pub const NIGHT_SKY_RADIANCE: Vec3 = Vec3::new(0.5e-3, 0.7e-3, 1.2e-3);
/// Moonlight at night (Bruneton sky only): a full moon opposite the sun,
/// cool, 0.01 klux: not the real 0.25 lux but scaled to the night floor as
/// the sun is to the day sky (moon : floor irradiance ~ 4.5 : 1), so that
/// night reads as moonlit with shadows rather than flat.
pub const MOON_ILLUMINANCE_KLUX: Vec3 = Vec3::new(0.008, 0.009, 0.010);
/// The moon fades in while the sun sinks from 0 to this many degrees below.
pub const MOON_FADE_DEG: f32 = 6.0;

/// The moon as the directional light (direction towards it, illuminance
/// klux) for a sun towards `sun`; `None` while the sun is up.
pub fn moon_light(sun: Vec3) -> Option<(Vec3, Vec3)> {
    let sun = sun.try_normalize()?;
    if sun.y >= 0.0 {
        return None;
    }
    let t = (-sun.y / MOON_FADE_DEG.to_radians().sin()).clamp(0.0, 1.0);
    Some((-sun, MOON_ILLUMINANCE_KLUX * (t * t * (3.0 - 2.0 * t))))
}

/// Below the horizon the sky blends into the ground fill over -dir.y in [0, this].
pub const GROUND_BLEND_Y: f32 = 0.1;

impl AtmosphereConfig {
    /// Earth's atmosphere (Bruneton 2017's demo values, [`GROUND_ALBEDO`], a viewer 200 m up) with
    /// tables of `sizes`.
    pub fn earth(sizes: TableSizes) -> Self {
        let mie_scattering = Vec3::splat(3.996e-3);
        AtmosphereConfig {
            bottom_radius_km: 6360.0,
            top_radius_km: 6420.0,
            rayleigh_scattering: Vec3::new(5.802e-3, 13.558e-3, 33.1e-3),
            rayleigh_scale_height_km: 8.0,
            mie_scattering,
            mie_extinction: mie_scattering / 0.9,
            mie_scale_height_km: 1.2,
            mie_g: 0.8,
            absorption_extinction: Vec3::new(0.650e-3, 1.881e-3, 0.085e-3),
            ground_albedo: GROUND_ALBEDO,
            sun_angular_radius: SUN_ANGULAR_RADIUS_DEG.to_radians(),
            mu_s_min: 102f32.to_radians().cos(),
            view_altitude_km: 0.2,
            night_radiance: NIGHT_SKY_RADIANCE,
            sizes,
        }
    }

    /// The `AtmosphereParams` uniform: these values, and the ozone tent, sun illuminance and
    /// ground blend in the spare w slots.
    pub fn gpu_params(&self) -> AtmosphereGpuParams {
        let v4 = |v: Vec3, w: f32| v.extend(w).to_array();
        let s = &self.sizes;
        AtmosphereGpuParams {
            shape: [
                self.bottom_radius_km,
                self.top_radius_km,
                self.mie_g,
                self.mu_s_min,
            ],
            rayleigh_scattering: v4(
                self.rayleigh_scattering,
                -1.0 / self.rayleigh_scale_height_km,
            ),
            mie_scattering: v4(self.mie_scattering, -1.0 / self.mie_scale_height_km),
            mie_extinction: v4(self.mie_extinction, OZONE_LAYER_WIDTH_KM),
            absorption_extinction: v4(self.absorption_extinction, self.sun_angular_radius),
            ozone_density: OZONE_TENT,
            ground_albedo: v4(self.ground_albedo, SUN_ILLUMINANCE_KLUX),
            solar_irradiance: v4(Vec3::ONE, self.view_altitude_km),
            sizes_2d: [
                s.transmittance.0 as f32,
                s.transmittance.1 as f32,
                s.irradiance.0 as f32,
                s.irradiance.1 as f32,
            ],
            sizes_4d: [s.r as f32, s.mu as f32, s.mu_s as f32, s.nu as f32],
            night_radiance: v4(self.night_radiance, GROUND_BLEND_Y),
        }
    }
}

/// Ozone tent (Bruneton 2017): density = 1/15 h - 2/3 below 25 km, -1/15 h + 8/3 above.
pub const OZONE_LAYER_WIDTH_KM: f32 = 25.0;
/// The tent as `AtmosphereParams::ozone_density`: slope (1/km) and constant below
/// [`OZONE_LAYER_WIDTH_KM`], then above.
pub const OZONE_TENT: [f32; 4] = [1.0 / 15.0, -2.0 / 3.0, -1.0 / 15.0, 8.0 / 3.0];

/// Uniform twin of `AtmosphereParams` in `shaders/atmosphere.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct AtmosphereGpuParams {
    /// Bottom and top radius (km), Mie g, mu_s_min.
    pub shape: [f32; 4],
    /// Rayleigh scattering = extinction (1/km); w the density's exponential scale, -1 / scale
    /// height (1/km).
    pub rayleigh_scattering: [f32; 4],
    /// Mie scattering (1/km); w the density's exponential scale (1/km).
    pub mie_scattering: [f32; 4],
    /// Mie extinction (1/km); w the width of the lower ozone layer (km).
    pub mie_extinction: [f32; 4],
    /// Ozone absorption at peak density (1/km); w the sun's angular radius (rad).
    pub absorption_extinction: [f32; 4],
    /// Ozone tent ([`OZONE_TENT`]): lower layer slope and constant, upper layer slope and
    /// constant.
    pub ozone_density: [f32; 4],
    /// Ground albedo; w the radiance scale (klux of the extraterrestrial sun).
    pub ground_albedo: [f32; 4],
    /// Solar irradiance at the top in table units (1); w the viewer's altitude (km).
    pub solar_irradiance: [f32; 4],
    /// Transmittance width, height; irradiance width, height (texels).
    pub sizes_2d: [f32; 4],
    /// Scattering-table sizes in r, mu, mu_s, nu.
    pub sizes_4d: [f32; 4],
    /// Night sky floor (linear RGB, kcd/m^2); w the ground blend width in -dir.y
    /// ([`GROUND_BLEND_Y`]).
    pub night_radiance: [f32; 4],
}

/// Highest scattering order summed into the tables (Bruneton 2017: 4).
pub const MAX_SCATTERING_ORDER: u32 = 4;

/// The precomputed tables (GPU) and the parameters they were made with.
pub struct BrunetonTables {
    /// The atmosphere and table sizes the tables were computed for.
    pub config: AtmosphereConfig,
    /// `AtmosphereGpuParams` uniform.
    pub params: wgpu::Buffer,
    /// T(r, mu) to the top of the atmosphere.
    pub transmittance: wgpu::Texture,
    /// Sky (indirect) irradiance of orders 1..MAX-1 on a horizontal surface.
    pub irradiance: wgpu::Texture,
    /// Single Rayleigh + multiple scattering / Rayleigh phase.
    pub scattering: wgpu::Texture,
    /// Single Rayleigh and single Mie scattering (no phase function).
    pub single_rayleigh: wgpu::Texture,
    /// Single Mie scattering on its own (no phase function; the sky applies the Mie phase).
    pub single_mie: wgpu::Texture,
    /// Linear clamp-to-edge sampler of every table.
    pub sampler: wgpu::Sampler,
}

fn table_texture(ctx: &GpuContext, label: &str, size: (u32, u32, u32), d3: bool) -> wgpu::Texture {
    table_texture_format(ctx, label, size, d3, TABLE_FORMAT)
}

pub(crate) fn table_texture_format(
    ctx: &GpuContext,
    label: &str,
    size: (u32, u32, u32),
    d3: bool,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0,
            height: size.1,
            depth_or_array_layers: size.2,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: if d3 {
            wgpu::TextureDimension::D3
        } else {
            wgpu::TextureDimension::D2
        },
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Linear, clamp-to-edge sampler of the f16 tables.
pub(crate) fn table_sampler(ctx: &GpuContext) -> wgpu::Sampler {
    ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("sky.tables"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    })
}

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

fn tex(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::TextureView(v)
}

impl BrunetonTables {
    /// Views of (transmittance, scattering, single Mie, irradiance) for binding.
    pub fn views(&self) -> TableViews {
        TableViews {
            transmittance: view(&self.transmittance),
            scattering: view(&self.scattering),
            single_mie: view(&self.single_mie),
            irradiance: view(&self.irradiance),
        }
    }
}

/// Texture views of the tables the sky is drawn from.
pub struct TableViews {
    /// View of [`BrunetonTables::transmittance`].
    pub transmittance: wgpu::TextureView,
    /// View of [`BrunetonTables::scattering`].
    pub scattering: wgpu::TextureView,
    /// View of [`BrunetonTables::single_mie`].
    pub single_mie: wgpu::TextureView,
    /// View of [`BrunetonTables::irradiance`].
    pub irradiance: wgpu::TextureView,
}

impl TableViews {
    /// Bindings named as in `atmosphere.wgsl` users (`draw.wgsl`, `sky_sh.wgsl`, `capture.wgsl`).
    pub fn bindings<'a>(
        &'a self,
        params: &'a wgpu::Buffer,
        sampler: &'a wgpu::Sampler,
    ) -> [(&'static str, wgpu::BindingResource<'a>); 6] {
        [
            ("atmosphere", params.as_entire_binding()),
            ("transmittance_load", tex(&self.transmittance)),
            ("scattering", tex(&self.scattering)),
            ("single_mie", tex(&self.single_mie)),
            ("irradiance", tex(&self.irradiance)),
            ("table_sampler", wgpu::BindingResource::Sampler(sampler)),
        ]
    }
}
