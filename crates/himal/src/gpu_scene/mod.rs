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

pub mod skin;
pub mod textures;
pub mod uniforms;

/// Bounds culling, the one CPU selection of draws by their object's box:
/// the draws of `draws` whose object has a box in `bounds` that `keep`
/// (object index, box) accepts. Used by the shadow cascades, the local
/// lights' projectors and atlas, and the sky-occlusion sectors.
pub fn cull<'d, I>(
    draws: I,
    bounds: &'d [crate::scene::Aabb],
    keep: impl Fn(usize, &crate::scene::Aabb) -> bool + 'd,
) -> impl Iterator<Item = Draw> + 'd
where
    I: IntoIterator<Item = &'d Draw>,
    I::IntoIter: 'd,
{
    draws.into_iter().filter_map(move |d| {
        let i = d.object as usize;
        bounds.get(i).filter(|b| keep(i, b)).map(|_| d.clone())
    })
}

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

/// What a G-buffer pass draws ([`SceneGpu::visible`]).
#[derive(Clone, Debug, Default)]
pub struct VisibleLists {
    /// Opaque objects inside the view (early-Z pipeline, no discard).
    pub opaque: Vec<Draw>,
    /// Alpha-tested, swaying vegetation inside the view.
    pub vegetation: Vec<Draw>,
    /// glTF draws with their material.
    pub textured: Vec<(Draw, usize)>,
    /// `Some((view, calls))`: opaque and vegetation objects come from view
    /// `view` of the GPU-culled lists instead, `calls` multi-draws (V6).
    pub gpu_view: Option<(u32, u32)>,
    /// Draws of the streamed pool from the CPU twin's lists (where the
    /// GPU path is off; `passes::cull::CullPath::Cpu`).
    pub pool_calls: u32,
}

impl VisibleLists {
    /// Draw calls these lists record in `scene` (its instancing and LOD
    /// settings); textured draws are merged within runs of one material.
    pub fn draw_calls(&self, scene: &SceneGpu) -> u32 {
        scene.draw_calls(&self.opaque)
            + scene.draw_calls(&self.vegetation)
            + material_runs(&self.textured)
                .map(|(_, draws)| scene.draw_calls(&draws))
                .sum::<u32>()
            + self.gpu_view.map_or(0, |(_, calls)| calls)
            + self.pool_calls
    }
}

/// Consecutive textured draws of one material (one bind group), as
/// (material, draws): each run is drawn as an ordinary list, so its objects
/// of one mesh are instanced (glTF instancing, repeated nodes).
pub fn material_runs(textured: &[(Draw, usize)]) -> impl Iterator<Item = (usize, Vec<Draw>)> + '_ {
    let mut i = 0;
    std::iter::from_fn(move || {
        let material = textured.get(i)?.1;
        let end = (i..textured.len())
            .find(|&k| textured[k].1 != material)
            .unwrap_or(textured.len());
        let draws = textured[i..end].iter().map(|(d, _)| d.clone()).collect();
        i = end;
        Some((material, draws))
    })
}

/// Consecutive draws of one mesh with consecutive objects, as one
/// instanced draw: (the first draw, instance count).
pub fn runs(draws: &[Draw]) -> impl Iterator<Item = (&Draw, u32)> {
    let mut i = 0;
    std::iter::from_fn(move || {
        let first = draws.get(i)?;
        let mut n = 1;
        while let Some(d) = draws.get(i + n as usize) {
            let same_mesh = (d.first_index, d.index_count, d.base_vertex)
                == (first.first_index, first.index_count, first.base_vertex);
            if !(same_mesh && d.object == first.object + n) {
                break;
            }
            n += 1;
        }
        i += n as usize;
        Some((first, n))
    })
}

/// The draws of `object` in `draws` (a list in object order, as every
/// list of [`SceneGpu`] is): a binary search, not a scan.
pub fn draws_of(draws: &[Draw], object: u32) -> &[Draw] {
    entries_of(draws, object, |d| d)
}

/// The entries of `object` in `list` (object order), `draw` naming each
/// entry's draw (e.g. `(Draw, material)` of the textured list).
pub fn entries_of<T>(list: &[T], object: u32, draw: impl Fn(&T) -> &Draw) -> &[T] {
    let start = list.partition_point(|e| draw(e).object < object);
    let end = list.partition_point(|e| draw(e).object <= object);
    &list[start..end.max(start)]
}

