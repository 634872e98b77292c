//! The bytes behind a glTF file: data and file URIs, buffer views and
//! accessor bounds, checked before the gltf crate's readers see them.

use std::path::PathBuf;

use super::MAX_ELEMENTS;
use super::material;
use crate::scene::SceneError;

/// The file being loaded, for messages and relative URIs.
pub(crate) struct GltfContext {
    pub(super) path: PathBuf,
}

impl GltfContext {
    pub(super) fn invalid(&self, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.path.display().to_string(),
            message: message.into(),
        }
    }

    /// Bytes of a URI: a `data:` URI (base64) or a file beside the model.
    pub(super) fn read_uri(&self, uri: &str) -> Result<Vec<u8>, SceneError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest
                .split_once(";base64,")
                .ok_or_else(|| self.invalid("data URI is not base64"))?;
            return base64_decode(data).ok_or_else(|| self.invalid("data URI: bad base64"));
        }
        let relative = percent_decode(uri);
        if relative.contains("://") {
            return Err(self.invalid(format!("URI \"{uri}\": only files and data URIs are read")));
        }
        let file = material::base_dir(&self.path).join(&relative);
        std::fs::read(&file)
            .map_err(|e| self.invalid(format!("cannot read \"{}\": {e}", file.display())))
    }
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((h * 16 + l) as u8);
            i += 3;
            continue;
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| match c {
        b'A'..=b'Z' => Some(c - b'A'),
        b'a'..=b'z' => Some(c - b'a' + 26),
        b'0'..=b'9' => Some(c - b'0' + 52),
        b'+' | b'-' => Some(62),
        b'/' | b'_' => Some(63),
        _ => None,
    };
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in s.bytes().filter(|c| !c.is_ascii_whitespace()) {
        if c == b'=' {
            break;
        }
        acc = (acc << 6) | value(c)? as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    Some(out)
}

/// Bytes of a buffer view, range-checked.
pub(super) fn view_bytes<'b>(
    cx: &GltfContext,
    view: &gltf::buffer::View,
    buffers: &'b [Vec<u8>],
) -> Result<&'b [u8], SceneError> {
    let data = &buffers[view.buffer().index()];
    data.get(view.offset()..view.offset().saturating_add(view.length()))
        .ok_or_else(|| {
            cx.invalid(format!(
                "buffer view {} (bytes {}..+{}) is outside buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                data.len()
            ))
        })
}

/// Checks that every accessor's elements lie inside its buffer view, so
/// the gltf crate's readers never run off the data.
pub(super) fn check_accessors(
    cx: &GltfContext,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<(), SceneError> {
    for a in doc.accessors() {
        let elem = a.size();
        if a.count() == 0 || a.count() > MAX_ELEMENTS {
            return Err(cx.invalid(format!("accessor {} has count {}", a.index(), a.count())));
        }
        if let Some(sparse) = a.sparse()
            && !(1..=a.count()).contains(&sparse.count())
        {
            return Err(cx.invalid(format!(
                "accessors[{}].sparse.count is {}; it must be 1..={} (the accessor's count)",
                a.index(),
                sparse.count(),
                a.count()
            )));
        }
        let Some(view) = a.view() else { continue };
        let bytes = view_bytes(cx, &view, buffers)?;
        if let Some(stride) = view.stride()
            && stride < elem
        {
            return Err(cx.invalid(format!(
                "accessors[{}]: byte stride {stride} of buffer view {} is smaller than its {elem}-byte element",
                a.index(),
                view.index()
            )));
        }
        let stride = view.stride().unwrap_or(elem);
        let end = (a.count() - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(a.offset()))
            .and_then(|x| x.checked_add(elem));
        if end.is_none_or(|e| e > bytes.len()) {
            return Err(cx.invalid(format!(
                "accessor {} ({} elements of {elem} bytes, stride {stride}, offset {}) runs past buffer view {} ({} bytes)",
                a.index(),
                a.count(),
                a.offset(),
                view.index(),
                bytes.len()
            )));
        }
    }
    Ok(())
}

/// Every primitive's POSITION names an existing accessor.
pub(super) fn check_position_accessors(
    cx: &GltfContext,
    root: &gltf::json::Root,
) -> Result<(), SceneError> {
    use gltf::json::mesh::Semantic;
    use gltf::json::validation::Checked;
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(a) = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
                && a.value() >= root.accessors.len()
            {
                return Err(cx.invalid(format!(
                    "mesh {m} primitive {p}: POSITION accessor {} does not exist ({} accessors)",
                    a.value(),
                    root.accessors.len()
                )));
            }
        }
    }
    Ok(())
}

