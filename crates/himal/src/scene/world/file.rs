//! A world from a scene file: its `[world]` table (seed, size, an optional
//! 16-bit height map, shape, placement rules, streaming, pool sizes), its
//! `[sun]` and its `[[camera]]`s. Every value is checked here, so a bad
//! file is an error naming the file, `line:column` and the key; nothing
//! the file says can panic generation or the GPU pools later.
//!
//! A world file holds no `[[object]]`, `[[material]]`, `[[light]]`,
//! `[[probe]]`, `[[gltf]]` or `[environment]`: the world draws only its own
//! terrain and streamed instances. Keys and defaults: the `[world]`
//! section of the `scene` module's documentation.

use std::ops::Range;
use std::path::Path;

use image::ImageDecoder;
use toml::Spanned;

use super::{HeightSource, InstanceKind, PoolSizes, SECTOR_SIZE, StreamSettings, World, WorldDesc};
use crate::scene::build::{Checker, build_cameras, build_sun};
use crate::scene::error::SourceMap;
use crate::scene::file::{FileHeightMap, FileScene, FileWorld};
use crate::scene::{HeightGrid, NamedCamera, SceneError, SunDesc};

type Result<T> = std::result::Result<T, SceneError>;

/// Sectors per side a file may ask for (1 km to Far Cry 4's 10.24 km).
pub const SECTORS: std::ops::RangeInclusive<i64> = 16..=160;
/// Largest height map side in pixels (an 8193^2 map holds 256 MiB of heights).
pub const MAX_HEIGHT_MAP_SIDE: u32 = 8193;
/// Largest terrain tile pool: the texture array layers desktop adapters offer.
pub const MAX_TILES: i64 = 2048;
/// Largest instance region of one kind (240 MiB of records and bounds).
pub const MAX_INSTANCES: i64 = 1 << 20;
/// Lowest and highest ground a height map may span (metres).
const HEIGHT_LIMIT: f32 = 20_000.0;

/// What a scene file with a `[world]` table describes.
#[derive(Clone, Debug)]
pub struct WorldFile {
    /// The world: shape or height map, placement rules, streaming and pool sizes.
    pub desc: WorldDesc,
    /// The file's `[[camera]]`s, in file order.
    pub cameras: Vec<NamedCamera>,
    /// The file's `[sun]` (defaults where absent).
    pub sun: SunDesc,
}

impl WorldFile {
    /// Reads the scene file at `path`: `None` when it has no `[world]`
    /// table (a scene of objects: [`crate::scene::Scene::load`]). A height
    /// map's path is relative to the file's folder.
    pub fn load(path: &Path) -> Result<Option<WorldFile>> {
        let text = crate::scene::read_scene_file(path)?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        Self::from_toml_str(&text, &path.display().to_string(), base_dir)
    }

    /// [`WorldFile::load`] on scene text; `origin` names it in messages,
    /// `base_dir` resolves the height map's path.
    pub fn from_toml_str(text: &str, origin: &str, base_dir: &Path) -> Result<Option<WorldFile>> {
        let ck = Checker {
            src: SourceMap { origin, text },
        };
        let file: FileScene = toml::from_str(text).map_err(|e| ck.src.toml_error(&e))?;
        let Some(world) = &file.world else {
            return Ok(None);
        };
        reject_scene_tables(&ck, &file)?;
        let desc = build_desc(&ck, world.get_ref(), base_dir)?;
        Ok(Some(WorldFile {
            desc,
            cameras: build_cameras(&ck, &file.camera)?,
            sun: build_sun(&ck, file.sun.as_ref())?,
        }))
    }

    /// The world, its file cameras first ([`World::with_cameras`]), lit by the file's sun.
    pub fn into_world(self) -> World {
        let mut w = World::new(self.desc).with_cameras(self.cameras);
        w.sun = self.sun;
        w
    }
}

impl WorldDesc {
    /// The description in the scene file at `path`; `None` when the file
    /// has no `[world]` table. Its cameras and sun: [`WorldFile::load`].
    pub fn from_file(path: &Path) -> Result<Option<WorldDesc>> {
        Ok(WorldFile::load(path)?.map(|f| f.desc))
    }
}

