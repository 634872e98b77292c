//! Scene description: meshes, materials, cameras, TOML scene files, procedural demo world,
//! the streamed open world ([`world`]).
//!
//! A [`Scene`] is a flat list of [`Object`]s (a mesh index and a transform),
//! the meshes they share, named cameras and the sun. Materials are baked into
//! the vertices (`color`, `surface`) when meshes are built, so a mesh exists
//! once per (primitive parameters, material) pair and the height field can
//! blend materials per vertex.
//!
//! # Scene files (TOML)
//!
//! Units are metres and degrees; the world is right-handed with Y up.
//! Unknown keys are errors, and every error names the file and `line:column`.
//!
//! ```toml
//! [sun]                        # optional; defaults shown
//! time = "14:00"               # "HH:MM" (24 h, local solar time) or hours as a number, in [0, 24)
//! latitude = 45.0              # degrees, [-90, 90]
//! day_of_year = 172            # 1..=366
//! turbidity = 3.0              # sky haze, [1, 10]
//!
//! [[material]]
//! name = "plaster"             # unique
//! albedo = [0.85, 0.80, 0.70]  # sRGB-encoded 0..1 (converted to linear), or
//! # albedo_linear = [...]      # linear 0..1; give exactly one of the two
//! glossiness = 0.3             # [0, 1], default 0.5
//! reflectance = 0.04           # [0, 1], specular F0 of a dielectric, default 0.04
//! metallic = 0.0               # [0, 1], default 0 (metals: albedo is their F0 colour)
//! anisotropy = 0.0             # [0, 1], default 0
//! ao = 1.0                     # [0, 1], baked ambient occlusion, default 1
//!
//! [[object]]
//! name = "house"               # unique
//! primitive = "box"            # plane | box | sphere | cylinder | prism | heightfield | grass | bush | tree
//! material = "plaster"
//! position = [0, 0, 0]         # default origin
//! rotation = [0, 30, 0]        # Euler degrees [x, y, z], R = Ry * Rx * Rz (roll, then pitch, then yaw)
//! scale = 1.0                  # number or [x, y, z], positive
//! size = [6, 3, 4]             # primitive parameters, see below
//! snap_to_ground = true        # put the lowest point on the height field (see below)
//! rest_on = "other"            # or put the lowest point on top of an earlier object
//! repeat = { count = 4, step = [2, 0, 0] }  # copies, `step` in the object's rotated frame
//! orbit = { radius = 4.0, period = 12.0, phase = 0.0, turn = false }  # moves over time, see below
//! ```
//!
//! Primitives (all centred on their local origin):
//! - `plane`: `size = [x, z]`, `segments` (quads per side, default 1); faces +Y.
//! - `box`: `size = [x, y, z]`.
//! - `sphere`: `radius`, `segments` (around, default 48), `rings` (pole to pole, default segments / 2).
//! - `cylinder`: `radius`, `height`, `segments` (default 32); axis Y, capped.
//! - `prism`: roof, `size = [length x, height y, depth z]`, ridge along X;
//!   optional `gable_material` for the two end triangles (default `material`).
//! - `heightfield`: `size = [x, z]`, `resolution` (vertices per side, >= 2) and either
//!   `noise = { seed, octaves, frequency, amplitude, ridged, lacunarity, gain, warp,
//!   erosion, flat_radius, valley_radius, floor_amplitude }` (see [`TerrainNoise`]) or
//!   `png = "relative/to/scene.png"` (grayscale, 16-bit recommended; column 0 at -x,
//!   row 0 at -z; `resolution` optional, resamples) with `height_scale` (metres at white).
//!   `layers = [{ material, min_height, max_height, min_slope, max_slope, blend,
//!   slope_blend, jitter }]`: slopes in degrees from horizontal, `blend` in metres,
//!   `slope_blend` in degrees, `jitter` metres of noise on the height test.
//!   `material` (if given) is the base layer, otherwise the first layer is;
//!   the base covers everything and later layers are painted over it in order.
//!   `albedo_variation` (0..1) adds low-frequency brightness variation.
//!   A height field may be moved, yawed and scaled but not pitched or rolled.
//! - `grass`: a field of crossed, alpha-tested cards over `size = [x, z]`:
//!   `density` (clumps per m², default 30; one clump per cell of a jittered
//!   grid, inside a ragged rounded rectangle), `height` (mean card height, default 0.3 m, 0.75..1.25 per clump),
//!   `width` (mean card width, default 0.15 m), `cards` (crossed cards per
//!   clump, 1..=4, default 3), `seed` (default 0), `sway` (tip amplitude in
//!   metres, [0, 1], default 0.04). The local origin is at root height.
//! - `bush`: `cards` (default 80) square leaf cards of edge `width` (default
//!   0.3 m) inside an ellipsoid of `radius` or full `size = [x, y, z]`;
//!   `seed`, `sway` (default 0.03).
//!   Vegetation is drawn double-sided with a procedural alpha pattern and
//!   sway (`docs/techniques/vegetation.md`; card UVs in [`vegetation`]).
//! - `tree` (V1, [`tree`], `docs/techniques/V1.md`): `species = "larch" |
//!   "rosewood"`, `material` (leaves), `bark_material` (default grey-brown
//!   bark), `tint` (sRGB second leaf colour; each leaf cluster mixes the two
//!   at random), `seed` (default 0), `sway` (default 0.03). One tree at
//!   `position`, or `count` trees scattered over `size = [x, z]` around it,
//!   or `positions = [[x, y, z], ...]` (offsets from `position`); each yawed
//!   and scaled 0.85..1.15 at random from the seed; `snap_to_ground` stands
//!   each on the ground under its trunk. Objects `name#k/trunk` and
//!   `name#k/leaves` (`name/trunk` for one tree). Not `repeat`, `rest_on`, `orbit`.
//!
//! Moving objects: `orbit = { radius, period, phase, turn }` moves the object
//! on a horizontal circle around its placed position at constant speed:
//! at time `t` (seconds, `FrameSettings::time_s`) it sits at
//! `position + radius * (cos a, 0, -sin a)` with
//! `a = phase + 360 * t / period` degrees (`phase` default 0; a negative
//! `period` runs clockwise seen from above); `turn = true` also yaws it by `a`.
//! See [`Orbit`]. Not for height fields and vegetation.
//!
//! Placement: `snap_to_ground = true` samples the height field under the
//! object's footprint (its rotated, scaled bounds' bottom rectangle, 5 x 5
//! points) on the exact mesh triangles and puts the object's lowest point
//! on the *lowest* sample, plus `position.y` as an offset: nothing floats,
//! and on the demo's gently rolling valley floor the sink at the uphill side
//! is a few centimetres. `rest_on` does the same on the top of an earlier
//! object's world bounds (roofs on walls, spheres on a plinth). An orbiting
//! object is snapped to the lowest ground under 16 points of its circle.
//! Snapped `grass` instead puts every clump's root on the ground below it
//! (plus `position.y`); unsnapped grass stands on its local y = 0.
//!
//! `[[gltf]]`: a glTF 2.0 model (`.gltf` or `.glb`, see [`gltf`]) placed in the world:
//! `file` (relative to the scene file), `name` (prefix of its object names,
//! default `gltfN`), `translation` (default origin), `rotation` (degrees about
//! +Y, e.g. `30`, or a quaternion `[x, y, z, w]`), `scale` (number or
//! `[x, y, z]`), `rest_on` (put the model's lowest point on top of an earlier
//! object, plus `translation.y`), `optional = true` (skip with a warning when
//! the file is missing). The model's own node transforms apply first; its
//! KHR_lights_punctual point and spot lights join `[[light]]`s; its cameras
//! are not imported. Errors point at `file` and name the glTF problem.
//!
//! `[[camera]]`: `name`, `position`, `target` or `forward` (one of them), optional
//! `up` (default +Y), `fov_y` (vertical degrees in (0, 180), default 60), `near` (default 0.1),
//! `cinematic_shadows = { near = 0.5, far = 20.0 }` (R3, over the scene's).
//!
//! `[cinematic_shadows]` (R3, Ryse's cinematic shadows; `--cinematic-shadows
//! on|off`, docs/techniques/R3.md): `near` (m, [0.05, 10000]) and `far` (m,
//! beyond `near`) of the sun's cascades, split fully logarithmically
//! between them, for every camera without its own (not in a `[world]`
//! file: give its cameras their own).
//!
//! `[[ambient_light]]` (Ryse's multiplicative ambient lights; at most
//! [`MAX_AMBIENT_LIGHTS`] = 64, more is an error; docs/ambient-lights.md):
//! inside a volume the ambient light (sky diffuse and ambient specular
//! alike; not the sun, not `[[light]]`s) is multiplied by `factor`, so
//! artists darken interiors (< 1) or brighten bounce areas (> 1).
//!
//! ```toml
//! [[ambient_light]]
//! name = "hall"               # optional, default ambientN
//! position = [0.0, 1.5, 0.0]  # centre (m)
//! size = [4.0, 1.5, 3.0]      # box half-extents (m), or
//! # radius = 3.0              # a sphere; give exactly one of the two
//! yaw = 30.0                  # box rotation about +Y (degrees), default 0
//! factor = 0.3                # number or [r, g, b], each in [0, 16]
//! falloff = 0.25              # [0, 1], the outer fraction of the half-extent
//!                             # or radius over which the factor fades
//!                             # (smoothstep) to 1 at the surface; default 0.25
//! ```
//! Overlapping volumes multiply.
//!
//! `[[emitter]]` (E4 particles, `passes/particles/`; at most
//! [`MAX_EMITTERS`] = 64):
//!
//! ```toml
//! [[emitter]]
//! name = "chimney"                 # optional, default emitterN; unique
//! on = "house1_chimney"            # optional: position is then an offset from the
//!                                  # top centre of this [[object]]'s box; on a moving
//!                                  # object (orbit, animation) its box at time 0, and
//!                                  # the emitter rides the object from there
//! position = [0.0, 6.0, 0.0]       # where particles are born (m)
//! rate = 40.0                      # particles per second, (0, 100000]
//! lifetime = 6.0                   # seconds, (0, 30]
//! velocity = [0.0, 0.8, 0.0]       # m/s, default 0
//! spread = 0.3                     # m/s added per axis in [-spread, spread], default 0
//! gravity = -0.05                  # multiple of 9.81 m/s^2 down, [-10, 10] (negative rises), default 0
//! wind = 0.5                       # 1/s: how fast the velocity follows the wind, [0, 100], default 1
//! size = [0.4, 2.5]                # quad edge at birth and death (m), default [0.5, 0.5]
//! color_start = [0.5, 0.5, 0.5, 0.6]  # linear RGBA, default white
//! color_end = [0.6, 0.6, 0.6, 0.0]    # default color_start with alpha 0
//! capacity = 4096                  # particle slots, [1, 65536]; births beyond replace the oldest
//! sprite = "puff"                  # "disc" (default), "puff" (built-in normal-mapped cloud) or an
//!                                  # image relative to this file: RGB tangent normal (green up), A opacity
//! ```
//!
//! `[wind]` (optional): the wind particles relax toward (each emitter's
//! `wind` is the rate). Without the table: [`DEFAULT_WIND`], (1.5, 0, 0.5) m/s.
//!
//! ```toml
//! [wind]
//! speed = 3.0                      # m/s, [0, 100]
//! direction = 90.0                 # degrees about +Y from +X that it blows toward, as
//!                                  # orbit angles: (cos a, 0, -sin a); 90 = toward -z; default 0
//! # velocity = [0.0, 0.5, -3.0]    # or the velocity itself (m/s, each axis in [-100, 100]);
//!                                  # give speed (and direction) or velocity, not both
//! ```
//!
//! `[wind]` also bends the trees and drives V2's wind field with gusts
//! (`--wind SPEED,DIR` replaces it per frame). `[[wind_source]]` (at most
//! 8): a local source pushing outward, like a helicopter's downwash, on
//! trees, grass and particles (`scene/wind.rs`, `docs/techniques/V2.md`):
//!
//! ```toml
//! [[wind_source]]
//! position = [0.0, 8.0, 0.0]       # centre (m); or a path flown back and forth:
//! # path = [[-40.0, 10.0, 0.0], [40.0, 10.0, 0.0]]   # 2 to 16 points (floats)
//! # speed = 8.0                    # m/s along the path (path only), default 5
//! radius = 20.0                    # m where the push falls to zero, (0, 1000]
//! strength = 12.0                  # m/s outward at the centre, [0, 100]
//! ```
//!
//! `[world]`: instead of objects, the file describes a streamed open world
//! ([`world::WorldFile::load`]; `himal render --scene FILE` renders it as it
//! does `--scene world`). Only `[sun]` and `[[camera]]` may join it: file
//! cameras come first (the default view), then the world's own (`air`,
//! `river`, `village`, `peak`, `grazing`, `top`) except those they rename;
//! `[[object]]`, `[[material]]`, `[[light]]`, `[[ambient_light]]`, `[[probe]]`, `[[emitter]]`, `[wind]`, `[[gltf]]` and
//! `[environment]` are errors. An empty `[world]` is the built-in world.
//! Every key is optional except `height_map.file` and `.max`; defaults shown:
//!
//! ```toml
//! [world]
//! seed = 7                  # 0..=4294967295
//! sectors = 160             # per side, 16..=160, each 64 m (160: 10.24 km)
//! height_map = { file = "h.png", min = 0.0, max = 1200.0 }
//!                           # none: procedural mountains, hills and river. A grayscale PNG
//!                           # (16-bit; 8-bit works), relative to this file, 2..=8193 px a side,
//!                           # stretched over the world (column 0 west/-x, row 0 north/-z);
//!                           # black = min, white = max metres (min default 0, |h| <= 20000);
//!                           # no river is carved
//! mountain_height = 1150.0  # m, massifs' peaks above the river (procedural only)
//! hill_height = 45.0        # m, rolling hills (procedural only)
//! snow_line = 720.0         # m, snow above it; more rocks from 120 m below it
//!
//! [world.rules]             # what each sector places
//! rock_density = 1.0        # [0, 100], scales each 8 m cell's rock chance (one rock per cell at most)
//! tree_density = 1.0        # [0, 100], scales each 4 m cell's tree chance (one tree at most)
//! tree_max_slope = 34.0     # degrees from horizontal, [0, 90]
//! larch_line = 160.0        # m: larches above, rosewoods below, mixed by noise within 60 m
//! tree_line = 560.0         # m, forests thin over the 80 m below it (+-20 m jitter);
//!                           # villages stand 40 m below it or lower
//! village_chance = 0.55     # [0, 1], per 768 m cell
//! village_max_rise = 24.0   # m, [0, 1000]: the largest rise or fall 110 m from a site's
//!                           # centre that levelling takes (lower: fewer, flatter sites)
//! houses = true             # village houses (walls and roofs)
//! fields = true             # village fields (false also drops their fences)
//! fences = true             # fences around the fields
//!
//! [world.stream]
//! radius = 1000.0           # m, [1, world edge]: sectors this near the camera stream in
//! unload_margin = 128.0     # m, [0, world edge]: resident sectors leave beyond radius + margin
//! workers = 0               # generator threads, 0..=64 (0: the machine's cores, at most 8)
//! upload_budget = "4MiB"    # per frame, bytes or "512KiB", "4MiB", "1MB"..., 1KiB..=1GiB
//!
//! [world.pools]             # fixed GPU pools, allocated once
//! tiles = 1024              # terrain tiles (65^2 heights, 16.5 KiB each), 1..=2048; must hold
//!                           # what the radius wants: (64^2 + 256 r + pi r^2) / 64^2 sectors
//! rock0 = 16384             # instance slots per kind (240 bytes each; a tree's 480:
//!                           # trunk and leaves), 1..=1048576
//! rock1 = 16384
//! rock2 = 16384
//! house = 4096
//! roof = 4096
//! field = 1024
//! fence = 16384
//! larch = 65536
//! rosewood = 65536
//! water = 1024
//! ```
//!
//! Mesh conventions (UVs, tangents, winding) are in [`primitives`].

