//! Sun shadows (TECHNIQUES S1, S2, S4; Ryse): four cascades with a practical
//! split and texel snapping ([`cascades`]), a static map of the far field
//! filled once with time-sliced updates ([`static_map`]), a hero map fitted
//! to one object ([`hero`]), all resolved in the full-screen `shadows.mask`
//! pass into a shadow-mask texture (R = sun) that lighting reads. The filter
//! is a per-texel rotated 16-tap Poisson disk (`shaders/shadow.wgsl`, twin
//! [`mod@reference`]). [`atlas`]: the S3 local-light atlas allocator.
//! [`world_map`]: S2 in a streamed world (a camera-centred map refreshed
//! where sectors stream in).
//! Docs: `docs/techniques/S1.md`..`S4.md`.

pub mod atlas;
pub mod cascades;
pub mod casters;
pub mod depth;
pub mod hero;
pub mod local;
mod nodes;
pub mod reference;
pub mod settings;
pub mod static_map;
pub mod world_map;

use glam::{Mat4, Vec3};

use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::SceneGpu;
use crate::graph::{FrameGraph, TextureDesc, TextureHandle};
use crate::passes::common::view_pipeline;
use crate::passes::gbuffer::GBuffer;
use crate::scene::{Camera, LightDesc, Scene};
use atlas::AtlasAllocator;
pub use cascades::{CASCADES, ShadowFit};
use casters::{Casters, DrawLists};
use depth::{DepthPipelines, ShadowViewGpu};
use local::{LocalLightGpu, Projector, ShadowTileGpu};
pub use nodes::SunMaps;
pub use settings::{ShadowMode, ShadowSettings, ShadowView};

/// Geometry outside the scene's objects that casts into the sun cascades
/// (the world's terrain): a node after cascade `layer`'s, drawing with that
/// cascade's view uniform.
pub trait CascadeCaster {
    /// Adds a node after cascade `layer`'s that draws this geometry into
    /// `cascades` (the cascade array) with that cascade's `view` uniform; returns the new version.
    fn add_cascade<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        cascades: TextureHandle,
        layer: u32,
        view: &'a wgpu::Buffer,
    ) -> TextureHandle;

    /// A node after static tile `rect`'s (texels x, y, w, h: its viewport
    /// and scissor) into the world's static map `map` ([`STATIC_FORMAT`]),
    /// drawing this frame's shadow view `index` (the cascades first, then
    /// the tiles, as `ShadowStats::fits` then `static_tiles`) with `view`.
    fn add_static_tile<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        map: TextureHandle,
        index: usize,
        view: &'a wgpu::Buffer,
        rect: [u32; 4],
    ) -> TextureHandle;
}
pub use static_map::STATIC_FORMAT;
use static_map::{StaticMapState, StaticUpdate};
use world_map::{TileUpdate, WorldMap, WorldMapState};

/// Tiles of the world's static map rendered a frame: each is a culling and
/// a terrain view (cull views: camera, 4 cascades, these 2, sky occlusion =
/// `cull::MAX_VIEWS`).
pub const MAX_STATIC_TILES: usize = 2;

/// Depth format of the cascades and the hero map.
pub const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Format of the shadow mask (R sun; G, B, A local lights).
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Normal offset and depth bias in texels of the map sampled: with the
/// 1.5-texel disk, 1 texel of bias left acne on the demo's plinth; 2 do not.
const NORMAL_OFFSET_TEXELS: f32 = 1.5;
const DEPTH_BIAS_TEXELS: f32 = 2.0;

/// Twin of `ShadowMaskParams` in `shaders/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct MaskParamsGpu {
    cascades: [[[f32; 4]; 4]; CASCADES],
    static_map: [[f32; 4]; 4],
    hero: [[f32; 4]; 4],
    splits: [f32; 4],
    texel: [f32; 4],
    depth_range: [f32; 4],
    static_info: [f32; 4],
    hero_info: [f32; 4],
    filter_params: [f32; 4],
    camera_forward: [f32; 4],
    light_rotation: [[f32; 4]; 4],
}

