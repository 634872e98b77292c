//! The scene file's TOML shape (serde). Every value a later check may
//! reject is `Spanned`, so the error can point at its line and column;
//! `deny_unknown_fields` turns typos into errors at the key.

use std::fmt;

use serde::Deserialize;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileScene {
    pub sun: Option<FileSun>,
    #[serde(default)]
    pub material: Vec<FileMaterial>,
    #[serde(default)]
    pub object: Vec<FileObject>,
    #[serde(default)]
    pub camera: Vec<FileCamera>,
    #[serde(default)]
    pub light: Vec<FileLight>,
    #[serde(default)]
    pub ambient_light: Vec<FileAmbientLight>,
    #[serde(default)]
    pub probe: Vec<FileProbe>,
    #[serde(default)]
    pub emitter: Vec<FileEmitter>,
    pub wind: Option<Spanned<FileWind>>,
    #[serde(default)]
    pub wind_source: Vec<FileWindSource>,
    pub environment: Option<FileEnvironment>,
    pub cinematic_shadows: Option<FileCinematicShadows>,
    #[serde(default)]
    pub gltf: Vec<FileGltf>,
    pub world: Option<Spanned<FileWorld>>,
}

/// `[world]`: the streamed open world (`scene/world/file.rs` builds it).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileWorld {
    pub seed: Option<Spanned<i64>>,
    pub sectors: Option<Spanned<i64>>,
    pub height_map: Option<Spanned<FileHeightMap>>,
    pub mountain_height: Option<Spanned<f32>>,
    pub hill_height: Option<Spanned<f32>>,
    pub snow_line: Option<Spanned<f32>>,
    pub rules: Option<FileRules>,
    pub stream: Option<FileStream>,
    /// Keyed by `tiles` and instance kind names; unknown names are checked later.
    pub pools: Option<std::collections::BTreeMap<String, Spanned<i64>>>,
}

/// `height_map = { file, min, max }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileHeightMap {
    pub file: Spanned<String>,
    pub min: Option<Spanned<f32>>,
    pub max: Spanned<f32>,
}

/// `[world.rules]`: what sectors place.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileRules {
    pub rock_density: Option<Spanned<f32>>,
    pub tree_density: Option<Spanned<f32>>,
    pub tree_max_slope: Option<Spanned<f32>>,
    pub larch_line: Option<Spanned<f32>>,
    pub tree_line: Option<Spanned<f32>>,
    pub village_chance: Option<Spanned<f32>>,
    pub village_max_rise: Option<Spanned<f32>>,
    pub houses: Option<bool>,
    pub fields: Option<bool>,
    pub fences: Option<bool>,
}

/// `[world.stream]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileStream {
    pub radius: Option<Spanned<f32>>,
    pub unload_margin: Option<Spanned<f32>>,
    pub workers: Option<Spanned<i64>>,
    pub upload_budget: Option<Spanned<ByteSize>>,
}

/// `4194304` (bytes) or `"4MiB"` ([`crate::budget::parse_bytes`]).
pub(crate) struct ByteSize(pub u64);

