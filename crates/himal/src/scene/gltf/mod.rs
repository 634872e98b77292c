//! glTF 2.0 import (.gltf + .bin and .glb) into himal meshes, objects,
//! materials, cameras and punctual lights. See `docs/gltf.md`.
//!
//! Each primitive becomes one [`Mesh`] (vertices carry the material's
//! factors in `color` / `surface`, as the per-vertex G-buffer path reads
//! them) and each node instance of it one [`Object`] with the node's world
//! transform. [`PbrSet`] keeps what the textured G-buffer path needs: the
//! materials, textures, samplers and decoded images, and which mesh uses
//! which material. Missing tangents are generated with MikkTSpace
//! (`tangents.rs`). Every problem is an error naming the file.

mod animation;
mod buffers;
mod deform;
mod instancing;
mod material;
mod morph;
pub(crate) mod placement;
mod primitive;
mod tangents;

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

pub use material::{
    AlphaMode, GLTF_DIELECTRIC_F0, ImageData, NORMAL_SLOTS, PbrMaterial, SamplerDesc,
    TEXTURE_SLOTS, TextureRef, TextureSlot, UvTransform, Wrap, anisotropy_from_khr,
    glossiness_from_roughness, srgb8_to_linear,
};

pub use animation::{
    Animated, Channel, Clip, Interpolation, Rig, RigNode, Skin, SkinVertex, SkinVertices, Target,
    Trs, skin_vertex,
};
pub(crate) use buffers::GltfContext;
use buffers::{
    check_accessors, check_attribute_types, check_document, check_image_sources, check_nodes,
    check_position_accessors,
};
use deform::{morphed, reweighted_copy, skinned};
pub use morph::{MorphTarget, MorphTargets};
use primitive::{draws_triangles, primitive, primitive_name};

use super::{Aabb, Camera, Mesh, NamedCamera, Object, SceneError, Vertex};
use crate::budget::MemoryBudget;

/// Largest accepted image side (texels); larger ones are refused, not decoded.
pub const MAX_TEXTURE_SIZE: u32 = 8192;
/// Largest accepted vertex or index count per primitive.
pub(crate) const MAX_ELEMENTS: usize = 1 << 26;

/// Materials and textures of the textured G-buffer path.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PbrSet {
    /// The file's materials (and glTF's default one, appended when used).
    pub materials: Vec<PbrMaterial>,
    /// Texture slots: an image and a sampler each.
    pub textures: Vec<TextureSlot>,
    /// Decoded images (RGBA8), indexed by the slots.
    pub images: Vec<ImageData>,
    /// `(mesh index in the scene, material index)`: meshes drawn textured.
    pub mesh_material: Vec<(usize, usize)>,
}

impl PbrSet {
    /// The material of scene mesh `mesh`, if it is drawn by the textured path.
    pub fn material_of(&self, mesh: usize) -> Option<usize> {
        self.mesh_material
            .iter()
            .find(|(m, _)| *m == mesh)
            .map(|(_, i)| *i)
    }

    /// E3: per image, whether its mips are baked with normal variance in
    /// alpha (it is used as a normal or clearcoat normal texture and by no
    /// other slot); and the names of the images used as a normal texture
    /// and by another slot too (they keep plain mips: no variance).
    pub fn normal_variance_images(&self) -> (Vec<bool>, Vec<String>) {
        let (mut normal, mut other) = (
            vec![false; self.images.len()],
            vec![false; self.images.len()],
        );
        for m in &self.materials {
            for (slot, r) in m.texture_refs().iter().enumerate() {
                let Some(image) = r
                    .and_then(|r| self.textures.get(r.texture))
                    .map(|t| t.image)
                else {
                    continue;
                };
                let uses = if NORMAL_SLOTS.contains(&slot) {
                    &mut normal
                } else {
                    &mut other
                };
                if let Some(u) = uses.get_mut(image) {
                    *u = true;
                }
            }
        }
        let shared = (normal.iter().zip(&other).enumerate())
            .filter(|(_, (n, o))| **n && **o)
            .map(|(i, _)| self.images[i].name.clone())
            .collect();
        let baked = normal.iter().zip(&other).map(|(n, o)| *n && !*o).collect();
        (baked, shared)
    }
}

