//! The scene's meshes and object transforms on the GPU: one vertex buffer,
//! one index buffer, one storage buffer of objects (instance index -> object
//! through `instances`).
//! Draws come in two lists: opaque objects (early-Z, no discard) and
//! vegetation (alpha-tested, swaying, double-sided), each drawn with its own
//! pipeline. Moving objects are rewritten every frame by [`SceneGpu::update_objects`].

use std::sync::atomic::{AtomicBool, Ordering};

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::gpu::{GpuContext, GpuError};
use crate::scene::gltf::SkinVertex;
use crate::scene::{Object, Scene, Vertex};

pub mod impostor;
pub mod ripple;
pub mod skin;
pub mod textures;
pub mod tree_ao;
pub mod uniforms;

mod draws;
mod lod;
mod pool;
pub mod trees;

pub use draws::{Draw, VisibleLists, cull, draw_calls, draws_of, entries_of, material_runs, runs};
pub use lod::{LodRange, LodView};
pub use pool::{PoolRegion, PoolSpec};

/// The GPU order of `scene`'s objects (GPU index -> scene index). Moving
/// objects come first, in scene order (the first is the default hero);
/// static objects follow grouped by mesh and, within a mesh, along a Morton
/// curve of their position on the ground plane, so that the objects one
/// culled list draws are mostly consecutive and merge into instanced draws
/// ([`SceneGpu::draw_list`], V6). Every consumer indexed by object (the
/// upload, shadow casters, sky-occlusion sectors) uses this order.
pub fn gpu_order(scene: &Scene) -> Vec<usize> {
    let b = scene.bounds;
    let extent = (b.max - b.min).max(glam::Vec3::splat(1e-3));
    let morton = |p: glam::Vec3| {
        let q = |v: f32| ((v.clamp(0.0, 1.0) * 65535.0) as u32) & 0xffff;
        let spread = |mut x: u32| {
            x = (x | (x << 8)) & 0x00ff_00ff;
            x = (x | (x << 4)) & 0x0f0f_0f0f;
            x = (x | (x << 2)) & 0x3333_3333;
            (x | (x << 1)) & 0x5555_5555
        };
        let n = (p - b.min) / extent;
        spread(q(n.x)) | (spread(q(n.z)) << 1)
    };
    let mut order: Vec<usize> = (0..scene.objects.len()).collect();
    // Stable: equal keys keep scene order, so the order is deterministic.
    order.sort_by_key(|&i| {
        let o = &scene.objects[i];
        match o.motion {
            Some(_) => (0u8, 0usize, 0u32),
            None => (1, o.mesh, morton(o.transform.w_axis.truncate())),
        }
    });
    order
}

/// Twin of `Object` in `shaders/scene.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ObjectGpu {
    /// Object to world at this frame's time (column-major).
    pub model: [[f32; 4]; 4],
    /// Inverse transpose of `model` (normals).
    pub normal_matrix: [[f32; 4]; 4],
    /// `model` at the previous frame's time (motion vectors).
    pub prev_model: [[f32; 4]; 4],
    /// x alpha pattern (0 opaque, 1 grass, 2 leaves), y sway amplitude (m),
    /// zw sway weight of leaves (local bottom y, 1 / height); see [`crate::scene::Foliage`].
    pub params: [f32; 4],
}

impl ObjectGpu {
    /// An object at `model` now that was at `prev_model` in the previous frame.
    pub fn new(model: glam::Mat4, prev_model: glam::Mat4, params: [f32; 4]) -> Self {
        ObjectGpu {
            model: model.to_cols_array_2d(),
            normal_matrix: model.inverse().transpose().to_cols_array_2d(),
            prev_model: prev_model.to_cols_array_2d(),
            params,
        }
    }
}

/// Twin of `Bounds` in `passes/cull/cull.wgsl`: centre (w: the object's
/// triangle size in metres, E2) and half extent (w: its linear scale) of
/// its world box.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct ObjectBounds {
    /// xyz: world box centre; w: triangle size (m).
    pub center: [f32; 4],
    /// xyz: world box half extent; w: linear scale.
    pub half_extent: [f32; 4],
}