/// What this frame's shadow passes render (planned by [`ShadowPass::update`]).
#[derive(Default)]
struct FramePlan {
    cascades: Vec<(ShadowFit, DrawLists)>,
    static_update: Option<(StaticUpdate, DrawLists)>,
    /// The world's static map: this frame's tiles.
    static_tiles: Vec<StaticTile>,
    hero: Option<(ShadowFit, DrawLists)>,
    /// With `ShadowSettings::hero_scissor`, the NDC rectangle (x0, y0, x1,
    /// y1) of the hero map's box on screen, `Some(None)` when it covers no
    /// pixel ([`hero_screen_rect`]); `None`: the whole screen.
    hero_rect: Option<Option<[f32; 4]>>,
    /// `ShadowSettings::mask_tiles`: classify the mask's tiles first.
    mask_tiles: bool,
    /// `ShadowSettings::alpha_test`: MASK and BLEND glTF casters alpha-tested.
    alpha_test: bool,
    /// S3 projectors into the atlas.
    projectors: Vec<Projector>,
}

/// One tile of the world's static map this frame: the tile, its static
/// scene objects (CPU-culled) and its pool instances (the GPU-culled view
/// after the cascades', `1 + cascades + k`).
struct StaticTile {
    update: TileUpdate,
    objects: DrawLists,
    pool: DrawLists,
}

/// Smallest and largest atlas tiles (S3).
const ATLAS_MIN_TILE: u32 = 64;
const ATLAS_MAX_TILE: u32 = 1024;

/// Per-frame numbers of the shadow passes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowStats {
    /// Shadow draw calls this frame (cascades + static slice + hero).
    pub draws: u32,
    /// Cascades rendered (3 once the static map replaces the far one).
    pub cascades_rendered: u32,
    /// Draws of the static map this frame (at most the cap).
    pub static_draws: u32,
    /// The static map is complete and shown.
    pub static_shown: bool,
    /// Fits of the cascades rendered (for tests and docs).
    pub fits: Vec<ShadowFit>,
    /// Far view distance of each cascade (m).
    pub splits: [f32; CASCADES],
    /// Atlas tiles rendered (S3 projectors).
    pub atlas_tiles: u32,
    /// The world's static-map tiles rendered this frame: their light
    /// view-projections (each a terrain and a culling view).
    pub static_tiles: Vec<Mat4>,
    /// Texels of the world's static map rendered this frame.
    pub static_texels: u64,
}

/// Sun and local-light shadows: the S1 cascades (with the world's static and
/// hero maps), the S3 projector atlas, and the screen-space shadow mask lighting reads.
pub struct ShadowPass {
    depth_program: Program,
    depth32: DepthPipelines,
    depth16: DepthPipelines,
    /// Sun views: cascades 0..3, static map, hero map.
    views: Vec<wgpu::Buffer>,
    mask_program: Program,
    mask: wgpu::RenderPipeline,
    /// The mask reading `shadows.mask_tiles`' states (`TILES`, #23).
    mask_tiled: wgpu::RenderPipeline,
    tiles_program: Program,
    tiles: wgpu::ComputePipeline,
    hero_blend: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    view_program: Program,
    /// Comparison sampler of every map.
    pub sampler: wgpu::Sampler,
    casters: Casters,
    static_state: StaticMapState,
    /// Every static object's draws in fill order, listed once.
    static_all: Option<Vec<(crate::gpu_scene::Draw, bool)>>,
    /// The two static maps (shown and filling) and their edge.
    static_maps: Option<(u32, [wgpu::Texture; 2])>,
    /// S2 in a streamed world ([`Self::attach_world`]): the camera-centred
    /// map, its tiled fills and one view uniform per tile of a frame.
    world: Option<WorldMap>,
    tiled: WorldMapState,
    tile_views: Vec<wgpu::Buffer>,
    /// Render every waiting tile next frame (offline frames).
    settle: bool,
    plan: Option<FramePlan>,
    cascade_resolution: u32,
    hero_resolution: u32,
    /// S3: the scene's lights, the allocator (keeps last frame's sizes),
    /// the light list the lighting pass reads, tiles, one view per projector.
    lights: Vec<LightDesc>,
    atlas: Option<AtlasAllocator>,
    /// `LocalLights` (count + lights) for lighting and the mask.
    pub local_lights: wgpu::Buffer,
    light_tiles: wgpu::Buffer,
    atlas_views: Vec<wgpu::Buffer>,
    atlas_resolution: u32,
}