/// Draw calls `draws` records: with instancing, one per run of
/// consecutive objects of one mesh; without, one per draw.
pub fn draw_calls(draws: &[Draw], instancing: bool) -> u32 {
    if instancing {
        runs(draws).count() as u32
    } else {
        draws.len() as u32
    }
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

/// E2 LOD selection of one frame: the eye and how levels are chosen
/// (`scale` 0: every object at LOD0; the band dithers on the GPU path
/// only, the CPU path pops).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LodView {
    /// Camera position (distances to boxes).
    pub eye: glam::Vec3,
    /// Thresholds, band and scale of the selection.
    pub selection: crate::scene::lod::Selection,
}

/// A streamed region of the objects buffer (the open world, V6): objects
/// `first_object..first_object + capacity` draw mesh `mesh`; streaming
/// writes their records ([`SceneGpu::write_objects`]) and bounds, packed
/// from the front; `passes::cull` culls them per view (on the GPU, or its
/// CPU twin where that path is off).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoolRegion {
    /// The scene mesh every object of the region draws.
    pub mesh: u32,
    /// First object record of the region.
    pub first_object: u32,
    /// Object records reserved.
    pub capacity: u32,
    /// Culled beyond this distance from the camera (m; 0: no limit).
    pub max_distance: f32,
}

/// A streamed region to reserve ([`SceneGpu::upload_with_pool`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoolSpec {
    /// The scene mesh every object of the region draws.
    pub mesh: usize,
    /// Object records to reserve.
    pub capacity: u32,
    /// Per-class distance culling (m; 0: no limit).
    pub max_distance: f32,
}

/// `Object.params.x` of an opaque object whose albedo is multiplied by
/// `params.yzw` (`OBJECT_TINTED` in `shaders/scene.wgsl`).
pub const OBJECT_TINTED: f32 = 3.0;

// scene::world sizes its upload budget by these records.
const _: () = assert!(
    std::mem::size_of::<ObjectGpu>() + std::mem::size_of::<ObjectBounds>()
        == crate::scene::world::GPU_INSTANCE_BYTES
);

/// One level of a mesh in the index buffer (E2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LodRange {
    /// First index of the level in the index buffer.
    pub first_index: u32,
    /// Indices of the level.
    pub index_count: u32,
    /// Geometric error (mesh units; 0 for LOD0).
    pub error: f32,
}

/// One indexed draw of one object.
#[derive(Clone, Debug)]
pub struct Draw {
    /// First index in the index buffer.
    pub first_index: u32,
    /// Indices drawn.
    pub index_count: u32,
    /// Offset added to each index (the mesh's first vertex).
    pub base_vertex: i32,
    /// The object record (GPU order) the draw is placed by.
    pub object: u32,
}

/// The scene uploaded: geometry, object records, draw lists, LODs, materials, skins.
pub struct SceneGpu {
    /// Every mesh's [`Vertex`] records (skinned meshes first).
    pub vertices: wgpu::Buffer,
    /// Every mesh's indices, LOD levels after LOD0.
    pub indices: wgpu::Buffer,
    /// [`ObjectGpu`] per object (GPU order), then the streamed regions.
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
    /// Skinned meshes (`passes/skin`); `None` without any.
    pub skins: Option<skin::SkinGpu>,
    /// Unique per upload: what caches of scene resources are keyed by
    /// ([`textures::MaterialGroups`]).
    pub id: u64,
}

