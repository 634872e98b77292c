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

fn allowed(semantic: Option<&gltf::Semantic>) -> Option<Allowed> {
    use gltf::Semantic as S;
    use gltf::accessor::DataType as T;
    use gltf::accessor::Dimensions as D;
    const FLOAT: &[(T, bool)] = &[(T::F32, false)];
    const UNIT: &[(T, bool)] = &[(T::F32, false), (T::U8, true), (T::U16, true)];
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
    let check = |path: String, semantic: Option<&gltf::Semantic>, a: &gltf::Accessor| {
        let Some(rule) = allowed(semantic) else {
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
                check(format!("{at}.indices"), None, &a)?;
            }
            for (semantic, a) in p.attributes() {
                let path = format!("{at}.attributes.{}", semantic.to_string());
                check(path, Some(&semantic), &a)?;
            }
            for (t, target) in p.morph_targets().enumerate() {
                let named = [
                    ("POSITION", target.positions()),
                    ("NORMAL", target.normals()),
                    ("TANGENT", target.tangents()),
                ];
                for (name, a) in named {
                    let Some(a) = a else { continue };
                    // Displacements: VEC3 of FLOAT (no quantization extension).
                    let s = gltf::Semantic::Positions;
                    check(format!("{at}.targets[{t}].{name}"), Some(&s), &a)?;
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