fn storage_buffer(ctx: &GpuContext, label: &str, size: u64) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

fn depth_texture(
    ctx: &GpuContext,
    label: &str,
    size: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    crate::gpu::texture_2d(
        &ctx.device,
        label,
        (size, size),
        1,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::COPY_SRC,
    )
}

/// A view of one layer as a 2D array of one (how every map is bound) or as a 2D target.
/// The 2D view of one layer of a shadow map (a depth attachment).
fn layer_view_desc(layer: u32) -> wgpu::TextureViewDescriptor<'static> {
    wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    }
}

impl ShadowPass {
    /// Compiles the depth, mask and view pipelines, makes the sun view uniforms and takes `scene`'s casters.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        let depth_program = Program::new(ctx, "passes/shadows/depth.wgsl")?;
        // Alpha-tested glTF casters: compiled only for scenes that have some.
        let alpha = scene
            .pbr
            .materials
            .iter()
            .any(|m| m.alpha_mode != crate::scene::gltf::AlphaMode::Opaque && !m.transmits());
        let masked = match alpha {
            true => Some(std::sync::Arc::new(depth::MaskedProgram::new(ctx)?)),
            false => None,
        };
        let depth32 = DepthPipelines::new(ctx, &depth_program, masked.as_ref(), SHADOW_FORMAT)?;
        let depth16 = DepthPipelines::new(ctx, &depth_program, masked.as_ref(), STATIC_FORMAT)?;
        let views = (0..CASCADES + 2)
            .map(|i| depth::view_buffer(ctx, &format!("shadows.view{i}")))
            .collect();
        let mask_program = Program::new(ctx, "passes/shadows/mask.wgsl")?;
        let targets = [crate::passes::common::target(MASK_FORMAT)];
        let mask =
            mask_program.render_pipeline(ctx, &RenderSpec::fullscreen("shadows.mask", &targets))?;
        let tiled = [("TILES", 1.0)];
        let mut tiled_spec = RenderSpec::fullscreen("shadows.mask", &targets);
        tiled_spec.constants = &tiled;
        let mask_tiled = mask_program.render_pipeline(ctx, &tiled_spec)?;
        let tiles_program = Program::new(ctx, "passes/shadows/mask_tiles.wgsl")?;
        let tiles = tiles_program.compute_pipeline(ctx, "cs_main", &[])?;
        // Min on R = max of the occlusions (Ryse's hero blend); G, B, A untouched.
        let min_blend = [Some(wgpu::ColorTargetState {
            format: MASK_FORMAT,
            blend: Some(wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Min,
                },
                alpha: wgpu::BlendComponent::REPLACE,
            }),
            write_mask: wgpu::ColorWrites::RED,
        })];
        let mut hero_spec = RenderSpec::fullscreen("shadows.mask.hero", &min_blend);
        hero_spec.fragment_entry = Some("fs_hero");
        let hero_blend = mask_program.render_pipeline(ctx, &hero_spec)?;
        let params = uniform_buffer(
            ctx,
            "shadows.mask.params",
            &<MaskParamsGpu as bytemuck::Zeroable>::zeroed(),
        );
        let view_program = Program::new(ctx, "passes/shadows/view.wgsl")?;
        let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadows.compare"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let n_lights = scene.lights.len().max(1) as u64;
        let light_size = std::mem::size_of::<LocalLightGpu>() as u64;
        let tile_size = std::mem::size_of::<ShadowTileGpu>() as u64;
        let local_lights = storage_buffer(ctx, "shadows.local_lights", 16 + light_size * n_lights);
        let light_tiles = storage_buffer(ctx, "shadows.light_tiles", tile_size * 6 * n_lights);
        Ok(Self {
            depth_program,
            depth32,
            depth16,
            views,
            mask_program,
            mask,
            mask_tiled,
            tiles_program,
            tiles,
            hero_blend,
            params,
            view_program,
            sampler,
            casters: Casters::from_scene(scene),
            static_state: StaticMapState::default(),
            static_all: None,
            static_maps: None,
            world: None,
            tiled: WorldMapState::default(),
            tile_views: (0..MAX_STATIC_TILES)
                .map(|i| depth::view_buffer(ctx, &format!("shadows.static.tile{i}")))
                .collect(),
            settle: false,
            plan: None,
            cascade_resolution: 0,
            hero_resolution: 0,
            lights: scene.lights.clone(),
            atlas: None,
            local_lights,
            light_tiles,
            atlas_views: Vec::new(),
            atlas_resolution: 0,
        })
    }

    /// The pipeline of a shadow debug view in `format`.
    pub fn view_pipeline(
        &self,
        ctx: &GpuContext,
        view: ShadowView,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        view_pipeline(ctx, &self.view_program, "shadows.view", view.id(), format)
    }

    /// Each shadowed local light's atlas tiles (`ShadowTileGpu`, six per
    /// point light), what the mask and particles read the atlas through.
    pub fn light_tiles(&self) -> &wgpu::Buffer {
        &self.light_tiles
    }

    /// The mask's parameters (`ShadowMaskParams`: every sun map's
    /// matrix and the filter), written by [`Self::update`].
    pub fn mask_params(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// S2 follows a streamed world: the static map becomes a square of
    /// [`world_map::WORLD_EXTENT`] around the camera holding casters
    /// between `heights` (m), re-centred and refilled tile by tile
    /// ([`WorldMapState`]); the terrain draws into it through
    /// [`CascadeCaster::add_static_tile`].
    pub fn attach_world(&mut self, heights: (f32, f32)) {
        self.world = Some(WorldMap::new(heights));
        self.tiled.reset();
    }

    /// Streaming placed casters inside `bounds` (a sector's ground and what
    /// stands on it): the static-map texels they cast into are rendered
    /// again. Returns the rectangles queued.
    pub fn refresh(&mut self, bounds: &crate::scene::Aabb) -> u32 {
        match (&self.world, &self.static_maps) {
            (Some(map), Some((n, _))) => self.tiled.mark_dirty(map, bounds, *n),
            _ => 0,
        }
    }

    /// The next frame renders every static-map tile that waits (offline
    /// frames after `Renderer::settle_world`: the same image on every run).
    pub fn settle(&mut self) {
        self.settle = true;
    }

    /// The shown static map read back: its fit, edge and 16-bit depths
    /// (row 0 = light-view +y); `None` while none is complete.
    pub fn read_static_map(
        &self,
        ctx: &GpuContext,
    ) -> Result<Option<(ShadowFit, u32, Vec<u16>)>, GpuError> {
        let shown = match self.world {
            Some(_) => self.tiled.shown.map(|(i, fit, _)| (i, fit)),
            None => self.static_state.shown,
        };
        let (Some((i, fit)), Some((n, maps))) = (shown, &self.static_maps) else {
            return Ok(None);
        };
        let data = crate::gpu::read_texture(ctx, &maps[i.min(1)], 0, 0)?;
        Ok(Some((fit, *n, bytemuck::pod_collect_to_vec(&data.bytes))))
    }

    /// The culled views whose pool lists this frame's sun maps draw
    /// (their calls are the culling's to count).
    pub fn pool_views(&self) -> impl Iterator<Item = u32> + '_ {
        let plan = self.plan.iter();
        let cascades = plan.clone().flat_map(|p| p.cascades.iter().map(|(_, l)| l));
        let tiles = plan.flat_map(|p| p.static_tiles.iter().map(|t| &t.pool));
        cascades.chain(tiles).filter_map(|l| l.pool_view)
    }

    /// The world's static-map state (tests, `bench`).
    pub fn world_map(&self) -> Option<(&WorldMap, &WorldMapState)> {
        self.world.as_ref().map(|m| (m, &self.tiled))
    }

    /// Plans this frame (fits, culled draw lists, the static slice, the hero)
    /// and uploads the uniforms; `None` settings = shadows off. `gpu_calls`:
    /// the cascades are culled on the GPU (V6), cascade i as view `1 + i`
    /// of the culled lists, with that many multi-draws per cascade. `pool`:
    /// the streamed pool is culled per view (cascades as above, the
    /// world's static tiles after them), on the GPU or by its CPU twin.
    #[allow(clippy::too_many_arguments)]
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        camera: &Camera,
        aspect: f32,
        sun_direction: Vec3,
        cascade_resolution: u32,
        settings: Option<&ShadowSettings>,
        time_s: f32,
        gpu_calls: Option<u32>,
        pool: bool,
    ) -> ShadowStats {
        let on = settings.filter(|s| s.mode != ShadowMode::Off && cascade_resolution > 0);
        // S3: the light list (lit with or without shadows), tiles when on.
        let atlas_n = on.map_or(0, |s| s.atlas_resolution);
        if atlas_n == 0 {
            self.atlas = None;
        } else if self
            .atlas
            .as_ref()
            .is_none_or(|a| a.size != atlas_n.next_power_of_two())
        {
            self.atlas = Some(AtlasAllocator::new(atlas_n, ATLAS_MIN_TILE, ATLAS_MAX_TILE));
        }
        let local = local::plan(
            &self.lights,
            camera.position,
            self.atlas.as_mut(),
            &self.casters,
            scene,
            on.is_none_or(|s| s.skip_casterless),
        );
        let mut bytes = bytemuck::bytes_of(&[local.lights.len() as u32, 0, 0, 0]).to_vec();
        bytes.extend_from_slice(bytemuck::cast_slice(&local.lights));
        ctx.queue.write_buffer(&self.local_lights, 0, &bytes);
        if !local.tiles.is_empty() {
            ctx.queue
                .write_buffer(&self.light_tiles, 0, bytemuck::cast_slice(&local.tiles));
        }
        while self.atlas_views.len() < local.projectors.len() {
            let i = self.atlas_views.len();
            self.atlas_views
                .push(depth::view_buffer(ctx, &format!("shadows.atlas.view{i}")));
        }
        for (p, buffer) in local.projectors.iter().zip(&self.atlas_views) {
            ctx.queue.write_buffer(
                buffer,
                0,
                bytemuck::bytes_of(&ShadowViewGpu::new(p.view_proj, time_s)),
            );
        }
        self.atlas_resolution = self.atlas.as_ref().map_or(0, |a| a.size);
        let Some(s) = on else {
            self.plan = None;
            return ShadowStats::default();
        };
        let bounds = self.casters.scene;
        let mut stats = ShadowStats::default();
        let mut plan = FramePlan {
            projectors: local.projectors,
            mask_tiles: s.mask_tiles,
            alpha_test: s.alpha_test,
            ..FramePlan::default()
        };
        stats.atlas_tiles = plan.projectors.len() as u32;
        let mut params = <MaskParamsGpu as bytemuck::Zeroable>::zeroed();
        let write_view = |i: usize, m: Mat4| {
            ctx.queue.write_buffer(
                &self.views[i],
                0,
                bytemuck::bytes_of(&ShadowViewGpu::new(m, time_s)),
            );
        };

        // S2: plan the static slice first; a complete map replaces cascade 3.
        // Below the horizon the sun lights nothing (lighting scales it to ~0):
        // no sun maps at night, R stays 1 and the local lights keep the frame.
        let sun_up = sun_direction.y > 0.0;
        let static_on = s.mode == ShadowMode::CsmStatic && sun_up;
        if static_on {
            // The world's map is whole tiles; a scene's the size asked for.
            let n = match self.world {
                Some(map) => map.resolution(s.static_resolution),
                None => s.static_resolution,
            };
            if self.static_maps.as_ref().is_none_or(|(m, _)| *m != n) {
                let make = |i| depth_texture(ctx, &format!("shadows.static{i}"), n, STATIC_FORMAT);
                self.static_maps = Some((n, [make(0), make(1)]));
                self.static_state.reset();
                self.tiled.reset();
            }
            // The map shown and the first cascade it replaces: the far one in
            // a scene; in the world none (the cascades draw the terrain at
            // this frame's LOD, the map at its fill's), it adds the far field.
            let shown = if let Some(map) = self.world {
                let whole = std::mem::take(&mut self.settle);
                let eye = glam::Vec2::new(camera.position.x, camera.position.z);
                let tiles = self
                    .tiled
                    .plan(&map, eye, sun_direction, n, MAX_STATIC_TILES, whole);
                // Culling views: the camera, the cascades (all four: the
                // sun is up), then the tiles.
                let first_view = 1 + CASCADES as u32;
                for (k, update) in tiles.into_iter().enumerate() {
                    let mut objects = DrawLists::default();
                    let keep_static = |is_static: bool| is_static;
                    (self.casters).cull_into(scene, &update.fit, keep_static, true, &mut objects);
                    let pool_lists = DrawLists {
                        pool_view: pool.then_some(first_view + k as u32),
                        ..DrawLists::default()
                    };
                    stats.static_draws += objects.len() as u32;
                    stats.static_tiles.push(update.fit.light_view_proj);
                    stats.static_texels += u64::from(update.rect[2]) * u64::from(update.rect[3]);
                    let m = update.fit.light_view_proj;
                    ctx.queue.write_buffer(
                        &self.tile_views[k.min(MAX_STATIC_TILES - 1)],
                        0,
                        bytemuck::bytes_of(&ShadowViewGpu::new(m, time_s)),
                    );
                    plan.static_tiles.push(StaticTile {
                        update,
                        objects,
                        pool: pool_lists,
                    });
                }
                self.tiled.shown.map(|(_, fit, _)| (fit, CASCADES))
            } else {
                if self.static_all.is_none() {
                    self.static_all = Some(static_draws(&self.casters, scene));
                }
                let all = self.static_all.as_deref().unwrap_or_default();
                if let Some(u) = self.static_state.plan(
                    &bounds,
                    sun_direction,
                    n,
                    all.len(),
                    s.static_draw_cap as usize,
                ) {
                    let slice = take_range(all, &u.range);
                    stats.static_draws = slice.len() as u32;
                    write_view(CASCADES, u.fit.light_view_proj);
                    plan.static_update = Some((u, slice));
                }
                self.static_state.shown.map(|(_, fit)| (fit, CASCADES - 1))
            };
            if let Some((fit, first)) = shown {
                stats.static_shown = true;
                params.static_map = fit.light_view_proj.to_cols_array_2d();
                params.static_info = [1.0, fit.texel_world, fit.depth_range, first as f32];
            }
        } else if s.mode != ShadowMode::CsmStatic {
            // Leaving csm+static frees 256 MB and restarts the fill next time.
            self.static_maps = None;
            self.static_state.reset();
            self.tiled.reset();
        }

        // S1: the cascades (the far one only while no static map is shown).
        let camera_near = camera.near.max(0.05);
        let splits = match s.cinematic {
            Some(c) => cascades::cinematic_splits(camera_near, c.near, c.far),
            None => cascades::practical_splits(camera_near, s.max_distance, s.split_lambda),
        };
        let rendered = if !sun_up {
            0
        } else if stats.static_shown && self.world.is_none() {
            CASCADES - 1
        } else {
            CASCADES
        };
        for i in 0..CASCADES {
            stats.splits[i] = splits[i + 1];
            params.splits[i] = splits[i + 1];
            let fit = cascades::fit_cascade(
                camera,
                aspect,
                &splits,
                i,
                sun_direction,
                &bounds,
                cascade_resolution,
                s.snap,
            );
            params.cascades[i] = fit.light_view_proj.to_cols_array_2d();
            params.texel[i] = fit.texel_world;
            params.depth_range[i] = fit.depth_range;
            if i < rendered {
                let mut lists = DrawLists::default();
                match gpu_calls {
                    Some(calls) => {
                        lists.gpu_view = Some((1 + i as u32, calls));
                        (self.casters).cull_into(scene, &fit, |_| true, false, &mut lists);
                    }
                    None => {
                        self.casters
                            .cull_into(scene, &fit, |_| true, true, &mut lists);
                        lists.pool_view = pool.then_some(1 + i as u32);
                    }
                }
                write_view(i, fit.light_view_proj);
                stats.fits.push(fit);
                plan.cascades.push((fit, lists));
            }
        }
        stats.cascades_rendered = rendered as u32;

        // S4: the hero map.
        if s.hero_resolution > 0
            && sun_up
            && let Some(h) = self.casters.hero_index(s.hero.as_deref())
            && let Some((object, mesh)) = self.casters.objects.get(h)
        {
            let fit = hero::hero_fit(
                object,
                mesh,
                time_s,
                sun_direction,
                &bounds,
                s.hero_resolution,
            );
            let of_hero = |draws| crate::gpu_scene::draws_of(draws, h as u32).to_vec();
            let textured = crate::gpu_scene::entries_of(&scene.draws_textured, h as u32, |e| &e.0);
            let blend = crate::gpu_scene::entries_of(&scene.draws_blend, h as u32, |e| &e.0);
            let textured: Vec<_> = (textured.iter().map(|(d, _)| d.clone()))
                .chain(blend.iter().map(|(d, _, _)| d.clone()))
                .collect();
            let lists = DrawLists {
                opaque: [of_hero(&scene.draws_opaque), textured].concat(),
                vegetation: of_hero(&scene.draws_vegetation),
                gpu_view: None,
                pool_view: None,
            };
            write_view(CASCADES + 1, fit.light_view_proj);
            params.hero = fit.light_view_proj.to_cols_array_2d();
            params.hero_info = [1.0, fit.texel_world, fit.depth_range, 0.0];
            if s.hero_scissor {
                let offset = NORMAL_OFFSET_TEXELS * fit.texel_world;
                let near = if camera.orthographic.is_some() {
                    0.0
                } else {
                    camera.near
                };
                let view_proj = camera.view_projection(aspect);
                // The hero's top in light view, 1 m up (as `hero_fit`).
                let b = mesh.transform(&object.transform_at(time_s));
                let top = b.transform(&fit.light_rotation).max.z + 1.0;
                plan.hero_rect = Some(hero_screen_rect(&fit, top, offset, view_proj, near));
            }
            plan.hero = Some((fit, lists));
        }

        params.filter_params = [
            s.filter_radius_texels,
            NORMAL_OFFSET_TEXELS,
            DEPTH_BIAS_TEXELS,
            rendered as f32,
        ];
        params.camera_forward = camera
            .forward
            .normalize_or(Vec3::NEG_Z)
            .extend(0.0)
            .to_array();
        params.light_rotation = cascades::light_rotation(sun_direction).to_cols_array_2d();
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));

        stats.draws = plan
            .cascades
            .iter()
            .map(|(_, l)| l.draw_calls(scene))
            .sum::<u32>()
            + plan
                .static_update
                .as_ref()
                .map_or(0, |(_, l)| l.draw_calls(scene))
            + plan.hero.as_ref().map_or(0, |(_, l)| l.draw_calls(scene))
            + (plan.static_tiles.iter())
                .map(|t| t.objects.draw_calls(scene) + t.pool.draw_calls(scene))
                .sum::<u32>()
            + plan
                .projectors
                .iter()
                .map(|p| p.draws.draw_calls(scene))
                .sum::<u32>();
        self.cascade_resolution = cascade_resolution;
        self.hero_resolution = s.hero_resolution;
        self.plan = Some(plan);
        stats
    }
}