/// The next [`SceneGpu::id`].
static NEXT_SCENE_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// The skinned meshes of `scene` with the object that poses each (the
/// first, where objects share one: a mesh has one pose).
fn skin_jobs(scene: &Scene) -> Vec<(usize, crate::scene::gltf::Animated)> {
    let mut out: Vec<(usize, crate::scene::gltf::Animated)> = Vec::new();
    for o in &scene.objects {
        let Some(a) = o.motion.as_ref().and_then(|m| m.animated.as_ref()) else {
            continue;
        };
        if a.skin.is_none() || o.mesh >= scene.meshes.len() {
            continue;
        }
        if out.iter().any(|(m, _)| *m == o.mesh) {
            log::warn!("skinned mesh {} is posed by its first object only", o.mesh);
            continue;
        }
        out.push((o.mesh, a.clone()));
    }
    out
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
        // Skinned meshes first: one range the skin pass copies into.
        let skinned = skin_jobs(scene);
        let mut order: Vec<usize> = skinned.iter().map(|(mesh, _)| *mesh).collect();
        order.extend((0..n).filter(|m| !skinned.iter().any(|(s, _)| s == m)));
        for mi in order {
            let mesh = &scene.meshes[mi];
            ranges[mi] = (
                indices.len() as u32,
                mesh.indices.len() as u32,
                vertices.len() as i32,
            );
            let mut levels = vec![LodRange {
                first_index: indices.len() as u32,
                index_count: mesh.indices.len() as u32,
                error: 0.0,
            }];
            let area = |i: &[u32]| crate::scene::lod::AreaHistogram::new(&mesh.vertices, i);
            let mut histograms = vec![area(&mesh.indices)];
            vertices.extend_from_slice(&mesh.vertices);
            indices.extend_from_slice(&mesh.indices);
            // E2: terrain-sized meshes are always near somewhere; no chain.
            if mesh.bounds.extent().max_element() <= crate::scene::lod::MAX_EXTENT {
                for lod in crate::scene::lod::lod_chain(mesh) {
                    histograms.push(area(&lod.indices));
                    levels.push(LodRange {
                        first_index: indices.len() as u32,
                        index_count: lod.indices.len() as u32,
                        error: lod.error,
                    });
                    indices.extend_from_slice(&lod.indices);
                }
            }
            lods[mi] = levels;
            area_histograms[mi] = histograms;
            mean_area[mi] = crate::scene::lod::geometric_mean_area(&mesh.vertices, &mesh.indices);
        }
        let skins = (!skinned.is_empty()).then(|| {
            let (mut sources, mut jobs, mut first_joint) = (Vec::new(), Vec::new(), 0u32);
            for (_, a) in &skinned {
                let Some((skin, bind)) = &a.skin else {
                    continue;
                };
                let joint_count = a.rig.skins[*skin].joints.len() as u32;
                sources.extend(bind.iter().map(|v| SkinVertex {
                    joints: v.joints.map(|j| j + first_joint),
                    ..*v
                }));
                jobs.push(skin::SkinJob {
                    animated: a.clone(),
                    first_joint,
                    joint_count,
                });
                first_joint += joint_count;
            }
            skin::SkinGpu::new(&ctx.device, jobs, &sources, &vertices[..sources.len()], 0)
        });
        let mut objects = Vec::with_capacity(scene.objects.len());
        let (mut draws_opaque, mut draws_vegetation) = (Vec::new(), Vec::new());
        let (mut draws_textured, mut draws_blend, mut draws_emissive) =
            (Vec::new(), Vec::new(), Vec::new());
        let (mut draws_layered, mut draws_unlit) = (Vec::new(), Vec::new());
        let mut draws_transmissive = Vec::new();
        let mut animated = Vec::new();
        let mut bounds = Vec::with_capacity(scene.objects.len());
        let mut cull_bounds = Vec::with_capacity(scene.objects.len());
        let mut object_mesh = Vec::with_capacity(scene.objects.len());
        let mut triangles = 0u64;
        for (i, object) in gpu_order(scene)
            .into_iter()
            .map(|i| &scene.objects[i])
            .enumerate()
        {
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
            // Swaying cards reach up to their amplitude (local metres,
            // scaled: a generous margin) beyond the mesh.
            let b = object.swept_bounds(&scene.meshes[object.mesh].bounds);
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
            if object.motion.is_some() {
                animated.push((i as u32, object.clone()));
            }
            let draw = Draw {
                first_index,
                index_count,
                base_vertex,
                object: i as u32,
            };
            match (scene.pbr.material_of(object.mesh), object.foliage) {
                (Some(material), _) => {
                    let m = scene.pbr.materials.get(material);
                    if m.is_some_and(|m| m.transmits()) {
                        draws_transmissive.push((draw, material));
                    } else if m
                        .is_some_and(|m| m.alpha_mode == crate::scene::gltf::AlphaMode::Blend)
                    {
                        let bounds = scene.meshes[object.mesh]
                            .bounds
                            .transform(&object.transform);
                        draws_blend.push((draw, material, bounds.center()));
                    } else {
                        if m.is_some_and(|m| m.emits()) {
                            draws_emissive.push((draw.clone(), material));
                        }
                        if m.is_some_and(|m| m.unlit) {
                            draws_unlit.push((draw.clone(), material));
                        }
                        if m.is_some_and(|m| m.layered()) {
                            draws_layered.push((draw.clone(), material));
                        }
                        draws_textured.push((draw, material));
                    }
                }
                (None, Some(_)) => draws_vegetation.push(draw),
                (None, None) => draws_opaque.push(draw),
            }
            triangles += index_count as u64 / 3;
        }
        let mut regions = Vec::with_capacity(pool.len());
        for &PoolSpec {
            mesh,
            capacity,
            max_distance,
        } in pool
        {
            if mesh >= scene.meshes.len() {
                return Err(GpuError::Other(format!(
                    "pool region names mesh {mesh} of {}",
                    scene.meshes.len()
                )));
            }
            regions.push(PoolRegion {
                mesh: mesh as u32,
                first_object: objects.len() as u32,
                capacity,
                max_distance,
            });
            let n = capacity as usize;
            objects.resize(objects.len() + n, ObjectGpu::zeroed());
            cull_bounds.resize(cull_bounds.len() + n, ObjectBounds::NONE);
            bounds.resize(bounds.len() + n, crate::scene::Aabb::EMPTY);
            object_mesh.resize(object_mesh.len() + n, mesh as u32);
        }
        if objects.is_empty() {
            objects.push(ObjectGpu::zeroed());
        }
        if indices.is_empty() {
            indices.extend([0, 0, 0]);
            vertices.push(Vertex::zeroed());
        }
        let identity: Vec<u32> = (0..objects.len() as u32).collect();
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
                draws_opaque,
                draws_vegetation,
                draws_textured,
                draws_blend,
                draws_transmissive,
                draws_emissive,
                draws_layered,
                draws_unlit,
                materials,
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
                skins,
                id: NEXT_SCENE_ID.fetch_add(1, Ordering::Relaxed),
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
            skins.update(queue, time);
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

    /// Writes object records from `first_object` on (streamed regions).
    pub fn write_objects(&self, queue: &wgpu::Queue, first_object: u32, objects: &[ObjectGpu]) {
        let offset = first_object as u64 * std::mem::size_of::<ObjectGpu>() as u64;
        queue.write_buffer(&self.objects, offset, bytemuck::cast_slice(objects));
    }

    /// Binds the shared vertex and index buffers.
    pub fn bind_geometry(&self, rp: &mut wgpu::RenderPass<'_>) {
        rp.set_vertex_buffer(0, self.vertices.slice(..));
        rp.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
    }

    /// The level `object` draws at under `lod` (E2; 0 without a chain).
    pub fn lod_level(&self, object: u32, lod: &LodView) -> u32 {
        let (Some(b), Some(&mesh)) = (
            self.cull_bounds.get(object as usize),
            self.object_mesh.get(object as usize),
        ) else {
            return 0;
        };
        let Some(levels) = self.lods.get(mesh as usize) else {
            return 0;
        };
        let mut errors = [0.0; crate::scene::lod::MAX_LODS];
        let n = levels.len().min(errors.len());
        for (e, l) in errors.iter_mut().zip(levels) {
            *e = l.error;
        }
        let d = crate::scene::lod::distance_to_box(lod.eye, b.center(), b.half_extent());
        // The CPU path pops: no band.
        let selection = crate::scene::lod::Selection {
            band: 0.0,
            ..lod.selection
        };
        let radius = b.half_extent().length();
        crate::scene::lod::choice_for(
            d,
            b.center[3],
            radius,
            b.half_extent[3],
            &errors[..n],
            &selection,
        )
        .0
    }

    /// `draws` at this frame's LOD (E2): each draw's index range replaced
    /// by its object's level; borrowed unchanged when LOD is off or no
    /// mesh has a chain.
    pub fn at_lod<'d>(&self, draws: &'d [Draw]) -> std::borrow::Cow<'d, [Draw]> {
        let lod = self.lod.lock().map(|l| *l).unwrap_or_default();
        if !lod.selection.enabled() || !self.has_lods {
            return std::borrow::Cow::Borrowed(draws);
        }
        let at = |d: &Draw| {
            let level = self.lod_level(d.object, &lod) as usize;
            let range = (self.object_mesh.get(d.object as usize))
                .and_then(|&m| self.lods.get(m as usize)?.get(level));
            match range {
                Some(r) if level > 0 => Draw {
                    first_index: r.first_index,
                    index_count: r.index_count,
                    ..d.clone()
                },
                _ => d.clone(),
            }
        };
        std::borrow::Cow::Owned(draws.iter().map(at).collect())
    }

    /// `draws` by the level [`Self::draw_list`] draws each at this frame
    /// (`--view lod`); all at 0 when LOD is off.
    pub fn split_levels(&self, draws: &[Draw]) -> [Vec<Draw>; crate::scene::lod::MAX_LODS] {
        let lod = self.lod.lock().map(|l| *l).unwrap_or_default();
        let mut out: [Vec<Draw>; crate::scene::lod::MAX_LODS] = Default::default();
        for d in draws {
            let level = if lod.selection.enabled() && self.has_lods {
                self.lod_level(d.object, &lod) as usize
            } else {
                0
            };
            out[level.min(out.len() - 1)].push(d.clone());
        }
        out
    }

    /// Draw calls [`Self::draw_list`] records for `draws`.
    pub fn draw_calls(&self, draws: &[Draw]) -> u32 {
        draw_calls(&self.at_lod(draws), self.instancing())
    }

    /// Records `draws` (geometry bound) at this frame's LOD: with
    /// instancing one draw per run of consecutive objects of one mesh and
    /// level (V6), else one draw per object.
    pub fn draw_list(&self, rp: &mut wgpu::RenderPass<'_>, draws: &[Draw]) {
        let draws = self.at_lod(draws);
        let draws = &draws[..];
        if self.instancing.load(Ordering::Relaxed) {
            for (d, n) in runs(draws) {
                let indices = d.first_index..d.first_index + d.index_count;
                rp.draw_indexed(indices, d.base_vertex, d.object..d.object + n);
            }
        } else {
            for d in draws {
                let indices = d.first_index..d.first_index + d.index_count;
                rp.draw_indexed(indices, d.base_vertex, d.object..d.object + 1);
            }
        }
    }

    /// Whether draws merge into instanced ones (V6).
    pub fn instancing(&self) -> bool {
        self.instancing.load(Ordering::Relaxed)
    }

    /// The G-buffer's lists: every object (`view` None: probe cubes) or
    /// those whose bounds may be inside the frustum `view` (the camera).
    /// `gpu_view`: opaque and vegetation objects are culled on the GPU
    /// (V6, `passes::cull`; view, calls), only glTF draws here.
    pub fn visible(&self, view: Option<glam::Mat4>, gpu_view: Option<(u32, u32)>) -> VisibleLists {
        let Some(vp) = view else {
            return VisibleLists {
                opaque: self.draws_opaque.clone(),
                vegetation: self.draws_vegetation.clone(),
                textured: self.draws_textured.clone(),
                gpu_view: None,
                pool_calls: 0,
            };
        };
        let inside = |i: usize| self.bounds.get(i).is_some_and(|b| !b.outside_clip(vp));
        let keep = |d: &&Draw| inside(d.object as usize);
        let cpu = |draws: &[Draw]| match gpu_view {
            Some(_) => Vec::new(),
            None => draws.iter().filter(keep).cloned().collect(),
        };
        VisibleLists {
            opaque: cpu(&self.draws_opaque),
            vegetation: cpu(&self.draws_vegetation),
            textured: (self.draws_textured.iter())
                .filter(|(d, _)| inside(d.object as usize))
                .cloned()
                .collect(),
            gpu_view,
            pool_calls: 0,
        }
    }

    /// Binds the geometry and records the opaque objects, glTF ones
    /// included (shadow casters; their alpha is not tested there).
    pub fn draw_opaque(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_opaque);
        for (d, _) in &self.draws_textured {
            self.draw_list(rp, std::slice::from_ref(d));
        }
    }

    /// Binds the geometry and records the vegetation (set a `VEGETATION` pipeline first).
    pub fn draw_vegetation(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_vegetation);
    }

    /// Records every draw, vegetation as plain cards (no alpha test, no
    /// sway); passes that need the true vegetation shape draw the two lists.
    pub fn draw_all(&self, rp: &mut wgpu::RenderPass<'_>) {
        self.bind_geometry(rp);
        self.draw_list(rp, &self.draws_opaque);
        self.draw_list(rp, &self.draws_vegetation);
    }
}

