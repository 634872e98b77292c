//! Scene file -> [`Scene`]: semantic checks (each error at the offending
//! key), materials, cameras, and mesh building shared per (shape, material).

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use glam::{EulerRot, Mat4, Quat, Vec3};
use toml::Spanned;

use super::error::SourceMap;
use super::file::{FileCamera, FileMaterial, FileObject, FileScene, FileSun};
use super::place::Placer;
use super::{Aabb, Camera, MaterialDesc, NamedCamera, Scene, SceneError, SunDesc};
use super::{heightfield, primitives, vegetation};
use crate::budget::MemoryBudget;

type Result<T> = std::result::Result<T, SceneError>;

const PRIMITIVES: &str = "plane, box, sphere, cylinder, prism, heightfield, grass, bush, tree";

/// Range checks that point at the offending value.
pub(crate) struct Checker<'a> {
    pub src: SourceMap<'a>,
}

/// Largest coordinate or length a scene may give, in metres (the open
/// world is 10.24 km; f32 positions this far out still resolve 6 cm).
pub(crate) const MAX_EXTENT: f32 = 1.0e6;
/// Smallest length (radius, height, size component), in metres.
pub(crate) const MIN_LENGTH: f32 = 1.0e-4;
/// Scale factors per axis lie in [1 / MAX_SCALE, MAX_SCALE].
pub(crate) const MAX_SCALE: f32 = 1.0e4;

impl Checker<'_> {
    pub fn err(&self, span: &Range<usize>, message: impl Into<String>) -> SceneError {
        self.src.error(span, message)
    }

    /// `v` in [lo, hi] (inclusive).
    pub fn range(&self, v: &Spanned<f32>, key: &str, lo: f32, hi: f32) -> Result<f32> {
        let x = *v.get_ref();
        if x >= lo && x <= hi {
            Ok(x)
        } else {
            Err(self.err(
                &v.span(),
                format!("{key} = {x} is out of range [{lo}, {hi}]"),
            ))
        }
    }

    pub fn unit(&self, v: &Option<Spanned<f32>>, key: &str, default: f32) -> Result<f32> {
        v.as_ref()
            .map_or(Ok(default), |v| self.range(v, key, 0.0, 1.0))
    }

    pub fn positive(&self, v: &Spanned<f32>, key: &str) -> Result<f32> {
        let x = *v.get_ref();
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(&v.span(), format!("{key} = {x} must be positive")))
        }
    }

    /// A length in metres: [`MIN_LENGTH`] to [`MAX_EXTENT`].
    pub fn length(&self, v: &Spanned<f32>, key: &str) -> Result<f32> {
        self.range(v, key, MIN_LENGTH, MAX_EXTENT)
    }

    /// A vector of finite numbers (TOML allows nan and inf) within
    /// [`MAX_EXTENT`] of the origin on each axis.
    pub fn finite3(&self, v: &Spanned<[f32; 3]>, key: &str) -> Result<Vec3> {
        let a = *v.get_ref();
        if a.iter().all(|c| c.is_finite() && c.abs() <= MAX_EXTENT) {
            Ok(Vec3::from(a))
        } else {
            Err(self.err(
                &v.span(),
                format!("{key} {a:?} must be finite numbers within +-{MAX_EXTENT}"),
            ))
        }
    }

    /// Optional finite vector, `default` when absent.
    pub fn finite3_or(
        &self,
        v: &Option<Spanned<[f32; 3]>>,
        key: &str,
        default: Vec3,
    ) -> Result<Vec3> {
        v.as_ref().map_or(Ok(default), |v| self.finite3(v, key))
    }

    pub fn non_negative(&self, v: &Option<Spanned<f32>>, key: &str, default: f32) -> Result<f32> {
        let Some(v) = v else { return Ok(default) };
        let x = *v.get_ref();
        if x >= 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(&v.span(), format!("{key} = {x} must be finite and >= 0")))
        }
    }

    pub fn int(&self, v: &Spanned<i64>, key: &str, lo: i64, hi: i64) -> Result<u32> {
        let x = *v.get_ref();
        if x >= lo && x <= hi {
            Ok(x as u32)
        } else {
            Err(self.err(
                &v.span(),
                format!("{key} = {x} is out of range [{lo}, {hi}]"),
            ))
        }
    }

    /// `size` with exactly `N` positive components.
    pub fn size<const N: usize>(&self, v: &Spanned<Vec<f32>>, primitive: &str) -> Result<[f32; N]> {
        let s = v.get_ref();
        if s.len() != N || s.iter().any(|c| !(MIN_LENGTH..=MAX_EXTENT).contains(c)) {
            let want = if N == 2 { "[x, z]" } else { "[x, y, z]" };
            return Err(self.err(
                &v.span(),
                format!(
                    "{primitive} size must be {N} numbers {want} in [{MIN_LENGTH}, {MAX_EXTENT}] m, got {s:?}"
                ),
            ));
        }
        let mut out = [0.0; N];
        out.copy_from_slice(s);
        Ok(out)
    }
}

pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

pub(crate) fn build_scene(
    text: &str,
    origin: &str,
    base_dir: &Path,
    budget: MemoryBudget,
) -> Result<Scene> {
    let ck = Checker {
        src: SourceMap { origin, text },
    };
    let file: FileScene = toml::from_str(text).map_err(|e| ck.src.toml_error(&e))?;
    if let Some(w) = &file.world {
        return Err(ck.err(
            &w.span(),
            "[world] describes a streamed world, not a scene of objects: load it with \
             scene::world::WorldFile::load (as `himal render --scene FILE` does)",
        ));
    }
    let sun = build_sun(&ck, file.sun.as_ref())?;
    let materials = build_materials(&ck, &file.material)?;
    let cameras = build_cameras(&ck, &file.camera)?;
    let probes = file
        .probe
        .iter()
        .map(|p| ck.finite3(&p.position, "position"))
        .collect::<Result<Vec<_>>>()?;
    let lights = super::lights::build_lights(&ck, &file.light)?;
    let ambient_lights = super::ambient::build_ambient_lights(&ck, &file.ambient_light)?;
    let environment = match &file.environment {
        Some(e) => {
            let file = e.file.get_ref();
            let mut desc = super::EnvironmentDesc::new(if file == super::STUDIO {
                std::path::PathBuf::from(file)
            } else {
                base_dir.join(file)
            });
            if let Some(i) = &e.intensity {
                desc.intensity = ck.range(i, "intensity", 0.0, 1e6)?;
            }
            if let Some(r) = &e.rotation {
                desc.rotation_deg = ck.range(r, "rotation", -360.0, 360.0)?;
            }
            desc.sun = e.sun.unwrap_or(false);
            Some(desc)
        }
        None => None,
    };
    let mut world = World {
        ck: &ck,
        base_dir,
        materials: &materials,
        meshes: Vec::new(),
        mesh_keys: HashMap::new(),
        budget,
        charged: 0,
        impostors: Default::default(),
        rigs: Vec::new(),
    };
    let mut objects = Placer::place_all(&mut world, &file.object)?;
    let charged = world.charged;
    let ao_volumes = world.impostors.volumes;
    let impostors = world.impostors.atlases;
    let tree_rigs = world.rigs;
    let mut meshes = world.meshes;
    let mut lights = lights;
    // Models share what the scene's own meshes left of the budget.
    let left = MemoryBudget {
        bytes: budget.bytes.saturating_sub(charged).max(1),
    };
    let placed =
        super::gltf::placement::place_all(&ck, base_dir, &file.gltf, &mut meshes, &objects, left)?;
    objects.extend(placed.objects);
    lights.extend(placed.lights);
    let mut pbr = placed.pbr;
    super::mirror_meshes(&mut meshes, &mut objects, &mut pbr);
    let bounds = objects.iter().fold(Aabb::EMPTY, |b, o| {
        b.union(&o.swept_bounds(&meshes[o.mesh].bounds))
    });
    let cinematic_shadows = file
        .cinematic_shadows
        .as_ref()
        .map(|f| build_cinematic_shadows(&ck, f))
        .transpose()?;
    let object_box = |name: &str| {
        let index = objects.iter().position(|o| o.name == name)?;
        let o = &objects[index];
        let mesh = &meshes[o.mesh].bounds;
        Some(match &o.motion {
            Some(m) => {
                let t0 = m.transform_at(0.0);
                super::emitters::OnObject {
                    index,
                    bounds: mesh.transform(&t0),
                    moving: Some(t0),
                }
            }
            None => super::emitters::OnObject {
                index,
                bounds: o.swept_bounds(mesh),
                moving: None,
            },
        })
    };
    let emitters = super::emitters::build_emitters(&ck, base_dir, &file.emitter, object_box)?;
    let wind = super::emitters::build_wind(&ck, file.wind.as_ref())?;
    let wind_sources = super::wind::build_sources(&ck, &file.wind_source)?;
    // E4: every particle slot holds its state and its light on the GPU.
    if let Some(first) = file.emitter.first() {
        let slots: u64 = emitters.iter().map(|e| e.capacity as u64).sum();
        let bytes = charged.saturating_add(slots * super::emitters::SLOT_BYTES);
        (budget.check("the scene with its emitters' particle slots", bytes))
            .map_err(|m| ck.err(&first.position.span(), m))?;
    }
    Ok(Scene {
        path: Some(origin.into()),
        impostors,
        ao_volumes,
        meshes,
        objects,
        materials,
        cameras,
        cinematic_shadows,
        sun,
        lights,
        ambient_lights,
        emitters,
        wind,
        wind_sources,
        tree_rigs,
        bounds,
        pbr,
        probes,
        environment,
    })
}

