//! The view the render options ask for: the environment light (`--env`)
//! and the camera (`--camera`, `--orbit`, `--fov`), shared by `render`,
//! `view` and `bench`.

use anyhow::{Context, Result, bail};
use himal::scene::{Camera, Scene};

use crate::render::RenderArgs;

/// `--env` on `scene`: a file, `studio`, `sky`; by default a `model`
/// (a glTF file) is judged under neutral studio light, a scene keeps its own.
pub fn apply_environment(args: &RenderArgs, scene: &mut Scene, model: bool) {
    let env = match args.env.as_deref() {
        Some("sky") => None,
        Some("studio") => Some(himal::scene::STUDIO),
        Some(file) => Some(file),
        None if model => Some(himal::scene::STUDIO),
        None => None,
    };
    match env {
        Some(env) => {
            let mut desc = himal::scene::EnvironmentDesc::new(env);
            desc.intensity = args.env_intensity;
            // A file's directional light is its sun: kept under the image.
            desc.sun = scene.sun.light.is_some();
            scene.environment = Some(desc);
        }
        None if args.env.is_some() => scene.environment = None,
        None => {}
    }
}

/// `--orbit`, `--fov` and `--camera` applied: a named camera, an orbit of
/// the scene's bounds (a bare model's default: three-quarter), or the
/// scene's first camera.
pub fn view_camera(args: &RenderArgs, scene: &Scene, model: bool) -> Result<Camera> {
    if let Some(fov) = args.fov
        && !(fov.is_finite() && fov > 0.5 && fov < 179.0)
    {
        bail!("--fov {fov}: degrees in (0.5, 179)");
    }
    if args.orbit.is_some() && args.camera.is_some() {
        bail!("--orbit places its own camera: leave out --camera");
    }
    let fov = args.fov.unwrap_or(40.0);
    let orbit = match &args.orbit {
        Some(spec) => Some(parse_orbit(spec)?),
        None if model && args.camera.is_none() => {
            let (yaw, pitch) = himal::scene::gltf::THREE_QUARTER;
            Some((yaw, pitch, None))
        }
        None => None,
    };
    let mut camera = match orbit {
        Some((yaw, pitch, distance)) => {
            himal::scene::gltf::orbit_camera(&scene.bounds, yaw, pitch, distance, fov)
        }
        None => pick_camera(scene, args.camera.as_deref())?,
    };
    if let Some(fov) = args.fov {
        camera.fov_y_deg = fov;
    }
    Ok(camera)
}

/// `YAW,PITCH[,DISTANCE]`: finite degrees, pitch within ±89.9, distance > 0.
pub fn parse_orbit(spec: &str) -> Result<(f32, f32, Option<f32>)> {
    let bad = || {
        anyhow::anyhow!("--orbit {spec}: expected YAW,PITCH[,DISTANCE] (degrees, degrees, metres)")
    };
    let v: Vec<f32> = spec
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|_| bad()))
        .collect::<Result<_>>()?;
    if !(2..=3).contains(&v.len()) || v.iter().any(|x| !x.is_finite()) {
        return Err(bad());
    }
    if v[1].abs() > 89.9 {
        bail!(
            "--orbit {spec}: pitch {} must lie within ±89.9 degrees",
            v[1]
        );
    }
    let distance = v.get(2).copied();
    if distance.is_some_and(|d| d <= 0.0) {
        bail!("--orbit {spec}: the distance must be positive");
    }
    Ok((v[0], v[1], distance))
}

/// The named camera, or the scene's first.
pub fn pick_camera(scene: &Scene, name: Option<&str>) -> Result<Camera> {
    let origin = scene
        .path
        .as_ref()
        .map_or_else(|| "the scene".to_string(), |p| p.display().to_string());
    match name {
        Some(n) => Ok(scene
            .camera(n)
            .map_err(|e| anyhow::anyhow!("--camera {n}: {e}"))?
            .clone()),
        None => scene
            .cameras
            .first()
            .map(|c| c.camera.clone())
            .with_context(|| format!("{origin}: the scene has no camera: add a [[camera]] table")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        render: RenderArgs,
    }

    /// The studio replaced the sun, and with it a glTF file's directional
    /// light (which stands in for the sun): it is kept under the studio.
    #[test]
    fn a_models_directional_light_stays_under_the_studio() {
        let args = Cli::parse_from(["himal"]).render;
        let mut scene = Scene::demo().expect("demo");
        apply_environment(&args, &mut scene, true);
        let env = scene.environment.clone().expect("studio");
        assert!(env.path.as_os_str() == himal::scene::STUDIO && !env.sun);
        scene.sun.light = Some(himal::scene::SunLight {
            to_light: glam::Vec3::Y,
            illuminance_klux: glam::Vec3::ONE,
        });
        apply_environment(&args, &mut scene, true);
        assert!(
            scene.environment.expect("studio").sun,
            "the file's light is dropped"
        );
    }
}