/// `ObjectGpu::params` of an object: its foliage, zero for opaque objects.
fn params(object: &Object) -> [f32; 4] {
    object.foliage.map_or([0.0; 4], |f| f.params())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(mesh: u32, object: u32) -> Draw {
        Draw {
            first_index: mesh * 36,
            index_count: 36,
            base_vertex: 0,
            object,
        }
    }

    #[test]
    fn runs_merge_consecutive_objects_of_one_mesh_only() {
        // Objects 0-2 of mesh 0, a gap (4), mesh 1 at 5, then 6 of mesh 0.
        let draws = [
            draw(0, 0),
            draw(0, 1),
            draw(0, 2),
            draw(0, 4),
            draw(1, 5),
            draw(0, 6),
        ];
        let got: Vec<(u32, u32)> = runs(&draws).map(|(d, n)| (d.object, n)).collect();
        assert_eq!(got, vec![(0, 3), (4, 1), (5, 1), (6, 1)]);
        assert_eq!(draw_calls(&draws, true), 4);
        assert_eq!(draw_calls(&draws, false), 6);
        assert_eq!(draw_calls(&[], true), 0);
        let objects = |o| {
            draws_of(&draws, o)
                .iter()
                .map(|d| d.object)
                .collect::<Vec<_>>()
        };
        assert_eq!(objects(4), vec![4]);
        assert_eq!(objects(3), Vec::<u32>::new());
        assert_eq!(objects(7), Vec::<u32>::new());
    }
}