impl ObjectBounds {
    /// Bounds no view keeps: every plane with a normal has the box wholly
    /// behind it (a pool slot streaming has not filled).
    pub const NONE: ObjectBounds = ObjectBounds {
        center: [0.0; 4],
        half_extent: [-1e30, -1e30, -1e30, 0.0],
    };

    /// `size`: the object's triangle size (m), `scale` its linear scale (w
    /// of the half extent: geometric errors). An empty box becomes a point
    /// at the origin (it draws nothing).
    pub fn new(b: &crate::scene::Aabb, size: f32, scale: f32) -> Self {
        if b.is_empty() {
            return Self::zeroed();
        }
        Self {
            center: b.center().extend(size).to_array(),
            half_extent: (b.extent() * 0.5).extend(scale).to_array(),
        }
    }

    /// The box's centre.
    pub fn center(&self) -> glam::Vec3 {
        glam::Vec3::from_slice(&self.center[..3])
    }

    /// The box's half extent.
    pub fn half_extent(&self) -> glam::Vec3 {
        glam::Vec3::from_slice(&self.half_extent[..3])
    }
}

/// `Object.params.x` of an opaque object whose albedo is multiplied by
/// `params.yzw` (`OBJECT_TINTED` in `shaders/scene.wgsl`).
pub const OBJECT_TINTED: f32 = 3.0;

// scene::world sizes its upload budget by these records.
const _: () = assert!(
    std::mem::size_of::<ObjectGpu>() + std::mem::size_of::<ObjectBounds>()
        == crate::scene::world::GPU_INSTANCE_BYTES
);

