//! One glTF primitive as a himal mesh: triangle lists (strips and fans
//! converted), attributes, skin vertices and morph targets (moved out of
//! `mod.rs`, unchanged).

use super::*;

/// Triangle lists, strips and fans are drawn (strips and fans as lists).
pub(super) fn draws_triangles(mode: gltf::mesh::Mode) -> bool {
    use gltf::mesh::Mode;
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

pub(super) fn primitive_name(mesh: &gltf::Mesh, p: &gltf::Primitive) -> String {
    format!(
        "{}.{}",
        mesh.name()
            .map_or_else(|| format!("mesh{}", mesh.index()), str::to_string),
        p.index()
    )
}

/// A strip's or fan's vertex order as a triangle list with the winding of
/// glTF 2.0 3.7.2.1: strip triangle i is (p[i], p[i + 1 + i % 2],
/// p[i + 2 - i % 2]), fan triangle i is (p[i + 1], p[i + 2], p[0]).
/// Degenerate triangles (repeated indices, used to join strips) are dropped.
pub(super) fn triangle_list(mode: gltf::mesh::Mode, p: Vec<u32>) -> Vec<u32> {
    use gltf::mesh::Mode;
    let tri = |i: usize| match mode {
        Mode::TriangleStrip => Some([p[i], p[i + 1 + i % 2], p[i + 2 - i % 2]]),
        Mode::TriangleFan => Some([p[i + 1], p[i + 2], p[0]]),
        _ => None,
    };
    if !matches!(mode, Mode::TriangleStrip | Mode::TriangleFan) {
        return p;
    }
    (0..p.len().saturating_sub(2))
        .filter_map(tri)
        .filter(|[a, b, c]| a != b && b != c && a != c)
        .flatten()
        .collect()
}

pub(super) type PrimitiveParts = (Mesh, Option<Vec<SkinVertex>>, Option<MorphTargets>);

/// One primitive as a mesh, with its bind-pose skin vertices where it has
/// JOINTS_0 and WEIGHTS_0 (else `None`) and its morph targets (kept for
/// animated weights).
pub(super) fn primitive<'a>(
    cx: &GltfContext,
    mesh: &gltf::Mesh<'a>,
    p: &gltf::Primitive<'a>,
    buffers: &'a [Vec<u8>],
    material: &PbrMaterial,
) -> Result<PrimitiveParts, SceneError> {
    let name = primitive_name(mesh, p);
    let reader = p.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    // Attributes read as floats whatever their storage (KHR_mesh_quantization).
    let data = |b: gltf::Buffer<'a>| buffers.get(b.index()).map(Vec::as_slice);
    let unreadable = |what: &str| cx.invalid(format!("mesh \"{name}\": {what} cannot be read"));
    let attribute = |semantic: gltf::Semantic| p.get(&semantic);
    let mut positions: Vec<[f32; 3]> = match attribute(gltf::Semantic::Positions) {
        Some(a) => buffers::read_floats::<3>(&a, data).ok_or_else(|| unreadable("POSITION"))?,
        None => return Err(cx.invalid(format!("mesh \"{name}\" has no POSITION"))),
    };
    let n = positions.len();
    // Morph targets at the mesh's default weights (glTF 2.0 3.7.2.2:
    // P = P0 + sum w_i dP_i, likewise normals and tangents).
    let weights = mesh.weights().unwrap_or(&[]);
    if weights.iter().any(|w| !w.is_finite()) {
        return Err(cx.invalid(format!("mesh \"{name}\": non-finite morph weights")));
    }
    let mut normal_deltas: Vec<(f32, Vec<[f32; 3]>)> = Vec::new();
    let mut tangent_deltas: Vec<(f32, Vec<[f32; 3]>)> = Vec::new();
    let base_positions = positions.clone();
    let mut targets: Vec<MorphTarget> = Vec::new();
    for (k, (dp, dn, dt)) in reader.read_morph_targets().enumerate() {
        let w = weights.get(k).copied().unwrap_or(0.0);
        let read = |d: Vec<[f32; 3]>, what: &str| {
            if d.len() != n {
                return Err(cx.invalid(format!(
                    "mesh \"{name}\": morph target {k} {what} has {} elements, POSITION {n}",
                    d.len()
                )));
            }
            Ok(d)
        };
        let mut target = MorphTarget::default();
        if let Some(dp) = dp {
            target.positions = read(dp.collect(), "POSITION")?;
            for (p, d) in positions.iter_mut().zip(&target.positions) {
                (0..3).for_each(|c| p[c] += w * d[c]);
            }
        }
        if let Some(dn) = dn {
            target.normals = read(dn.collect(), "NORMAL")?;
            normal_deltas.push((w, target.normals.clone()));
        }
        if let Some(dt) = dt {
            target.tangents = read(dt.collect(), "TANGENT")?;
            tangent_deltas.push((w, target.tangents.clone()));
        }
        if (target
            .positions
            .iter()
            .chain(&target.normals)
            .chain(&target.tangents))
        .flatten()
        .any(|c| !c.is_finite())
        {
            return Err(cx.invalid(format!("mesh \"{name}\": morph target {k} is not finite")));
        }
        targets.push(target);
    }
    let morph = |values: &mut [[f32; 3]], deltas: &[(f32, Vec<[f32; 3]>)]| {
        for (w, d) in deltas {
            for (v, d) in values.iter_mut().zip(d) {
                (0..3).for_each(|c| v[c] += w * d[c]);
            }
        }
    };
    let count_ok = |len: usize, what: &str| {
        if len == n {
            Ok(())
        } else {
            Err(cx.invalid(format!(
                "mesh \"{name}\": {what} has {len} elements, POSITION {n}"
            )))
        }
    };
    if positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err(cx.invalid(format!("mesh \"{name}\": non-finite POSITION")));
    }
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..n as u32).collect(),
    };
    let indices = triangle_list(p.mode(), indices);
    if !indices.len().is_multiple_of(3) {
        return Err(cx.invalid(format!(
            "mesh \"{name}\": {} indices is not whole triangles",
            indices.len()
        )));
    }
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= n) {
        return Err(cx.invalid(format!(
            "mesh \"{name}\": index {bad} is out of range (vertices: {n})"
        )));
    }
    // A UV set; one a texture reads must be there.
    let read_uvs = |set: u32| -> Result<Vec<[f32; 2]>, SceneError> {
        let uvs = match attribute(gltf::Semantic::TexCoords(set)) {
            Some(a) => buffers::read_floats::<2>(&a, data).ok_or_else(|| unreadable("TEXCOORD"))?,
            None if material.reads_uv_set(set) => {
                return Err(cx.invalid(format!(
                    "mesh \"{name}\": its material \"{}\" reads TEXCOORD_{set}, \
                     which the primitive does not have",
                    material.name
                )));
            }
            None => vec![[0.0; 2]; n],
        };
        count_ok(uvs.len(), "TEXCOORD")?;
        Ok(uvs)
    };
    // The material's sets in the vertex's two slots (PbrMaterial::uv_sets).
    let [set0, set1] = material.uv_sets();
    let (uvs, uvs1) = (read_uvs(set0)?, read_uvs(set1)?);
    // A third set is drawn with the first slot's (warned at load) but must exist.
    for set in material.uv_sets_past_slots() {
        if attribute(gltf::Semantic::TexCoords(set)).is_none() {
            return Err(cx.invalid(format!(
                "mesh \"{name}\": its material \"{}\" reads TEXCOORD_{set}, \
                 which the primitive does not have",
                material.name
            )));
        }
    }
    let mut base_normals = None;
    let normals: Vec<[f32; 3]> = match attribute(gltf::Semantic::Normals) {
        Some(a) => {
            let mut normals =
                buffers::read_floats::<3>(&a, data).ok_or_else(|| unreadable("NORMAL"))?;
            base_normals = Some(normals.clone());
            morph(&mut normals, &normal_deltas);
            normals
        }
        // From the morphed positions.
        None => tangents::flat_normals(&positions, &indices),
    };
    count_ok(normals.len(), "NORMAL")?;
    let colors: Option<Vec<[f32; 4]>> = reader.read_colors(0).map(|c| c.into_rgba_f32().collect());
    if let Some(c) = &colors {
        count_ok(c.len(), "COLOR_0")?;
    }
    let (color, surface) = (material.vertex_color(), material.vertex_surface());
    let mut vertices: Vec<Vertex> = (0..n)
        .map(|i| {
            let c = colors.as_ref().map_or([1.0; 4], |c| c[i]);
            Vertex {
                position: positions[i],
                normal: Vec3::from(normals[i]).normalize_or(Vec3::Y).to_array(),
                tangent: [1.0, 0.0, 0.0, 1.0],
                uv: uvs[i],
                color: [color[0] * c[0], color[1] * c[1], color[2] * c[2], color[3]],
                surface,
                uv1: uvs1[i],
            }
        })
        .collect();
    let mut indices = indices;
    let mut remap: Option<Vec<u32>> = None;
    let mut base_tangents = None;
    match attribute(gltf::Semantic::Tangents) {
        Some(a) => {
            let t = buffers::read_floats::<4>(&a, data).ok_or_else(|| unreadable("TANGENT"))?;
            count_ok(t.len(), "TANGENT")?;
            let mut xyz: Vec<[f32; 3]> = t.iter().map(|t| [t[0], t[1], t[2]]).collect();
            base_tangents = Some(xyz.clone());
            morph(&mut xyz, &tangent_deltas);
            for ((v, t), m) in vertices.iter_mut().zip(&t).zip(xyz) {
                let w = if t[3] < 0.0 { -1.0 } else { 1.0 };
                v.tangent = [m[0], m[1], m[2], w];
            }
        }
        // Only normal-mapped or anisotropic materials need a tangent frame from the UVs.
        None if material.normal_texture.is_some() || material.anisotropy_strength > 0.0 => {
            let set = material
                .normal_texture
                .map_or(0, |t| material.uv_slot(t.tex_coord));
            let (v, i, origins) = tangents::generate(&vertices, &indices, set);
            (vertices, indices, remap) = (v, i, Some(origins));
        }
        None => {}
    }
    // himal's vertex contract: a unit tangent orthogonal to the normal
    // (MikkTSpace and files need not give one; the shader re-orthogonalises
    // per pixel all the same, so the shading does not change).
    for v in &mut vertices {
        let n = Vec3::from(v.normal);
        let t = Vec3::from_slice(&v.tangent[..3]);
        let t = (t - n * n.dot(t))
            .try_normalize()
            .unwrap_or_else(|| n.any_orthonormal_vector());
        v.tangent[..3].copy_from_slice(&t.to_array());
    }
    let bounds = Aabb::from_points(vertices.iter().map(|v| Vec3::from(v.position)));
    let skin = match (reader.read_joints(0), reader.read_weights(0)) {
        (Some(j), Some(w)) => {
            let joints: Vec<[u16; 4]> = j.into_u16().collect();
            let weights: Vec<[f32; 4]> = w.into_f32().collect();
            count_ok(joints.len(), "JOINTS_0")?;
            count_ok(weights.len(), "WEIGHTS_0")?;
            if !weights.iter().flatten().all(|w| w.is_finite() && *w >= 0.0) {
                return Err(cx.invalid(format!(
                    "mesh \"{name}\": WEIGHTS_0 must be finite and not negative"
                )));
            }
            let skin_vertex = |(k, v): (usize, &Vertex)| {
                let i = remap.as_ref().map_or(k, |r| r[k] as usize);
                let w = weights[i];
                let sum: f32 = w.iter().sum();
                // glTF asks for a sum of 1; exporters round. No weight: joint 0.
                let weights = if sum > 0.0 {
                    w.map(|x| x / sum)
                } else {
                    [1.0, 0.0, 0.0, 0.0]
                };
                let [px, py, pz] = v.position;
                let [nx, ny, nz] = v.normal;
                SkinVertex {
                    position: [px, py, pz, 0.0],
                    normal: [nx, ny, nz, 0.0],
                    tangent: v.tangent,
                    weights,
                    // Unweighted slots may hold anything; they read joint 0.
                    joints: std::array::from_fn(|c| {
                        if weights[c] > 0.0 {
                            u32::from(joints[i][c])
                        } else {
                            0
                        }
                    }),
                }
            };
            Some(vertices.iter().enumerate().map(skin_vertex).collect())
        }
        _ => None,
    };
    // Indexed like the drawn vertices (MikkTSpace may have split some).
    let morph = (!targets.is_empty()).then(|| {
        let origin = |k: usize| remap.as_ref().map_or(k, |r| r[k] as usize);
        let by_vertex = |v: &[[f32; 3]]| -> Vec<[f32; 3]> {
            match v.is_empty() {
                true => Vec::new(),
                false => (0..vertices.len()).map(|k| v[origin(k)]).collect(),
            }
        };
        MorphTargets {
            defaults: (0..targets.len())
                .map(|k| weights.get(k).copied().unwrap_or(0.0))
                .collect(),
            positions: by_vertex(&base_positions),
            normals: base_normals.as_deref().map(by_vertex),
            tangents: base_tangents.as_deref().map(by_vertex),
            targets: (targets.iter())
                .map(|t| MorphTarget {
                    positions: by_vertex(&t.positions),
                    normals: by_vertex(&t.normals),
                    tangents: by_vertex(&t.tangents),
                })
                .collect(),
        }
    });
    Ok((
        Mesh {
            name,
            vertices,
            indices,
            bounds,
            levels: Vec::new(),
        },
        skin,
        morph,
    ))
}