/// KHR_lights_punctual kinds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Parallel light (lux); the scene's sun.
    Directional,
    /// Omnidirectional (candela).
    Point,
    /// Cone angles in radians.
    Spot {
        /// Full-intensity half angle.
        inner_cone: f32,
        /// Cut-off half angle.
        outer_cone: f32,
    },
}

/// A KHR_lights_punctual light placed by its node (parsed, not yet lit:
/// wiring into lighting is the lead's, with the S3 point / spot lights).
#[derive(Clone, Debug, PartialEq)]
pub struct PunctualLight {
    /// The light's name (its node's when it has none).
    pub name: String,
    /// Directional, point or spot.
    pub kind: LightKind,
    /// Linear colour, not scaled by `intensity`.
    pub color: Vec3,
    /// The file's intensity (candela for point and spot, lux for directional).
    pub intensity: f32,
    /// Distance where the light reaches zero; `None`: unbounded (inverse square).
    pub range: Option<f32>,
    /// World position of its node.
    pub position: Vec3,
    /// Unit direction the light points to (the node's -Z).
    pub direction: Vec3,
}

/// A loaded glTF file.
#[derive(Clone, Debug)]
pub struct GltfAsset {
    /// The file it was read from (errors and warnings name it).
    pub path: PathBuf,
    /// One per primitive, in (mesh, primitive) order.
    pub meshes: Vec<Mesh>,
    /// Node instances of `meshes` with world transforms.
    pub objects: Vec<Object>,
    /// `pbr.mesh_material` indexes `meshes`.
    pub pbr: PbrSet,
    /// The file's cameras at their nodes.
    pub cameras: Vec<NamedCamera>,
    /// The file's KHR_lights_punctual lights at their nodes.
    pub lights: Vec<PunctualLight>,
    /// Meshes in the file.
    pub gltf_meshes: usize,
    /// Primitives in the file, points and lines included.
    pub gltf_primitives: usize,
    /// World bounds of all objects.
    pub bounds: Aabb,
    /// What the file holds that himal does not show (also logged once at
    /// load): unimplemented extensions, point and line primitives.
    pub warnings: Vec<String>,
    /// `KHR_materials_variants` names, in the file's order.
    pub variants: Vec<String>,
}

/// Loads a .gltf (with its .bin and images) or a .glb file.
pub fn load(path: &Path) -> Result<GltfAsset, SceneError> {
    load_within(path, MemoryBudget::default())
}

/// [`load`] with meshes and images charged against `budget` before they
/// are read.
pub fn load_within(path: &Path, budget: MemoryBudget) -> Result<GltfAsset, SceneError> {
    load_with(path, budget, None)
}

/// [`load_within`] with the materials of `KHR_materials_variants` variant
/// `variant` (by name; `None`: the default materials).
pub fn load_with(
    path: &Path,
    budget: MemoryBudget,
    variant: Option<&str>,
) -> Result<GltfAsset, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    let cx = GltfContext {
        path: path.to_path_buf(),
    };
    // A directory, a device or an endless pipe is not read.
    if !meta.is_file() {
        return Err(cx.invalid("not a regular file"));
    }
    budget
        .check("the file", meta.len())
        .map_err(|e| cx.invalid(e))?;
    let bytes = std::fs::read(path).map_err(io)?;
    load_from_bytes_with(path, &bytes, budget, variant)
}

/// Like [`load`] for bytes already read; `path` names it and resolves URIs.
pub fn load_from_bytes(path: &Path, bytes: &[u8]) -> Result<GltfAsset, SceneError> {
    load_from_bytes_within(path, bytes, MemoryBudget::default())
}

/// [`load_from_bytes`] within `budget`.
pub fn load_from_bytes_within(
    path: &Path,
    bytes: &[u8],
    budget: MemoryBudget,
) -> Result<GltfAsset, SceneError> {
    load_from_bytes_with(path, bytes, budget, None)
}