pub(crate) fn build_sun(ck: &Checker, sun: Option<&FileSun>) -> Result<SunDesc> {
    let mut out = SunDesc::default();
    let Some(s) = sun else { return Ok(out) };
    if let Some(t) = &s.time {
        let h = t.get_ref().0;
        if !(0.0..24.0).contains(&h) {
            return Err(ck.err(
                &t.span(),
                format!("time = {h} hours is out of range [0, 24)"),
            ));
        }
        out.time_hours = h;
    }
    if let Some(l) = &s.latitude {
        out.latitude_deg = ck.range(l, "latitude", -90.0, 90.0)?;
    }
    if let Some(d) = &s.day_of_year {
        out.day_of_year = ck.int(d, "day_of_year", 1, 366)?;
    }
    if let Some(t) = &s.turbidity {
        out.turbidity = ck.range(t, "turbidity", 1.0, 10.0)?;
    }
    Ok(out)
}

fn build_materials(ck: &Checker, file: &[FileMaterial]) -> Result<Vec<MaterialDesc>> {
    let mut out: Vec<MaterialDesc> = Vec::new();
    let mut first_at: HashMap<&str, Range<usize>> = HashMap::new();
    for m in file {
        let name = m.name.get_ref();
        if let Some(prev) = first_at.get(name.as_str()) {
            let (line, _) = ck.src.line_column(prev.start);
            return Err(ck.err(
                &m.name.span(),
                format!("material \"{name}\" is defined twice (first on line {line})"),
            ));
        }
        first_at.insert(name, m.name.span());
        let albedo = match (&m.albedo, &m.albedo_linear) {
            (Some(_), Some(l)) => {
                return Err(ck.err(&l.span(), "give albedo (sRGB) or albedo_linear, not both"));
            }
            (None, None) => {
                return Err(ck.err(
                    &m.name.span(),
                    format!("material \"{name}\" needs albedo (sRGB) or albedo_linear"),
                ));
            }
            (Some(a), None) | (None, Some(a)) => {
                let v = a.get_ref();
                if v.iter().any(|c| !(0.0..=1.0).contains(c)) {
                    return Err(ck.err(&a.span(), format!("albedo {v:?} must lie in [0, 1]")));
                }
                let v = Vec3::from(*v);
                if m.albedo.is_some() {
                    v.map(srgb_to_linear)
                } else {
                    v
                }
            }
        };
        out.push(MaterialDesc {
            name: name.clone(),
            albedo,
            glossiness: ck.unit(&m.glossiness, "glossiness", 0.5)?,
            reflectance: ck.unit(&m.reflectance, "reflectance", 0.04)?,
            metallic: ck.unit(&m.metallic, "metallic", 0.0)?,
            anisotropy: ck.unit(&m.anisotropy, "anisotropy", 0.0)?,
            ao: ck.unit(&m.ao, "ao", 1.0)?,
        });
    }
    Ok(out)
}

