//! Scene-file checks for the vegetation primitives (`grass`, `bush`,
//! `tree`) and their per-object foliage parameters; meshes are built in
//! `vegetation.rs` and `tree/`.

use toml::Spanned;

use super::build::World;
use super::file::FileObject;
use glam::Vec3;

use super::tree::{self, Species};
use super::vegetation::{self, BushParams, GrassParams, MAX_CLUMPS, Rng};
use super::{AlphaPattern, Foliage, MaterialDesc, SceneError};

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
/// Trees: a margin in their bounds only; V2's bones move them
/// (`gpu_scene/trees.rs` points their `params.y` at the bones).
pub(crate) const TREE_SWAY: f32 = 0.03;
/// Most trees one `[[object]]` may place.
pub(crate) const MAX_TREES: i64 = 100_000;

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
            "tree" => (AlphaPattern::Leaves, TREE_SWAY),
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

    /// The (trunk, leaves) meshes of a `tree` object (V1), shared by every
    /// object of the same species, seed, materials and tint.
    pub(crate) fn tree_meshes(&mut self, o: &FileObject) -> Result<(usize, usize)> {
        let species_key = self.required(o, &o.species, "species")?;
        let species = Species::parse(species_key.get_ref()).ok_or_else(|| {
            let known: Vec<&str> = Species::ALL.iter().map(|s| s.name()).collect();
            self.ck.err(
                &species_key.span(),
                format!(
                    "unknown species \"{}\" (known: {})",
                    species_key.get_ref(),
                    known.join(", ")
                ),
            )
        })?;
        let seed = self.seed(o)?;
        let leaves = self.material(self.required(o, &o.material, "material")?)?;
        let bark = o
            .bark_material
            .as_ref()
            .map(|b| self.material(b))
            .transpose()?;
        let leaf_albedo = self.materials[leaves].albedo;
        let tint = match &o.tint {
            Some(t) => {
                let v = t.get_ref();
                if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
                    return Err(self
                        .ck
                        .err(&t.span(), format!("tint {v:?} must lie in [0, 1]")));
                }
                Vec3::from(*v).map(super::build::srgb_to_linear)
            }
            // Default: a yellower, lighter green beside the leaves' own.
            None => (leaf_albedo * Vec3::new(1.3, 1.15, 0.55)).min(Vec3::ONE),
        };
        let key = format!("tree {species:?} {seed} {leaves} {bark:?} {tint:?}");
        if let Some(&i) = self.mesh_keys.get(&key) {
            return Ok((i, i + 1));
        }
        let bark_material = match bark {
            Some(b) => self.materials[b].clone(),
            None => default_bark(),
        };
        let name = format!("{}/{seed}", species.name());
        let mut m = tree::cached(
            species,
            seed,
            &name,
            &bark_material,
            &self.materials[leaves],
            tint,
        );
        // V3: the impostor as the leaves' level after LOD2.
        let (layer, imp) = self.impostors.layer(species, seed);
        let colours =
            tree::impostor_level::Colours::new(&bark_material, &self.materials[leaves], tint);
        tree::impostor_level::append(&mut m.leaves, &imp, layer, &colours);
        for (part, mesh) in [("trunk", &m.trunk), ("leaves", &m.leaves)] {
            let indices =
                mesh.indices.len() + mesh.levels.iter().map(|l| l.indices.len()).sum::<usize>();
            let what = format!("object \"{}\": tree {part}", o.name.get_ref());
            self.charge_mesh(
                &species_key.span(),
                what,
                mesh.vertices.len() as u64,
                indices as u64,
            )?;
        }
        self.meshes.push(m.trunk);
        self.meshes.push(m.leaves);
        let trunk = self.meshes.len() - 2;
        self.rigs.push(tree::rig::SceneRig {
            meshes: [trunk, trunk + 1],
            rig: m.rig,
        });
        self.mesh_keys.insert(key, trunk);
        Ok((trunk, trunk + 1))
    }

    /// Where a `tree` object's trees stand (before snapping): `position` plus
    /// each of `positions`, or `count` trees uniform over `size = [x, z]`
    /// around `position` (seeded), or one at `position`.
    pub(crate) fn tree_bases(&self, o: &FileObject, position: Vec3) -> Result<Vec<Vec3>> {
        if let Some(p) = &o.positions {
            if let Some(c) = &o.count {
                return Err(self
                    .ck
                    .err(&c.span(), "give a tree count or positions, not both"));
            }
            if p.get_ref().len() as i64 > MAX_TREES {
                return Err(self
                    .ck
                    .err(&p.span(), format!("more than {MAX_TREES} positions")));
            }
            return p
                .get_ref()
                .iter()
                .map(|q| {
                    let v = Vec3::from(*q);
                    if v.is_finite() {
                        Ok(position + v)
                    } else {
                        Err(self
                            .ck
                            .err(&p.span(), format!("position {q:?} is not finite")))
                    }
                })
                .collect();
        }
        let count = o
            .count
            .as_ref()
            .map_or(Ok(1), |c| self.ck.int(c, "count", 1, MAX_TREES))?;
        let size = match &o.size {
            Some(s) => self.ck.size::<2>(s, "tree")?,
            None if count > 1 => {
                return Err(self.ck.err(
                    &o.name.span(),
                    format!(
                        "object \"{}\": {count} trees need `size = [x, z]` (the area they cover)",
                        o.name.get_ref()
                    ),
                ));
            }
            None => [0.0, 0.0],
        };
        let mut rng = Rng::new(self.seed(o)?, -2);
        Ok((0..count)
            .map(|_| {
                let (x, z) = (rng.next() - 0.5, rng.next() - 0.5);
                position + Vec3::new(x * size[0], 0.0, z * size[1])
            })
            .collect())
    }
}

/// Bark when a tree names none: grey-brown, rough.
fn default_bark() -> MaterialDesc {
    MaterialDesc {
        name: "bark".into(),
        albedo: Vec3::new(0.33, 0.26, 0.2).map(super::build::srgb_to_linear),
        glossiness: 0.2,
        ..MaterialDesc::default()
    }
}