/// The scene uploaded: geometry, object records, draw lists, LODs, materials, skins.
pub struct SceneGpu {
    /// Every mesh's [`Vertex`] records (skinned meshes first).
    pub vertices: wgpu::Buffer,
    /// Every mesh's indices, LOD levels after LOD0.
    pub indices: wgpu::Buffer,
    /// [`ObjectGpu`] per object (GPU order), then the streamed regions,
    /// then the trees' bone records (`tree_layout`).
    pub objects: wgpu::Buffer,
    /// Instance -> object for draws recorded on the CPU: the identity, so a
    /// draw of instances `k..k+n` draws objects `k..k+n` (the GPU-culled
    /// passes bind `passes::cull`'s lists instead).
    pub instances: wgpu::Buffer,
    /// Opaque objects (G-buffer and shadow pipelines without a discard).
    pub draws_opaque: Vec<Draw>,
    /// Alpha-tested, swaying vegetation (the `VEGETATION` pipelines).
    pub draws_vegetation: Vec<Draw>,
    /// glTF objects with their material index (the textured G-buffer path).
    pub draws_textured: Vec<(Draw, usize)>,
    /// glTF alpha BLEND objects with their material and world bounds'
    /// centre (drawn by `forward.blend`, back to front; not in the G-buffer).
    pub draws_blend: Vec<(Draw, usize, glam::Vec3)>,
    /// glTF objects with a KHR_materials_transmission material (any alpha
    /// mode), drawn by `forward.transmission` over a copy of the opaque
    /// scene they refract; not in the G-buffer, not shadow casters.
    pub draws_transmissive: Vec<(Draw, usize)>,
    /// Opaque / mask glTF objects whose material emits (`forward.emissive`);
    /// each is in `draws_textured` too.
    pub draws_emissive: Vec<(Draw, usize)>,
    /// Opaque / mask glTF objects with a clearcoat or sheen layer
    /// (`forward.layers`); each is in `draws_textured` too.
    pub draws_layered: Vec<(Draw, usize)>,
    /// Opaque / mask glTF objects with an unlit material (`forward.unlit`);
    /// each is in `draws_textured` too.
    pub draws_unlit: Vec<(Draw, usize)>,
    /// Their textures and material uniforms; `None` without glTF materials.
    pub materials: Option<textures::MaterialTextures>,
    /// Per object (GPU order): the material of a glTF MASK or BLEND (not
    /// transmissive) object, which casts shadows alpha-tested
    /// (`passes/shadows/depth_masked.wgsl`); `None` for the rest.
    pub alpha_casters: Vec<Option<usize>>,
    /// Moving objects with their index into `objects`, rewritten per frame.
    pub animated: Vec<(u32, Object)>,
    /// World bounds of each object over all time (GPU order): culling.
    pub bounds: Vec<crate::scene::Aabb>,
    /// The same as centre and half extent, `w` of the centre the object's
    /// triangle size (E2): what the GPU culls and selects LODs with, and the
    /// CPU path's LOD selection too.
    pub cull_bounds: Vec<ObjectBounds>,
    /// Mesh of each object (GPU order).
    pub object_mesh: Vec<u32>,
    /// E2: per mesh its levels, LOD0 first.
    pub lods: Vec<Vec<LodRange>>,
    /// Some mesh has more than one level (checked once, at upload).
    pub has_lods: bool,
    /// E2 statistics: per mesh and level, its triangles' areas.
    pub area_histograms: Vec<Vec<crate::scene::lod::AreaHistogram>>,
    /// E2: this frame's LOD selection for draws recorded on the CPU (set by
    /// `frame::plan`; scale 0 = LOD0 everywhere).
    pub lod: std::sync::Mutex<LodView>,
    /// Streamed regions after the scene's own objects (empty: none).
    pub pool: Vec<PoolRegion>,
    /// Per mesh: first index, index count and base vertex of LOD0.
    pub mesh_ranges: Vec<(u32, u32, i32)>,
    /// Triangles of every object at LOD0.
    pub triangles: u64,
    /// GPU bytes of the upload (geometry, objects, materials).
    pub bytes: u64,
    /// V6: merge runs of consecutive objects into instanced draws
    /// (`FrameSettings::instancing`, set per frame).
    pub instancing: AtomicBool,
    /// Whether vegetation draws (`FrameSettings::vegetation`, set per frame).
    pub vegetation: AtomicBool,
    /// Per object (GPU order): foliage or a tree trunk, what
    /// `--vegetation off` skips.
    pub vegetation_objects: Vec<bool>,
    /// Skinned meshes and meshes with animated morph weights
    /// (`passes/skin`); `None` without any.
    pub skins: Option<skin::SkinGpu>,
    /// The deformed vertices' previous-frame positions (`shaders/deform.wgsl`:
    /// header, then the deformed meshes' from vertex 0, written by
    /// `passes/skin`).
    pub deform: wgpu::Buffer,
    /// A `deform_prev` header of count 0: bound with `--deform-motion off`.
    pub no_deform: wgpu::Buffer,
    /// Unique per upload: what caches of scene resources are keyed by
    /// ([`textures::MaterialGroups`]).
    pub id: u64,
    /// V3: the trees' impostor atlases (a one-texel fallback without trees).
    pub impostor_atlas: impostor::ImpostorAtlas,
    /// Per mesh: its last level is an impostor (`--impostors off` drops it).
    pub impostor_mesh: Vec<bool>,
    /// Whether impostor levels draw (`FrameSettings::impostors`, set per
    /// frame; off: LOD2 stays to the end).
    pub impostors: AtomicBool,
    /// V4: the trees' occlusion volumes and the list of trees the decal draws.
    pub tree_ao: tree_ao::TreeAoGpu,
    /// V2: the trees' slots and rigs, and where their bone records start
    /// in `objects` (after every object and streamed region).
    pub tree_layout: trees::TreeLayout,
    /// V2: their GPU buffers (`None`: no trees).
    pub tree_buffers: Option<trees::TreeBuffers>,
    /// V2: the grass ripple grid around the camera (`shaders/ripple.wgsl`;
    /// one cell without grass), stepped by `vegetation.ripple`.
    pub ripple: wgpu::Buffer,
    /// Its cells per side.
    pub ripple_n: i32,
}