mod ambient;
mod build;
mod build_vegetation;
pub mod builtin;
mod camera;
mod emitters;
mod environment;
mod error;
mod file;
pub mod gltf;
pub mod heightfield;
mod lights;
pub mod lod;
mod motion;
pub mod noise;
mod place;
pub mod primitives;
pub mod raycast;
mod terrain;
pub mod tree;
pub mod vegetation;
pub mod wind;
pub mod world;

use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};

use crate::budget::MemoryBudget;

pub use ambient::{AmbientLightDesc, AmbientShape, MAX_AMBIENT_FACTOR, MAX_AMBIENT_LIGHTS};
pub use camera::{Camera, CinematicShadows, DEFAULT_NEAR, Orthographic};
pub use emitters::{
    DEFAULT_EMITTER_CAPACITY, DEFAULT_WIND, EmitterDesc, EmitterFollow, MAX_EMITTER_CAPACITY,
    MAX_EMITTERS, MAX_LIFETIME_S, MAX_PARTICLE_SLOTS, MAX_WIND, SLOT_BYTES, SPRITE_SIZE, Sprite,
    SpriteImage, load_sprite,
};
pub use environment::{EnvironmentDesc, EnvironmentFormat, EnvironmentImage, STUDIO};
pub use error::SceneError;
pub use heightfield::{HeightGrid, TerrainLayer, TerrainNoise};
pub use lights::{LightDesc, LightKind};
pub use motion::{Motion, Orbit};

