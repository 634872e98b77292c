//! `EXT_mesh_gpu_instancing`: a node's mesh drawn once per instance, each
//! with its own TRANSLATION / ROTATION / SCALE (applied before the node's
//! own transform). Every instance becomes an [`Object`] of the same mesh,
//! so the renderer's instancing (V6) draws them together.
//!
//! [`Object`]: crate::scene::Object

use glam::{Mat4, Quat, Vec3};

use super::GltfContext;
use crate::scene::SceneError;

/// The instance transforms of `node` (local to the node), or `None` when it
/// has no `EXT_mesh_gpu_instancing`.
pub(super) fn node_instances(
    cx: &GltfContext,
    doc: &gltf::Document,
    node: &gltf::Node,
    buffers: &[Vec<u8>],
) -> Result<Option<Vec<Mat4>>, SceneError> {
    let Some(ext) = node
        .extensions()
        .and_then(|e| e.get("EXT_mesh_gpu_instancing"))
    else {
        return Ok(None);
    };
    let at = |what: &str| {
        format!(
            "nodes[{}].extensions.EXT_mesh_gpu_instancing{what}",
            node.index()
        )
    };
    let attributes = ext
        .get("attributes")
        .and_then(|a| a.as_object())
        .ok_or_else(|| cx.invalid(format!("{} has no attributes object", at(""))))?;
    let accessor = |name: &str| -> Result<Option<gltf::Accessor>, SceneError> {
        let Some(v) = attributes.get(name) else {
            return Ok(None);
        };
        let index = v.as_u64().ok_or_else(|| {
            cx.invalid(format!(
                "{}: not an accessor index",
                at(&format!(".attributes.{name}"))
            ))
        })?;
        doc.accessors()
            .nth(index as usize)
            .map(Some)
            .ok_or_else(|| {
                cx.invalid(format!(
                    "{}: no accessor {index}",
                    at(&format!(".attributes.{name}"))
                ))
            })
    };
    let (t, r, s) = (
        accessor("TRANSLATION")?,
        accessor("ROTATION")?,
        accessor("SCALE")?,
    );
    let count = match [&t, &r, &s]
        .into_iter()
        .flatten()
        .map(|a| a.count())
        .collect::<Vec<_>>()[..]
    {
        [] => {
            return Err(cx.invalid(format!(
                "{}: none of TRANSLATION, ROTATION, SCALE",
                at(".attributes")
            )));
        }
        [first, ref rest @ ..] => {
            if rest.iter().any(|&c| c != first) {
                return Err(cx.invalid(format!(
                    "{}: the attributes' counts differ",
                    at(".attributes")
                )));
            }
            first
        }
    };
    let data = |b: gltf::Buffer| buffers.get(b.index()).map(Vec::as_slice);
    let translations = match &t {
        Some(a) => vec3s(cx, a, &at(".attributes.TRANSLATION"), data)?,
        None => vec![Vec3::ZERO; count],
    };
    let scales = match &s {
        Some(a) => vec3s(cx, a, &at(".attributes.SCALE"), data)?,
        None => vec![Vec3::ONE; count],
    };
    let rotations = match &r {
        Some(a) => quats(cx, a, &at(".attributes.ROTATION"), data)?,
        None => vec![Quat::IDENTITY; count],
    };
    Ok(Some(
        (0..count)
            .map(|i| {
                Mat4::from_scale_rotation_translation(scales[i], rotations[i], translations[i])
            })
            .collect(),
    ))
}

fn vec3s<'a>(
    cx: &GltfContext,
    a: &gltf::Accessor<'a>,
    what: &str,
    data: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> Result<Vec<Vec3>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    if (a.data_type(), a.dimensions()) != (DataType::F32, Dimensions::Vec3) {
        return Err(cx.invalid(format!("{what}: must be VEC3 of FLOAT")));
    }
    let v: Vec<Vec3> = super::buffers::read_floats::<3>(a, data)
        .ok_or_else(|| cx.invalid(format!("{what}: cannot be read")))?
        .into_iter()
        .map(Vec3::from)
        .collect();
    if v.iter().any(|v| !v.is_finite()) {
        return Err(cx.invalid(format!("{what}: non-finite values")));
    }
    Ok(v)
}

/// Unit quaternions: FLOAT, or normalized BYTE / SHORT (glTF's rotation types).
fn quats<'a>(
    cx: &GltfContext,
    a: &gltf::Accessor<'a>,
    what: &str,
    data: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> Result<Vec<Quat>, SceneError> {
    use gltf::accessor::{DataType, Dimensions};
    if a.dimensions() != Dimensions::Vec4 {
        return Err(cx.invalid(format!("{what}: must be VEC4")));
    }
    let rotation_type = matches!(
        (a.data_type(), a.normalized()),
        (DataType::F32, _) | (DataType::I16, true) | (DataType::I8, true)
    );
    if !rotation_type {
        return Err(cx.invalid(format!("{what}: must be FLOAT or normalized BYTE / SHORT")));
    }
    let raw = super::buffers::read_floats::<4>(a, data)
        .ok_or_else(|| cx.invalid(format!("{what}: cannot be read")))?;
    raw.into_iter()
        .map(|q| {
            let q = Quat::from_array(q);
            let len = q.length();
            if !(len.is_finite() && (0.9..=1.1).contains(&len)) {
                return Err(cx.invalid(format!("{what}: {q} is not a unit quaternion")));
            }
            Ok(q / len)
        })
        .collect()
}