/// [`load_from_bytes_within`] with variant `variant` (see [`load_with`]).
pub fn load_from_bytes_with(
    path: &Path,
    bytes: &[u8],
    budget: MemoryBudget,
    variant: Option<&str>,
) -> Result<GltfAsset, SceneError> {
    let cx = GltfContext {
        path: path.to_path_buf(),
    };
    let invalid = |e: gltf::Error| cx.invalid(format!("not valid glTF: {e}"));
    // A GLB's header states its whole length (glTF 2.0 4.4.2).
    if let Some(declared) = bytes
        .strip_prefix(b"glTF")
        .and_then(|rest| rest.get(4..8))
        .map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as usize)
        && declared != bytes.len()
    {
        return Err(cx.invalid(format!(
            "GLB header declares {declared} bytes, the file has {}",
            bytes.len()
        )));
    }
    // Parsed first, validated after our own index check: the gltf crate's
    // validation indexes the POSITION accessor unchecked (a panic found by
    // tests/gltf_fuzz.rs).
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    let mut root = document.into_json();
    let mut warnings: Vec<String> = check_extensions(&cx, &mut root)?.into_iter().collect();
    check_position_accessors(&cx, &root)?;
    check_image_sources(&cx, &root)?;
    check_nodes(&cx, &root)?;
    let doc = gltf::Document::from_json(root).map_err(invalid)?;
    let mut blob = blob;
    let mut buffers = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                cx.invalid(format!(
                    "buffer {} refers to a missing GLB BIN chunk",
                    b.index()
                ))
            })?,
            gltf::buffer::Source::Uri(uri) => cx.read_uri(uri)?,
        };
        if data.len() < b.length() {
            return Err(cx.invalid(format!(
                "buffer {} has {} bytes, the file declares {}",
                b.index(),
                data.len(),
                b.length()
            )));
        }
        buffers.push(data);
    }
    check_accessors(&cx, &doc, &buffers)?;
    check_attribute_types(&cx, &doc)?;
    check_document(&cx, &doc, &buffers)?;
    // Meshes are charged before they are read, images as they are decoded
    // (each is at most MAX_TEXTURE_SIZE square).
    let mut charged: u64 = buffers.iter().map(|b| b.len() as u64).sum();
    for m in doc.meshes() {
        for p in m.primitives() {
            let vertices = p.get(&gltf::Semantic::Positions).map_or(0, |a| a.count());
            let indices = p.indices().map_or(vertices, |a| a.count());
            charged =
                charged.saturating_add(MemoryBudget::mesh_bytes(vertices as u64, indices as u64));
        }
    }
    budget
        .check("its meshes", charged)
        .map_err(|e| cx.invalid(e))?;

    let mut pbr = PbrSet::default();
    for img in doc.images() {
        let image = material::image(&cx, &img, &buffers)?;
        // The decoded texels, their mip chain and the GPU copy.
        charged = charged.saturating_add(image.rgba8.len() as u64 * 3);
        budget
            .check(
                format!("its meshes and images up to images[{}]", img.index()),
                charged,
            )
            .map_err(|e| cx.invalid(e))?;
        pbr.images.push(image);
    }
    for t in doc.textures() {
        pbr.textures.push(TextureSlot {
            image: t.source().index(),
            sampler: material::sampler(&t.sampler()),
        });
    }
    let texture_count = pbr.textures.len();
    for m in doc.materials() {
        pbr.materials
            .push(material::material(&cx, &m, texture_count)?);
    }
    // glTF's default material, appended only when a primitive has none.
    let default_material = pbr.materials.len();
    let fallback = PbrMaterial::default();

    let variants = variant_names(&doc);
    let selected = match variant {
        None => None,
        Some(name) => Some(variants.iter().position(|v| v == name).ok_or_else(|| {
            cx.invalid(if variants.is_empty() {
                format!("--variant {name}: the file has no KHR_materials_variants")
            } else {
                format!(
                    "no variant \"{name}\" (the file's: {})",
                    variants.join(", ")
                )
            })
        })?),
    };
    // Meshes: one himal mesh per triangle primitive; points and lines are
    // named in a warning, not drawn.
    let mut primitive_mesh: Vec<Vec<Option<usize>>> = Vec::new();
    let mut meshes = Vec::new();
    let mut mesh_skin: Vec<Option<Vec<SkinVertex>>> = Vec::new();
    // Morph targets of each mesh (those with targets), for animated weights.
    let mut mesh_morph: Vec<Option<std::sync::Arc<MorphTargets>>> = Vec::new();
    let mut gltf_primitives = 0;
    let mut not_drawn = Vec::new();
    for m in doc.meshes() {
        let mut of_mesh = Vec::new();
        for p in m.primitives() {
            gltf_primitives += 1;
            if !draws_triangles(p.mode()) {
                not_drawn.push(format!("{} ({:?})", primitive_name(&m, &p), p.mode()));
                of_mesh.push(None);
                continue;
            }
            let mapped = selected.and_then(|v| variant_material(&p, v));
            if let Some(bad) = mapped.filter(|&i| i >= default_material) {
                return Err(cx.invalid(format!(
                    "{}: KHR_materials_variants maps to material {bad}, which does not exist ({default_material} materials)",
                    primitive_name(&m, &p)
                )));
            }
            let material = mapped.or(p.material().index()).unwrap_or(default_material);
            let desc = pbr.materials.get(material).unwrap_or(&fallback);
            let (mesh, skin, morph) = primitive(&cx, &m, &p, &buffers, desc)?;
            pbr.mesh_material.push((meshes.len(), material));
            of_mesh.push(Some(meshes.len()));
            meshes.push(mesh);
            mesh_skin.push(skin);
            mesh_morph.push(morph.map(std::sync::Arc::new));
        }
        primitive_mesh.push(of_mesh);
    }
    if !not_drawn.is_empty() {
        warnings.push(format!(
            "does not draw {} point or line primitive(s) (himal draws triangles): {}",
            not_drawn.len(),
            not_drawn.join(", ")
        ));
    }
    let names = |v: Vec<String>| v.join(", ");
    let rig = animation::read_rig(&cx, &doc, &buffers)?.map(std::sync::Arc::new);
    // Nodes an animation moves: targeted by a channel, or below one that is.
    let moved: Vec<bool> = match &rig {
        Some(rig) => {
            let mut moved = vec![false; rig.nodes.len()];
            for ch in rig.clips.iter().flat_map(|c| &c.channels) {
                moved[ch.node] = true;
            }
            (0..moved.len())
                .map(|mut n| {
                    loop {
                        if moved[n] {
                            break true;
                        }
                        match rig.nodes[n].parent {
                            Some(p) => n = p,
                            None => break false,
                        }
                    }
                })
                .collect()
        }
        None => Vec::new(),
    };
    // The clip played until the caller picks one (Scene::set_animation).
    let first_clip = rig
        .as_ref()
        .and_then(|r| (!r.clips.is_empty()).then_some(0));
    let mut unskinned = Vec::new();
    let mut skinned_meshes = std::collections::HashSet::new();
    let mut morphed_meshes = std::collections::HashSet::new();
    let mut unmorphed = Vec::new();
    // Two UV slots per vertex (`Vertex::uv`, `uv1`) hold the two sets a
    // material reads (PbrMaterial::uv_sets); a third is named here.
    let past_slots: Vec<String> = (pbr.materials.iter())
        .filter_map(|m| {
            let past = m.uv_sets_past_slots();
            (!past.is_empty()).then(|| {
                let sets: Vec<String> = past.iter().map(|k| format!("TEXCOORD_{k}")).collect();
                format!("{} ({})", m.name, sets.join(", "))
            })
        })
        .collect();
    let blended_layers: Vec<String> = (pbr.materials.iter())
        .filter(|m| m.coated() && (m.alpha_mode == AlphaMode::Blend || m.transmits()))
        .map(|m| m.name.clone())
        .collect();
    if !blended_layers.is_empty() {
        warnings.push(format!(
            "alpha BLEND and transmissive materials are drawn without their clearcoat or sheen: {}",
            names(blended_layers)
        ));
    }
    let (_, shared_normals) = pbr.normal_variance_images();
    if !shared_normals.is_empty() {
        warnings.push(format!(
            "images used as a normal texture and by another slot keep plain mips (no specular anti-aliasing from their normal variance): {}",
            names(shared_normals)
        ));
    }
    if !past_slots.is_empty() {
        warnings.push(format!(
            "himal draws two UV sets per material; textures reading a third set use the material's first: {}",
            names(past_slots)
        ));
    }

    if pbr
        .mesh_material
        .iter()
        .any(|(_, m)| *m == default_material)
    {
        pbr.materials.push(fallback);
    }

    // Nodes: world transforms from the default scene (or every root).
    let mut out = GltfAsset {
        path: path.to_path_buf(),
        objects: Vec::new(),
        pbr,
        cameras: Vec::new(),
        lights: Vec::new(),
        gltf_meshes: doc.meshes().count(),
        gltf_primitives,
        bounds: Aabb::EMPTY,
        meshes: Vec::new(),
        warnings,
        variants,
    };
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => s.nodes().collect(),
        None => Vec::new(),
    };
    let mut reweighted = Vec::new();
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(cx.invalid("node hierarchy deeper than 256 (a cycle?)"));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        if !local.is_finite() {
            return Err(cx.invalid(format!("node {} has a non-finite transform", node.index())));
        }
        let world = parent * local;
        let name = node
            .name()
            .map_or_else(|| format!("node{}", node.index()), str::to_string);
        if let Some(m) = node.mesh() {
            let drawn = &primitive_mesh[m.index()];
            let count = drawn.len();
            // EXT_mesh_gpu_instancing: one object per instance, the
            // instance's transform before the node's.
            let instances = instancing::node_instances(&cx, &doc, &node, &buffers)?;
            // A node's own weights replace its mesh's defaults (glTF 2.0
            // 3.7.2.2): each such node draws its own copy, shared by its
            // instances (EXT_mesh_gpu_instancing instances share the node's).
            let own = node.weights().filter(|w| Some(*w) != m.weights());
            let targets = drawn.iter().flatten().any(|&p| mesh_morph[p].is_some());
            if own.is_some() && !targets {
                reweighted.push(name.clone());
            }
            let drawn: Vec<Option<usize>> = (drawn.iter())
                .map(|p| {
                    let mesh = (*p)?;
                    Some(match (own, mesh_morph[mesh].clone()) {
                        (Some(w), Some(t)) => reweighted_copy(
                            w,
                            &t,
                            mesh,
                            (&mut meshes, &mut mesh_skin, &mut mesh_morph),
                            &mut out.pbr,
                        ),
                        _ => mesh,
                    })
                })
                .collect();
            let placements = instances.as_deref().unwrap_or(&[Mat4::IDENTITY]);
            let drawn_objects = out.objects.len() + placements.len() * count;
            if drawn_objects as u64 > buffers::MAX_NODE_INSTANCES {
                return Err(cx.invalid(format!(
                    "node {} makes the file draw {drawn_objects} objects, more than {}",
                    node.index(),
                    buffers::MAX_NODE_INSTANCES
                )));
            }
            for (i, instance) in placements.iter().enumerate() {
                let transform = world * *instance;
                let base = match instances {
                    Some(_) => format!("{name}#{i}"),
                    None => name.clone(),
                };
                for (k, mesh) in drawn.iter().enumerate() {
                    let Some(mut mesh) = *mesh else { continue };
                    let rig = rig.as_ref().filter(|_| instances.is_none());
                    let skin = node.skin().map(|s| s.index());
                    if skin.is_some() && mesh_skin[mesh].is_none() {
                        unskinned.push(format!("{name} ({})", meshes[mesh].name));
                    }
                    let animated = match (rig, skin.filter(|_| mesh_skin[mesh].is_some())) {
                        (Some(rig), Some(skin)) => {
                            // Each skinned node deforms its own copy.
                            if !skinned_meshes.insert(mesh) {
                                meshes.push(meshes[mesh].clone());
                                mesh_skin.push(mesh_skin[mesh].clone());
                                mesh_morph.push(mesh_morph[mesh].clone());
                                if let Some(m) = out.pbr.material_of(mesh) {
                                    out.pbr.mesh_material.push((meshes.len() - 1, m));
                                }
                                mesh = meshes.len() - 1;
                            }
                            let vertices = mesh_skin[mesh].clone().unwrap_or_default();
                            let joints = rig.skins[skin].joints.len();
                            if let Some(bad) = (vertices.iter().zip(0..))
                                .find(|(v, _)| v.joints.iter().any(|&j| j as usize >= joints))
                            {
                                return Err(cx.invalid(format!(
                                    "mesh \"{}\": vertex {} names joint {:?} of skin {skin}, which has {joints}",
                                    meshes[mesh].name, bad.1, bad.0.joints
                                )));
                            }
                            // Animated weights: morphed, then skinned.
                            let morph = (mesh_morph[mesh].clone())
                                .filter(|_| rig.animates_weights(node.index()));
                            Some(skinned(
                                rig,
                                (node.index(), skin),
                                first_clip,
                                (vertices, morph),
                                &mut meshes[mesh],
                            ))
                        }
                        (Some(rig), None) if moved[node.index()] => {
                            // Animated morph weights: each morphed node
                            // deforms its own copy of the mesh.
                            let morph = (mesh_morph[mesh].clone())
                                .filter(|_| rig.animates_weights(node.index()));
                            if morph.is_some() && !morphed_meshes.insert(mesh) {
                                meshes.push(meshes[mesh].clone());
                                mesh_skin.push(None);
                                mesh_morph.push(mesh_morph[mesh].clone());
                                if let Some(m) = out.pbr.material_of(mesh) {
                                    out.pbr.mesh_material.push((meshes.len() - 1, m));
                                }
                                mesh = meshes.len() - 1;
                            }
                            if let Some(m) = &morph {
                                morphed(rig, node.index(), first_clip, m, &mut meshes[mesh]);
                            }
                            Some(Animated {
                                rig: rig.clone(),
                                node: node.index(),
                                skin: None,
                                clip: first_clip,
                                swept: animation::swept_rigid(
                                    rig,
                                    node.index(),
                                    &meshes[mesh].bounds,
                                ),
                                morph,
                            })
                        }
                        _ => None,
                    };
                    if let Some(rig) = rig
                        && rig.animates_weights(node.index())
                        && animated.as_ref().is_none_or(|a| a.morph.is_none())
                    {
                        unmorphed.push(format!("{name} ({})", meshes[mesh].name));
                    }
                    let motion = animated.map(|a| crate::scene::Motion {
                        orbit: None,
                        base: Mat4::IDENTITY,
                        animated: Some(a),
                    });
                    let mut object = Object {
                        name: if count == 1 {
                            base.clone()
                        } else {
                            format!("{base}.{k}")
                        },
                        mesh,
                        transform,
                        motion,
                        foliage: None,
                        ground: false,
                    };
                    object.transform = object.transform_at(0.0);
                    out.bounds = out.bounds.union(&object.swept_bounds(&meshes[mesh].bounds));
                    out.objects.push(object);
                }
            }
        }
        if let Some(c) = node.camera() {
            out.cameras.push(camera(&name, &c, &world));
        }
        if let Some(l) = node.light() {
            out.lights.push(light(&name, &l, &world));
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    if !unskinned.is_empty() {
        out.warnings.push(format!(
            "skinned nodes whose primitives have no JOINTS_0 and WEIGHTS_0 are drawn rigid: {}",
            unskinned.join(", ")
        ));
    }
    if !unmorphed.is_empty() {
        out.warnings.push(format!(
            "animated morph weights of meshes without targets are not applied: {}",
            unmorphed.join(", ")
        ));
    }
    if !reweighted.is_empty() {
        out.warnings.push(format!(
            "nodes with their own morph weights whose mesh has no targets: {}",
            reweighted.join(", ")
        ));
    }
    for w in &out.warnings {
        log::warn!("{}: {w}", cx.path.display());
    }
    out.meshes = meshes;
    Ok(out)
}