/// The next [`SceneGpu::id`].
static NEXT_SCENE_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// The deformed meshes of `scene` (skinned, or with animated morph
/// weights) with the object that deforms each (the first, where objects
/// share one: a mesh has one pose).
fn deform_jobs(scene: &Scene) -> Vec<(usize, crate::scene::gltf::Animated)> {
    let mut out: Vec<(usize, crate::scene::gltf::Animated)> = Vec::new();
    for o in &scene.objects {
        let Some(a) = o.motion.as_ref().and_then(|m| m.animated.as_ref()) else {
            continue;
        };
        if (a.skin.is_none() && a.morph.is_none()) || o.mesh >= scene.meshes.len() {
            continue;
        }
        if out.iter().any(|(m, _)| *m == o.mesh) {
            log::warn!("deformed mesh {} is posed by its first object only", o.mesh);
            continue;
        }
        out.push((o.mesh, a.clone()));
    }
    out
}

/// `passes/skin`'s buffers for `jobs` (meshes of `scene`, drawn from vertex
/// 0 in this order in `vertices`).
fn deform_gpu(
    device: &wgpu::Device,
    scene: &Scene,
    jobs: &[(usize, crate::scene::gltf::Animated)],
    vertices: &[Vertex],
) -> skin::SkinGpu {
    let (mut sources, mut info, mut deltas) = (Vec::new(), Vec::new(), Vec::new());
    let (mut out, mut first_joint, mut first_weight) = (Vec::new(), 0u32, 0u32);
    let v3 = |v: &[f32]| [v[0], v[1], v[2]];
    for (mesh, a) in jobs {
        let drawn = &scene.meshes[*mesh].vertices;
        let (joint_count, bind): (u32, Vec<SkinVertex>) = match &a.skin {
            Some((skin, bind)) => (
                a.rig.skins[*skin].joints.len() as u32,
                (bind.iter())
                    .map(|v| SkinVertex {
                        joints: v.joints.map(|j| j + first_joint),
                        ..*v
                    })
                    .collect(),
            ),
            // Only morphed: no weight, so not skinned.
            None => (0, drawn.iter().map(SkinVertex::unskinned).collect()),
        };
        let targets = a.morph.as_ref().map_or(0, |m| m.targets.len() as u32);
        for (i, mut s) in bind.into_iter().enumerate() {
            match &a.morph {
                Some(m) => {
                    let (p, n, t) = m.base(i, (v3(&s.position), v3(&s.normal), v3(&s.tangent)));
                    s.position[..3].copy_from_slice(&p);
                    s.normal[..3].copy_from_slice(&n);
                    s.tangent[..3].copy_from_slice(&t);
                    let first = deltas.len() as u32;
                    info.push([first, targets, first_weight, 0].map(f32::from_bits));
                    m.gpu_deltas(i, &mut deltas);
                }
                None => info.push([0.0; 4]),
            }
            sources.push(s);
        }
        out.push(skin::SkinJob {
            animated: a.clone(),
            first_joint,
            joint_count,
            first_weight,
            target_count: targets,
        });
        first_joint += joint_count;
        first_weight += 2 * targets;
    }
    info.extend(deltas);
    let rest = &vertices[..sources.len().min(vertices.len())];
    skin::SkinGpu::new(device, out, (&sources, &info), rest, 0)
}

/// Vertex attributes of [`Vertex`], locations as in gbuffer.wgsl.
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 7] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2, 4 => Float32x4, 5 => Float32x4,
    6 => Float32x2
];

/// The vertex buffer layout of [`Vertex`] (stride 88 bytes).
pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

impl SceneGpu {
    /// Uploads `scene` with no streamed regions.
    pub fn upload(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        Self::upload_with_pool(ctx, scene, &[])
    }

