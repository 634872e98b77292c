//! Object placement: transforms, `repeat`, `snap_to_ground` and `rest_on`.

use std::collections::HashMap;

use glam::{Mat4, Vec3};

use super::build::{World, rotation_from_euler_deg, trs};
use super::file::FileObject;
use super::file::FileOrbit;
use super::heightfield::HeightGrid;
use super::{Aabb, Motion, Object, Orbit, SceneError};

type Result<T> = std::result::Result<T, SceneError>;

/// Footprint samples per side for `snap_to_ground`.
const FOOTPRINT_SAMPLES: usize = 5;
/// Points along an orbit where `snap_to_ground` samples the ground.
const PATH_SAMPLES: usize = 16;

/// A placed height field that objects can be snapped onto.
struct Ground {
    grid: HeightGrid,
    transform: Mat4,
    inverse: Mat4,
}

impl Ground {
    /// World height of the terrain surface at world (x, z); height fields
    /// are only yawed, so local y never mixes into x and z.
    fn height(&self, x: f32, z: f32) -> Option<f32> {
        let local = self.inverse.transform_point3(Vec3::new(x, 0.0, z));
        let h = self.grid.height_at(local.x, local.z)?;
        Some(
            self.transform
                .transform_point3(Vec3::new(local.x, h, local.z))
                .y,
        )
    }
}

pub(crate) struct Placer;