/// NDC rectangle (x0, y0, x1, y1) holding every receiver the hero map can
/// shadow. The mask's hero pass reads the map at q = p + n * `offset`; a q
/// outside the fit's light-view box reads lit (`shadow_map_visibility`
/// returns 1 off the map and beyond its far plane), and so does a q nearer
/// the sun than `top` (the hero's highest light-view z: every depth stored
/// lies below it, the comparison passes). So that box, its near side cut
/// to `top` and grown by `offset`, cut at the camera's near plane (clip w =
/// `near`) and projected by `view_proj`, bounds the pixels the pass can
/// change (the hull of its corners and its edges' crossings of that plane).
/// `None`: no pixel.
pub fn hero_screen_rect(
    fit: &ShadowFit,
    top: f32,
    offset: f32,
    view_proj: Mat4,
    near: f32,
) -> Option<[f32; 4]> {
    let lo = fit.min - Vec3::splat(offset);
    let hi = Vec3::new(fit.max.x, fit.max.y, fit.max.z.min(top)) + Vec3::splat(offset);
    let to_world = view_proj * fit.light_rotation.inverse();
    let bit = |k: usize, b: usize, a: f32, c: f32| if k & b == 0 { a } else { c };
    let clip: Vec<glam::Vec4> = (0..8)
        .map(|k| {
            let p = Vec3::new(
                bit(k, 1, lo.x, hi.x),
                bit(k, 2, lo.y, hi.y),
                bit(k, 4, lo.z, hi.z),
            );
            to_world * p.extend(1.0)
        })
        .collect();
    let mut points: Vec<glam::Vec4> = clip.iter().copied().filter(|c| c.w >= near).collect();
    // The 12 edges: corner pairs differing in one bit.
    for k in 0..8usize {
        for b in [1usize, 2, 4] {
            let (a, c) = (clip[k], clip[k | b]);
            if k & b == 0 && (a.w - near) * (c.w - near) < 0.0 {
                points.push(a.lerp(c, (near - a.w) / (c.w - a.w)));
            }
        }
    }
    let mut r = [
        f32::INFINITY,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NEG_INFINITY,
    ];
    for c in points {
        let (x, y) = (c.x / c.w, c.y / c.w);
        r = [r[0].min(x), r[1].min(y), r[2].max(x), r[3].max(y)];
    }
    r.iter().all(|v| v.is_finite()).then_some(r)
}