/// The extensions the loader reads (the gltf crate's typed ones and
/// those read from the JSON).
pub const IMPLEMENTED_EXTENSIONS: [&str; 14] = [
    "EXT_mesh_gpu_instancing",
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
    "KHR_texture_transform",
];

/// A required extension the loader does not implement is an error naming
/// them all; a used one is named in one warning. The required list is then
/// emptied: every entry left is ours, and the gltf crate's validation
/// knows only its own features' extensions (it refused
/// `KHR_materials_anisotropy`).
fn check_extensions(
    cx: &GltfContext,
    root: &mut gltf::json::Root,
) -> Result<Option<String>, SceneError> {
    let missing = |list: &[String]| -> Vec<String> {
        let mut out: Vec<String> = (list.iter())
            .filter(|e| !IMPLEMENTED_EXTENSIONS.contains(&e.as_str()))
            .cloned()
            .collect();
        out.sort();
        out.dedup();
        out
    };
    let required = missing(&root.extensions_required);
    if !required.is_empty() {
        return Err(cx.invalid(format!(
            "requires extensions himal does not implement: {} (it implements {})",
            required.join(", "),
            IMPLEMENTED_EXTENSIONS.join(", ")
        )));
    }
    let ignored = missing(&root.extensions_used);
    root.extensions_required.clear();
    Ok((!ignored.is_empty()).then(|| {
        format!(
            "ignores the extensions it does not implement: {} (the model may look wrong)",
            ignored.join(", ")
        )
    }))
}