/// What a vertex attribute or index accessor may be (glTF 2.0 3.7.2.1 and
/// 3.7.2.2): element types and (component type, normalized) pairs.
struct Allowed {
    dims: &'static [gltf::accessor::Dimensions],
    components: &'static [(gltf::accessor::DataType, bool)],
    text: &'static str,
}

/// What `semantic` may be stored as; `quantized`: the file uses
/// KHR_mesh_quantization (integer positions, normals, tangents, UVs).
fn allowed(semantic: Option<&gltf::Semantic>, quantized: bool) -> Option<Allowed> {
    use gltf::Semantic as S;
    use gltf::accessor::DataType as T;
    use gltf::accessor::Dimensions as D;
    const FLOAT: &[(T, bool)] = &[(T::F32, false)];
    const UNIT: &[(T, bool)] = &[(T::F32, false), (T::U8, true), (T::U16, true)];
    // KHR_mesh_quantization's table (positions and UVs: any 8 or 16 bit).
    const Q_ANY: &[(T, bool)] = &[
        (T::F32, false),
        (T::I8, false),
        (T::I8, true),
        (T::U8, false),
        (T::U8, true),
        (T::I16, false),
        (T::I16, true),
        (T::U16, false),
        (T::U16, true),
    ];
    const Q_DIRECTION: &[(T, bool)] = &[(T::F32, false), (T::I8, true), (T::I16, true)];
    if quantized {
        match semantic {
            Some(S::Positions) => {
                return Some(Allowed {
                    dims: &[D::Vec3],
                    components: Q_ANY,
                    text: "VEC3 of FLOAT or (KHR_mesh_quantization) BYTE / SHORT, signed or not, normalized or not",
                });
            }
            Some(S::Normals) => {
                return Some(Allowed {
                    dims: &[D::Vec3],
                    components: Q_DIRECTION,
                    text: "VEC3 of FLOAT or (KHR_mesh_quantization) normalized BYTE / SHORT",
                });
            }
            Some(S::Tangents) => {
                return Some(Allowed {
                    dims: &[D::Vec4],
                    components: Q_DIRECTION,
                    text: "VEC4 of FLOAT or (KHR_mesh_quantization) normalized BYTE / SHORT",
                });
            }
            Some(S::TexCoords(_)) => {
                return Some(Allowed {
                    dims: &[D::Vec2],
                    components: Q_ANY,
                    text: "VEC2 of FLOAT or (KHR_mesh_quantization) BYTE / SHORT, signed or not, normalized or not",
                });
            }
            _ => {}
        }
    }
    Some(match semantic {
        None => Allowed {
            dims: &[D::Scalar],
            components: &[(T::U8, false), (T::U16, false), (T::U32, false)],
            text: "SCALAR of UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        },
        Some(S::Positions) | Some(S::Normals) => Allowed {
            dims: &[D::Vec3],
            components: FLOAT,
            text: "VEC3 of FLOAT",
        },
        Some(S::Tangents) => Allowed {
            dims: &[D::Vec4],
            components: FLOAT,
            text: "VEC4 of FLOAT",
        },
        Some(S::TexCoords(_)) => Allowed {
            dims: &[D::Vec2],
            components: UNIT,
            text: "VEC2 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT",
        },
        Some(S::Colors(_)) => Allowed {
            dims: &[D::Vec3, D::Vec4],
            components: UNIT,
            text: "VEC3 or VEC4 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT",
        },
        Some(S::Joints(_)) => Allowed {
            dims: &[D::Vec4],
            components: &[(T::U8, false), (T::U16, false)],
            text: "VEC4 of UNSIGNED_BYTE or UNSIGNED_SHORT",
        },
        Some(S::Weights(_)) => Allowed {
            dims: &[D::Vec4],
            components: UNIT,
            text: "VEC4 of FLOAT, normalized UNSIGNED_BYTE or normalized UNSIGNED_SHORT",
        },
        // Application-specific attributes (_FOO) are not read.
        Some(_) => return None,
    })
}

fn describe(a: &gltf::Accessor) -> String {
    use gltf::accessor::DataType as T;
    let component = match a.data_type() {
        T::I8 => "BYTE",
        T::U8 => "UNSIGNED_BYTE",
        T::I16 => "SHORT",
        T::U16 => "UNSIGNED_SHORT",
        T::U32 => "UNSIGNED_INT",
        T::F32 => "FLOAT",
    };
    let normalized = if a.normalized() { "normalized " } else { "" };
    let dims = format!("{:?}", a.dimensions()).to_uppercase();
    format!("{dims} of {normalized}{component}")
}

/// Every index, attribute and morph-target accessor has an element and
/// component type its semantic allows (the gltf crate's readers assert or
/// reach `unreachable!` on the others); errors name the JSON path.
pub(super) fn check_attribute_types(
    cx: &GltfContext,
    doc: &gltf::Document,
) -> Result<(), SceneError> {
    let quantized = doc.extensions_used().any(|e| e == "KHR_mesh_quantization");
    let check = |path: String, semantic: Option<&gltf::Semantic>, a: &gltf::Accessor, q: bool| {
        let Some(rule) = allowed(semantic, q) else {
            return Ok(());
        };
        let fits = rule.dims.contains(&a.dimensions())
            && rule.components.contains(&(a.data_type(), a.normalized()));
        if fits {
            Ok(())
        } else {
            Err(cx.invalid(format!(
                "{path}: accessor {} is {}; it must be {}",
                a.index(),
                describe(a),
                rule.text
            )))
        }
    };
    for mesh in doc.meshes() {
        for p in mesh.primitives() {
            let at = format!("meshes[{}].primitives[{}]", mesh.index(), p.index());
            if let Some(a) = p.indices() {
                check(format!("{at}.indices"), None, &a, quantized)?;
            }
            for (semantic, a) in p.attributes() {
                let path = format!("{at}.attributes.{}", semantic.to_string());
                check(path, Some(&semantic), &a, quantized)?;
            }
            for (t, target) in p.morph_targets().enumerate() {
                let named = [
                    ("POSITION", target.positions()),
                    ("NORMAL", target.normals()),
                    ("TANGENT", target.tangents()),
                ];
                for (name, a) in named {
                    let Some(a) = a else { continue };
                    // Displacements: VEC3 of FLOAT (quantized targets are not read).
                    let s = gltf::Semantic::Positions;
                    check(format!("{at}.targets[{t}].{name}"), Some(&s), &a, false)?;
                }
            }
        }
    }
    Ok(())
}

/// Every image has a source the loader can read: a `uri` or a `bufferView`.
pub(super) fn check_image_sources(
    cx: &GltfContext,
    root: &gltf::json::Root,
) -> Result<(), SceneError> {
    for (i, image) in root.images.iter().enumerate() {
        if image.uri.is_none() && image.buffer_view.is_none() {
            return Err(cx.invalid(format!("images[{i}] has neither a uri nor a bufferView")));
        }
    }
    Ok(())
}

/// Most node instances a hierarchy may expand to (each is an object drawn
/// every frame; a DAG of 40 levels with two edges each would be 2^40).
pub(crate) const MAX_NODE_INSTANCES: u64 = 1_000_000;

/// The node graph before it is walked: no cycle, an expansion (instances
/// counted through shared children) of at most [`MAX_NODE_INSTANCES`], and
/// per node the transform glTF allows (a matrix or TRS, a unit quaternion).
pub(super) fn check_nodes(cx: &GltfContext, root: &gltf::json::Root) -> Result<(), SceneError> {
    let nodes = &root.nodes;
    for (i, n) in nodes.iter().enumerate() {
        if n.matrix.is_some()
            && (n.translation.is_some() || n.rotation.is_some() || n.scale.is_some())
        {
            return Err(cx.invalid(format!(
                "nodes[{i}] has both matrix and translation/rotation/scale (glTF allows one)"
            )));
        }
        if let Some(r) = &n.rotation {
            let len = r.0.iter().map(|c| c * c).sum::<f32>().sqrt();
            if !(0.9..=1.1).contains(&len) {
                return Err(cx.invalid(format!(
                    "nodes[{i}].rotation {:?} is not a unit quaternion (length {len})",
                    r.0
                )));
            }
        }
        for c in n.children.iter().flatten() {
            if c.value() >= nodes.len() {
                return Err(cx.invalid(format!(
                    "nodes[{i}].children names node {}, which does not exist ({} nodes)",
                    c.value(),
                    nodes.len()
                )));
            }
        }
    }
    // Instances below each node, children first (iterative post-order; a
    // node met again while on the path is a cycle).
    const NEW: u8 = 0;
    const ON_PATH: u8 = 1;
    const DONE: u8 = 2;
    let mut state = vec![NEW; nodes.len()];
    let mut instances = vec![0u64; nodes.len()];
    let children = |i: usize| -> Vec<usize> {
        nodes[i]
            .children
            .iter()
            .flatten()
            .map(|c| c.value())
            .collect()
    };
    for start in 0..nodes.len() {
        if state[start] != NEW {
            continue;
        }
        let mut stack = vec![(start, false)];
        while let Some((i, expanded)) = stack.pop() {
            if expanded {
                let below = children(i)
                    .into_iter()
                    .fold(1u64, |s, c| s.saturating_add(instances[c]));
                instances[i] = below;
                state[i] = DONE;
                continue;
            }
            if state[i] == DONE {
                continue;
            }
            state[i] = ON_PATH;
            stack.push((i, true));
            for c in children(i) {
                match state[c] {
                    ON_PATH => {
                        return Err(cx.invalid(format!(
                            "nodes[{i}].children names node {c}, an ancestor: the node hierarchy has a cycle"
                        )));
                    }
                    NEW => stack.push((c, false)),
                    _ => {}
                }
            }
        }
    }
    let roots: Vec<usize> = match root.scene.map(|s| s.value()).or(if root.scenes.is_empty() {
        None
    } else {
        Some(0)
    }) {
        Some(s) => root
            .scenes
            .get(s)
            .map(|s| s.nodes.iter().map(|n| n.value()).collect())
            .unwrap_or_default(),
        None => Vec::new(),
    };
    let total = roots
        .iter()
        .filter(|&&r| r < nodes.len())
        .fold(0u64, |s, &r| s.saturating_add(instances[r]));
    if total > MAX_NODE_INSTANCES {
        return Err(cx.invalid(format!(
            "the node hierarchy expands to {total} node instances (children shared by several parents), \
             more than {MAX_NODE_INSTANCES}"
        )));
    }
    Ok(())
}

/// The asset's version (glTF 2.0 3.2: `asset.version` "2.x", a
/// `minVersion` no newer than 2.0), meshes with primitives, and sparse
/// accessor indices inside the accessor and increasing.
pub(super) fn check_document(
    cx: &GltfContext,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<(), SceneError> {
    let asset = &doc.as_json().asset;
    let major = |v: &str| v.split('.').next().and_then(|m| m.parse::<u32>().ok());
    if major(&asset.version) != Some(2) {
        return Err(cx.invalid(format!(
            "asset.version is \"{}\"; this loader reads glTF 2.x",
            asset.version
        )));
    }
    if let Some(min) = &asset.min_version
        && min.as_str() > "2.0"
    {
        return Err(cx.invalid(format!(
            "asset.minVersion is \"{min}\"; this loader reads glTF 2.0"
        )));
    }
    for m in doc.meshes() {
        if m.primitives().len() == 0 {
            return Err(cx.invalid(format!("meshes[{}] has no primitives", m.index())));
        }
    }
    for a in doc.accessors() {
        let Some(sparse) = a.sparse() else { continue };
        let idx = sparse.indices();
        let bytes = view_bytes(cx, &idx.view(), buffers)?;
        let size = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        let start = idx.offset();
        let Some(data) = start
            .checked_add(sparse.count() * size)
            .and_then(|end| bytes.get(start..end))
        else {
            return Err(cx.invalid(format!(
                "accessors[{}].sparse.indices: {} indices at offset {start} run past buffer view {}",
                a.index(),
                sparse.count(),
                idx.view().index()
            )));
        };
        let mut previous: Option<u64> = None;
        for k in data.chunks_exact(size) {
            let i = k.iter().rev().fold(0u64, |v, b| (v << 8) | *b as u64);
            if i >= a.count() as u64 || previous.is_some_and(|p| i <= p) {
                return Err(cx.invalid(format!(
                    "accessors[{}].sparse.indices: index {i} is out of order or not below the count {}",
                    a.index(),
                    a.count()
                )));
            }
            previous = Some(i);
        }
        let values = sparse.values();
        let vbytes = view_bytes(cx, &values.view(), buffers)?;
        let need = values.offset().checked_add(sparse.count() * a.size());
        if need.is_none_or(|n| n > vbytes.len()) {
            return Err(cx.invalid(format!(
                "accessors[{}].sparse.values: {} values of {} bytes run past buffer view {}",
                a.index(),
                sparse.count(),
                a.size(),
                values.view().index()
            )));
        }
    }
    for anim in doc.animations() {
        for s in anim.samplers() {
            let input = s.input();
            if input.dimensions() != gltf::accessor::Dimensions::Scalar
                || input.data_type() != gltf::accessor::DataType::F32
            {
                return Err(cx.invalid(format!(
                    "animations[{}]: sampler input accessor {} is {:?} {:?}; key times are SCALAR FLOAT",
                    anim.index(),
                    input.index(),
                    input.dimensions(),
                    input.data_type()
                )));
            }
        }
    }
    Ok(())
}

/// The elements of accessor `a` as floats (glTF 2.0 3.11): FLOAT as stored,
/// normalized integers to [0, 1] (unsigned) or [-1, 1] (signed, the most
/// negative value clamped), other integers as their values. `None` when
/// its type has no `N`-component reading or the data cannot be read.
pub(super) fn read_floats<'a, const N: usize>(
    a: &gltf::Accessor<'a>,
    data: impl Clone + Fn(gltf::Buffer<'a>) -> Option<&'a [u8]>,
) -> Option<Vec<[f32; N]>>
where
    [f32; N]: gltf::accessor::Item,
    [i8; N]: gltf::accessor::Item,
    [u8; N]: gltf::accessor::Item,
    [i16; N]: gltf::accessor::Item,
    [u16; N]: gltf::accessor::Item,
{
    use gltf::accessor::{DataType as T, Iter};
    let norm = a.normalized();
    let scale = |max: f32| move |c: f32| if norm { (c / max).max(-1.0) } else { c };
    Some(match a.data_type() {
        T::F32 => Iter::<[f32; N]>::new(a.clone(), data)?.collect(),
        T::I8 => Iter::<[i8; N]>::new(a.clone(), data)?
            .map(|v| v.map(|c| scale(127.0)(c as f32)))
            .collect(),
        T::U8 => Iter::<[u8; N]>::new(a.clone(), data)?
            .map(|v| v.map(|c| scale(255.0)(c as f32)))
            .collect(),
        T::I16 => Iter::<[i16; N]>::new(a.clone(), data)?
            .map(|v| v.map(|c| scale(32767.0)(c as f32)))
            .collect(),
        T::U16 => Iter::<[u16; N]>::new(a.clone(), data)?
            .map(|v| v.map(|c| scale(65535.0)(c as f32)))
            .collect(),
        T::U32 => return None,
    })
}