/// Pixel scissor (x, y, w, h) of NDC rectangle `r` in a `size` image, grown
/// by two pixels (the TAA jitter moves the image by under one); `None` when
/// it covers no pixel.
pub fn ndc_scissor(r: [f32; 4], size: (u32, u32)) -> Option<[u32; 4]> {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let x0 = ((r[0] * 0.5 + 0.5) * w - 2.0).floor().clamp(0.0, w);
    let x1 = ((r[2] * 0.5 + 0.5) * w + 2.0).ceil().clamp(0.0, w);
    let y0 = ((0.5 - r[3] * 0.5) * h - 2.0).floor().clamp(0.0, h);
    let y1 = ((0.5 - r[1] * 0.5) * h + 2.0).ceil().clamp(0.0, h);
    (x1 > x0 && y1 > y0).then_some([x0 as u32, y0 as u32, (x1 - x0) as u32, (y1 - y0) as u32])
}

/// Every static object's draws, opaque first (the static map's fill order).
fn static_draws(casters: &Casters, scene: &SceneGpu) -> Vec<(crate::gpu_scene::Draw, bool)> {
    let keep = |d: &crate::gpu_scene::Draw| {
        !casters
            .moving
            .get(d.object as usize)
            .copied()
            .unwrap_or(true)
    };
    let opaque = (scene.draws_opaque.iter().chain(scene.textured_casters()))
        .filter(|d| keep(d))
        .map(|d| (d.clone(), false));
    let veg = scene
        .draws_vegetation
        .iter()
        .filter(|d| keep(d))
        .map(|d| (d.clone(), true));
    opaque.chain(veg).collect()
}

/// The draws of `all[range]` split back into opaque and vegetation lists.
fn take_range(all: &[(crate::gpu_scene::Draw, bool)], range: &std::ops::Range<usize>) -> DrawLists {
    let mut lists = DrawLists::default();
    for (d, veg) in &all[range.start.min(all.len())..range.end.min(all.len())] {
        if *veg {
            lists.vegetation.push(d.clone());
        } else {
            lists.opaque.push(d.clone());
        }
    }
    lists
}
