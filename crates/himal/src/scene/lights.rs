//! `[[light]]` tables: point and spot lights (TECHNIQUES S3), built and
//! checked like the rest of the scene file.

use glam::Vec3;

use super::SceneError;
use super::build::Checker;
use super::file::FileLight;

type Result<T> = std::result::Result<T, SceneError>;

/// Point light (all directions) or spot light (a cone).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightKind {
    /// Radiates equally in all directions; shadowed through six cube-face
    /// projectors (S3).
    Point,
    /// Radiates into a cone about `LightDesc::direction`, shaped by
    /// `inner_deg` / `outer_deg`; one shadow projector.
    Spot,
}

/// A local light. Illuminance at distance d: `intensity / d²` lux (candela),
/// faded to zero at `range` by `(1 − (d/range)⁴)²`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    /// The table's `name`, unique among the file's lights (a duplicate is an
    /// error).
    pub name: String,
    /// `kind = "point" | "spot"`.
    pub kind: LightKind,
    /// World-space position (m).
    pub position: Vec3,
    /// Linear colour (multiplies the intensity).
    pub color: Vec3,
    /// Luminous intensity (cd).
    pub intensity: f32,
    /// Distance at which the light fades out (m).
    pub range: f32,
    /// Spot axis (unit); unused for point lights.
    pub direction: Vec3,
    /// Spot cone: full intensity inside `inner_deg`, none outside `outer_deg` (half angles).
    /// Degrees, in [0, `outer_deg`]; default 0.8 · `outer_deg`.
    pub inner_deg: f32,
    /// Half angle (degrees, [1, 89], default 45) beyond which a spot gives no
    /// light; also the spot's shadow projector's half field of view.
    pub outer_deg: f32,
    /// Casts shadows (S3 atlas).
    pub shadow: bool,
}

pub(crate) fn build_lights(ck: &Checker, file: &[FileLight]) -> Result<Vec<LightDesc>> {
    file.iter()
        .enumerate()
        .map(|(k, l)| {
            if file[..k]
                .iter()
                .any(|o| o.name.get_ref() == l.name.get_ref())
            {
                return Err(ck.err(
                    &l.name.span(),
                    format!("light \"{}\" is defined twice", l.name.get_ref()),
                ));
            }
            let kind = match l.kind.get_ref().as_str() {
                "point" => LightKind::Point,
                "spot" => LightKind::Spot,
                other => {
                    return Err(ck.err(
                        &l.kind.span(),
                        format!("light kind \"{other}\": expected point or spot"),
                    ));
                }
            };
            let position = ck.finite3(&l.position, "position")?;
            let color = match &l.color {
                Some(c) => {
                    let v = ck.finite3(c, "color")?;
                    if v.min_element() < 0.0 {
                        return Err(ck.err(&c.span(), format!("color {v} must not be negative")));
                    }
                    v
                }
                None => Vec3::ONE,
            };
            let intensity = ck.positive(&l.intensity, "intensity")?;
            let range = ck.length(&l.range, "range")?;
            let direction = match &l.direction {
                Some(d) => {
                    let v = ck.finite3(d, "direction")?;
                    if v.length_squared() < 1e-12 {
                        return Err(ck.err(&d.span(), "direction must not be zero"));
                    }
                    v.normalize()
                }
                None => Vec3::NEG_Y,
            };
            let outer_deg = match &l.outer_angle {
                Some(a) => ck.range(a, "outer_angle", 1.0, 89.0)?,
                None => 45.0,
            };
            let inner_deg = match &l.inner_angle {
                Some(a) => ck.range(a, "inner_angle", 0.0, outer_deg)?,
                None => outer_deg * 0.8,
            };
            Ok(LightDesc {
                name: l.name.get_ref().clone(),
                kind,
                position,
                color,
                intensity,
                range,
                direction,
                inner_deg,
                outer_deg,
                shadow: l.shadow.unwrap_or(true),
            })
        })
        .collect()
}
