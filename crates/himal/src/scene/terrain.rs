//! Height field objects of the scene file: noise or PNG source, layers.

use toml::Spanned;

use super::SceneError;
use super::build::World;
use super::file::{FileLayer, FileNoise, FileObject};
use super::heightfield::{HeightGrid, TerrainLayer, TerrainNoise};

type Result<T> = std::result::Result<T, SceneError>;

/// The grid, the seed for layer jitter and albedo variation, the layers
/// (base first) and the albedo variation.
pub(crate) fn build(
    w: &mut World,
    o: &FileObject,
) -> Result<(HeightGrid, u32, Vec<TerrainLayer>, f32)> {
    let ck = w.ck;
    let name = o.name.get_ref();
    let size = ck.size::<2>(w.required(o, &o.size, "size")?, "heightfield")?;
    let resolution = o
        .resolution
        .as_ref()
        .map(|r| ck.int(r, "resolution", 2, 4097).map(|r| r as usize))
        .transpose()?;
    let (grid, seed) = match (&o.noise, &o.png) {
        (Some(n), None) => {
            if let Some(h) = &o.height_scale {
                return Err(ck.err(
                    &h.span(),
                    "height_scale applies to png height fields; use noise.amplitude",
                ));
            }
            let Some(resolution) = resolution else {
                return Err(ck.err(
                    &n.span(),
                    "a noise height field needs `resolution` (vertices per side)",
                ));
            };
            let noise = terrain_noise(w, n)?;
            let span = o.resolution.as_ref().map_or(n.span(), |r| r.span());
            charge_grid(w, &span, name, resolution, resolution, 0)?;
            (HeightGrid::from_noise(size, resolution, &noise), noise.seed)
        }
        (None, Some(png)) => {
            let scale = ck.positive(
                w.required(o, &o.height_scale, "height_scale")?,
                "height_scale",
            )?;
            let path = w.base_dir.join(png.get_ref());
            let cannot = |e: String| {
                ck.err(
                    &png.span(),
                    format!("cannot load height map {}: {e}", path.display()),
                )
            };
            let (pw, ph) = HeightGrid::png_dimensions(&path).map_err(cannot)?;
            let (nx, nz) = resolution.map_or((pw as usize, ph as usize), |r| (r, r));
            // Decoding holds the image at up to 16 bits per channel, 4 channels.
            let decoded = pw as u64 * ph as u64 * 8;
            let span = o.resolution.as_ref().map_or(png.span(), |r| r.span());
            let what = format!("{} ({pw}x{ph} pixels)", path.display());
            charge_grid(w, &span, &what, nx, nz, decoded)?;
            let grid = HeightGrid::from_png(&path, size, scale, resolution).map_err(|e| {
                ck.err(
                    &png.span(),
                    format!("cannot load height map {}: {e}", path.display()),
                )
            })?;
            (grid, 0)
        }
        (Some(_), Some(png)) => return Err(ck.err(&png.span(), "give noise or png, not both")),
        (None, None) => {
            return Err(ck.err(
                &o.name.span(),
                format!(
                    "height field \"{}\" needs noise = {{ ... }} or png = \"...\"",
                    o.name.get_ref()
                ),
            ));
        }
    };
    let mut layers = Vec::new();
    if let Some(m) = &o.material {
        layers.push(TerrainLayer::new(w.materials[w.material(m)?].clone()));
    }
    for l in o.layers.iter().flat_map(|l| l.get_ref()) {
        layers.push(layer(w, l)?);
    }
    if layers.is_empty() {
        return Err(ck.err(
            &o.name.span(),
            format!(
                "height field \"{}\" needs material or layers",
                o.name.get_ref()
            ),
        ));
    }
    let variation = ck.unit(&o.albedo_variation, "albedo_variation", 0.0)?;
    Ok((grid, seed, layers, variation))
}