impl Placer {
    pub fn place_all(world: &mut World, objects: &[FileObject]) -> Result<Vec<Object>> {
        let ck = world.ck;
        let mut seen: HashMap<&str, ()> = HashMap::new();
        for o in objects {
            if seen.insert(o.name.get_ref(), ()).is_some() {
                return Err(ck.err(
                    &o.name.span(),
                    format!("object \"{}\" is defined twice", o.name.get_ref()),
                ));
            }
        }
        // Height fields first: snapping needs every ground, wherever it is listed.
        let mut grounds = Vec::new();
        let mut terrain_objects: HashMap<usize, (usize, Mat4)> = HashMap::new();
        for (i, o) in objects.iter().enumerate() {
            if o.primitive.get_ref() != "heightfield" {
                continue;
            }
            for (key, span) in [
                (
                    "snap_to_ground",
                    o.snap_to_ground.as_ref().map(|s| s.span()),
                ),
                ("rest_on", o.rest_on.as_ref().map(|s| s.span())),
                ("repeat", o.repeat.as_ref().map(|s| s.span())),
                ("orbit", o.orbit.as_ref().map(|s| s.span())),
            ] {
                if let Some(span) = span {
                    return Err(ck.err(&span, format!("`{key}` does not apply to a height field")));
                }
            }
            let rotation = ck
                .finite3_or(&o.rotation, "rotation", Vec3::ZERO)?
                .to_array();
            if rotation[0] != 0.0 || rotation[2] != 0.0 {
                let span = o.rotation.as_ref().map(|r| r.span()).unwrap_or_default();
                return Err(ck.err(
                    &span,
                    "a height field may only be rotated about Y: [0, yaw, 0]",
                ));
            }
            let transform = trs(
                ck.finite3_or(&o.position, "position", Vec3::ZERO)?,
                rotation_from_euler_deg(rotation),
                scale(world, o)?,
            );
            let (mesh, grid) = world.heightfield(o)?;
            grounds.push(Ground {
                grid,
                transform,
                inverse: transform.inverse(),
            });
            terrain_objects.insert(i, (mesh, transform));
        }

        let mut out = Vec::new();
        let mut placed: HashMap<&str, Aabb> = HashMap::new();
        for (i, o) in objects.iter().enumerate() {
            let name = o.name.get_ref().as_str();
            if let Some(&(mesh, transform)) = terrain_objects.get(&i) {
                placed.insert(name, world.meshes[mesh].bounds.transform(&transform));
                out.push(Object {
                    name: name.to_string(),
                    mesh,
                    transform,
                    motion: None,
                    foliage: None,
                    ground: true,
                });
                continue;
            }
            let prim = o.primitive.get_ref().as_str();
            if prim == "tree" {
                let bounds = place_trees(world, o, &grounds, &mut out)?;
                placed.insert(name, bounds);
                continue;
            }
            let orbit = match &o.orbit {
                Some(r) if prim == "grass" || prim == "bush" => {
                    return Err(ck.err(&r.span(), format!("`orbit` does not apply to {prim}")));
                }
                Some(r) => Some(orbit(world.ck, r)?),
                None => None,
            };
            let snap = o.snap_to_ground.as_ref().filter(|s| *s.get_ref());
            // Snapped grass gets a mesh per copy (below); the rest share one.
            let (mesh, foliage, local) = if prim == "grass" && snap.is_some() {
                world.check_keys(o)?;
                (usize::MAX, None, Aabb::EMPTY)
            } else {
                let mesh = world.mesh_for(o)?;
                (mesh, world.foliage(o, mesh)?, world.meshes[mesh].bounds)
            };
            let rotation = rotation_from_euler_deg(
                ck.finite3_or(&o.rotation, "rotation", Vec3::ZERO)?
                    .to_array(),
            );
            let scale = scale(world, o)?;
            let position = ck.finite3_or(&o.position, "position", Vec3::ZERO)?;
            let (count, step) = match &o.repeat {
                Some(r) => (
                    ck.int(&r.get_ref().count, "count", 1, 10_000)?,
                    ck.finite3(&r.get_ref().step, "step")?,
                ),
                None => (1, Vec3::ZERO),
            };
            if let (Some(_), Some(r)) = (snap, &o.rest_on) {
                return Err(ck.err(&r.span(), "use snap_to_ground or rest_on, not both"));
            }
            let support_top = match &o.rest_on {
                Some(r) => Some(
                    placed
                        .get(r.get_ref().as_str())
                        .ok_or_else(|| {
                            ck.err(
                                &r.span(),
                                format!(
                                    "rest_on \"{}\": no object of that name before this one",
                                    r.get_ref()
                                ),
                            )
                        })?
                        .max
                        .y,
                ),
                None => None,
            };
            // Rotation and scale only: where the lowest point and the footprint lie.
            let rs = trs(Vec3::ZERO, rotation, scale);
            let lowest = local.transform(&rs).min.y;
            let mut bounds = Aabb::EMPTY;
            for k in 0..count {
                let base = position + rotation * (step * k as f32);
                let copy_name = if count > 1 {
                    format!("{name}#{k}")
                } else {
                    name.to_string()
                };
                if let (Some(snap), "grass") = (snap, prim) {
                    // Each clump's root on the ground below it, `position.y` above.
                    let transform = trs(base, rotation, scale);
                    let up = transform.y_axis.y;
                    let suffix = if count > 1 {
                        format!("#{k}")
                    } else {
                        String::new()
                    };
                    let grass = world.snapped_grass(o, &suffix, |x, z| {
                        let w = transform.transform_point3(Vec3::new(x, 0.0, z));
                        let h = grounds.iter().find_map(|g| g.height(w.x, w.z))?;
                        (up.abs() > 1e-6).then(|| (h + base.y - w.y) / up)
                    })?;
                    let mesh = grass.map_err(|p| {
                        let w = transform.transform_point3(Vec3::new(p.x, 0.0, p.y));
                        ck.err(
                            &snap.span(),
                            format!(
                                "object \"{name}\": grass at ({:.1}, {:.1}) is not over any height field",
                                w.x, w.z
                            ),
                        )
                    })?;
                    bounds = bounds.union(&world.meshes[mesh].bounds.transform(&transform));
                    out.push(Object {
                        name: copy_name,
                        mesh,
                        transform,
                        motion: None,
                        foliage: world.foliage(o, mesh)?,
                        ground: false,
                    });
                    continue;
                }
                // A moving object rests on the lowest ground along its path.
                let path: Vec<Vec3> = match &orbit {
                    Some(orbit) => (0..PATH_SAMPLES)
                        .map(|i| {
                            let a = i as f32 * std::f32::consts::TAU / PATH_SAMPLES as f32;
                            base + Vec3::new(a.cos(), 0.0, -a.sin()) * orbit.radius
                        })
                        .collect(),
                    None => vec![base],
                };
                let y = if let Some(snap) = snap {
                    let ground = path
                        .iter()
                        .map(|&p| footprint_ground(&grounds, &local, &rs, p))
                        .try_fold(f32::INFINITY, |lo, h| h.map(|h| lo.min(h)))
                        .ok_or_else(|| {
                            ck.err(
                            &snap.span(),
                            format!(
                                "object \"{name}\" at ({:.1}, {:.1}) is not over any height field",
                                base.x, base.z
                            ),
                        )
                        })?;
                    ground - lowest + base.y
                } else if let Some(top) = support_top {
                    top - lowest + base.y
                } else {
                    base.y
                };
                let mut transform = trs(Vec3::new(base.x, y, base.z), rotation, scale);
                let motion = orbit.map(|mut orbit| {
                    orbit.centre = Vec3::new(base.x, y, base.z);
                    Motion::orbit(orbit, transform)
                });
                if let Some(m) = &motion {
                    transform = m.transform_at(0.0);
                }
                let object = Object {
                    name: copy_name,
                    mesh,
                    transform,
                    motion,
                    foliage,
                    ground: prim == "plane",
                };
                bounds = bounds.union(&object.swept_bounds(&local));
                out.push(object);
            }
            placed.insert(name, bounds);
        }
        Ok(out)
    }
}