/// The names of the file's `KHR_materials_variants`.
fn variant_names(doc: &gltf::Document) -> Vec<String> {
    let list = doc
        .extensions()
        .and_then(|e| e.get("KHR_materials_variants"))
        .and_then(|v| v.get("variants"))
        .and_then(|v| v.as_array());
    list.map(|l| {
        l.iter()
            .enumerate()
            .map(|(i, v)| {
                v.get("name")
                    .and_then(|n| n.as_str())
                    .map_or_else(|| format!("variant{i}"), str::to_string)
            })
            .collect()
    })
    .unwrap_or_default()
}

/// The material primitive `p` maps variant `variant` to, if it does.
fn variant_material(p: &gltf::Primitive, variant: usize) -> Option<usize> {
    let mappings = p
        .extensions()?
        .get("KHR_materials_variants")?
        .get("mappings")?
        .as_array()?;
    mappings.iter().find_map(|m| {
        let listed = m.get("variants")?.as_array()?;
        listed
            .iter()
            .any(|v| v.as_u64() == Some(variant as u64))
            .then(|| m.get("material")?.as_u64().map(|i| i as usize))
            .flatten()
    })
}

fn camera(name: &str, c: &gltf::Camera, world: &Mat4) -> NamedCamera {
    let position = world.transform_point3(Vec3::ZERO);
    let forward = world
        .transform_vector3(Vec3::NEG_Z)
        .normalize_or(Vec3::NEG_Z);
    let up = world.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
    let (fov, near, orthographic) = match c.projection() {
        gltf::camera::Projection::Perspective(p) => (p.yfov().to_degrees(), p.znear(), None),
        // The world scale of the node scales the view box (glTF 3.10.3).
        gltf::camera::Projection::Orthographic(o) => {
            let scale = world.transform_vector3(Vec3::Y).length();
            let ortho = crate::scene::Orthographic {
                half_height: (o.ymag().abs() * scale).max(1e-6),
                far: o.zfar().max(o.znear() + 1e-3),
            };
            (40.0, o.znear().max(0.0), Some(ortho))
        }
    };
    NamedCamera {
        cinematic_shadows: None,
        name: c.name().unwrap_or(name).to_string(),
        camera: Camera {
            position,
            forward,
            up,
            fov_y_deg: if fov > 0.0 && fov < 179.0 { fov } else { 40.0 },
            // An orthographic near plane may be 0; depth needs it in front.
            near: if near > 0.0 { near } else { 0.01 },
            orthographic,
        },
    }
}

