//! Height-field sky occlusion (TECHNIQUES L2; Far Cry 4 talk, SKY OCCLUSION).
//!
//! When a 64x64 m sector comes within [`RANGE`] of the camera and into the
//! frustum, `skyocc.heightfield` renders the scene's opaque geometry top-down
//! (orthographic, 25 cm per texel, with an apron of [`MARGIN_TEXELS`]),
//! `skyocc.blur_x`/`_y` blur it (binomial, sigma 25 cm) and `skyocc.visibility`
//! turns it into an SH2 visibility per texel (rotated Poisson disk, cap
//! rotated to the mean visible direction) plus (terrain, blurred) heights,
//! stored in a fixed pool of texture-array layers with LRU eviction
//! ([`pool`]). Lighting looks the sector up in a 32x32 table
//! (`shaders/sky_occlusion.wgsl`). CPU twin: [`mod@reference`]. Docs:
//! `docs/techniques/L2.md`.
//!
//! In the streamed world the height fields follow the streaming: the
//! terrain is sampled into them (`skyocc.terrain`, `terrain.wgsl`), the
//! pool instances come from a culling view over the frame's sectors
//! ([`SkyOccPass::cull_view`]), and a sector whose neighbourhood streams in
//! after it was rendered is rendered again ([`SkyOccPass::refresh`]).

pub mod pool;
pub mod reference;
mod resources;
mod tools;

use glam::{Mat4, Vec2, Vec4};

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::{Draw, SceneGpu};
use crate::graph::{FrameGraph, TextureHandle};
use crate::passes::common::{view_node, view_pipeline};
use crate::passes::cull::{CullView, Culled, List, SHADOW, bind_instances};
use crate::passes::gbuffer::GBuffer;
use crate::passes::terrain::TerrainHeights;
use crate::scene::{Aabb, Camera, Scene};
use pool::{Sector, SectorPool, visible_sectors};
pub use reference::{MARGIN_TEXELS, RENDER_TEXELS, SECTOR_TEXELS, TEXEL_SIZE};
use resources::{Intermediates, PoolTextures, SectorViewGpu};
use wgpu::StoreOp::{Discard, Store};

/// Sectors whose nearest point is within this distance (m) of the camera are wanted.
pub const RANGE: f32 = 160.0;
/// Most sectors rendered in one frame (the rest follow in later frames).
pub const MAX_SECTORS_PER_FRAME: usize = 16;
/// Pool layers (resident sectors): 32 x 1 MB.
pub const POOL_LAYERS: u32 = 32;

/// The debug views (`--view sky-visibility`, `--view bent-normal`); `id` is `VIEW`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SkyOccView {
    /// The diffuse sky visibility lighting applies (SH2 along the bent normal), as grey.
    Visibility = 1,
    /// The bent normal (mean unoccluded direction), world space, as n * 0.5 + 0.5.
    BentNormal = 2,
}

/// What the sky occlusion did this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SkyOccStats {
    /// Sectors in range and view.
    pub wanted: u32,
    /// Sectors rendered this frame (height field, blur, visibility).
    pub rendered: u32,
    /// Sectors resident in the pool.
    pub resident: u32,
}

/// One sector rendered this frame: every opaque draw, and the ground's
/// (rendered again alone for the terrain height the lighting fades from).
#[derive(Clone, Debug)]
struct Job {
    /// World x, z of the rendered image's texel (0, 0).
    origin: Vec2,
    draws: Vec<Draw>,
    ground_draws: Vec<Draw>,
}

/// What the streamed world adds to the height fields (`None`s: a plain
/// scene's objects alone).
#[derive(Clone, Copy, Default)]
pub struct SkyOccSources<'a> {
    /// The culled lists; the pool instances of view [`SkyOccPass::culled_view`] are drawn.
    pub culled: Option<Culled<'a>>,
    /// The terrain's height data, sampled under the objects.
    pub terrain: Option<TerrainHeights<'a>>,
}

/// The pool textures lighting reads, as graph handles (ordering after this
/// frame's sector updates).
#[derive(Clone, Copy, Debug)]
pub struct SkyOccFrame {
    /// The SH2 visibility pool (one array layer per resident sector).
    pub vis: TextureHandle,
    /// The (terrain, fade) height pool, same layers.
    pub heights: TextureHandle,
}