/// How far a snapped tree's trunk sinks below the ground at its centre (m):
/// on a slope its uphill side stays buried.
const TREE_SINK: f32 = 0.15;

/// Places a `tree` object's trees (V1): per tree a trunk object
/// (`name#k/trunk`, opaque) and a leaves object (`name#k/leaves`,
/// alpha-tested), yawed and scaled (0.85..1.15) at random from the seed;
/// snapped trees stand on the ground under their trunk. Returns their bounds.
fn place_trees(
    world: &mut World,
    o: &FileObject,
    grounds: &[Ground],
    out: &mut Vec<Object>,
) -> Result<Aabb> {
    let ck = world.ck;
    let name = o.name.get_ref();
    for (key, span) in [
        ("orbit", o.orbit.as_ref().map(|s| s.span())),
        ("rest_on", o.rest_on.as_ref().map(|s| s.span())),
        ("repeat", o.repeat.as_ref().map(|s| s.span())),
    ] {
        if let Some(span) = span {
            return Err(ck.err(
                &span,
                format!("`{key}` does not apply to trees (use count and size, or positions)"),
            ));
        }
    }
    world.check_keys(o)?;
    let (trunk, leaves) = world.tree_meshes(o)?;
    let foliage = world.foliage(o, leaves)?;
    let rotation = rotation_from_euler_deg(
        ck.finite3_or(&o.rotation, "rotation", Vec3::ZERO)?
            .to_array(),
    );
    let scale = scale(world, o)?;
    let position = ck.finite3_or(&o.position, "position", Vec3::ZERO)?;
    let bases = world.tree_bases(o, position)?;
    let snap = o.snap_to_ground.as_ref().filter(|s| *s.get_ref());
    let seed = o.seed.as_ref().map_or(0, |s| *s.get_ref() as u32);
    let local = world.meshes[trunk]
        .bounds
        .union(&world.meshes[leaves].bounds);
    let mut bounds = Aabb::EMPTY;
    for (k, base) in bases.iter().enumerate() {
        let mut rng = super::vegetation::Rng::new(seed, k as i32 + 1);
        let yaw = glam::Quat::from_rotation_y(rng.next() * std::f32::consts::TAU);
        let size = 0.85 + 0.3 * rng.next();
        let y = match snap {
            Some(snap) => {
                let ground = grounds.iter().find_map(|g| g.height(base.x, base.z));
                let ground = ground.ok_or_else(|| {
                    ck.err(
                        &snap.span(),
                        format!(
                            "object \"{name}\": tree at ({:.1}, {:.1}) is not over any height field",
                            base.x, base.z
                        ),
                    )
                })?;
                ground - TREE_SINK + base.y
            }
            None => base.y,
        };
        let transform = trs(Vec3::new(base.x, y, base.z), yaw * rotation, scale * size);
        let copy = if bases.len() > 1 {
            format!("{name}#{k}")
        } else {
            name.to_string()
        };
        for (part, mesh, foliage) in [("trunk", trunk, None), ("leaves", leaves, foliage)] {
            out.push(Object {
                name: format!("{copy}/{part}"),
                mesh,
                transform,
                motion: None,
                foliage,
                ground: false,
            });
        }
        bounds = bounds.union(&local.transform(&transform));
    }
    Ok(bounds)
}

