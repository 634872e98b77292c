//! S3 local lights on the CPU: the GPU light list (lit by the lighting pass
//! with the BRDF), their projectors (six cube faces for a point light, one
//! frustum for a spot), atlas tiles by importance ([`super::atlas`]) and the
//! shadow-mask channel of each shadowed light: G, B or A, shared by lights
//! whose spheres do not overlap.

use glam::{Mat4, Vec3};

use super::atlas::{AtlasAllocator, AtlasRequest, AtlasTile, importance};
use super::casters::{Casters, DrawLists};
use crate::gpu_scene::SceneGpu;
use crate::scene::{Aabb, LightDesc, LightKind};

/// Twin of `LocalLight` in `shaders/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LocalLightGpu {
    /// xyz world position (m), w range (m): the light reaches zero there.
    pub position_range: [f32; 4],
    /// rgb colour times intensity in klux at 1 m, w 0 for a point light, 1 for a spot.
    pub color_kind: [f32; 4],
    /// xyz unit spot axis (world), w cosine of the outer half angle.
    pub direction_cos_outer: [f32; 4],
    /// x cosine of the inner half angle, y shadow-mask channel (0 none, 1..3 = G, B, A), z first atlas tile, w unused.
    pub params: [f32; 4],
}

impl LocalLightGpu {
    /// `l` as the GPU reads it, unshadowed (no mask channel, no tile).
    pub fn new(l: &LightDesc) -> Self {
        Self {
            position_range: l.position.extend(l.range).to_array(),
            color_kind: (l.color * l.intensity * 1e-3)
                .extend(if l.kind == LightKind::Spot { 1.0 } else { 0.0 })
                .to_array(),
            direction_cos_outer: l
                .direction
                .extend(l.outer_deg.to_radians().cos())
                .to_array(),
            params: [l.inner_deg.to_radians().cos(), 0.0, 0.0, 0.0],
        }
    }
}

/// Twin of `ShadowTile` in `shaders/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowTileGpu {
    /// World to the projector's clip space (perspective, depth 0 at the near plane to 1 at the range).
    pub view_proj: [[f32; 4]; 4],
    /// xy atlas uv of the tile's corner, zw its uv size.
    pub rect: [f32; 4],
    /// x world texel size per metre of distance, yzw unused.
    pub info: [f32; 4],
}

/// Casters wider than this many light ranges (the terrain) cast no local shadows.
pub const MAX_CASTER_RANGES: f32 = 8.0;

/// Near plane of every projector (m).
pub const PROJECTOR_NEAR: f32 = 0.05;

/// One projector this frame: its tile, matrix and draws.
pub struct Projector {
    /// Its tile of the atlas.
    pub tile: AtlasTile,
    /// World to the projector's clip space (see [`projector`]).
    pub view_proj: Mat4,
    /// Casters inside the projector's frustum.
    pub draws: DrawLists,
}

/// Cube face directions and up vectors, in `shadow_cube_face` order.
const FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y),
    (Vec3::NEG_X, Vec3::Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::Z),
    (Vec3::Z, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y),
];

/// Projector `face` of `light` for a tile of `size` texels. The field of view
/// is widened by two texels a side, so the filter's taps at a face's edge
/// still read depths of that face.
pub fn projector(light: &LightDesc, face: u32, size: u32) -> (Mat4, f32) {
    let n = size.max(8) as f32;
    let (half_tan, dir, up) = match light.kind {
        LightKind::Point => {
            let (d, u) = FACES[face.min(5) as usize];
            (1.0, d, u)
        }
        LightKind::Spot => {
            let d = light.direction;
            let u = if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
            (light.outer_deg.to_radians().tan(), d, u)
        }
    };
    let half_tan = half_tan * n / (n - 4.0);
    let view = glam::camera::rh::view::look_to_mat4(light.position, dir, up);
    // wgpu clip space, depth 0 at the near plane .. 1 at the range.
    let proj = glam::camera::rh::proj::directx::perspective(
        2.0 * half_tan.atan(),
        1.0,
        PROJECTOR_NEAR,
        light.range,
    );
    // World texel per metre of distance.
    (proj * view, 2.0 * half_tan / n)
}

/// The light list and this frame's projectors.
pub struct LocalPlan {
    /// Every local light as the lighting pass reads it, in scene order.
    pub lights: Vec<LocalLightGpu>,
    /// One atlas tile per projector, in projector order.
    pub tiles: Vec<ShadowTileGpu>,
    /// This frame's projectors: the cube faces of shadowed point lights, the frusta of shadowed spots.
    pub projectors: Vec<Projector>,
}