/// One vertex as the G-buffer pass reads it (88 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Object-space position (metres for scene primitives).
    pub position: [f32; 3],
    /// Unit object-space normal.
    pub normal: [f32; 3],
    /// xyz: unit tangent along +u; w: handedness sign (+1/-1), glTF convention
    /// (bitangent = cross(normal, tangent.xyz) * w).
    pub tangent: [f32; 4],
    /// Texture coordinates (glTF convention: v down the image).
    pub uv: [f32; 2],
    /// Linear albedo rgb; a = material (baked) ambient occlusion.
    pub color: [f32; 4],
    /// Glossiness, reflectance, metallic, anisotropy (TECHNIQUES.md M1), each in [0, 1].
    pub surface: [f32; 4],
    /// The second texture coordinate set (glTF `TEXCOORD_1`; zero where
    /// the mesh has none). Material slots pick `uv` or `uv1`.
    pub uv1: [f32; 2],
}

// The GPU vertex layout (and passes/skin's output stride) depends on this size.
const _: () = assert!(std::mem::size_of::<Vertex>() == 88);

/// Axis-aligned bounding box. The empty box has `min > max` (+inf / -inf).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lowest corner.
    pub min: Vec3,
    /// Highest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box of no points: the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// The box from `min` to `max`.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Aabb { min, max }
    }

    /// The smallest box holding `points` (empty for none).
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Aabb::EMPTY, |b, p| Aabb {
            min: b.min.min(p),
            max: b.max.max(p),
        })
    }

    /// Whether the box holds no point (`min > max` on an axis).
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// The middle of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Full size along each axis (`max - min`), not the half size.
    /// Whether the boxes share a point (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        !self.max.cmplt(other.min).any() && !self.min.cmpgt(other.max).any()
    }

    /// Whether all eight corners lie beyond one clip plane of `view_proj`
    /// (reverse-Z, 0 <= z <= w): then nothing of the box can be seen.
    pub fn outside_clip(&self, view_proj: Mat4) -> bool {
        let clip = self.corners().map(|c| view_proj * c.extend(1.0));
        let all = |f: &dyn Fn(&glam::Vec4) -> bool| clip.iter().all(f);
        all(&|c| c.x < -c.w)
            || all(&|c| c.x > c.w)
            || all(&|c| c.y < -c.w)
            || all(&|c| c.y > c.w)
            || all(&|c| c.z < 0.0)
            || all(&|c| c.z > c.w)
    }

    /// Edge lengths (`max - min`).
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// The eight corners; bit 0 of the index picks x, bit 1 y, bit 2 z.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { a.x } else { b.x },
                if i & 2 == 0 { a.y } else { b.y },
                if i & 4 == 0 { a.z } else { b.z },
            )
        })
    }

    /// Bounds of the eight transformed corners (affine `m`).
    pub fn transform(&self, m: &Mat4) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        Aabb::from_points(self.corners().map(|c| m.transform_point3(c)))
    }

    /// Whether `p` lies inside the box grown by `tolerance`.
    pub fn contains_point(&self, p: Vec3, tolerance: f32) -> bool {
        p.cmpge(self.min - tolerance).all() && p.cmple(self.max + tolerance).all()
    }

    /// Whether `other` lies inside the box grown by `tolerance`.
    pub fn contains(&self, other: &Aabb, tolerance: f32) -> bool {
        other.is_empty()
            || (self.contains_point(other.min, tolerance)
                && self.contains_point(other.max, tolerance))
    }
}