impl<'de> Deserialize<'de> for ByteSize {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = ByteSize;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("bytes as an integer or a size such as \"4MiB\"")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<ByteSize, E> {
                crate::budget::parse_bytes(s)
                    .map(ByteSize)
                    .map_err(|e| E::custom(format!("\"{s}\": {e}")))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ByteSize, E> {
                u64::try_from(v)
                    .map(ByteSize)
                    .map_err(|_| E::custom(format!("{v} bytes: must not be negative")))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ByteSize, E> {
                Ok(ByteSize(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// `[[gltf]]`: a glTF model placed in the scene (`scene/gltf/placement.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileGltf {
    pub file: Spanned<String>,
    pub name: Option<Spanned<String>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub translation: Option<Spanned<[f32; 3]>>,
    pub rotation: Option<Spanned<GltfRotation>>,
    pub scale: Option<Spanned<Scale>>,
    /// Put the model's lowest point on top of an earlier object (plus translation.y).
    pub rest_on: Option<Spanned<String>>,
    /// Skip (with a warning) when the file does not exist.
    pub optional: Option<bool>,
    /// The model moves along a circle around `translation` (as objects' `orbit`).
    pub orbit: Option<Spanned<FileOrbit>>,
    /// The glTF animation it plays (default: its first; "none": rest pose).
    pub animation: Option<Spanned<String>>,
}

/// `rotation = 30` (degrees about +Y) or `rotation = [x, y, z, w]` (unit quaternion).
#[derive(Deserialize)]
#[serde(untagged)]
pub(crate) enum GltfRotation {
    Yaw(f32),
    Quaternion([f32; 4]),
}

/// `[environment]`: an equirectangular HDR image instead of the physical sky.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileEnvironment {
    pub file: Spanned<String>,
    pub intensity: Option<Spanned<f32>>,
    pub rotation: Option<Spanned<f32>>,
    pub sun: Option<bool>,
}

/// An environment probe (L3): where a G-buffer cube is captured.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileProbe {
    #[serde(deserialize_with = "exact3")]
    pub position: Spanned<[f32; 3]>,
}

/// `[[light]]`: a point or spot light (S3).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileLight {
    pub name: Spanned<String>,
    pub kind: Spanned<String>,
    #[serde(deserialize_with = "exact3")]
    pub position: Spanned<[f32; 3]>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub color: Option<Spanned<[f32; 3]>>,
    pub intensity: Spanned<f32>,
    pub range: Spanned<f32>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub direction: Option<Spanned<[f32; 3]>>,
    pub inner_angle: Option<Spanned<f32>>,
    pub outer_angle: Option<Spanned<f32>>,
    pub shadow: Option<bool>,
}

/// `[[emitter]]`: a particle emitter (E4, `scene/emitters.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileEmitter {
    pub name: Option<Spanned<String>>,
    pub on: Option<Spanned<String>>,
    #[serde(deserialize_with = "exact3")]
    pub position: Spanned<[f32; 3]>,
    pub rate: Spanned<f32>,
    pub lifetime: Spanned<f32>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub velocity: Option<Spanned<[f32; 3]>>,
    pub spread: Option<Spanned<f32>>,
    pub gravity: Option<Spanned<f32>>,
    pub wind: Option<Spanned<f32>>,
    #[serde(default, deserialize_with = "exact_opt")]
    pub size: Option<Spanned<[f32; 2]>>,
    #[serde(default, deserialize_with = "exact_opt")]
    pub color_start: Option<Spanned<[f32; 4]>>,
    #[serde(default, deserialize_with = "exact_opt")]
    pub color_end: Option<Spanned<[f32; 4]>>,
    pub capacity: Option<Spanned<i64>>,
    pub sprite: Option<Spanned<String>>,
}

/// `[wind]`: the wind particles drift in (E4): `speed` and `direction`,
/// or `velocity`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileWind {
    pub speed: Option<Spanned<f32>>,
    pub direction: Option<Spanned<f32>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub velocity: Option<Spanned<[f32; 3]>>,
}

/// `[[wind_source]]`: a local wind source (V2, `scene/wind.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileWindSource {
    #[serde(default, deserialize_with = "exact3_opt")]
    pub position: Option<Spanned<[f32; 3]>>,
    pub path: Option<Spanned<Vec<[f32; 3]>>>,
    pub speed: Option<Spanned<f32>>,
    pub radius: Spanned<f32>,
    pub strength: Spanned<f32>,
}

