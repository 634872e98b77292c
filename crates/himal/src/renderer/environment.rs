//! An HDR environment on the GPU (issue #8): the equirectangular image for
//! the background, its SH9 irradiance for diffuse light, and its cube
//! filtered by the L4 path for specular light (filtered once at load).

use crate::Error;
use crate::gpu::GpuContext;
use crate::math::sh::Sh9Rgb;
use crate::passes::envmap::EnvMapPass;
use crate::scene::{EnvironmentDesc, EnvironmentImage};

/// The loaded `[environment]` of a scene, as the sky pass and lighting use it.
pub struct EnvironmentGpu {
    /// The equirectangular radiance (Rgba16Float, scaled by the scene's
    /// intensity and drawn as kcd/m^2; u = longitude, v = 0 at +Y), one mip.
    pub image: wgpu::Texture,
    /// View of [`Self::image`] the sky pass samples for the background.
    pub view: wgpu::TextureView,
    /// Bilinear; wraps in u (longitude), clamps in v (the poles).
    pub sampler: wgpu::Sampler,
    /// Irradiance E(n) as SH9 (what `Lighting::sky_irradiance` holds).
    pub irradiance_sh: Sh9Rgb,
    /// L5: the image's radiance above the horizon (what the probes
    /// transfer) and the irradiance of its part below (the ground they replace).
    pub above_horizon: Sh9Rgb,
    /// See [`Self::above_horizon`].
    pub ground_irradiance: Sh9Rgb,
    /// Keep the analytic sun (`sun = true` in the scene): otherwise its
    /// illuminance is zero, as the image holds its own sun.
    pub sun: bool,
    /// Turn of the image about +Y (radians), added to the longitude.
    pub rotation: f32,
}

impl EnvironmentGpu {
    /// Loads `desc`, uploads the image and fills `envmap` with its filtered cube.
    pub fn new(
        ctx: &GpuContext,
        desc: &EnvironmentDesc,
        envmap: &mut EnvMapPass,
    ) -> Result<Self, Error> {
        let env = EnvironmentImage::load(desc)?;
        let texels: Vec<half::f16> = env
            .texels
            .iter()
            .flat_map(|c| [c.x, c.y, c.z, 1.0].map(half::f16::from_f32))
            .collect();
        use wgpu::util::DeviceExt;
        let image = ctx.device.create_texture_with_data(
            &ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("environment"),
                size: wgpu::Extent3d {
                    width: env.width as u32,
                    height: env.height as u32,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&texels),
        );
        envmap.filter_faces(ctx, &env.cube_faces(envmap.size as usize))?;
        envmap.fixed_source = true;
        let radiance = env.radiance_sh();
        let above_horizon = crate::passes::indirect::reference::sky_radiance_sh(|d| env.sample(d));
        let ground_irradiance = radiance
            .add(&above_horizon.scale(-1.0))
            .radiance_to_irradiance_coeffs();
        Ok(Self {
            above_horizon,
            ground_irradiance,
            view: image.create_view(&Default::default()),
            image,
            sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("environment"),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..Default::default()
            }),
            irradiance_sh: radiance.radiance_to_irradiance_coeffs(),
            sun: desc.sun,
            rotation: env.rotation,
        })
    }
}
