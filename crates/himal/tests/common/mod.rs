//! Helpers shared by the whole-frame GPU tests.
// Each test binary uses a subset of these helpers.
#![allow(dead_code)]

use glam::{Vec3, Vec4};
use himal::Renderer;
use himal::gpu::{GpuContext, GpuOptions};
use himal::passes::lighting::reference::LightingParams;
use himal::passes::sky::SkyLight;
use himal::scene::{Camera, Scene};

/// A renderer on the adapter present (lavapipe in CI).
pub fn renderer(scene: &Scene) -> Renderer {
    let ctx = GpuContext::new(&GpuOptions::default()).expect("a GPU adapter (lavapipe in CI)");
    Renderer::new(ctx, scene).expect("renderer")
}

/// Raw debug views (`lighting`, `normal`, `tangent`, `depth`, ...) of
/// `scene` from `camera`, `size` square, no anti-aliasing: RGBA f32 per view.
pub fn raw_views(scene: &Scene, camera: &Camera, size: u32, names: &[&str]) -> Vec<Vec<[f32; 4]>> {
    let mut r = renderer(scene);
    names
        .iter()
        .map(|name| {
            let mut s = himal::FrameSettings::new(size, size, scene.sun.clone());
            s.view = name.parse().expect("view");
            s.raw = true;
            s.aa = himal::passes::aa::AaMode::None;
            r.render(camera, &s)
                .expect("frame")
                .image
                .to_rgba_f32()
                .expect("rgba")
        })
        .collect()
}

/// Sun and sky of the scene's time of day, as the lighting pass gets them.
pub fn lighting_params(scene: &Scene) -> LightingParams {
    let sun = &scene.sun;
    let sky = SkyLight::new(
        sun.time_hours,
        sun.latitude_deg,
        sun.day_of_year,
        sun.turbidity,
    );
    LightingParams {
        sun_direction: sky.sun_direction,
        sun_illuminance: sky.sun_illuminance,
        sky_irradiance: sky.irradiance_sh,
        environment: None,
    }
}

/// Unit direction of the camera ray through the centre of pixel (x, y).
pub fn pixel_ray(camera: &Camera, size: (u32, u32), x: u32, y: u32) -> Vec3 {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let inv = camera.view_projection(w / h).inverse();
    let ndc = Vec4::new(
        (x as f32 + 0.5) / w * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / h * 2.0,
        1.0,
        1.0,
    );
    let p = inv * ndc;
    (p.truncate() / p.w - camera.position).normalize()
}

/// The renderer's filtered environment cube and DFG table read back, for
/// the lighting twin's `ENV_SPECULAR` path.
pub fn environment_specular(
    r: &Renderer,
) -> himal::passes::lighting::reference::EnvironmentSpecular {
    use himal::passes::envmap::reference::CubeMip;
    let env = r.envmap();
    let ctx = r.context();
    let read = |texture: &wgpu::Texture, mip: u32, layer: u32| {
        himal::gpu::read_texture(ctx, texture, mip, layer)
            .expect("read back")
            .to_rgba_f32()
            .expect("float texels")
    };
    let filtered = (0..env.filtered().mip_level_count())
        .map(|mip| {
            let faces: [Vec<Vec3>; 6] = std::array::from_fn(|face| {
                read(env.filtered(), mip, face as u32)
                    .iter()
                    .map(|t| Vec3::new(t[0], t[1], t[2]))
                    .collect()
            });
            CubeMip {
                size: (env.size >> mip) as usize,
                faces,
            }
        })
        .collect();
    let dfg = read(&env.dfg, 0, 0)
        .iter()
        .map(|t| glam::Vec2::new(t[0], t[1]))
        .collect();
    himal::passes::lighting::reference::EnvironmentSpecular {
        filtered,
        dfg,
        dfg_size: env.dfg.width() as usize,
    }
}
