//! `[[gltf]]` entries of scene files: a glTF model loaded, placed by a
//! scene transform (`translation`, `rotation`, `scale`) on top of its own
//! node hierarchy, and merged into the scene's meshes, objects, textured
//! materials and local lights. Errors point at the entry's line and name
//! the glTF file and its problem. See docs/gltf.md.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};

use super::{GltfAsset, PbrSet, TextureRef};
use crate::scene::build::{Checker, trs};
use crate::scene::file::{FileGltf, GltfRotation};
use crate::scene::{LightDesc, Mesh, Motion, Object, SceneError};

/// What the scene file's `[[gltf]]` entries add to the scene.
#[derive(Default)]
pub(crate) struct Placed {
    pub objects: Vec<Object>,
    pub pbr: PbrSet,
    pub lights: Vec<LightDesc>,
}

/// Scene transform of one entry: T · R · S with R from degrees about +Y or
/// a quaternion `[x, y, z, w]` (normalised; must not be zero).
fn entry_transform(ck: &Checker, g: &FileGltf) -> Result<Mat4, SceneError> {
    let t = ck.finite3_or(&g.translation, "translation", Vec3::ZERO)?;
    let r = match &g.rotation {
        None => Quat::IDENTITY,
        Some(r) => match r.get_ref() {
            GltfRotation::Yaw(deg) if deg.is_finite() => Quat::from_rotation_y(deg.to_radians()),
            GltfRotation::Quaternion(q)
                if q.iter().all(|c| c.is_finite()) && Quat::from_array(*q).length() > 1e-6 =>
            {
                Quat::from_array(*q).normalize()
            }
            _ => {
                return Err(ck.err(
                    &r.span(),
                    "rotation must be finite degrees about +Y or a non-zero quaternion [x, y, z, w]",
                ));
            }
        },
    };
    let s = match &g.scale {
        None => Vec3::ONE,
        Some(s) => {
            let v = Vec3::from(s.get_ref().0);
            let max = crate::scene::build::MAX_SCALE;
            if !v.to_array().iter().all(|c| (1.0 / max..=max).contains(c)) {
                return Err(ck.err(
                    &s.span(),
                    format!("scale {v} must lie in [{}, {max}] on each axis", 1.0 / max),
                ));
            }
            v
        }
    };
    Ok(trs(t, r, s))
}

/// Loads and places every `[[gltf]]` entry; their meshes are appended to
/// `meshes` (object mesh indices and the PBR set's mesh indices follow).
pub(crate) fn place_all(
    ck: &Checker,
    base_dir: &Path,
    entries: &[FileGltf],
    meshes: &mut Vec<Mesh>,
    placed_objects: &[Object],
    budget: crate::budget::MemoryBudget,
) -> Result<Placed, SceneError> {
    let mut out = Placed::default();
    for (k, g) in entries.iter().enumerate() {
        let file = g.file.get_ref();
        let builtin = file.strip_prefix(crate::scene::builtin::PREFIX);
        let path = match builtin {
            Some(_) => std::path::PathBuf::from(file),
            None => base_dir.join(file),
        };
        if builtin.is_none() && g.optional == Some(true) && !path.exists() {
            log::warn!(
                "{}: optional glTF \"{}\" not found, skipped",
                ck.src.origin,
                path.display()
            );
            continue;
        }
        let mut transform = entry_transform(ck, g)?;
        let asset = crate::scene::builtin::load_gltf(&path, budget, None).map_err(|e| {
            ck.err(
                &g.file.span(),
                format!("glTF \"{}\": {e}", g.file.get_ref()),
            )
        })?;
        if let Some(support) = &g.rest_on {
            let name = support.get_ref();
            let Some(o) = placed_objects.iter().find(|o| &o.name == name) else {
                return Err(ck.err(
                    &support.span(),
                    format!("rest_on: no earlier object \"{name}\""),
                ));
            };
            let top = meshes[o.mesh].bounds.transform(&o.transform).max.y;
            let bottom = asset.bounds.transform(&transform).min.y;
            // The lowest point goes to the support's top plus translation.y
            // (already in `transform`, so in `bottom`).
            let lift = top + transform.w_axis.y - bottom;
            transform = Mat4::from_translation(Vec3::Y * lift) * transform;
        }
        let prefix = g
            .name
            .as_ref()
            .map_or_else(|| format!("gltf{k}"), |n| n.get_ref().clone());
        let mut asset = asset;
        if let Some(name) = &g.animation {
            play(ck, &mut asset, name)?;
        }
        let orbit = match &g.orbit {
            Some(o) => Some(crate::scene::place::orbit(ck, o).map(|mut o| {
                o.centre = transform.w_axis.truncate();
                o
            })?),
            None => None,
        };
        merge(&mut out, meshes, asset, transform, orbit, &prefix);
    }
    Ok(out)
}

