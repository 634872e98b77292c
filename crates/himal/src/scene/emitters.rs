//! `[[emitter]]` tables: particle emitters (TECHNIQUES E4), checked like
//! the rest of the scene file. The simulation is `passes/particles/`.

use glam::{Mat4, Vec3, Vec4};

use super::SceneError;
use super::build::Checker;
use super::file::{FileEmitter, FileWind};

type Result<T> = std::result::Result<T, SceneError>;

/// Default particle capacity of one emitter.
pub const DEFAULT_EMITTER_CAPACITY: u32 = 4096;
/// Largest capacity of one emitter (a hard limit: more is an error).
pub const MAX_EMITTER_CAPACITY: u32 = 65536;
/// Most emitters in one scene.
pub const MAX_EMITTERS: usize = 64;
/// Longest particle lifetime (s): the simulation pre-warms over it.
pub const MAX_LIFETIME_S: f32 = 30.0;
/// Most particle slots of all emitters together ([`SLOT_BYTES`] each).
pub const MAX_PARTICLE_SLOTS: u32 = 1 << 18;
/// GPU bytes of one particle slot: state 32 B, light 5 x 32 B (a record at
/// the centre and at each corner of its quad), draw order 4 B and sort key
/// 8 B.
pub const SLOT_BYTES: u64 = 204;
/// Highest emission rate (particles per second).
pub const MAX_RATE: f32 = 100_000.0;
/// The wind of a scene without `[wind]` (m/s): a light breeze toward +x
/// and a little +z (1.58 m/s), what particles drifted in before scenes
/// carried wind.
pub const DEFAULT_WIND: Vec3 = Vec3::new(1.5, 0.0, 0.5);
/// Fastest wind (m/s): `speed`, and each axis of `velocity`.
pub const MAX_WIND: f32 = 100.0;

/// `[wind]`: its velocity (m/s). `speed` toward `direction` degrees about
/// +Y from +X (the `orbit` angle's convention: 90 blows toward -z), or
/// `velocity` (which may rise or fall); no table: [`DEFAULT_WIND`].
pub(crate) fn build_wind(ck: &Checker, wind: Option<&toml::Spanned<FileWind>>) -> Result<Vec3> {
    let Some(w) = wind else {
        return Ok(DEFAULT_WIND);
    };
    let table = w.span();
    let w = w.get_ref();
    match (&w.speed, &w.velocity) {
        (Some(_), Some(v)) => Err(ck.err(
            &v.span(),
            "wind: give speed (with direction) or velocity, not both",
        )),
        (None, None) => Err(ck.err(
            &table,
            "[wind]: speed (m/s, with direction in degrees) or velocity ([x, y, z] m/s) is missing",
        )),
        (None, Some(v)) => {
            if let Some(d) = &w.direction {
                return Err(ck.err(&d.span(), "wind direction goes with speed, not velocity"));
            }
            let x = ck.finite3(v, "wind velocity")?;
            if x.abs().max_element() > MAX_WIND {
                return Err(ck.err(
                    &v.span(),
                    format!("wind velocity {x}: each axis in [-{MAX_WIND}, {MAX_WIND}] m/s"),
                ));
            }
            Ok(x)
        }
        (Some(s), None) => {
            let speed = ck.range(s, "wind speed", 0.0, MAX_WIND)?;
            let deg = match &w.direction {
                Some(d) => ck.range(d, "wind direction", -360.0, 360.0)?,
                None => 0.0,
            };
            let a = deg.to_radians();
            Ok(speed * Vec3::new(a.cos(), 0.0, -a.sin()))
        }
    }
}

/// A particle emitter: particles are born at `rate` per second at
/// `position`, move with `velocity` plus a random spread, fall with
/// `gravity` g, relax toward the wind at `wind` per second, and die after
/// `lifetime` seconds; size and colour run linearly over the life.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterDesc {
    /// The table's `name` (default `emitterN`), unique.
    pub name: String,
    /// Where particles are born (m); on a moving object, at time 0.
    pub position: Vec3,
    /// `on` a moving object: the emitter rides it.
    pub follow: Option<EmitterFollow>,
    /// Particles per second, (0, [`MAX_RATE`]].
    pub rate: f32,
    /// Seconds a particle lives, (0, [`MAX_LIFETIME_S`]].
    pub lifetime: f32,
    /// Initial velocity (m/s).
    pub velocity: Vec3,
    /// Random spread of the initial velocity: each axis plus a uniform
    /// number in [-spread, spread] (m/s), >= 0.
    pub spread: f32,
    /// Multiple of standard gravity (9.81 m/s² down); negative rises
    /// (buoyant smoke). [-10, 10], default 0.
    pub gravity: f32,
    /// Wind response (1/s): the velocity relaxes toward the wind's at this
    /// rate. [0, 100], default 1.
    pub wind: f32,
    /// Quad edge (m) at birth and at death.
    pub size: [f32; 2],
    /// Linear RGBA at birth (alpha: opacity).
    pub color_start: Vec4,
    /// Linear RGBA at death.
    pub color_end: Vec4,
    /// Particles alive at most: a ring of this many slots; births beyond it
    /// replace the oldest. [1, [`MAX_EMITTER_CAPACITY`]], default 4096.
    pub capacity: u32,
    /// What a particle looks like (`sprite`, default the disc).
    pub sprite: Sprite,
}