/// Lights as the GPU reads them; with `atlas`, shadowed lights get tiles
/// (by importance from `camera`) and mask channels. With `skip_casterless`,
/// a shadowed light with no caster in its reach gets neither (no projector
/// pass, no mask work: the channel would read lit everywhere).
pub fn plan(
    lights: &[LightDesc],
    camera: Vec3,
    atlas: Option<&mut AtlasAllocator>,
    casters: &Casters,
    scene: &SceneGpu,
    skip_casterless: bool,
) -> LocalPlan {
    let mut out: Vec<LocalLightGpu> = lights.iter().map(LocalLightGpu::new).collect();
    let mut plan = LocalPlan {
        lights: Vec::new(),
        tiles: Vec::new(),
        projectors: Vec::new(),
    };
    let Some(atlas) = atlas else {
        plan.lights = out;
        return plan;
    };
    // Each shadowed light's casters: those within its reach.
    let reach: Vec<Option<DrawLists>> = lights
        .iter()
        .map(|l| {
            l.shadow.then(|| {
                let bounds = Aabb::new(
                    l.position - Vec3::splat(l.range),
                    l.position + Vec3::splat(l.range),
                );
                let mut draws = DrawLists::default();
                casters.cull_local_into(scene, &bounds, MAX_CASTER_RANGES * l.range, &mut draws);
                draws
            })
        })
        .collect();
    let requests: Vec<AtlasRequest> = lights
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            reach[*i]
                .as_ref()
                .is_some_and(|d| !(skip_casterless && d.is_empty()))
        })
        .map(|(i, l)| AtlasRequest {
            light: i as u32,
            faces: if l.kind == LightKind::Point { 6 } else { 1 },
            importance: importance(l.position, l.range, camera),
        })
        .collect();
    let tiles = atlas.allocate(&requests);
    // Channels, most important first: the first of G, B, A no overlapping
    // light took; none left = no shadow.
    let mut order: Vec<&AtlasRequest> = requests.iter().collect();
    order.sort_by(|a, b| {
        b.importance
            .total_cmp(&a.importance)
            .then(a.light.cmp(&b.light))
    });
    let mut taken: Vec<(usize, u32)> = Vec::new();
    let inv = 1.0 / atlas.size as f32;
    for r in order {
        let i = r.light as usize;
        let mine: Vec<&AtlasTile> = tiles.iter().filter(|t| t.light == r.light).collect();
        if mine.is_empty() {
            continue;
        }
        let (l, Some(draws)) = (&lights[i], &reach[i]) else {
            continue;
        };
        let overlaps = |j: usize| {
            let o = &lights[j];
            l.position.distance(o.position) < l.range + o.range
        };
        let Some(channel) =
            (1..=3u32).find(|&c| !taken.iter().any(|&(j, cj)| cj == c && overlaps(j)))
        else {
            continue;
        };
        taken.push((i, channel));
        out[i].params[1] = channel as f32;
        out[i].params[2] = plan.tiles.len() as f32;
        let mut faces = mine;
        faces.sort_by_key(|t| t.face);
        for t in faces {
            let (view_proj, texel_per_m) = projector(l, t.face, t.size);
            plan.tiles.push(ShadowTileGpu {
                view_proj: view_proj.to_cols_array_2d(),
                rect: [
                    t.x as f32 * inv,
                    t.y as f32 * inv,
                    t.size as f32 * inv,
                    t.size as f32 * inv,
                ],
                info: [texel_per_m, 0.0, 0.0, 0.0],
            });
            plan.projectors.push(Projector {
                tile: *t,
                view_proj,
                draws: cull_frustum(draws, casters, view_proj),
            });
        }
    }
    plan.lights = out;
    plan
}

/// The draws of `lists` whose bounds may be inside the frustum `view_proj`
/// (not all eight corners beyond one clip plane): a cube face sees about a
/// sixth of the light's sphere.
fn cull_frustum(lists: &DrawLists, casters: &Casters, view_proj: Mat4) -> DrawLists {
    let inside = |_: usize, b: &crate::scene::Aabb| !b.outside_clip(view_proj);
    let bounds = &casters.bounds;
    DrawLists {
        opaque: crate::gpu_scene::cull(&lists.opaque, bounds, inside).collect(),
        vegetation: crate::gpu_scene::cull(&lists.vegetation, bounds, inside).collect(),
        gpu_view: None,
        pool_view: None,
    }
}