/// Tables a world file cannot use, at the first entry of each.
fn reject_scene_tables(ck: &Checker, f: &FileScene) -> Result<()> {
    let first: [(&str, Option<Range<usize>>); 11] = [
        ("[[object]]", f.object.first().map(|o| o.name.span())),
        ("[[material]]", f.material.first().map(|m| m.name.span())),
        ("[[light]]", f.light.first().map(|l| l.name.span())),
        (
            "[[ambient_light]]",
            f.ambient_light.first().map(|a| a.position.span()),
        ),
        ("[[probe]]", f.probe.first().map(|p| p.position.span())),
        ("[[emitter]]", f.emitter.first().map(|e| e.position.span())),
        ("[wind]", f.wind.as_ref().map(|w| w.span())),
        (
            "[[wind_source]]",
            f.wind_source.first().map(|w| w.radius.span()),
        ),
        ("[[gltf]]", f.gltf.first().map(|g| g.file.span())),
        (
            "[environment]",
            f.environment.as_ref().map(|e| e.file.span()),
        ),
        // A world's cameras take `cinematic_shadows = { near, far }` instead.
        (
            "[cinematic_shadows]",
            f.cinematic_shadows.as_ref().map(|c| c.near.span()),
        ),
    ];
    for (table, span) in first {
        if let Some(span) = span {
            return Err(ck.err(
                &span,
                format!(
                    "{table} cannot be used with [world]: the streamed world draws only its \
                     terrain and generated instances (only [sun] and [[camera]] apply)"
                ),
            ));
        }
    }
    Ok(())
}

fn build_desc(ck: &Checker, w: &FileWorld, base_dir: &Path) -> Result<WorldDesc> {
    let mut d = WorldDesc::default();
    if let Some(s) = &w.seed {
        d.shape.seed = ck.int(s, "world.seed", 0, u32::MAX.into())?;
    }
    if let Some(s) = &w.sectors {
        d.sectors = ck.int(s, "world.sectors", *SECTORS.start(), *SECTORS.end())? as u16;
    }
    let extent = d.sectors as f32 * SECTOR_SIZE;
    if let Some(hm) = &w.height_map {
        // The procedural shape's keys would silently do nothing.
        for (key, v) in [
            ("mountain_height", &w.mountain_height),
            ("hill_height", &w.hill_height),
        ] {
            if let Some(v) = v {
                return Err(ck.err(
                    &v.span(),
                    format!("world.{key} shapes the procedural terrain; with height_map it has no effect"),
                ));
            }
        }
        d.source = HeightSource::Image(height_map(ck, hm, base_dir, extent)?);
    }
    let shape = &mut d.shape;
    if let Some(v) = &w.mountain_height {
        shape.mountain_height = ck.range(v, "world.mountain_height", 0.0, HEIGHT_LIMIT)?;
    }
    if let Some(v) = &w.hill_height {
        shape.hill_height = ck.range(v, "world.hill_height", 0.0, HEIGHT_LIMIT)?;
    }
    if let Some(v) = &w.snow_line {
        shape.snow_line = ck.range(v, "world.snow_line", -HEIGHT_LIMIT, HEIGHT_LIMIT)?;
    }
    if let Some(r) = &w.rules {
        let rules = &mut d.rules;
        if let Some(v) = &r.rock_density {
            rules.rock_density = ck.range(v, "world.rules.rock_density", 0.0, 100.0)?;
        }
        if let Some(v) = &r.tree_density {
            rules.tree_density = ck.range(v, "world.rules.tree_density", 0.0, 100.0)?;
        }
        if let Some(v) = &r.tree_max_slope {
            rules.tree_max_slope = ck.range(v, "world.rules.tree_max_slope", 0.0, 90.0)?;
        }
        if let Some(v) = &r.larch_line {
            rules.larch_line =
                ck.range(v, "world.rules.larch_line", -HEIGHT_LIMIT, HEIGHT_LIMIT)?;
        }
        rules.houses = r.houses.unwrap_or(rules.houses);
        rules.fields = r.fields.unwrap_or(rules.fields);
        rules.fences = r.fences.unwrap_or(rules.fences);
        if let Some(v) = &r.tree_line {
            shape.tree_line = ck.range(v, "world.rules.tree_line", -HEIGHT_LIMIT, HEIGHT_LIMIT)?;
        }
        if let Some(v) = &r.village_chance {
            shape.village_chance = ck.range(v, "world.rules.village_chance", 0.0, 1.0)?;
        }
        if let Some(v) = &r.village_max_rise {
            shape.village_max_rise = ck.range(v, "world.rules.village_max_rise", 0.0, 1000.0)?;
        }
    }
    d.stream = stream(ck, w, extent)?;
    d.pools = pools(ck, w, &d.stream, d.sectors)?;
    Ok(d)
}