/// Triangle list, counter-clockwise front faces seen from outside.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// Name for messages and statistics.
    pub name: String,
    /// Vertices, indexed by `indices`.
    pub vertices: Vec<Vertex>,
    /// Triangle list, counter-clockwise front faces.
    pub indices: Vec<u32>,
    /// Object-space bounds of the vertices (for skinned meshes: over every clip).
    pub bounds: Aabb,
    /// Precomputed LODs after LOD0, indexing `vertices` (trees: visibility-
    /// driven leaf clusters, coarser trunks); empty: E2's simplifier makes them.
    pub levels: Vec<lod::Level>,
}

impl Mesh {
    /// Triangles in `indices`.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The mesh as a mirroring transform (negative determinant) needs it:
    /// each triangle's winding reversed, so its front stays the side its
    /// normal leaves. (Tangent handedness is the shader's: it folds the
    /// model matrix's determinant into `w`, `gltf_world_tangent`.)
    pub fn mirrored(&self) -> Mesh {
        let mut m = self.clone();
        m.name = format!("{} (mirrored)", self.name);
        for t in m.indices.chunks_exact_mut(3) {
            t.swap(1, 2);
        }
        for l in &mut m.levels {
            for t in l.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        m
    }
}

/// Objects whose transform mirrors (negative determinant) draw a mirrored
/// copy of their mesh ([`Mesh::mirrored`], one per mesh, with the
/// original's textured material): back-face culling and a double-sided
/// surface's front-facing test are right without a pipeline per winding.
pub(crate) fn mirror_meshes(
    meshes: &mut Vec<Mesh>,
    objects: &mut [Object],
    pbr: &mut gltf::PbrSet,
) {
    let mut copies: std::collections::HashMap<usize, usize> = Default::default();
    for o in objects.iter_mut() {
        if o.transform.determinant() >= 0.0 || o.mesh >= meshes.len() {
            continue;
        }
        let mesh = *copies.entry(o.mesh).or_insert_with(|| {
            meshes.push(meshes[o.mesh].mirrored());
            if let Some(material) = pbr.material_of(o.mesh) {
                pbr.mesh_material.push((meshes.len() - 1, material));
            }
            meshes.len() - 1
        });
        o.mesh = mesh;
    }
}

/// An instance of a mesh in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Unique within the scene (copies: `name#i`; glTF objects: `entry/node`).
    pub name: String,
    /// Index into [`Scene::meshes`].
    pub mesh: usize,
    /// Local to world (translation * rotation * scale) at time 0.
    pub transform: Mat4,
    /// Movement over time; `None` for static objects.
    pub motion: Option<Motion>,
    /// Alpha-tested, swaying cards; `None` for opaque geometry.
    pub foliage: Option<Foliage>,
    /// Terrain (height fields and planes): sky occlusion fades by the height
    /// above it (L2).
    pub ground: bool,
}