/// A KHR_lights_punctual point or spot light as a scene light (S3);
/// directional lights are left to the sun. Without a range, the light fades
/// out where it falls to 0.05 lux (clamped to 1..200 m).
pub fn local_light(l: &PunctualLight) -> Option<crate::scene::LightDesc> {
    let (kind, inner_deg, outer_deg) = match l.kind {
        LightKind::Directional => return None,
        LightKind::Point => (crate::scene::LightKind::Point, 0.0, 0.0),
        LightKind::Spot {
            inner_cone,
            outer_cone,
        } => (
            crate::scene::LightKind::Spot,
            inner_cone.to_degrees(),
            outer_cone.to_degrees(),
        ),
    };
    Some(crate::scene::LightDesc {
        name: l.name.clone(),
        kind,
        position: l.position,
        color: l.color,
        intensity: l.intensity,
        range: l
            .range
            .unwrap_or_else(|| (l.intensity.max(0.0) / 0.05).sqrt().clamp(1.0, 200.0)),
        direction: l.direction,
        inner_deg,
        outer_deg,
        shadow: true,
    })
}

/// The file's first directional light as the scene's sun (lux to klux);
/// further directional lights are named in a warning (one sun is drawn).
pub fn sun_light(path: &Path, lights: &[PunctualLight]) -> Option<crate::scene::SunLight> {
    let mut directional = lights.iter().filter(|l| l.kind == LightKind::Directional);
    let first = directional.next()?;
    let rest: Vec<&str> = directional.map(|l| l.name.as_str()).collect();
    if !rest.is_empty() {
        log::warn!(
            "{}: directional light \"{}\" is the sun; the other directional lights are not drawn: {}",
            path.display(),
            first.name,
            rest.join(", ")
        );
    }
    Some(crate::scene::SunLight {
        to_light: -first.direction,
        illuminance_klux: first.color * first.intensity.max(0.0) * 1e-3,
    })
}