/// The lighting bindings of the pool (views owned by the pass).
pub struct SkyOccBindings<'a> {
    /// The 32x32 sector table: per slot (sector x, sector z, pool layer, valid), sectors wrapped modulo 32.
    pub table: &'a wgpu::TextureView,
    /// SH2 visibility per texel, an array layer per resident sector.
    pub vis: &'a wgpu::TextureView,
    /// (terrain, fade) heights in metres per texel, same layers.
    pub heights: &'a wgpu::TextureView,
    /// Bilinear clamp sampler for the visibility.
    pub sampler: &'a wgpu::Sampler,
}

/// One sector's results read back (tests): row-major [`SECTOR_TEXELS`]².
#[derive(Clone, Debug)]
pub struct SectorReadback {
    /// SH2 visibility per texel (coefficients L00, L1-1, L10, L11).
    pub sh: Vec<Vec4>,
    /// (terrain, fade) heights.
    pub heights: Vec<Vec2>,
    /// The rendered image, highest surface ([`RENDER_TEXELS`]²).
    pub raw: Vec<f32>,
    /// The blurred rendered image ([`RENDER_TEXELS`]²).
    pub blurred: Vec<f32>,
}

/// L2 sky occlusion: renders sector height fields top-down, turns them into
/// SH2 visibility in a pooled texture array, and keeps the sector table lighting reads.
pub struct SkyOccPass {
    height_program: Program,
    height_pipeline: wgpu::RenderPipeline,
    blur_program: Program,
    blur: [wgpu::ComputePipeline; 2],
    vis_program: Program,
    visibility: wgpu::ComputePipeline,
    smooth_program: Program,
    smooth: wgpu::ComputePipeline,
    view_program: Program,
    pool: SectorPool,
    textures: PoolTextures,
    work: Option<Intermediates>,
    disk: wgpu::Buffer,
    /// Object bounds over all time (draw culling per sector) and the scene's heights.
    bounds: Vec<Aabb>,
    /// Per object: terrain ([`crate::scene::Object::ground`]).
    ground: Vec<bool>,
    /// Per object: moves (left out of the height fields).
    moving: Vec<bool>,
    heights: (f32, f32),
    /// `skyocc.terrain` (a streamed world's terrain, [`Self::attach_terrain`]).
    terrain: Option<(Program, wgpu::RenderPipeline)>,
    /// The culling view of this frame's sectors (`frame::plan` sets it).
    pub culled_view: Option<u32>,
    jobs: Vec<Job>,
    /// What the pass did in the last frame planned.
    pub stats: SkyOccStats,
}