impl Object {
    /// Local to world at time `t` (seconds); `transform` for static objects.
    pub fn transform_at(&self, t: f32) -> Mat4 {
        self.motion
            .as_ref()
            .map_or(self.transform, |m| m.transform_at(t))
    }

    /// Vegetation (`FrameSettings::vegetation`): foliage cards, or a tree's
    /// trunk (`meshes`: the scene's).
    pub fn is_vegetation(&self, meshes: &[Mesh]) -> bool {
        self.foliage.is_some()
            || meshes
                .get(self.mesh)
                .is_some_and(|m| m.name.starts_with(tree::TRUNK_PREFIX))
    }

    /// World bounds over all time: the path swept by a moving object, the
    /// sway of foliage (`mesh_bounds`: the bounds of its mesh).
    pub fn swept_bounds(&self, mesh_bounds: &Aabb) -> Aabb {
        let mut b = mesh_bounds.transform(&self.transform);
        if let Some(m) = &self.motion {
            // Animated: the mesh's bounds over every clip.
            let local = match &m.animated {
                Some(a) => a.swept.transform(&m.base),
                None => mesh_bounds.transform(&m.base),
            };
            b = b.union(&local);
            if let Some(orbit) = &m.orbit {
                // The bounds' sphere around its centre, swept around the circle.
                let r = if orbit.turn {
                    Vec3::splat(local.extent().length() * 0.5)
                } else {
                    local.extent() * 0.5
                };
                let c = local.center();
                let reach = Vec3::new(orbit.radius, 0.0, orbit.radius);
                b = b.union(&Aabb::new(c - reach - r, c + reach + r));
            }
        }
        if let Some(f) = &self.foliage {
            let pad = Vec3::new(f.sway, 0.0, f.sway) * std::f32::consts::SQRT_2;
            b = Aabb::new(b.min - pad, b.max + pad);
        }
        b
    }
}