fn light(name: &str, l: &gltf::khr_lights_punctual::Light, world: &Mat4) -> PunctualLight {
    use gltf::khr_lights_punctual::Kind;
    let kind = match l.kind() {
        Kind::Directional => LightKind::Directional,
        Kind::Point => LightKind::Point,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner_cone: inner_cone_angle,
            outer_cone: outer_cone_angle,
        },
    };
    PunctualLight {
        name: l.name().unwrap_or(name).to_string(),
        kind,
        color: Vec3::from(l.color()),
        intensity: l.intensity(),
        range: l.range(),
        position: world.transform_point3(Vec3::ZERO),
        direction: world
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or(Vec3::NEG_Z),
    }
}

/// A primitive's mesh, its bind-pose skin vertices where it has JOINTS_0
/// and WEIGHTS_0, and its morph targets where it has any.
/// A camera on +Z looking at the centre of `bounds` (glTF models face +Z),
/// 14° above it, far enough that the bounding sphere fills the
/// vertical field of view `fov_y_deg` (square images) with a 10 % margin.
pub fn framing_camera(bounds: &Aabb, fov_y_deg: f32) -> Camera {
    orbit_camera(bounds, 0.0, 0.25f32.atan().to_degrees(), None, fov_y_deg)
}

/// The three-quarter view a bare `--gltf` opens with (front-right, above).
pub const THREE_QUARTER: (f32, f32) = (35.0, 20.0);

/// A camera orbiting the centre of `bounds`: `yaw_deg` about +Y from the
/// front (+Z; positive toward +X), `pitch_deg` above the horizon, at
/// `distance` (default: the bounding sphere fills `fov_y_deg` with a 10 %
/// margin), looking at the centre.
pub fn orbit_camera(
    bounds: &Aabb,
    yaw_deg: f32,
    pitch_deg: f32,
    distance: Option<f32>,
    fov_y_deg: f32,
) -> Camera {
    let (centre, radius) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), (bounds.extent().length() * 0.5).max(1e-3))
    };
    let distance = distance.unwrap_or_else(|| 1.1 * radius / (fov_y_deg.to_radians() * 0.5).sin());
    let mut camera = Camera::orbit(centre, yaw_deg, pitch_deg, distance, fov_y_deg);
    camera.near = (distance - radius).max(distance * 1e-3) * 0.5;
    camera
}