pub(crate) fn build_cameras(ck: &Checker, file: &[FileCamera]) -> Result<Vec<NamedCamera>> {
    let mut out: Vec<NamedCamera> = Vec::new();
    for c in file {
        let name = c.name.get_ref();
        if out.iter().any(|o| &o.name == name) {
            return Err(ck.err(
                &c.name.span(),
                format!("camera \"{name}\" is defined twice"),
            ));
        }
        let position = ck.finite3(&c.position, "position")?;
        let (dir, span) = match (&c.target, &c.forward) {
            (Some(t), None) => (ck.finite3(t, "target")? - position, t.span()),
            (None, Some(f)) => (ck.finite3(f, "forward")?, f.span()),
            _ => {
                return Err(ck.err(
                    &c.name.span(),
                    format!("camera \"{name}\" needs exactly one of target or forward"),
                ));
            }
        };
        if dir.length() <= 1e-6 {
            return Err(ck.err(&span, "view direction has zero length (target = position?)"));
        }
        let forward = dir.normalize();
        let up = match &c.up {
            Some(u) => {
                let v = ck.finite3(u, "up")?;
                if v.cross(forward).length() <= 1e-3 {
                    return Err(ck.err(
                        &u.span(),
                        "up must be non-zero and not parallel to the view",
                    ));
                }
                v.normalize()
            }
            None => super::camera::up_for(forward),
        };
        let fov_y_deg = match &c.fov_y {
            Some(f) if !(*f.get_ref() > 0.0 && *f.get_ref() < 180.0) => {
                return Err(ck.err(
                    &f.span(),
                    format!("fov_y = {} must lie in (0, 180) degrees", f.get_ref()),
                ));
            }
            Some(f) => *f.get_ref(),
            None => 60.0,
        };
        let near = match &c.near {
            Some(n) => ck.range(n, "near", MIN_LENGTH, 1000.0)?,
            None => super::DEFAULT_NEAR,
        };
        let cinematic_shadows = c
            .cinematic_shadows
            .as_ref()
            .map(|f| build_cinematic_shadows(ck, f))
            .transpose()?;
        out.push(NamedCamera {
            name: name.clone(),
            cinematic_shadows,
            camera: Camera {
                position,
                forward,
                up,
                fov_y_deg,
                near,
                orthographic: None,
            },
        });
    }
    Ok(out)
}

/// R3: near in [0.05, 10 km], far beyond it (the error names the key).
pub(crate) fn build_cinematic_shadows(
    ck: &Checker,
    f: &super::file::FileCinematicShadows,
) -> Result<super::CinematicShadows> {
    let near = ck.range(&f.near, "cinematic_shadows near", 0.05, 10_000.0)?;
    let far = ck.range(&f.far, "cinematic_shadows far", 0.1, MAX_EXTENT)?;
    if far <= near {
        return Err(ck.err(
            &f.far.span(),
            format!("cinematic_shadows far = {far} must be greater than near = {near}"),
        ));
    }
    Ok(super::CinematicShadows { near, far })
}

/// Meshes built so far, shared by (shape, material) key.
pub(crate) struct World<'a> {
    pub ck: &'a Checker<'a>,
    pub base_dir: &'a Path,
    pub materials: &'a [MaterialDesc],
    pub meshes: Vec<super::Mesh>,
    pub mesh_keys: HashMap<String, usize>,
    pub budget: MemoryBudget,
    /// Bytes charged to the budget by the meshes built so far.
    pub charged: u64,
    /// V3: the impostor atlas layers of the scene's trees.
    pub impostors: super::tree::impostor_level::Layers,
    /// V2: the bones of the scene's tree meshes.
    pub rigs: Vec<super::tree::rig::SceneRig>,
}

/// A validated primitive; its Debug text (with the material) keys mesh sharing.
#[derive(Debug)]
enum Shape {
    Plane {
        size: [f32; 2],
        segments: u32,
    },
    Box {
        size: [f32; 3],
    },
    Sphere {
        radius: f32,
        segments: u32,
        rings: u32,
    },
    Cylinder {
        radius: f32,
        height: f32,
        segments: u32,
    },
    Prism {
        size: [f32; 3],
        gable: usize,
    },
    Grass(vegetation::GrassParams),
    Bush(vegetation::BushParams),
}

impl Shape {
    /// Vertices and indices of the mesh (upper bounds) and the parameters
    /// that set them, for the budget.
    fn size(&self) -> (u64, u64, String) {
        let n = |x: u32| x as u64;
        match self {
            Shape::Plane { segments, .. } => (
                (n(*segments) + 1).pow(2),
                6 * n(*segments).pow(2),
                format!("with {segments} segments"),
            ),
            Shape::Sphere {
                segments, rings, ..
            } => (
                (n(*segments) + 1) * (n(*rings) + 1),
                6 * n(*segments) * n(*rings),
                format!("with {segments} segments and {rings} rings"),
            ),
            Shape::Cylinder { segments, .. } => (
                4 * (n(*segments) + 1) + 2,
                12 * n(*segments),
                format!("with {segments} segments"),
            ),
            Shape::Box { .. } | Shape::Prism { .. } => (24, 36, String::new()),
            Shape::Grass(p) => {
                let cards = p.clump_count().saturating_mul(n(p.cards));
                (4 * cards, 6 * cards, format!("with {cards} cards"))
            }
            Shape::Bush(p) => (
                4 * n(p.cards),
                6 * n(p.cards),
                format!("with {} cards", p.cards),
            ),
        }
    }
}