    /// [`Self::upload`] with streamed regions after the scene's objects,
    /// empty until written.
    pub fn upload_with_pool(
        ctx: &GpuContext,
        scene: &Scene,
        pool: &[PoolSpec],
    ) -> Result<Self, GpuError> {
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let n = scene.meshes.len();
        let mut ranges = vec![(0, 0, 0); n];
        let mut lods = vec![Vec::new(); n];
        let mut mean_area = vec![0.0; n];
        let mut area_histograms = vec![Vec::new(); n];
        // Deformed meshes first: one range the skin pass writes and copies
        // into (`deform` too).
        let deform_jobs = deform_jobs(scene);
        let mut placed = vec![false; n];
        let mut order: Vec<usize> = Vec::with_capacity(n);
        for m in deform_jobs.iter().map(|(m, _)| *m).chain(0..n) {
            if m < n && !placed[m] {
                placed[m] = true;
                order.push(m);
            }
        }
        let deformed_count: usize = (deform_jobs.iter())
            .map(|(m, _)| scene.meshes[*m].vertices.len())
            .sum();
        for mi in order {
            let mesh = &scene.meshes[mi];
            ranges[mi] = (
                indices.len() as u32,
                mesh.indices.len() as u32,
                vertices.len() as i32,
            );
            vertices.extend_from_slice(&mesh.vertices);
            let (levels, histograms) = lod::append_levels(mesh, &mut indices);
            lods[mi] = levels;
            area_histograms[mi] = histograms;
            mean_area[mi] = crate::scene::lod::geometric_mean_area(&mesh.vertices, &mesh.indices);
        }
        let skins = (!deform_jobs.is_empty())
            .then(|| deform_gpu(&ctx.device, scene, &deform_jobs, &vertices));
        // The deformed range: the skinned and morphed meshes, from vertex 0.
        let deformed = deformed_count.min(vertices.len());
        let mut deform: Vec<[f32; 4]> = vertices[..deformed]
            .iter()
            .map(|v| [v.position[0], v.position[1], v.position[2], 1.0])
            .collect();
        deform.insert(0, skin::deform_header(0, deformed as u32));
        let mut objects = Vec::with_capacity(scene.objects.len());
        let mut lists = draws::DrawLists::default();
        let mut animated = Vec::new();
        let mut bounds = Vec::with_capacity(scene.objects.len());
        let mut cull_bounds = Vec::with_capacity(scene.objects.len());
        let mut object_mesh = Vec::with_capacity(scene.objects.len());
        let mut vegetation_objects = Vec::with_capacity(scene.objects.len());
        let mut alpha_casters = Vec::with_capacity(scene.objects.len());
        let mut triangles = 0u64;
        // V4: each tree's leaves object (its impostor layer names its volume).
        let volume_of: Vec<Option<u32>> = (scene.meshes.iter())
            .map(crate::scene::tree::impostor_level::layer_of)
            .map(|l| l.filter(|&l| (l as usize) < scene.ao_volumes.len()))
            .collect();
        let mut trees = Vec::new();
        let mut placed = Vec::with_capacity(scene.objects.len());
        for (i, si) in gpu_order(scene).into_iter().enumerate() {
            let object = &scene.objects[si];
            placed.push((i, si));
            let Some(&(first_index, index_count, base_vertex)) = ranges.get(object.mesh) else {
                return Err(GpuError::Other(format!(
                    "object \"{}\" names mesh {} of {}",
                    object.name,
                    object.mesh,
                    ranges.len()
                )));
            };
            let m = object.transform;
            objects.push(ObjectGpu::new(m, m, params(object)));
            if let Some(Some(v)) = volume_of.get(object.mesh) {
                trees.push([i as u32, *v]);
            }
            // Swaying cards reach up to their amplitude (local metres,
            // scaled: a generous margin) beyond the mesh.
            let b = object.swept_bounds(&scene.meshes[object.mesh].bounds);
            // V2: a tree's bend stays out of its box: E2 measures LOD
            // distances to the box, and its switches must not move.
            let sway = object.foliage.map_or(0.0, |f| f.sway)
                * object
                    .transform
                    .to_scale_rotation_translation()
                    .0
                    .max_element();
            let margin = glam::Vec3::splat(sway);
            let b = crate::scene::Aabb::new(b.min - margin, b.max + margin);
            let size = crate::scene::lod::object_size(
                mean_area.get(object.mesh).copied().unwrap_or(0.0),
                &object.transform,
            );
            let scale = crate::scene::lod::linear_scale(&object.transform);
            cull_bounds.push(ObjectBounds::new(&b, size, scale));
            bounds.push(b);
            object_mesh.push(object.mesh as u32);
            vegetation_objects.push(object.is_vegetation(&scene.meshes));
            alpha_casters.push(alpha_caster(scene, object));
            if object.motion.is_some() {
                animated.push((i as u32, object.clone()));
            }
            let draw = Draw {
                first_index,
                index_count,
                base_vertex,
                object: i as u32,
            };
            lists.push(scene, object, draw);
            triangles += index_count as u64 / 3;
        }
        let regions = pool::reserve(
            pool,
            scene.meshes.len(),
            &mut objects,
            &mut cull_bounds,
            &mut bounds,
            &mut object_mesh,
        )?;
        if objects.is_empty() {
            objects.push(ObjectGpu::zeroed());
        }
        if indices.is_empty() {
            indices.extend([0, 0, 0]);
            vertices.push(Vertex::zeroed());
        }
        let identity: Vec<u32> = (0..objects.len() as u32).collect();
        // V2: the trees' bone records after every object (never drawn).
        let tree_layout = trees::layout(scene, &placed, &mut objects);
        let tree_buffers = trees::TreeBuffers::new(&ctx.device, &tree_layout);
        // V2: grass and bushes (foliage that is no tree's) bend with the ripple.
        let rigged = trees::mesh_rigs(scene);
        let grass = (scene.objects.iter())
            .any(|o| o.foliage.is_some() && rigged.get(o.mesh).is_some_and(|r| r.is_none()));
        let ripple_n = if grass { ripple::RIPPLE_N } else { 1 };
        let mut ripple = vec![0u8; ripple::ripple_bytes(ripple_n) as usize];
        let header = ripple::header(ripple_n, glam::Vec3::ZERO, 0, 0.0);
        ripple[..32].copy_from_slice(bytemuck::bytes_of(&header));
        let materials = if scene.pbr.materials.is_empty() {
            None
        } else {
            Some(textures::MaterialTextures::upload(ctx, &scene.pbr)?)
        };
        let bytes = materials.as_ref().map_or(0, |m| m.bytes)
            + (std::mem::size_of_val(vertices.as_slice())
                + std::mem::size_of_val(indices.as_slice())
                + std::mem::size_of_val(objects.as_slice())
                + std::mem::size_of_val(identity.as_slice())) as u64;
        ctx.scoped("scene upload", || {
            let init = |label, contents: &[u8], usage| {
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some(label),
                        contents,
                        usage,
                    })
            };
            SceneGpu {
                vertices: init(
                    "scene.vertices",
                    bytemuck::cast_slice(&vertices),
                    // The skin pass copies the posed vertices in.
                    wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                ),
                indices: init(
                    "scene.indices",
                    bytemuck::cast_slice(&indices),
                    wgpu::BufferUsages::INDEX,
                ),
                objects: init(
                    "scene.objects",
                    bytemuck::cast_slice(&objects),
                    wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                ),
                instances: init(
                    "scene.instances",
                    bytemuck::cast_slice(&identity),
                    wgpu::BufferUsages::STORAGE,
                ),
                draws_opaque: lists.opaque,
                draws_vegetation: lists.vegetation,
                draws_textured: lists.textured,
                draws_blend: lists.blend,
                draws_transmissive: lists.transmissive,
                draws_emissive: lists.emissive,
                draws_layered: lists.layered,
                draws_unlit: lists.unlit,
                materials,
                alpha_casters,
                animated,
                bounds,
                cull_bounds,
                object_mesh,
                has_lods: lods.iter().any(|l| l.len() > 1),
                lods,
                area_histograms,
                lod: std::sync::Mutex::new(LodView::default()),
                pool: regions,
                mesh_ranges: ranges,
                triangles,
                bytes,
                instancing: AtomicBool::new(true),
                vegetation: AtomicBool::new(true),
                vegetation_objects,
                skins,
                deform: init(
                    "scene.deform",
                    bytemuck::cast_slice(&deform),
                    wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                ),
                no_deform: init(
                    "scene.no_deform",
                    bytemuck::cast_slice(&[skin::deform_header(0, 0)]),
                    wgpu::BufferUsages::STORAGE,
                ),
                id: NEXT_SCENE_ID.fetch_add(1, Ordering::Relaxed),
                impostor_atlas: impostor::ImpostorAtlas::upload(
                    &ctx.device,
                    &ctx.queue,
                    &scene.impostors,
                ),
                impostor_mesh: (scene.meshes.iter())
                    .map(crate::scene::tree::impostor_level::has_impostor)
                    .collect(),
                impostors: AtomicBool::new(true),
                tree_ao: tree_ao::TreeAoGpu::upload(
                    &ctx.device,
                    &ctx.queue,
                    &scene.ao_volumes,
                    &trees,
                ),
                tree_layout,
                tree_buffers,
                ripple: init(
                    "scene.ripple",
                    &ripple,
                    wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC,
                ),
                ripple_n,
            }
        })
    }

    /// Writes the transforms of moving objects at `time` (s), with
    /// `prev_model` at `prev_time`, so motion vectors cover the movement.
    /// Static objects keep `prev_model = model` from the upload.
    pub fn update_objects(&self, queue: &wgpu::Queue, time: f32, prev_time: f32) {
        for (i, object) in &self.animated {
            let gpu = ObjectGpu::new(
                object.transform_at(time),
                object.transform_at(prev_time),
                params(object),
            );
            let offset = *i as u64 * std::mem::size_of::<ObjectGpu>() as u64;
            queue.write_buffer(&self.objects, offset, bytemuck::bytes_of(&gpu));
        }
        if let Some(skins) = &self.skins {
            skins.update(queue, time, prev_time);
        }
    }

    /// The `deform_prev` buffer the G-buffer binds: the deformed vertices'
    /// previous-frame positions (`on`), else a header of count 0.
    pub fn deform_prev(&self, on: bool) -> &wgpu::Buffer {
        match on {
            true => &self.deform,
            false => &self.no_deform,
        }
    }

    /// Plays glTF animation `name` on the uploaded objects whose file has
    /// it (`None`: every animated object holds its rest pose), as
    /// [`Scene::set_animation`] does on a scene; nothing is re-uploaded.
    pub fn set_animation(&mut self, name: Option<&str>) {
        for (_, o) in &mut self.animated {
            if let Some(a) = o.motion.as_mut().and_then(|m| m.animated.as_mut()) {
                a.play(name);
            }
        }
        for job in self.skins.iter_mut().flat_map(|s| &mut s.jobs) {
            job.animated.play(name);
        }
    }
}

/// The material of `object` when it casts shadows alpha-tested: a glTF
/// MASK or BLEND material that does not transmit (transmissive surfaces cast
/// nothing, docs/gltf.md).
fn alpha_caster(scene: &Scene, object: &Object) -> Option<usize> {
    let material = scene.pbr.material_of(object.mesh)?;
    let m = scene.pbr.materials.get(material)?;
    let alpha = !matches!(m.alpha_mode, crate::scene::gltf::AlphaMode::Opaque);
    (alpha && !m.transmits()).then_some(material)
}

/// `ObjectGpu::params` of an object: its foliage, zero for opaque objects.
fn params(object: &Object) -> [f32; 4] {
    object.foliage.map_or([0.0; 4], |f| f.params())
}