impl SkyOccPass {
    /// Compiles the height-field, blur, visibility and view pipelines and takes `scene`'s object bounds and flags.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        let height_program = Program::new(ctx, "passes/skyocc/heightfield.wgsl")?;
        let height_pipeline = resources::height_pipeline(ctx, &height_program)?;
        let blur_program = Program::new(ctx, "passes/skyocc/blur.wgsl")?;
        let blur = [
            blur_program.compute_pipeline(ctx, "cs_main", &[("AXIS", 0.0)])?,
            blur_program.compute_pipeline(ctx, "cs_main", &[("AXIS", 1.0)])?,
        ];
        let vis_program = Program::new(ctx, "passes/skyocc/visibility.wgsl")?;
        let constants = [
            ("RADIUS", reference::SAMPLE_RADIUS as f64),
            ("STEPS", reference::MARCH_STEPS as f64),
            ("MARGIN", MARGIN_TEXELS as f64),
            ("TEXEL", TEXEL_SIZE as f64),
            ("ORIGIN_LIFT", reference::ORIGIN_LIFT as f64),
            ("FADE_RADIUS", reference::FADE_RADIUS as f64),
            ("BORDER", reference::SMOOTH_BORDER as f64),
        ];
        let visibility = vis_program.compute_pipeline(ctx, "cs_main", &constants)?;
        let smooth_program = Program::new(ctx, "passes/skyocc/visibility_smooth.wgsl")?;
        let border = [("BORDER", reference::SMOOTH_BORDER as f64)];
        let smooth = smooth_program.compute_pipeline(ctx, "cs_main", &border)?;
        let casters = crate::passes::shadows::casters::Casters::from_scene(scene);
        let heights = if casters.scene.is_empty() {
            (-1.0, 1.0)
        } else {
            (casters.scene.min.y - 1.0, casters.scene.max.y + 1.0)
        };
        Ok(Self {
            height_program,
            height_pipeline,
            blur_program,
            blur,
            vis_program,
            visibility,
            smooth_program,
            smooth,
            view_program: Program::new(ctx, "passes/skyocc/view.wgsl")?,
            pool: SectorPool::new(POOL_LAYERS as usize),
            textures: PoolTextures::new(ctx, 1, 1),
            work: None,
            disk: resources::disk_buffer(ctx),
            bounds: casters.bounds,
            ground: crate::gpu_scene::gpu_order(scene)
                .into_iter()
                .map(|i| scene.objects[i].ground)
                .collect(),
            moving: casters.moving,
            heights,
            terrain: None,
            culled_view: None,
            jobs: Vec::new(),
            stats: SkyOccStats::default(),
        })
    }

    /// Samples a streamed world's terrain into every height field from now
    /// on; `heights` (bottom, top, m) bounds the terrain and what stands on
    /// it (the orthographic depth range grows to hold it). Forgets resident
    /// sectors.
    pub fn attach_terrain(
        &mut self,
        ctx: &GpuContext,
        heights: (f32, f32),
    ) -> Result<(), GpuError> {
        let program = Program::new(ctx, "passes/skyocc/terrain.wgsl")?;
        let pipeline = resources::terrain_pipeline(ctx, &program)?;
        self.terrain = Some((program, pipeline));
        self.heights = (self.heights.0.min(heights.0), self.heights.1.max(heights.1));
        self.pool.clear();
        Ok(())
    }

    /// The world x, z rectangle of every sector whose rendered image
    /// (sector and apron) overlaps `min..max` is rendered again when next
    /// wanted (a world sector streamed in there: its tile and instances
    /// were not in the image). Returns the sectors marked.
    pub fn refresh(&mut self, min: Vec2, max: Vec2) -> u32 {
        let apron = MARGIN_TEXELS as f32 * TEXEL_SIZE;
        let lo = pool::sector_of(min.x - apron, min.y - apron);
        let hi = pool::sector_of(max.x + apron, max.y + apron);
        let before = self.pool.stale();
        for j in lo.y..=hi.y {
            for i in lo.x..=hi.x {
                self.pool.mark_stale(Sector::new(i, j));
            }
        }
        (self.pool.stale() - before) as u32
    }

    /// The culling view holding this frame's sectors' images (the union of
    /// their rectangles, every height); `None` when no sector is rendered.
    pub fn cull_view(&self) -> Option<CullView> {
        let w = RENDER_TEXELS as f32 * TEXEL_SIZE;
        let mut jobs = self.jobs.iter();
        let first = jobs.next()?.origin;
        let (min, max) = jobs.fold((first, first + w), |(lo, hi), j| {
            (lo.min(j.origin), hi.max(j.origin + w))
        });
        Some(CullView::prism(min, max))
    }

    /// The pipeline of a debug view in `format`.
    pub fn view_pipeline(
        &self,
        ctx: &GpuContext,
        view: SkyOccView,
        format: wgpu::TextureFormat,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        view_pipeline(ctx, &self.view_program, "skyocc.view", view as u32, format)
    }

    /// Orthographic top-down projection of the rendered image at `origin`:
    /// clip x from world x, clip y = 1 at the image's min z (row 0), depth 0
    /// at the top of the scene and 1 at its bottom.
    fn sector_view_proj(&self, origin: Vec2) -> Mat4 {
        let w = RENDER_TEXELS as f32 * TEXEL_SIZE;
        let (bottom, top) = self.heights;
        let d = top - bottom;
        Mat4::from_cols(
            Vec4::new(2.0 / w, 0.0, 0.0, 0.0),
            Vec4::new(0.0, 0.0, -1.0 / d, 0.0),
            Vec4::new(0.0, -2.0 / w, 0.0, 0.0),
            Vec4::new(
                -1.0 - 2.0 * origin.x / w,
                1.0 + 2.0 * origin.y / w,
                top / d,
                1.0,
            ),
        )
    }

    /// Origin (world x, z of texel (0, 0)) of a sector's rendered image.
    pub fn render_origin(sector: Sector) -> Vec2 {
        sector.as_vec2() * reference::SECTOR_SIZE - MARGIN_TEXELS as f32 * TEXEL_SIZE
    }

    /// Plans this frame: the sectors in range and view, the pool's LRU
    /// update, the jobs of up to [`MAX_SECTORS_PER_FRAME`] new sectors; and
    /// uploads their views, the job list and the sector table. `enabled`
    /// false: nothing is rendered (the lighting permutation reads nothing).
    pub fn update(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        camera: &Camera,
        aspect: f32,
        enabled: bool,
    ) -> SkyOccStats {
        self.jobs.clear();
        if !enabled {
            self.stats = SkyOccStats::default();
            return self.stats;
        }
        let wanted = visible_sectors(
            camera.position,
            camera.view_projection(aspect),
            RANGE,
            self.heights,
        );
        let planned = self.pool.plan(&wanted, MAX_SECTORS_PER_FRAME);
        self.plan_jobs(ctx, scene, &planned, &wanted);
        self.stats = SkyOccStats {
            wanted: wanted.len() as u32,
            rendered: self.jobs.len() as u32,
            resident: self.pool.resident().count() as u32,
        };
        self.stats
    }

    fn plan_jobs(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        planned: &[(Sector, u32)],
        wanted: &[Sector],
    ) {
        if self.textures.layers < POOL_LAYERS {
            self.textures = PoolTextures::new(ctx, POOL_LAYERS, SECTOR_TEXELS as u32);
        }
        if self.work.is_none() {
            self.work = Some(Intermediates::new(ctx, MAX_SECTORS_PER_FRAME as u32));
        }
        let Some(work) = &self.work else { return };
        let w = RENDER_TEXELS as f32 * TEXEL_SIZE;
        let mut gpu_jobs = Vec::new();
        let mut jobs = Vec::new();
        for (i, &(sector, layer)) in planned.iter().enumerate() {
            let origin = Self::render_origin(sector);
            // Static geometry only: a moving object's footprint would stay
            // where it was when the sector was rendered.
            let region = Aabb {
                min: glam::Vec3::new(origin.x, f32::NEG_INFINITY, origin.y),
                max: glam::Vec3::new(origin.x + w, f32::INFINITY, origin.y + w),
            };
            let inside =
                |i: usize, b: &Aabb| self.moving.get(i) == Some(&false) && b.overlaps(&region);
            let all = scene
                .draws_opaque
                .iter()
                .chain(scene.draws_textured.iter().map(|(d, _)| d));
            let draws: Vec<Draw> = crate::gpu_scene::cull(all, &self.bounds, inside).collect();
            let ground_draws = draws
                .iter()
                .filter(|d| self.ground.get(d.object as usize) == Some(&true))
                .cloned()
                .collect();
            let view_proj = self.sector_view_proj(origin);
            ctx.queue.write_buffer(
                &work.views[i],
                0,
                bytemuck::bytes_of(&SectorViewGpu {
                    view_proj: view_proj.to_cols_array_2d(),
                    origin: [origin.x, origin.y, TEXEL_SIZE, 0.0],
                }),
            );
            gpu_jobs.push(resources::JobGpu {
                origin: [origin.x, origin.y, 0.0, 0.0],
                layer: [layer, 0, 0, 0],
            });
            jobs.push(Job {
                origin,
                draws,
                ground_draws,
            });
        }
        self.jobs = jobs;
        if !gpu_jobs.is_empty() {
            ctx.queue
                .write_buffer(&work.jobs, 0, bytemuck::cast_slice(&gpu_jobs));
        }
        let table = pool::sector_table(&self.pool, wanted);
        self.textures.write_table(ctx, &table);
    }

    /// The lighting and view bindings of the pool.
    pub fn bindings(&self) -> SkyOccBindings<'_> {
        SkyOccBindings {
            table: &self.textures.table_view,
            vis: &self.textures.vis_view,
            heights: &self.textures.heights_view,
            sampler: &self.textures.sampler,
        }
    }

    /// Adds this frame's sector updates (none when nothing is planned) and
    /// returns the pool textures lighting reads.
    pub fn add<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        sources: SkyOccSources<'a>,
    ) -> SkyOccFrame {
        let vis = graph.import_texture("skyocc.vis", &self.textures.vis);
        let heights = graph.import_texture("skyocc.heights", &self.textures.heights);
        let Some(work) = self.work.as_ref().filter(|_| !self.jobs.is_empty()) else {
            return SkyOccFrame { vis, heights };
        };
        let (raw, ground) = self.add_heightfields(graph, scene, work, sources);
        let n = self.jobs.len() as u32;
        self.add_kernels(graph, work, (raw, ground), (vis, heights), n)
    }

    /// Per job i, one depth layer kept across the three: `skyocc.terrain{i}`
    /// (a world's terrain into both images), `skyocc.ground{i}` (the ground
    /// objects into the terrain height image) and `skyocc.heightfield{i}`
    /// (every static object, and a world's pool instances, into the raw
    /// image); returns both images' new versions.
    fn add_heightfields<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        scene: &'a SceneGpu,
        work: &'a Intermediates,
        sources: SkyOccSources<'a>,
    ) -> (TextureHandle, TextureHandle) {
        let mut raw = graph.import_texture("skyocc.raw", &work.raw);
        let mut ground = graph.import_texture("skyocc.ground", &work.ground);
        let mut depth = graph.import_texture("skyocc.depth", &work.depth);
        let (bottom, _) = self.heights;
        let clear = wgpu::LoadOp::Clear(wgpu::Color {
            r: bottom as f64,
            g: 0.0,
            b: 0.0,
            a: 1.0,
        });
        let ops = |load, store| wgpu::Operations { load, store };
        let pool = sources.culled.zip(self.culled_view);
        let terrain = sources.terrain.zip(self.terrain.as_ref());
        for (i, job) in self.jobs.iter().enumerate() {
            let layer = || Some(resources::layer_view_desc(i as u32));
            let (colour_load, depth_load) = match terrain {
                Some((t, (program, pipeline))) => {
                    let written = graph
                        .raster(&format!("skyocc.terrain{i}"), program)
                        .pipeline(Ok(pipeline.clone()))
                        .uniform("sector", &work.views[i])
                        .uniform("terrain", t.params)
                        .external("coarse_load", t.coarse)
                        .external("fine_load", t.fine)
                        .external("pages", t.pages)
                        .color_view(raw, layer(), clear)
                        .color_view(ground, layer(), clear)
                        .depth(depth, layer(), ops(wgpu::LoadOp::Clear(1.0), Store))
                        .record(|_, rp| {
                            rp.draw(0..3, 0..1);
                            Ok(())
                        });
                    raw = written.colors.first().copied().unwrap_or(raw);
                    ground = written.colors.get(1).copied().unwrap_or(ground);
                    depth = written.depth.unwrap_or(depth);
                    (wgpu::LoadOp::Load, wgpu::LoadOp::Load)
                }
                None => (clear, wgpu::LoadOp::Clear(1.0)),
            };
            let draws = &job.ground_draws;
            let written = graph
                .raster(&format!("skyocc.ground{i}"), &self.height_program)
                .pipeline(Ok(self.height_pipeline.clone()))
                .uniform("sector", &work.views[i])
                .uniform("objects", &scene.objects)
                .uniform("instances", &scene.instances)
                .color_view(ground, layer(), colour_load)
                .depth(depth, layer(), ops(depth_load, Store))
                .record(move |_, rp| {
                    if !draws.is_empty() {
                        scene.bind_geometry(rp);
                        scene.draw_list(rp, draws);
                    }
                    Ok(())
                });
            ground = written.colors.first().copied().unwrap_or(ground);
            depth = written.depth.unwrap_or(depth);
            // Every object over the ground's depth (LessEqual: the ground
            // objects again, at the same depth, into the raw image too).
            let draws = &job.draws;
            let node = graph
                .raster(&format!("skyocc.heightfield{i}"), &self.height_program)
                .pipeline(Ok(self.height_pipeline.clone()))
                .uniform("sector", &work.views[i])
                .uniform("objects", &scene.objects);
            let node = bind_instances(node, pool.as_ref().map(|(c, _)| c), &scene.instances);
            let written = node
                .color_view(raw, layer(), colour_load)
                .depth(depth, layer(), ops(wgpu::LoadOp::Load, Discard))
                .record(move |ctx, rp| {
                    scene.bind_geometry(rp);
                    if !draws.is_empty() {
                        scene.draw_list(rp, draws);
                    }
                    if let Some((c, view)) = pool {
                        // Opaque regions alone: the height pipeline does
                        // not alpha-test (the trees' trunks stand in).
                        c.draw_pool(rp, ctx, view, List::Opaque, SHADOW);
                    }
                    Ok(())
                });
            raw = written.colors.first().copied().unwrap_or(raw);
            depth = written.depth.unwrap_or(depth);
        }
        (raw, ground)
    }

    /// `skyocc.blur_x`, `skyocc.blur_y`, `skyocc.visibility` and
    /// `skyocc.smooth` over `n` jobs' height images into the pool's
    /// visibility and heights; returns the pool's new versions.
    fn add_kernels<'a>(
        &'a self,
        graph: &mut FrameGraph<'a>,
        work: &'a Intermediates,
        (raw, ground): (TextureHandle, TextureHandle),
        (vis, heights): (TextureHandle, TextureHandle),
        n: u32,
    ) -> SkyOccFrame {
        let (mut vis, mut heights) = (vis, heights);
        let scratch = graph.import_texture("skyocc.scratch", &work.scratch);
        let blurred = graph.import_texture("skyocc.blurred", &work.blurred);
        let vis_ext = graph.import_texture("skyocc.vis_ext", &work.vis_ext);
        let array = resources::array_view_desc;
        // Blur along x (raw -> scratch), then y (scratch -> blurred).
        let groups = (RENDER_TEXELS as u32).div_ceil(8);
        let blur = |g: &mut FrameGraph<'a>, id: &str, axis: usize, src, dst| {
            g.compute(id, &self.blur_program)
                .compute_pipeline(Ok(self.blur[axis].clone()))
                .read_array("src_load", src)
                .storage_view("dst", dst, array())
                .dispatch([groups, groups, n])
                .storage
                .first()
                .copied()
                .unwrap_or(dst)
        };
        let scratch = blur(graph, "skyocc.blur_x", 0, raw, scratch);
        let blurred = blur(graph, "skyocc.blur_y", 1, scratch, blurred);
        // SH2 visibility over the sector and its border, then the smoothing
        // into the pool (side effect: later frames read the pool).
        let ext = (SECTOR_TEXELS + 2 * reference::SMOOTH_BORDER) as u32;
        let written = graph
            .compute("skyocc.visibility", &self.vis_program)
            .compute_pipeline(Ok(self.visibility.clone()))
            .side_effect()
            .read_array("raw_load", raw)
            .read_array("ground_load", ground)
            .read_array("blurred_load", blurred)
            .uniform("disk", &self.disk)
            .uniform("jobs", &work.jobs)
            .storage_view("vis_out", vis_ext, array())
            .storage_view("heights_out", heights, array())
            .dispatch([ext.div_ceil(8), ext.div_ceil(8), n]);
        let vis_ext = written.storage.first().copied().unwrap_or(vis_ext);
        heights = written.storage.get(1).copied().unwrap_or(heights);
        let texels = (SECTOR_TEXELS as u32).div_ceil(8);
        let written = graph
            .compute("skyocc.smooth", &self.smooth_program)
            .compute_pipeline(Ok(self.smooth.clone()))
            .side_effect()
            .read_array("vis_load", vis_ext)
            .uniform("jobs", &work.jobs)
            .storage_view("vis_out", vis, array())
            .dispatch([texels, texels, n]);
        vis = written.storage.first().copied().unwrap_or(vis);
        SkyOccFrame { vis, heights }
    }

    /// The debug view of the sky visibility or the bent normal into `output`.
    pub fn add_view<'a>(
        &'a self,
        ctx: &GpuContext,
        graph: &mut FrameGraph<'a>,
        kind: SkyOccView,
        frame: SkyOccFrame,
        gbuffer: GBuffer,
        output: TextureHandle,
    ) -> TextureHandle {
        let id = kind as u32;
        let node = view_node(ctx, graph, &self.view_program, "skyocc.view", id, output);
        let b = self.bindings();
        node.read("gbuffer_frame", gbuffer.frame)
            .read("depth", gbuffer.depth)
            .external("skyocc_table", b.table)
            .read_array("skyocc_vis", frame.vis)
            .read_array("skyocc_heights_load", frame.heights)
            .sampler("skyocc_sampler", b.sampler)
            .draw()
    }

    /// Forgets resident sectors (the scene's geometry changed).
    pub fn invalidate(&mut self) {
        self.pool.clear();
    }

    /// The sectors a camera wants (in range and view), nearest first.
    pub fn wanted(&self, camera: &Camera, aspect: f32) -> Vec<Sector> {
        visible_sectors(
            camera.position,
            camera.view_projection(aspect),
            RANGE,
            self.heights,
        )
    }
}