/// Charges a height field of `nx` x `nz` vertices (its heights and mesh)
/// plus `extra` bytes to the budget.
fn charge_grid(
    w: &mut World,
    span: &std::ops::Range<usize>,
    what: &str,
    nx: usize,
    nz: usize,
    extra: u64,
) -> Result<()> {
    let vertices = nx as u64 * nz as u64;
    let indices = 6 * (nx as u64).saturating_sub(1) * (nz as u64).saturating_sub(1);
    let bytes = crate::budget::MemoryBudget::mesh_bytes(vertices, indices)
        .saturating_add(vertices * 4)
        .saturating_add(extra);
    let what = format!("height field \"{what}\" of {nx}x{nz} vertices");
    w.charge(span, what, bytes)
}

fn terrain_noise(w: &World, n: &Spanned<FileNoise>) -> Result<TerrainNoise> {
    let ck = w.ck;
    let n = n.get_ref();
    let d = TerrainNoise::default();
    let f = |v: &Option<Spanned<f32>>, key: &str, default: f32| ck.non_negative(v, key, default);
    let noise = TerrainNoise {
        seed: n
            .seed
            .as_ref()
            .map_or(Ok(d.seed), |s| ck.int(s, "seed", 0, u32::MAX as i64))?,
        octaves: n
            .octaves
            .as_ref()
            .map_or(Ok(d.octaves), |s| ck.int(s, "octaves", 1, 16))?,
        frequency: n
            .frequency
            .as_ref()
            .map_or(Ok(d.frequency), |v| ck.positive(v, "frequency"))?,
        amplitude: f(&n.amplitude, "amplitude", d.amplitude)?,
        ridged: n.ridged.unwrap_or(d.ridged),
        lacunarity: n
            .lacunarity
            .as_ref()
            .map_or(Ok(d.lacunarity), |v| ck.range(v, "lacunarity", 1.0, 4.0))?,
        gain: n
            .gain
            .as_ref()
            .map_or(Ok(d.gain), |v| ck.range(v, "gain", 0.0, 1.0))?,
        warp: f(&n.warp, "warp", d.warp)?,
        erosion: f(&n.erosion, "erosion", d.erosion)?,
        flat_radius: f(&n.flat_radius, "flat_radius", d.flat_radius)?,
        valley_radius: f(&n.valley_radius, "valley_radius", d.valley_radius)?,
        floor_amplitude: f(&n.floor_amplitude, "floor_amplitude", d.floor_amplitude)?,
    };
    if let Some(v) = &n.valley_radius
        && noise.valley_radius < noise.flat_radius
    {
        return Err(ck.err(&v.span(), "valley_radius must be at least flat_radius"));
    }
    Ok(noise)
}

fn layer(w: &World, l: &FileLayer) -> Result<TerrainLayer> {
    let ck = w.ck;
    let mut t = TerrainLayer::new(w.materials[w.material(&l.material)?].clone());
    if let Some(h) = &l.min_height {
        t.min_height = ck.range(h, "min_height", f32::NEG_INFINITY, f32::INFINITY)?;
    }
    if let Some(h) = &l.max_height {
        t.max_height = ck.range(h, "max_height", f32::NEG_INFINITY, f32::INFINITY)?;
        if t.max_height < t.min_height {
            return Err(ck.err(&h.span(), "max_height is below min_height"));
        }
    }
    if let Some(s) = &l.min_slope {
        t.min_slope = ck.range(s, "min_slope", 0.0, 90.0)?;
    }
    if let Some(s) = &l.max_slope {
        t.max_slope = ck.range(s, "max_slope", t.min_slope, 90.0)?;
    }
    t.blend = ck.non_negative(&l.blend, "blend", 0.0)?;
    t.slope_blend = ck.non_negative(&l.slope_blend, "slope_blend", 0.0)?;
    t.jitter = ck.non_negative(&l.jitter, "jitter", 0.0)?;
    Ok(t)
}
