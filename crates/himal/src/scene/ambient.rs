//! `[[ambient_light]]` tables: Ryse's multiplicative "ambient lights"
//! (SIGGRAPH 2014), volumes inside which the ambient light (sky diffuse and
//! ambient specular alike, not the sun or local lights) is scaled by a
//! factor, for artists to darken interiors or brighten bounce areas.
//! The shading: `shaders/ambient_lights.wgsl`; docs/ambient-lights.md.

use glam::Vec3;

use super::SceneError;
use super::build::Checker;
use super::file::FileAmbientLight;

type Result<T> = std::result::Result<T, SceneError>;

/// The most ambient lights a scene may hold (the GPU buffer's fixed size;
/// a file with more is an error).
pub const MAX_AMBIENT_LIGHTS: usize = 64;
/// Largest factor per channel.
pub const MAX_AMBIENT_FACTOR: f32 = 16.0;

/// The volume of an ambient light, centred on its position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AmbientShape {
    /// Box of these half-extents (m), yawed about +Y.
    Box(Vec3),
    /// Sphere of this radius (m).
    Sphere(f32),
}

/// One ambient light: inside the volume the ambient light is multiplied by
/// `factor`; over the outer `falloff` fraction of the volume (of the
/// half-extent or radius) the multiplier fades smoothly back to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct AmbientLightDesc {
    /// The table's `name`, or `ambient<k>` (k: its index in the file) when
    /// it has none.
    pub name: String,
    /// World-space centre of the volume (m).
    pub position: Vec3,
    /// Box (`size`, half-extents) or sphere (`radius`); exactly one is given.
    pub shape: AmbientShape,
    /// Rotation about +Y (degrees; boxes).
    pub yaw_deg: f32,
    /// Linear RGB multiplier, each channel in [0, 16].
    pub factor: Vec3,
    /// Fraction of the volume, (0, 1], over which the factor fades to 1 at
    /// its surface (0: a hard edge).
    pub falloff: f32,
}

pub(crate) fn build_ambient_lights(
    ck: &Checker,
    file: &[FileAmbientLight],
) -> Result<Vec<AmbientLightDesc>> {
    if file.len() > MAX_AMBIENT_LIGHTS {
        return Err(ck.err(
            &file[MAX_AMBIENT_LIGHTS].position.span(),
            format!(
                "{} [[ambient_light]] tables: at most {MAX_AMBIENT_LIGHTS} are supported",
                file.len()
            ),
        ));
    }
    file.iter()
        .enumerate()
        .map(|(k, a)| {
            let position = ck.finite3(&a.position, "position")?;
            let shape = match (&a.size, &a.radius) {
                (Some(s), None) => {
                    let v = ck.finite3(s, "size")?;
                    if v.min_element() < super::build::MIN_LENGTH {
                        return Err(ck.err(
                            &s.span(),
                            format!("size {v} (half-extents) must be positive"),
                        ));
                    }
                    AmbientShape::Box(v)
                }
                (None, Some(r)) => AmbientShape::Sphere(ck.length(r, "radius")?),
                (Some(s), Some(_)) => {
                    return Err(ck.err(
                        &s.span(),
                        "ambient light: give size (box) or radius (sphere), not both",
                    ));
                }
                (None, None) => {
                    return Err(ck.err(
                        &a.position.span(),
                        "ambient light: size (box half-extents) or radius (sphere) is missing",
                    ));
                }
            };
            let yaw_deg = match &a.yaw {
                Some(y) => ck.range(y, "yaw", -360.0, 360.0)?,
                None => 0.0,
            };
            let factor = Vec3::from(a.factor.get_ref().0);
            if !factor
                .to_array()
                .iter()
                .all(|c| (0.0..=MAX_AMBIENT_FACTOR).contains(c))
            {
                return Err(ck.err(
                    &a.factor.span(),
                    format!("factor {factor} must be in [0, {MAX_AMBIENT_FACTOR}] per channel"),
                ));
            }
            let falloff = match &a.falloff {
                Some(f) => ck.range(f, "falloff", 0.0, 1.0)?,
                None => 0.25,
            };
            let name = match &a.name {
                Some(n) => n.get_ref().clone(),
                None => format!("ambient{k}"),
            };
            Ok(AmbientLightDesc {
                name,
                position,
                shape,
                yaw_deg,
                factor,
                falloff,
            })
        })
        .collect()
}