/// Alpha-test pattern of vegetation cards (GPU `Object.params.x`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AlphaPattern {
    /// Tapered blades, several per card (`grass`).
    Grass = 1,
    /// Elliptic leaves (`bush`).
    Leaves = 2,
}

/// Vegetation drawing parameters (GPU `Object.params`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Foliage {
    /// The cut-out shape the shader tests.
    pub pattern: AlphaPattern,
    /// Sway amplitude (metres) at full weight; see `docs/techniques/vegetation.md`.
    pub sway: f32,
    /// Sway weight source: grass uses `v^2`; leaves use
    /// `((y_local - sway_base) * sway_inv_height)^2` (0 at the bush's bottom).
    pub sway_base: f32,
    /// 1 / card height (the leaves' sway weight).
    pub sway_inv_height: f32,
}

impl Foliage {
    /// `Object.params` in `shaders/scene.wgsl`.
    pub fn params(&self) -> [f32; 4] {
        [
            self.pattern as u32 as f32,
            self.sway,
            self.sway_base,
            self.sway_inv_height,
        ]
    }
}

/// Material parameters as written in the scene file (albedo already linear).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    /// The name objects refer to it by.
    pub name: String,
    /// Linear albedo; for metals their F0 colour.
    pub albedo: Vec3,
    /// Perceptual smoothness, 1 - roughness (M1).
    pub glossiness: f32,
    /// F0 of a dielectric, [0, 1].
    pub reflectance: f32,
    /// 0 dielectric, 1 metal.
    pub metallic: f32,
    /// Anisotropy strength along the tangent (M1).
    pub anisotropy: f32,
    /// Material ambient occlusion, multiplied into the indirect light.
    pub ao: f32,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc {
            name: "default".into(),
            albedo: Vec3::splat(0.5),
            glossiness: 0.5,
            reflectance: 0.04,
            metallic: 0.0,
            anisotropy: 0.0,
            ao: 1.0,
        }
    }
}

impl MaterialDesc {
    /// `Vertex::color`: linear albedo and ao.
    pub fn vertex_color(&self) -> [f32; 4] {
        self.albedo.extend(self.ao).to_array()
    }

    /// `Vertex::surface`: glossiness, reflectance, metallic, anisotropy.
    pub fn vertex_surface(&self) -> [f32; 4] {
        [
            self.glossiness,
            self.reflectance,
            self.metallic,
            self.anisotropy,
        ]
    }
}

/// Time of day from text as the scene file takes it: "HH:MM" (24-hour
/// clock) or hours as a number, in [0, 24). For command-line overrides.
pub fn parse_time(text: &str) -> Result<f32, String> {
    let text = text.trim();
    let hours = if text.contains(':') {
        file::parse_hh_mm(text)?
    } else {
        text.parse::<f32>()
            .map_err(|_| format!("bad time \"{text}\": expected \"HH:MM\" or hours like 14.5"))?
    };
    if (0.0..24.0).contains(&hours) {
        Ok(hours)
    } else {
        Err(format!("time {hours} hours is out of range [0, 24)"))
    }
}

/// Sun position inputs (the sky pass turns them into a direction and colour).
/// World orientation assumed by the demo's cameras: north is -Z, east is +X,
/// so an afternoon sun shines from +Z, -X (south-west).
#[derive(Clone, Debug, PartialEq)]
pub struct SunDesc {
    /// Local solar time in hours, [0, 24).
    pub time_hours: f32,
    /// Degrees north (positive) or south.
    pub latitude_deg: f32,
    /// 1..=366 (the sun's declination).
    pub day_of_year: u32,
    /// Atmospheric turbidity (Preetham sky), [1, 10].
    pub turbidity: f32,
    /// A directional light that stands in for the computed sun (a glTF
    /// file's `KHR_lights_punctual` directional light): the sky and the
    /// sun light follow its direction, the sun its illuminance.
    pub light: Option<SunLight>,
}

/// A directional light in place of the sun of [`SunDesc`]'s time and place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunLight {
    /// Unit vector towards the light (opposite to where it shines).
    pub to_light: Vec3,
    /// Illuminance, linear RGB klux (the sun's unit in himal).
    pub illuminance_klux: Vec3,
}