/// Texels along a sprite image's edge once loaded (`sprite = "file.png"`).
pub const SPRITE_SIZE: u32 = 128;

/// An emitter's sprite: its opacity and the normal it is shaded with.
#[derive(Clone, Debug, PartialEq)]
pub enum Sprite {
    /// `"disc"`: a soft disc, opacity 1 − r², with a hemisphere's normal.
    Disc,
    /// `"puff"`: the built-in normal-mapped cloud puff
    /// (`passes::particles::sprite`).
    Puff,
    /// An image file (PNG, any format `image` reads), relative to the
    /// scene file: RGB its tangent-space normal (green up), A its opacity.
    Image(std::sync::Arc<SpriteImage>),
}

/// A sprite image, loaded and resized to [`SPRITE_SIZE`]².
#[derive(Debug, PartialEq)]
pub struct SpriteImage {
    /// The file it was read from.
    pub path: std::path::PathBuf,
    /// [`SPRITE_SIZE`]² RGBA8, row 0 at the top.
    pub rgba: Vec<u8>,
}

/// Reads `path` as a sprite: resized to [`SPRITE_SIZE`]² (triangle
/// filter), RGBA8. Errors name the problem (the caller names the file).
pub fn load_sprite(path: &std::path::Path) -> std::result::Result<SpriteImage, String> {
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| e.to_string())?;
    let rgba = image::imageops::resize(
        &img.to_rgba8(),
        SPRITE_SIZE,
        SPRITE_SIZE,
        image::imageops::FilterType::Triangle,
    )
    .into_raw();
    Ok(SpriteImage {
        path: path.to_path_buf(),
        rgba,
    })
}

/// An emitter riding a moving object (`on = "object"` with `orbit` or
/// animation): at time t it is at `Object::transform_at(t)` applied to
/// `local`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterFollow {
    /// Index into [`super::Scene::objects`].
    pub object: usize,
    /// The birth point in the object's frame.
    pub local: Vec3,
}

/// What `on = "name"` finds: the object's index, its world box (at time 0
/// when it moves) and, when it moves, its transform at time 0.
pub(crate) struct OnObject {
    pub index: usize,
    pub bounds: super::Aabb,
    pub moving: Option<Mat4>,
}

fn rgba(ck: &Checker, v: &toml::Spanned<[f32; 4]>, key: &str) -> Result<Vec4> {
    let a = *v.get_ref();
    if a.iter().all(|c| c.is_finite() && *c >= 0.0)
        && a[3] <= 1.0
        && a[..3].iter().all(|c| *c <= 1e6)
    {
        Ok(Vec4::from(a))
    } else {
        Err(ck.err(
            &v.span(),
            format!("{key} {a:?}: linear RGBA, colour in [0, 1e6], alpha in [0, 1]"),
        ))
    }
}