/// The entry's `animation`: the clip every animated object of `asset`
/// plays, or `"none"` for the rest pose; an unknown name lists the file's.
fn play(
    ck: &Checker,
    asset: &mut GltfAsset,
    name: &toml::Spanned<String>,
) -> Result<(), SceneError> {
    let wanted = (name.get_ref() != "none").then(|| name.get_ref().as_str());
    let mut clips: Vec<String> = Vec::new();
    for o in &mut asset.objects {
        let Some(a) = o.motion.as_mut().and_then(|m| m.animated.as_mut()) else {
            continue;
        };
        for c in &a.rig.clips {
            if !clips.contains(&c.name) {
                clips.push(c.name.clone());
            }
        }
        a.play(wanted);
        o.transform = o.transform_at(0.0);
    }
    match wanted {
        Some(w) if !clips.iter().any(|c| c == w) => Err(ck.err(
            &name.span(),
            format!(
                "animation \"{w}\": {} has {}",
                asset.path.display(),
                if clips.is_empty() {
                    "no animations".to_string()
                } else {
                    clips.join(", ")
                }
            ),
        )),
        _ => Ok(()),
    }
}

/// Appends `asset` under `transform` (moving along `orbit` if given),
/// renumbering meshes, materials, textures and images.
fn merge(
    out: &mut Placed,
    meshes: &mut Vec<Mesh>,
    asset: GltfAsset,
    transform: Mat4,
    orbit: Option<crate::scene::Orbit>,
    prefix: &str,
) {
    let mesh_base = meshes.len();
    let (material_base, texture_base, image_base) = (
        out.pbr.materials.len(),
        out.pbr.textures.len(),
        out.pbr.images.len(),
    );
    let shift = |r: &mut Option<TextureRef>| {
        if let Some(r) = r {
            r.texture += texture_base;
        }
    };
    for mut m in asset.pbr.materials {
        for slot in [
            &mut m.base_color_texture,
            &mut m.metallic_roughness_texture,
            &mut m.normal_texture,
            &mut m.occlusion_texture,
            &mut m.emissive_texture,
            &mut m.anisotropy_texture,
        ] {
            shift(slot);
        }
        out.pbr.materials.push(m);
    }
    out.pbr
        .textures
        .extend(asset.pbr.textures.into_iter().map(|mut t| {
            t.image += image_base;
            t
        }));
    out.pbr.images.extend(asset.pbr.images);
    out.pbr.mesh_material.extend(
        asset
            .pbr
            .mesh_material
            .iter()
            .map(|(m, mat)| (m + mesh_base, mat + material_base)),
    );
    meshes.extend(asset.meshes);
    out.objects.extend(asset.objects.into_iter().map(|o| {
        // The entry's transform (and path) before the file's own motion.
        let motion = match o.motion {
            Some(m) => Some(Motion {
                orbit,
                base: transform * m.base,
                ..m
            }),
            None => orbit.map(|orbit| Motion::orbit(orbit, transform * o.transform)),
        };
        let mut object = Object {
            name: format!("{prefix}/{}", o.name),
            mesh: o.mesh + mesh_base,
            transform: transform * o.transform,
            motion,
            foliage: None,
            ground: false,
        };
        object.transform = object.transform_at(0.0);
        object
    }));
    let directional: Vec<&str> = (asset.lights.iter())
        .filter(|l| l.kind == super::LightKind::Directional)
        .map(|l| l.name.as_str())
        .collect();
    if !directional.is_empty() {
        log::warn!(
            "{}: the scene's [sun] lights it; its directional lights are not drawn: {}",
            asset.path.display(),
            directional.join(", ")
        );
    }
    out.lights.extend(asset.lights.iter().filter_map(|l| {
        let mut l = super::local_light(l)?;
        l.name = format!("{prefix}/{}", l.name);
        l.position = transform.transform_point3(l.position);
        l.direction = transform
            .transform_vector3(l.direction)
            .normalize_or(l.direction);
        Some(l)
    }));
}