/// Which keys each primitive takes besides the common ones.
fn allowed_keys(primitive: &str) -> Option<&'static [&'static str]> {
    Some(match primitive {
        "plane" => &["size", "segments"],
        "box" => &["size"],
        "sphere" => &["radius", "segments", "rings"],
        "cylinder" => &["radius", "height", "segments"],
        "prism" => &["size", "gable_material"],
        "heightfield" => &[
            "size",
            "resolution",
            "noise",
            "png",
            "height_scale",
            "layers",
            "albedo_variation",
        ],
        "grass" => &[
            "size", "density", "height", "width", "seed", "cards", "sway",
        ],
        "bush" => &["radius", "size", "width", "seed", "cards", "sway"],
        "tree" => &[
            "species",
            "bark_material",
            "tint",
            "seed",
            "count",
            "size",
            "positions",
            "sway",
        ],
        _ => return None,
    })
}

impl World<'_> {
    pub fn material(&self, name: &Spanned<String>) -> Result<usize> {
        let n = name.get_ref();
        self.materials
            .iter()
            .position(|m| &m.name == n)
            .ok_or_else(|| {
                let known: Vec<&str> = self.materials.iter().map(|m| m.name.as_str()).collect();
                self.ck.err(
                    &name.span(),
                    format!("unknown material \"{n}\" (known: {})", known.join(", ")),
                )
            })
    }

    pub fn required<'o, T>(&self, o: &FileObject, v: &'o Option<T>, key: &str) -> Result<&'o T> {
        v.as_ref().ok_or_else(|| {
            self.ck.err(
                &o.name.span(),
                format!(
                    "object \"{}\": primitive {} needs `{key}`",
                    o.name.get_ref(),
                    o.primitive.get_ref()
                ),
            )
        })
    }

    fn segments(&self, v: &Option<Spanned<i64>>, key: &str, default: u32, lo: i64) -> Result<u32> {
        v.as_ref()
            .map_or(Ok(default), |s| self.ck.int(s, key, lo, 4096))
    }

    /// Charges `bytes` for `what` (an object's mesh, at `span`) against the
    /// memory budget before it is allocated.
    pub fn charge(&mut self, span: &Range<usize>, what: String, bytes: u64) -> Result<()> {
        let total = self.charged.saturating_add(bytes);
        let what = if self.charged > 0 {
            format!("{what}, with the scene's earlier meshes,")
        } else {
            what
        };
        self.budget
            .check(what, total)
            .map_err(|e| self.ck.err(span, e))?;
        self.charged = total;
        Ok(())
    }

    /// Charges a mesh of `vertices` and `indices` (see [`MemoryBudget::mesh_bytes`]).
    pub fn charge_mesh(
        &mut self,
        span: &Range<usize>,
        what: String,
        vertices: u64,
        indices: u64,
    ) -> Result<()> {
        let what = format!("{what} ({vertices} vertices, {indices} indices)");
        self.charge(span, what, MemoryBudget::mesh_bytes(vertices, indices))
    }

    /// Rejects unknown primitives and keys that do not apply to the primitive.
    pub fn check_keys(&self, o: &FileObject) -> Result<()> {
        let prim = o.primitive.get_ref().as_str();
        let Some(allowed) = allowed_keys(prim) else {
            return Err(self.ck.err(
                &o.primitive.span(),
                format!("unknown primitive \"{prim}\" (known: {PRIMITIVES})"),
            ));
        };
        match o
            .parameter_keys()
            .into_iter()
            .find(|(k, _)| !allowed.contains(k))
        {
            Some((key, span)) => Err(self.ck.err(
                &span,
                format!(
                    "`{key}` does not apply to primitive {prim} (its keys: {})",
                    allowed.join(", ")
                ),
            )),
            None => Ok(()),
        }
    }

    /// Mesh index for a non-height-field object, shared when identical.
    pub fn mesh_for(&mut self, o: &FileObject) -> Result<usize> {
        self.check_keys(o)?;
        let prim = o.primitive.get_ref().as_str();
        let material = self.material(self.required(o, &o.material, "material")?)?;
        let shape = match prim {
            "plane" => Shape::Plane {
                size: self.ck.size(self.required(o, &o.size, "size")?, prim)?,
                segments: self.segments(&o.segments, "segments", 1, 1)?,
            },
            "box" => Shape::Box {
                size: self.ck.size(self.required(o, &o.size, "size")?, prim)?,
            },
            "sphere" => {
                let segments = self.segments(&o.segments, "segments", 48, 3)?;
                Shape::Sphere {
                    radius: self
                        .ck
                        .length(self.required(o, &o.radius, "radius")?, "radius")?,
                    segments,
                    rings: self.segments(&o.rings, "rings", (segments / 2).max(2), 2)?,
                }
            }
            "cylinder" => Shape::Cylinder {
                radius: self
                    .ck
                    .length(self.required(o, &o.radius, "radius")?, "radius")?,
                height: self
                    .ck
                    .length(self.required(o, &o.height, "height")?, "height")?,
                segments: self.segments(&o.segments, "segments", 32, 3)?,
            },
            "grass" => Shape::Grass(self.grass_params(o)?),
            "bush" => Shape::Bush(self.bush_params(o)?),
            _ => Shape::Prism {
                size: self.ck.size(self.required(o, &o.size, "size")?, prim)?,
                gable: match &o.gable_material {
                    Some(g) => self.material(g)?,
                    None => material,
                },
            },
        };
        // f32 Debug output round-trips, so equal keys mean identical meshes.
        let key = format!("{shape:?} {material}");
        if let Some(&i) = self.mesh_keys.get(&key) {
            return Ok(i);
        }
        let (vertices, indices, what) = shape.size();
        let span = o.segments.as_ref().map_or(o.name.span(), |s| s.span());
        let what = format!("object \"{}\": {prim} {what}", o.name.get_ref());
        self.charge_mesh(&span, what, vertices, indices)?;
        let m = &self.materials[material];
        let name = format!("{prim}/{}/{}", m.name, self.meshes.len());
        let mesh = match shape {
            Shape::Plane { size, segments } => primitives::plane(name, size, [segments; 2], m),
            Shape::Box { size } => primitives::cuboid(name, Vec3::from(size), m),
            Shape::Sphere {
                radius,
                segments,
                rings,
            } => primitives::uv_sphere(name, radius, segments, rings, m),
            Shape::Cylinder {
                radius,
                height,
                segments,
            } => primitives::cylinder(name, radius, height, segments, m),
            Shape::Prism { size, gable } => {
                primitives::prism(name, Vec3::from(size), m, &self.materials[gable])
            }
            Shape::Grass(p) => vegetation::grass(name, &p, m, |_, _| Some(0.0)).map_err(|_| {
                SceneError::Invalid {
                    file: self.ck.src.origin.to_string(),
                    message: "grass on a plane cannot fail".into(),
                }
            })?,
            Shape::Bush(p) => vegetation::bush(name, &p, m),
        };
        self.meshes.push(mesh);
        self.mesh_keys.insert(key, self.meshes.len() - 1);
        Ok(self.meshes.len() - 1)
    }

    /// Height field mesh and grid.
    pub fn heightfield(&mut self, o: &FileObject) -> Result<(usize, heightfield::HeightGrid)> {
        self.check_keys(o)?;
        let (grid, seed, layers, variation) = super::terrain::build(self, o)?;
        let name = format!("heightfield/{}", o.name.get_ref());
        let mesh = grid.mesh(name, &layers, seed, variation);
        self.meshes.push(mesh);
        Ok((self.meshes.len() - 1, grid))
    }
}

/// Local-to-world rotation from Euler degrees [x, y, z]: R = Ry * Rx * Rz.
pub(crate) fn rotation_from_euler_deg(r: [f32; 3]) -> Quat {
    Quat::from_euler(
        EulerRot::YXZ,
        r[1].to_radians(),
        r[0].to_radians(),
        r[2].to_radians(),
    )
}

/// Translation * rotation * scale.
pub(crate) fn trs(t: Vec3, r: Quat, s: Vec3) -> Mat4 {
    Mat4::from_scale_rotation_translation(s, r, t)
}