/// Checked `orbit = { radius, period, phase, turn }`; the centre is set at placement.
/// An `orbit = { radius, period, phase, turn }` table (centre left at 0).
pub(crate) fn orbit(ck: &super::build::Checker, o: &toml::Spanned<FileOrbit>) -> Result<Orbit> {
    let f = o.get_ref();
    let period = *f.period.get_ref();
    if !(period.is_finite() && period != 0.0) {
        return Err(ck.err(
            &f.period.span(),
            format!("orbit period = {period} must be a non-zero number of seconds"),
        ));
    }
    let phase = match &f.phase {
        Some(p) if !p.get_ref().is_finite() => {
            return Err(ck.err(&p.span(), "orbit phase must be finite (degrees)"));
        }
        Some(p) => p.get_ref().to_radians(),
        None => 0.0,
    };
    Ok(Orbit {
        centre: Vec3::ZERO,
        radius: ck.positive(&f.radius, "orbit radius")?,
        period,
        phase,
        turn: f.turn.unwrap_or(false),
    })
}

fn scale(world: &World, o: &FileObject) -> Result<Vec3> {
    match &o.scale {
        None => Ok(Vec3::ONE),
        Some(s) => {
            let v = s.get_ref().0;
            let max = super::build::MAX_SCALE;
            if v.iter().all(|c| (1.0 / max..=max).contains(c)) {
                Ok(Vec3::from(v))
            } else {
                Err(world.ck.err(
                    &s.span(),
                    format!(
                        "scale {v:?} must lie in [{}, {max}] on each axis",
                        1.0 / max
                    ),
                ))
            }
        }
    }
}

/// Lowest terrain height under the object's bottom face: the face of the
/// `local` bounds whose normal `rs` turns most downward (exact for yaw-only
/// objects and for boxes lying on a side), sampled on a 5 x 5 grid moved
/// to `base`; `None` where a sample is over no height field.
fn footprint_ground(grounds: &[Ground], local: &Aabb, rs: &Mat4, base: Vec3) -> Option<f32> {
    let (axis, min_side) = (0..3)
        .flat_map(|a| [(a, true), (a, false)])
        .min_by(|x, y| {
            let down = |&(a, min_side): &(usize, bool)| {
                let n = Vec3::AXES[a] * if min_side { -1.0 } else { 1.0 };
                rs.transform_vector3(n).y
            };
            down(x).total_cmp(&down(y))
        })?;
    let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
    let n = FOOTPRINT_SAMPLES;
    let mut lowest = f32::INFINITY;
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            let mut p = Vec3::ZERO;
            p[axis] = if min_side {
                local.min[axis]
            } else {
                local.max[axis]
            };
            p[u_axis] = local.min[u_axis] + u * (local.max[u_axis] - local.min[u_axis]);
            p[v_axis] = local.min[v_axis] + v * (local.max[v_axis] - local.min[v_axis]);
            let w = rs.transform_point3(p) + base;
            let h = grounds.iter().find_map(|g| g.height(w.x, w.z))?;
            lowest = lowest.min(h);
        }
    }
    Some(lowest)
}