/// `on`: a placed object by name (`None`: no such object).
pub(crate) fn build_emitters(
    ck: &Checker,
    base_dir: &std::path::Path,
    file: &[FileEmitter],
    on: impl Fn(&str) -> Option<OnObject>,
) -> Result<Vec<EmitterDesc>> {
    if let Some(e) = file.get(MAX_EMITTERS) {
        return Err(ck.err(
            &e.position.span(),
            format!("more than {MAX_EMITTERS} [[emitter]] tables"),
        ));
    }
    let mut out: Vec<EmitterDesc> = Vec::with_capacity(file.len());
    for (k, e) in file.iter().enumerate() {
        let name = match &e.name {
            Some(n) => {
                if out.iter().any(|o| &o.name == n.get_ref()) {
                    return Err(ck.err(
                        &n.span(),
                        format!("emitter \"{}\" is defined twice", n.get_ref()),
                    ));
                }
                n.get_ref().clone()
            }
            None => format!("emitter{k}"),
        };
        let mut position = ck.finite3(&e.position, "position")?;
        let mut follow = None;
        // Attached: `position` is an offset from the top centre of the object's box.
        if let Some(name) = &e.on {
            let o = on(name.get_ref()).ok_or_else(|| {
                ck.err(
                    &name.span(),
                    format!("on = \"{}\": no [[object]] of that name", name.get_ref()),
                )
            })?;
            let b = o.bounds;
            let top = Vec3::new(
                0.5 * (b.min.x + b.max.x),
                b.max.y,
                0.5 * (b.min.z + b.max.z),
            );
            position += top;
            // Moving: the point rides the object (turns with it when it turns).
            if let Some(m) = o.moving {
                if m.determinant().abs() < 1e-12 {
                    return Err(ck.err(
                        &name.span(),
                        format!(
                            "on = \"{}\": the object's transform at time 0 is singular",
                            name.get_ref()
                        ),
                    ));
                }
                follow = Some(EmitterFollow {
                    object: o.index,
                    local: m.inverse().transform_point3(position),
                });
            }
        }
        let rate = ck.range(&e.rate, "rate", f32::MIN_POSITIVE, MAX_RATE)?;
        let lifetime = ck.range(&e.lifetime, "lifetime", 1e-3, MAX_LIFETIME_S)?;
        let velocity = ck.finite3_or(&e.velocity, "velocity", Vec3::ZERO)?;
        let spread = match &e.spread {
            Some(s) => ck.range(s, "spread", 0.0, 1e3)?,
            None => 0.0,
        };
        let gravity = match &e.gravity {
            Some(g) => ck.range(g, "gravity", -10.0, 10.0)?,
            None => 0.0,
        };
        let wind = match &e.wind {
            Some(w) => ck.range(w, "wind", 0.0, 100.0)?,
            None => 1.0,
        };
        let size = match &e.size {
            Some(s) => {
                let a = *s.get_ref();
                if !a.iter().all(|x| x.is_finite() && *x >= 0.0 && *x <= 1e3) {
                    return Err(ck.err(
                        &s.span(),
                        format!("size {a:?}: [start, end] in metres, each in [0, 1000]"),
                    ));
                }
                a
            }
            None => [0.5, 0.5],
        };
        let color_start = match &e.color_start {
            Some(c) => rgba(ck, c, "color_start")?,
            None => Vec4::ONE,
        };
        let color_end = match &e.color_end {
            Some(c) => rgba(ck, c, "color_end")?,
            None => color_start.truncate().extend(0.0),
        };
        let capacity = match &e.capacity {
            Some(c) => ck.int(c, "capacity", 1, MAX_EMITTER_CAPACITY as i64)?,
            None => DEFAULT_EMITTER_CAPACITY,
        };
        let total: u32 = out.iter().map(|o| o.capacity).sum::<u32>() + capacity;
        if total > MAX_PARTICLE_SLOTS {
            let at = e.capacity.as_ref().map_or(e.position.span(), |c| c.span());
            return Err(ck.err(
                &at,
                format!(
                    "the emitters' capacities add up to {total}, more than {MAX_PARTICLE_SLOTS}"
                ),
            ));
        }
        let sprite = match e.sprite.as_ref().map(|s| (s, s.get_ref().as_str())) {
            None | Some((_, "disc")) => Sprite::Disc,
            Some((_, "puff")) => Sprite::Puff,
            Some((s, file)) => {
                // Emitters naming the same file share its layer.
                let path = base_dir.join(file);
                let same = out.iter().find_map(|o| match &o.sprite {
                    Sprite::Image(i) if i.path == path => Some(i.clone()),
                    _ => None,
                });
                match same {
                    Some(i) => Sprite::Image(i),
                    None => Sprite::Image(std::sync::Arc::new(load_sprite(&path).map_err(
                        |m| {
                            ck.err(
                                &s.span(),
                                format!(
                                    "sprite \"{file}\" ({}): {m} (expected \"disc\", \"puff\" or an image file)",
                                    path.display()
                                ),
                            )
                        },
                    )?)),
                }
            }
        };
        out.push(EmitterDesc {
            name,
            position,
            follow,
            rate,
            lifetime,
            velocity,
            spread,
            gravity,
            wind,
            size,
            color_start,
            color_end,
            capacity,
            sprite,
        });
    }
    Ok(out)
}