/// `[[ambient_light]]`: a multiplier on the ambient light inside a box or
/// sphere (Ryse's ambient lights).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileAmbientLight {
    pub name: Option<Spanned<String>>,
    #[serde(deserialize_with = "exact3")]
    pub position: Spanned<[f32; 3]>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub size: Option<Spanned<[f32; 3]>>,
    pub radius: Option<Spanned<f32>>,
    pub yaw: Option<Spanned<f32>>,
    pub factor: Spanned<Scale>,
    pub falloff: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileSun {
    pub time: Option<Spanned<TimeOfDay>>,
    pub latitude: Option<Spanned<f32>>,
    pub day_of_year: Option<Spanned<i64>>,
    pub turbidity: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileMaterial {
    pub name: Spanned<String>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub albedo: Option<Spanned<[f32; 3]>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub albedo_linear: Option<Spanned<[f32; 3]>>,
    pub glossiness: Option<Spanned<f32>>,
    pub reflectance: Option<Spanned<f32>>,
    pub metallic: Option<Spanned<f32>>,
    pub anisotropy: Option<Spanned<f32>>,
    pub ao: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileRepeat {
    pub count: Spanned<i64>,
    #[serde(deserialize_with = "exact3")]
    pub step: Spanned<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileObject {
    pub name: Spanned<String>,
    pub primitive: Spanned<String>,
    pub material: Option<Spanned<String>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub position: Option<Spanned<[f32; 3]>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub rotation: Option<Spanned<[f32; 3]>>,
    pub scale: Option<Spanned<Scale>>,
    pub snap_to_ground: Option<Spanned<bool>>,
    pub rest_on: Option<Spanned<String>>,
    pub repeat: Option<Spanned<FileRepeat>>,
    pub orbit: Option<Spanned<FileOrbit>>,
    // Primitive parameters; which ones apply is checked per primitive.
    pub size: Option<Spanned<Vec<f32>>>,
    pub radius: Option<Spanned<f32>>,
    pub height: Option<Spanned<f32>>,
    pub segments: Option<Spanned<i64>>,
    pub rings: Option<Spanned<i64>>,
    pub gable_material: Option<Spanned<String>>,
    pub resolution: Option<Spanned<i64>>,
    pub noise: Option<Spanned<FileNoise>>,
    pub png: Option<Spanned<String>>,
    pub height_scale: Option<Spanned<f32>>,
    pub layers: Option<Spanned<Vec<FileLayer>>>,
    pub albedo_variation: Option<Spanned<f32>>,
    pub density: Option<Spanned<f32>>,
    pub width: Option<Spanned<f32>>,
    pub seed: Option<Spanned<i64>>,
    pub cards: Option<Spanned<i64>>,
    pub sway: Option<Spanned<f32>>,
    // Trees (V1).
    pub species: Option<Spanned<String>>,
    pub bark_material: Option<Spanned<String>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub tint: Option<Spanned<[f32; 3]>>,
    pub count: Option<Spanned<i64>>,
    pub positions: Option<Spanned<Vec<[f32; 3]>>>,
}

impl FileObject {
    /// Primitive parameter keys present, with their spans, for the per-primitive check.
    pub fn parameter_keys(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        let mut keys = Vec::new();
        macro_rules! key {
            ($($field:ident),*) => {$(
                if let Some(v) = &self.$field {
                    keys.push((stringify!($field), v.span()));
                }
            )*};
        }
        key!(
            size,
            radius,
            height,
            segments,
            rings,
            gable_material,
            resolution,
            noise,
            png,
            height_scale,
            layers,
            albedo_variation,
            density,
            width,
            seed,
            cards,
            sway,
            species,
            bark_material,
            tint,
            count,
            positions
        );
        keys
    }
}

/// `orbit = { radius, period, phase, turn }` (see `scene/motion.rs`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileOrbit {
    pub radius: Spanned<f32>,
    pub period: Spanned<f32>,
    pub phase: Option<Spanned<f32>>,
    pub turn: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileNoise {
    pub seed: Option<Spanned<i64>>,
    pub octaves: Option<Spanned<i64>>,
    pub frequency: Option<Spanned<f32>>,
    pub amplitude: Option<Spanned<f32>>,
    pub ridged: Option<bool>,
    pub lacunarity: Option<Spanned<f32>>,
    pub gain: Option<Spanned<f32>>,
    pub warp: Option<Spanned<f32>>,
    pub erosion: Option<Spanned<f32>>,
    pub flat_radius: Option<Spanned<f32>>,
    pub valley_radius: Option<Spanned<f32>>,
    pub floor_amplitude: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileLayer {
    pub material: Spanned<String>,
    pub min_height: Option<Spanned<f32>>,
    pub max_height: Option<Spanned<f32>>,
    pub min_slope: Option<Spanned<f32>>,
    pub max_slope: Option<Spanned<f32>>,
    pub blend: Option<Spanned<f32>>,
    pub slope_blend: Option<Spanned<f32>>,
    pub jitter: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileCamera {
    pub name: Spanned<String>,
    #[serde(deserialize_with = "exact3")]
    pub position: Spanned<[f32; 3]>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub target: Option<Spanned<[f32; 3]>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub forward: Option<Spanned<[f32; 3]>>,
    #[serde(default, deserialize_with = "exact3_opt")]
    pub up: Option<Spanned<[f32; 3]>>,
    pub fov_y: Option<Spanned<f32>>,
    pub near: Option<Spanned<f32>>,
    pub cinematic_shadows: Option<FileCinematicShadows>,
}

/// `[cinematic_shadows]` or a camera's `cinematic_shadows = { near, far }` (R3).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct FileCinematicShadows {
    pub near: Spanned<f32>,
    pub far: Spanned<f32>,
}

/// `[x, y, z]` with exactly three numbers (serde's array reader would
/// ignore a fourth).
fn exact3<'de, D: Deserializer<'de>>(d: D) -> Result<Spanned<[f32; 3]>, D::Error> {
    let v = Spanned::<Vec<f32>>::deserialize(d)?;
    let span = v.span();
    let n = v.get_ref().len();
    <[f32; 3]>::try_from(v.into_inner())
        .map(|a| Spanned::new(span, a))
        .map_err(|_| de::Error::invalid_length(n, &"three numbers [x, y, z]"))
}

fn exact3_opt<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Spanned<[f32; 3]>>, D::Error> {
    exact3(d).map(Some)
}

/// `[a, b, ..]` with exactly `N` numbers.
fn exact_opt<'de, D: Deserializer<'de>, const N: usize>(
    d: D,
) -> Result<Option<Spanned<[f32; N]>>, D::Error> {
    let v = Spanned::<Vec<f32>>::deserialize(d)?;
    let span = v.span();
    let n = v.get_ref().len();
    let want = format!("{N} numbers");
    <[f32; N]>::try_from(v.into_inner())
        .map(|a| Some(Spanned::new(span, a)))
        .map_err(|_| de::Error::invalid_length(n, &want.as_str()))
}

/// `time = "HH:MM"` or `time = 14.5` (hours); range checked later.
pub(crate) struct TimeOfDay(pub f32);

/// Parses "HH:MM" (24-hour clock) into hours.
pub(crate) fn parse_hh_mm(s: &str) -> Result<f32, String> {
    let bad = || format!("bad time \"{s}\": expected \"HH:MM\" with HH in 00..23 and MM in 00..59");
    let (h, m) = s.split_once(':').ok_or_else(bad)?;
    let digits = |t: &str| !t.is_empty() && t.len() <= 2 && t.bytes().all(|b| b.is_ascii_digit());
    if !digits(h) || m.len() != 2 || !digits(m) {
        return Err(bad());
    }
    let (h, m): (u32, u32) = (h.parse().map_err(|_| bad())?, m.parse().map_err(|_| bad())?);
    if h > 23 || m > 59 {
        return Err(bad());
    }
    Ok(h as f32 + m as f32 / 60.0)
}

impl<'de> Deserialize<'de> for TimeOfDay {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = TimeOfDay;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a time \"HH:MM\" or hours as a number")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<TimeOfDay, E> {
                parse_hh_mm(s).map(TimeOfDay).map_err(E::custom)
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<TimeOfDay, E> {
                Ok(TimeOfDay(v as f32))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<TimeOfDay, E> {
                Ok(TimeOfDay(v as f32))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<TimeOfDay, E> {
                Ok(TimeOfDay(v as f32))
            }
        }
        d.deserialize_any(V)
    }
}

/// `scale = 2.0` or `scale = [1, 2, 1]`.
pub(crate) struct Scale(pub [f32; 3]);

impl<'de> Deserialize<'de> for Scale {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Scale;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number or an array of three numbers")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Scale, E> {
                Ok(Scale([v as f32; 3]))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Scale, E> {
                Ok(Scale([v as f32; 3]))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Scale, E> {
                Ok(Scale([v as f32; 3]))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Scale, A::Error> {
                let mut s = [0.0f32; 3];
                for (i, c) in s.iter_mut().enumerate() {
                    *c = seq
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<f32>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                Ok(Scale(s))
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::parse_hh_mm;

    #[test]
    fn parse_time_takes_clock_or_hours() {
        use crate::scene::parse_time;
        assert_eq!(parse_time("10:30"), Ok(10.5));
        assert_eq!(parse_time(" 14.25 "), Ok(14.25));
        assert!(parse_time("24").is_err() && parse_time("-1").is_err());
        assert!(parse_time("25:99").unwrap_err().contains("25:99"));
        assert!(parse_time("noon").is_err());
    }

    #[test]
    fn hh_mm_parses_and_rejects() {
        assert_eq!(parse_hh_mm("14:30"), Ok(14.5));
        assert_eq!(parse_hh_mm("0:00"), Ok(0.0));
        assert_eq!(parse_hh_mm("23:59").map(|h| (h * 60.0).round()), Ok(1439.0));
        for bad in [
            "25:99", "24:00", "12:60", "12", "12:5", "a:bc", ":30", "12:30:00", "-1:30",
        ] {
            assert!(parse_hh_mm(bad).is_err(), "{bad} accepted");
        }
    }
}