impl Default for SunDesc {
    fn default() -> Self {
        SunDesc {
            time_hours: 14.0,
            latitude_deg: 45.0,
            day_of_year: 172,
            turbidity: 3.0,
            light: None,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
/// A camera with the name `--camera` picks it by.
pub struct NamedCamera {
    /// Unique within the scene.
    pub name: String,
    /// Pose and projection.
    pub camera: Camera,
    /// R3 shadows for this camera (over the scene's `[cinematic_shadows]`).
    pub cinematic_shadows: Option<CinematicShadows>,
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The file it came from: the loaded path, or the `origin` given to
    /// [`Scene::from_toml_str`]; `None` only for scenes assembled in code.
    pub path: Option<PathBuf>,
    /// Every mesh; objects and the PBR set index them.
    pub meshes: Vec<Mesh>,
    /// Every placed object.
    pub objects: Vec<Object>,
    /// Scene-file materials (by name in `[[object]]`).
    pub materials: Vec<MaterialDesc>,
    /// Named cameras; the first is the default.
    pub cameras: Vec<NamedCamera>,
    /// R3: the scene's `[cinematic_shadows]`, for cameras without their own.
    pub cinematic_shadows: Option<CinematicShadows>,
    /// The sun's time and place, or a light standing in for it.
    pub sun: SunDesc,
    /// Point and spot lights (`[[light]]`, S3).
    pub lights: Vec<LightDesc>,
    /// Multipliers on the ambient light inside volumes (`[[ambient_light]]`).
    pub ambient_lights: Vec<AmbientLightDesc>,
    /// Particle emitters (`[[emitter]]`, E4).
    pub emitters: Vec<EmitterDesc>,
    /// The wind particles drift in (m/s; `[wind]`, else [`DEFAULT_WIND`]).
    pub wind: Vec3,
    /// V2: local wind sources (`[[wind_source]]`); with `wind` the field
    /// that moves the trees ([`Scene::wind_field`]).
    pub wind_sources: Vec<wind::WindSource>,
    /// V2: the bones of the tree meshes (`passes/vegetation` moves them).
    pub tree_rigs: Vec<tree::rig::SceneRig>,
    /// World bounds of all objects over all time ([`Object::swept_bounds`]).
    pub bounds: Aabb,
    /// Textured (glTF) materials and the meshes drawn with them.
    pub pbr: gltf::PbrSet,
    /// Environment probe positions (L3: G-buffer cubes relit with the sky).
    pub probes: Vec<Vec3>,
    /// An HDR environment lighting the scene instead of the physical sky.
    pub environment: Option<EnvironmentDesc>,
    /// V3: the impostor captures of the scene's trees, one atlas layer each
    /// (the leaves meshes' impostor levels name their layer).
    pub impostors: Vec<std::sync::Arc<tree::impostor::Impostor>>,
    /// V4: the occlusion volume of each impostor layer's tree (same order).
    pub ao_volumes: Vec<std::sync::Arc<tree::ao::AoVolume>>,
}

/// Largest scene file read (the demo is 30 kB).
const MAX_SCENE_FILE_BYTES: u64 = 64 << 20;

/// The budget of `HIMAL_MEMORY_BUDGET` (or the machine default).
fn env_budget() -> Result<MemoryBudget, SceneError> {
    MemoryBudget::from_env().map_err(|message| SceneError::Invalid {
        file: crate::budget::MEMORY_BUDGET_ENV.into(),
        message,
    })
}

/// The text of the scene file at `path`, refusing what is not a regular
/// file of at most [`MAX_SCENE_FILE_BYTES`].
pub(crate) fn read_scene_file(path: &Path) -> Result<String, SceneError> {
    let io = |source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    // A directory, a device or an endless pipe is not read.
    if !meta.is_file() || meta.len() > MAX_SCENE_FILE_BYTES {
        return Err(SceneError::Invalid {
            file: path.display().to_string(),
            message: format!(
                "not a scene file: {} (at most {} MiB of TOML)",
                if meta.is_file() {
                    "too large"
                } else {
                    "not a regular file"
                },
                MAX_SCENE_FILE_BYTES >> 20
            ),
        });
    }
    std::fs::read_to_string(path).map_err(io)
}

/// Text of the demo world, embedded so the renderer runs from anywhere.
pub const DEMO_TOML: &str = include_str!("../../../../scenes/demo.toml");

impl Scene {
    /// V2: the wind field of the scene: `wind` and the local sources.
    pub fn wind_field(&self) -> wind::WindField {
        wind::WindField {
            global: self.wind,
            sources: self.wind_sources.clone(),
        }
    }

    /// Reads, parses and builds the scene file at `path`; relative paths
    /// inside it are resolved against its folder.
    /// Allocations are checked against [`MemoryBudget::from_env`].
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_within(path, env_budget()?)
    }

    /// [`Scene::load`] with an explicit memory budget.
    pub fn load_within(path: &Path, budget: MemoryBudget) -> Result<Scene, SceneError> {
        let text = read_scene_file(path)?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        let mut scene = build::build_scene(&text, &path.display().to_string(), base_dir, budget)?;
        scene.path = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses scene text; `origin` names it in messages, `base_dir` resolves relative paths.
    pub fn from_toml_str(text: &str, origin: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        build::build_scene(text, origin, base_dir, env_budget()?)
    }

    /// [`Scene::from_toml_str`] with an explicit memory budget.
    pub fn from_toml_str_within(
        text: &str,
        origin: &str,
        base_dir: &Path,
        budget: MemoryBudget,
    ) -> Result<Scene, SceneError> {
        build::build_scene(text, origin, base_dir, budget)
    }

    /// The demo world (`scenes/demo.toml`, embedded at compile time).
    pub fn demo() -> Result<Scene, SceneError> {
        let base_dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes"));
        Self::from_toml_str(DEMO_TOML, "scenes/demo.toml", base_dir)
    }

    /// A glTF model (`scene/gltf`) as a scene: its nodes, its cameras after
    /// an auto-framed `"default"` camera, the default sun.
    pub fn from_gltf(path: &Path) -> Result<Scene, SceneError> {
        Self::from_gltf_within(path, env_budget()?)
    }

    /// [`Scene::from_gltf`] with an explicit memory budget.
    pub fn from_gltf_within(path: &Path, budget: MemoryBudget) -> Result<Scene, SceneError> {
        Self::from_gltf_variant(path, budget, None)
    }

    /// [`Scene::from_gltf_within`] with `KHR_materials_variants` variant
    /// `variant` (by name; an unknown one is an error listing the file's).
    pub fn from_gltf_variant(
        path: &Path,
        budget: MemoryBudget,
        variant: Option<&str>,
    ) -> Result<Scene, SceneError> {
        let mut asset = builtin::load_gltf(path, budget, variant)?;
        mirror_meshes(&mut asset.meshes, &mut asset.objects, &mut asset.pbr);
        let mut cameras = vec![NamedCamera {
            name: "default".into(),
            camera: gltf::framing_camera(&asset.bounds, 40.0),
            cinematic_shadows: None,
        }];
        cameras.extend(asset.cameras);
        Ok(Scene {
            path: Some(path.to_path_buf()),
            cinematic_shadows: None,
            meshes: asset.meshes,
            objects: asset.objects,
            materials: Vec::new(),
            cameras,
            sun: SunDesc {
                light: gltf::sun_light(path, &asset.lights),
                ..SunDesc::default()
            },
            bounds: asset.bounds,
            pbr: asset.pbr,
            lights: asset.lights.iter().filter_map(gltf::local_light).collect(),
            ambient_lights: Vec::new(),
            emitters: Vec::new(),
            wind: DEFAULT_WIND,
            wind_sources: Vec::new(),
            tree_rigs: Vec::new(),
            probes: Vec::new(),
            environment: None,
            impostors: Vec::new(),
            ao_volumes: Vec::new(),
        })
    }

    /// The names of the glTF animations the scene's objects can play, in
    /// file order (each name once).
    pub fn animations(&self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        let rigs = (self.objects.iter())
            .filter_map(|o| o.motion.as_ref()?.animated.as_ref())
            .map(|a| &a.rig);
        for clip in rigs.flat_map(|r| &r.clips) {
            if !names.contains(&clip.name) {
                names.push(clip.name.clone());
            }
        }
        names
    }

    /// Plays glTF animation `name` on every object whose file has it
    /// (`None`: every animated object holds its rest pose). The error lists
    /// the animations there are.
    pub fn set_animation(&mut self, name: Option<&str>) -> Result<(), SceneError> {
        let known = self.animations();
        if let Some(name) = name.filter(|n| !known.iter().any(|k| k == n)) {
            return Err(SceneError::Invalid {
                file: self
                    .path
                    .as_ref()
                    .map_or_else(|| "<scene>".to_string(), |p| p.display().to_string()),
                message: if known.is_empty() {
                    format!("--animation {name}: the scene has no animations")
                } else {
                    format!(
                        "no animation \"{name}\" (the scene's: {})",
                        known.join(", ")
                    )
                },
            });
        }
        for o in &mut self.objects {
            let Some(a) = o.motion.as_mut().and_then(|m| m.animated.as_mut()) else {
                continue;
            };
            a.play(name);
            o.transform = o.transform_at(0.0);
        }
        Ok(())
    }

    /// The camera called `name`; the error lists the names there are.
    pub fn camera(&self, name: &str) -> Result<&Camera, SceneError> {
        self.cameras
            .iter()
            .find(|c| c.name == name)
            .map(|c| &c.camera)
            .ok_or_else(|| SceneError::UnknownCamera {
                file: self
                    .path
                    .as_ref()
                    .map_or_else(|| "<scene>".to_string(), |p| p.display().to_string()),
                name: name.to_string(),
                known: self
                    .cameras
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// R3: the cinematic shadows of camera `name`: its own, else the scene's.
    pub fn cinematic_shadows_for(&self, name: &str) -> Option<CinematicShadows> {
        self.cameras
            .iter()
            .find(|c| c.name == name)
            .and_then(|c| c.cinematic_shadows)
            .or(self.cinematic_shadows)
    }

    /// Triangles drawn per frame (each object counts its mesh's triangles).
    pub fn triangle_count(&self) -> usize {
        self.objects
            .iter()
            .map(|o| self.meshes[o.mesh].triangle_count())
            .sum()
    }
}
