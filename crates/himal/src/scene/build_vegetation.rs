//! Scene-file checks for the vegetation primitives (`grass`, `bush`) and
//! their per-object foliage parameters; meshes are built in `vegetation.rs`.

use toml::Spanned;

use super::build::World;
use super::file::FileObject;
use super::vegetation::{self, BushParams, GrassParams, MAX_CLUMPS};
use super::{AlphaPattern, Foliage, SceneError};

type Result<T> = std::result::Result<T, SceneError>;

/// Defaults: short meadow grass and a waist-high bush, swaying a few centimetres.
pub(crate) const GRASS_DENSITY: f32 = 30.0;
pub(crate) const GRASS_HEIGHT: f32 = 0.3;
pub(crate) const GRASS_WIDTH: f32 = 0.15;
pub(crate) const GRASS_CARDS: u32 = 3;
pub(crate) const GRASS_SWAY: f32 = 0.04;
pub(crate) const BUSH_CARDS: u32 = 80;
pub(crate) const BUSH_CARD_SIZE: f32 = 0.3;
pub(crate) const BUSH_SWAY: f32 = 0.03;

impl World<'_> {
    fn positive_or(&self, v: &Option<Spanned<f32>>, key: &str, default: f32) -> Result<f32> {
        v.as_ref().map_or(Ok(default), |v| self.ck.positive(v, key))
    }

    fn seed(&self, o: &FileObject) -> Result<u32> {
        o.seed
            .as_ref()
            .map_or(Ok(0), |s| self.ck.int(s, "seed", 0, u32::MAX as i64))
    }

    pub(crate) fn grass_params(&self, o: &FileObject) -> Result<GrassParams> {
        let size_key = self.required(o, &o.size, "size")?;
        let p = GrassParams {
            size: self.ck.size(size_key, "grass")?,
            density: self.positive_or(&o.density, "density", GRASS_DENSITY)?,
            height: self.positive_or(&o.height, "height", GRASS_HEIGHT)?,
            width: self.positive_or(&o.width, "width", GRASS_WIDTH)?,
            cards: o
                .cards
                .as_ref()
                .map_or(Ok(GRASS_CARDS), |c| self.ck.int(c, "cards", 1, 4))?,
            seed: self.seed(o)?,
        };
        let clumps = p.clump_count();
        if clumps > MAX_CLUMPS as u64 {
            let span = o.density.as_ref().map_or(size_key.span(), |d| d.span());
            return Err(self.ck.err(
                &span,
                format!(
                    "grass of {} x {} m at {} clumps/m^2 makes {clumps} clumps, more than {MAX_CLUMPS}",
                    p.size[0], p.size[1], p.density
                ),
            ));
        }
        Ok(p)
    }

    pub(crate) fn bush_params(&self, o: &FileObject) -> Result<BushParams> {
        let radii = match (&o.radius, &o.size) {
            (Some(r), None) => [self.ck.positive(r, "radius")?; 3],
            (None, Some(s)) => self.ck.size::<3>(s, "bush")?.map(|c| c * 0.5),
            (Some(_), Some(s)) => {
                return Err(self
                    .ck
                    .err(&s.span(), "give a bush radius or size, not both"));
            }
            (None, None) => {
                return Err(self.ck.err(
                    &o.name.span(),
                    format!(
                        "object \"{}\": primitive bush needs `radius` or `size`",
                        o.name.get_ref()
                    ),
                ));
            }
        };
        Ok(BushParams {
            radii,
            cards: o
                .cards
                .as_ref()
                .map_or(Ok(BUSH_CARDS), |c| self.ck.int(c, "cards", 1, 100_000))?,
            card_size: self.positive_or(&o.width, "width", BUSH_CARD_SIZE)?,
            seed: self.seed(o)?,
        })
    }

    /// Foliage parameters of a grass or bush object (`None` for other primitives).
    pub(crate) fn foliage(&self, o: &FileObject, mesh: usize) -> Result<Option<Foliage>> {
        let (pattern, default_sway) = match o.primitive.get_ref().as_str() {
            "grass" => (AlphaPattern::Grass, GRASS_SWAY),
            "bush" => (AlphaPattern::Leaves, BUSH_SWAY),
            _ => return Ok(None),
        };
        let sway = match &o.sway {
            Some(s) => self.ck.range(s, "sway", 0.0, 1.0)?,
            None => default_sway,
        };
        let b = self.meshes[mesh].bounds;
        let (sway_base, sway_inv_height) = match pattern {
            AlphaPattern::Grass => (0.0, 0.0),
            AlphaPattern::Leaves => (b.min.y, 1.0 / b.extent().y.max(1e-3)),
        };
        Ok(Some(Foliage {
            pattern,
            sway,
            sway_base,
            sway_inv_height,
        }))
    }

    /// A grass mesh whose clump roots sit at `root_y(x, z)` (local); not
    /// shared, as each placement has its own ground.
    pub(crate) fn snapped_grass(
        &mut self,
        o: &FileObject,
        name_suffix: &str,
        root_y: impl FnMut(f32, f32) -> Option<f32>,
    ) -> Result<std::result::Result<usize, glam::Vec2>> {
        self.check_keys(o)?;
        let p = self.grass_params(o)?;
        let m = &self.materials[self.material(self.required(o, &o.material, "material")?)?];
        let name = format!("grass/{}{name_suffix}", o.name.get_ref());
        Ok(vegetation::grass(name, &p, m, root_y).map(|mesh| {
            self.meshes.push(mesh);
            self.meshes.len() - 1
        }))
    }
}