/// A grayscale image stretched over the world, black at `min`, white at `max`.
fn height_map(
    ck: &Checker,
    hm: &Spanned<FileHeightMap>,
    base_dir: &Path,
    extent: f32,
) -> Result<HeightGrid> {
    let m = hm.get_ref();
    let lo = match &m.min {
        Some(v) => ck.range(v, "world.height_map.min", -HEIGHT_LIMIT, HEIGHT_LIMIT)?,
        None => 0.0,
    };
    let hi = ck.range(&m.max, "world.height_map.max", -HEIGHT_LIMIT, HEIGHT_LIMIT)?;
    if hi <= lo {
        return Err(ck.err(
            &m.max.span(),
            format!("world.height_map.max = {hi} must be above min = {lo}"),
        ));
    }
    let path = base_dir.join(m.file.get_ref());
    let at_file = |what: String| {
        ck.err(
            &m.file.span(),
            format!("world.height_map.file {}: {what}", path.display()),
        )
    };
    // The header alone tells the size and pixel format, before any decoding.
    let decoder = image::ImageReader::open(&path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| at_file(format!("cannot read: {e}")))?
        .into_decoder()
        .map_err(|e| at_file(format!("not a readable image: {e}")))?;
    let (w, h) = decoder.dimensions();
    match decoder.color_type() {
        image::ColorType::L16 | image::ColorType::L8 => {}
        other => {
            return Err(at_file(format!(
                "{other:?} pixels; a height map is a grayscale image (16-bit, or 8-bit) without alpha"
            )));
        }
    }
    if !(2..=MAX_HEIGHT_MAP_SIDE).contains(&w) || !(2..=MAX_HEIGHT_MAP_SIDE).contains(&h) {
        return Err(at_file(format!(
            "{w}x{h} pixels; each side must be 2 to {MAX_HEIGHT_MAP_SIDE}"
        )));
    }
    let mut g = HeightGrid::from_png(&path, [extent, extent], hi - lo, None).map_err(at_file)?;
    for v in &mut g.heights {
        *v += lo;
    }
    Ok(g)
}

fn stream(ck: &Checker, w: &FileWorld, extent: f32) -> Result<StreamSettings> {
    let mut s = StreamSettings::default();
    let Some(f) = &w.stream else { return Ok(s) };
    if let Some(v) = &f.radius {
        s.radius = ck.range(v, "world.stream.radius", 1.0, extent)?;
    }
    if let Some(v) = &f.unload_margin {
        s.unload_margin = ck.range(v, "world.stream.unload_margin", 0.0, extent)?;
    }
    if let Some(v) = &f.workers {
        s.workers = ck.int(v, "world.stream.workers", 0, 64)? as usize;
    }
    if let Some(v) = &f.upload_budget {
        let b = v.get_ref().0;
        if !(1024..=1 << 30).contains(&b) {
            return Err(ck.err(
                &v.span(),
                format!("world.stream.upload_budget = {b} bytes must lie in 1KiB..=1GiB"),
            ));
        }
        s.upload_budget = b;
    }
    Ok(s)
}

/// Most sectors whose rectangle lies within `radius` of one point: the
/// area of a sector grown by the radius, in sectors, at most the world.
pub fn max_wanted(radius: f32, sectors: u16) -> u32 {
    let s = SECTOR_SIZE;
    let area = s * s + 4.0 * s * radius + std::f32::consts::PI * radius * radius;
    ((area / (s * s)).ceil() as u32).min(u32::from(sectors).pow(2))
}

fn pools(ck: &Checker, w: &FileWorld, stream: &StreamSettings, sectors: u16) -> Result<PoolSizes> {
    let mut p = PoolSizes::default();
    let mut tiles_span = None;
    for (name, v) in w.pools.iter().flatten() {
        let key = format!("world.pools.{name}");
        if name == "tiles" {
            p.tiles = ck.int(v, &key, 1, MAX_TILES)?;
            tiles_span = Some(v.span());
        } else if let Some(k) = InstanceKind::ALL.iter().find(|k| k.name() == name) {
            p.instances[*k as usize] = ck.int(v, &key, 1, MAX_INSTANCES)?;
        } else {
            let known: Vec<&str> = InstanceKind::ALL.iter().map(|k| k.name()).collect();
            return Err(ck.err(
                &v.span(),
                format!("{key}: no such pool (known: tiles, {})", known.join(", ")),
            ));
        }
    }
    // Wanted sectors beyond the tile pool would never stream in.
    let wanted = max_wanted(stream.radius, sectors);
    if wanted > p.tiles {
        let message = format!(
            "world.pools.tiles = {} holds fewer sectors than world.stream.radius = {} m wants \
             (up to {wanted}): raise tiles or lower the radius",
            p.tiles, stream.radius
        );
        let radius_span = w
            .stream
            .as_ref()
            .and_then(|s| s.radius.as_ref())
            .map(|r| r.span());
        return Err(match tiles_span.or(radius_span) {
            Some(span) => ck.err(&span, message),
            None => ck.src.invalid(message),
        });
    }
    Ok(p)
}
