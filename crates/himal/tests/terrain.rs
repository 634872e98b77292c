//! CDLOD terrain (`passes/terrain`, docs/techniques/terrain.md): the GPU's
//! patch list and rendered depth against the CPU twin, cracks from grazing
//! and top-down views with tiles resident in part of the world, popping
//! with and without morph, determinism, view distance and shadows. Drawn
//! after a real `gbuffer` node into its targets, on lavapipe, <= 320 x 180.

mod common;

use std::sync::Mutex;

use glam::{Mat4, Vec2, Vec3, Vec4};
use himal::gpu::{GpuContext, read_texture};
use himal::gpu_scene::SceneGpu;
use himal::gpu_scene::uniforms::ViewUniform;
use himal::graph::{FrameGraph, TextureAccess, TextureHandle};
use himal::passes::cull::CullView;
use himal::passes::gbuffer::{ALBEDO_FORMAT, DEPTH_FORMAT, FRAME_FORMAT, GBufferPass};
use himal::passes::terrain::reference::{
    self, Heights, PATCH_QUADS, PATCH_VERTICES, Patch, Ranges, Selector,
};
use himal::passes::terrain::{MAX_PATCHES, TerrainDesc, TerrainPass, TerrainStats, TerrainView};
use himal::scene::{Camera, Scene, TerrainNoise};

const SIZE: (u32, u32) = (320, 180);

/// A 32 x 32-sector world (2048 m) centred on the origin.
const SECTORS: u32 = 32;

fn noise() -> TerrainNoise {
    TerrainNoise {
        octaves: 6,
        amplitude: 160.0,
        frequency: 1.0 / 600.0,
        ..TerrainNoise::default()
    }
}

fn desc(sectors: u32) -> TerrainDesc {
    let n = noise();
    let half = sectors as f32 * 32.0;
    TerrainDesc::from_fn(Vec2::splat(-half), sectors, |x, z| n.height(x, z))
}

fn ground(x: f32, z: f32) -> f32 {
    noise().height(x, z)
}

/// One device for the whole binary; the GPU tests run one at a time.
fn ctx() -> &'static GpuContext {
    himal::gpu::testing::shared_context().expect("a GPU adapter (lavapipe in CI)")
}
static GPU: Mutex<()> = Mutex::new(());

/// A G-buffer node over an almost empty scene (a ball far below ground),
/// then the terrain node, then copies of albedo, frame and depth.
struct Rig {
    scene: SceneGpu,
    gbuffer: GBufferPass,
    view: wgpu::Buffer,
    terrain: TerrainPass,
}

struct Frame {
    albedo: Vec<[f32; 4]>,
    depth: Vec<f32>,
    /// Albedo, frame and depth bytes.
    bytes: Vec<u8>,
    stats: TerrainStats,
    view_proj: Mat4,
}

const SCENE: &str = r#"
[sun]
time = "10:30"

[[material]]
name = "m"
albedo_linear = [0.5, 0.5, 0.5]

[[object]]
name = "ball"
primitive = "sphere"
material = "m"
radius = 1.0
segments = 8
position = [0.0, -5000.0, 0.0]
"#;

impl Rig {
    fn new(desc: &TerrainDesc) -> Self {
        let ctx = ctx();
        let scene =
            Scene::from_toml_str(SCENE, "terrain test", std::path::Path::new(".")).expect("scene");
        let view = himal::gpu::pipeline::uniform_buffer(
            ctx,
            "view",
            &ViewUniform::new(
                Mat4::IDENTITY,
                Mat4::IDENTITY,
                Mat4::IDENTITY,
                Vec3::ZERO,
                0.1,
                SIZE,
                0,
                0.0,
            ),
        );
        Self {
            scene: SceneGpu::upload(ctx, &scene).expect("upload"),
            gbuffer: GBufferPass::new(ctx).expect("gbuffer"),
            view,
            terrain: TerrainPass::new(ctx, desc).expect("terrain pass"),
        }
    }

    /// Tiles for the sectors in `x.0..x.1` x `z.0..z.1`, from [`ground`].
    fn upload(&self, desc: &TerrainDesc, x: (u32, u32), z: (u32, u32)) {
        let mut slot = 0;
        for sz in z.0..z.1 {
            for sx in x.0..x.1 {
                let tile = desc.tile_from_fn(sx, sz, ground);
                self.terrain
                    .upload_tile(&ctx().queue, slot, sx, sz, &tile)
                    .expect("upload");
                slot += 1;
            }
        }
    }

    fn draw(&mut self, camera: &Camera, prev: Option<Mat4>) -> Frame {
        let ctx = ctx();
        let (w, h) = SIZE;
        let aspect = w as f32 / h as f32;
        let view_proj = camera.view_projection(aspect);
        let stats = self
            .terrain
            .prepare(&ctx.queue, &TerrainView::from_camera(camera, SIZE), &[]);
        let uniform = ViewUniform::new(
            camera.view(),
            camera.projection(aspect),
            prev.unwrap_or(view_proj),
            camera.position,
            camera.near,
            SIZE,
            0,
            0.0,
        );
        ctx.queue
            .write_buffer(&self.view, 0, bytemuck::bytes_of(&uniform));
        let out = |format| {
            ctx.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("terrain.test.out"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let outs = [out(ALBEDO_FORMAT), out(FRAME_FORMAT), out(DEPTH_FORMAT)];
        {
            let mut g = FrameGraph::new();
            g.set_frame_constants(&[("view", &self.view)]);
            let gb = self
                .gbuffer
                .add(ctx, &mut g, SIZE, &self.scene, None, None, false);
            let gb = self.terrain.add(ctx, &mut g, gb, &self.view);
            let imported: Vec<TextureHandle> = ["out.albedo", "out.frame", "out.depth"]
                .iter()
                .zip(&outs)
                .map(|(name, t)| g.import_texture(name, t))
                .collect();
            let mut pass = g.add_pass("readback");
            let src: Vec<TextureHandle> = [gb.albedo, gb.frame, gb.depth]
                .iter()
                .map(|&h| pass.read(h, TextureAccess::CopySrc))
                .collect();
            let dst: Vec<TextureHandle> = imported
                .iter()
                .map(|&h| pass.write(h, TextureAccess::CopyDst))
                .collect();
            let marks = dst.clone();
            pass.execute(move |pc| {
                for (s, d) in src.iter().zip(&dst) {
                    let (s, d) = (pc.texture(*s), pc.texture(*d));
                    pc.encoder.copy_texture_to_texture(
                        s.as_image_copy(),
                        d.as_image_copy(),
                        s.size(),
                    );
                }
                Ok(())
            });
            for d in marks {
                g.mark_output(d);
            }
            himal::graph::run(ctx, g, None, "terrain test").expect("frame");
        }
        let data: Vec<_> = outs
            .iter()
            .map(|t| read_texture(ctx, t, 0, 0).expect("read back"))
            .collect();
        let bytes = data.iter().flat_map(|d| d.bytes.clone()).collect();
        Frame {
            albedo: data[0].to_rgba_f32().expect("albedo"),
            depth: data[2]
                .to_rgba_f32()
                .expect("depth")
                .iter()
                .map(|p| p[0])
                .collect(),
            bytes,
            stats,
            view_proj,
        }
    }
}

/// Ray through the centre of pixel (x, y).
fn ray(view_proj: Mat4, eye: Vec3, x: u32, y: u32) -> Vec3 {
    let inv = view_proj.inverse();
    let ndc = Vec4::new(
        (x as f32 + 0.5) / SIZE.0 as f32 * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / SIZE.1 as f32 * 2.0,
        1.0,
        1.0,
    );
    let p = inv * ndc;
    (p.truncate() / p.w - eye).normalize()
}

/// The twin's mesh: per patch its morphed vertices and bounds.
struct Mesh {
    patches: Vec<(Vec<Vec3>, Vec3, Vec3)>,
}

impl Mesh {
    fn new(h: &Heights, r: &Ranges, eye: Vec3, patches: &[Patch]) -> Self {
        let patches = patches
            .iter()
            .map(|p| {
                let v: Vec<Vec3> = (0..PATCH_VERTICES * PATCH_VERTICES)
                    .map(|i| {
                        reference::vertex(h, r, eye, p, [i % PATCH_VERTICES, i / PATCH_VERTICES])
                    })
                    .collect();
                let lo = v.iter().copied().fold(Vec3::INFINITY, Vec3::min);
                let hi = v.iter().copied().fold(Vec3::NEG_INFINITY, Vec3::max);
                (v, lo, hi)
            })
            .collect();
        Self { patches }
    }

    /// Nearest hit distance of the ray `o + t d` (Moller-Trumbore, front faces).
    fn cast(&self, o: Vec3, d: Vec3) -> Option<f32> {
        let n = PATCH_VERTICES as usize;
        let indices = reference::patch_indices();
        let mut best: Option<f32> = None;
        for (v, lo, hi) in &self.patches {
            if !common::hits_box(o, d, (*lo - 1e-3, *hi + 1e-3), f32::INFINITY) {
                continue;
            }
            debug_assert_eq!(v.len(), n * n);
            for t in indices.chunks_exact(3) {
                let (a, b, c) = (v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]);
                let (e1, e2) = (b - a, c - a);
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-12 {
                    continue;
                }
                let s = o - a;
                let u = s.dot(p) / det;
                let q = s.cross(e1);
                let w = d.dot(q) / det;
                if u < 0.0 || w < 0.0 || u + w > 1.0 {
                    continue;
                }
                let dist = e2.dot(q) / det;
                if dist > 1e-3 && best.is_none_or(|b| dist < b) {
                    best = Some(dist);
                }
            }
        }
        best
    }
}

fn camera(position: Vec3, target: Vec3) -> Camera {
    let mut c = Camera::look_at(position, target, 60.0);
    c.near = 0.5;
    c
}

/// A camera `above` metres over the ground at (x, z).
fn over(x: f32, z: f32, above: f32, target: Vec3) -> Camera {
    camera(Vec3::new(x, ground(x, z) + above, z), target)
}

#[test]
fn patches_and_depth_match_the_cpu_twin() {
    let _gpu = GPU.lock().unwrap_or_else(|e| e.into_inner());
    let d = desc(SECTORS);
    let mut rig = Rig::new(&d);
    // Tiles in the 8 x 8 sectors around the world's centre (512 m).
    rig.upload(&d, (12, 20), (12, 20));
    let eye_xz = Vec2::new(-40.0, 10.0);
    let target = Vec3::new(400.0, ground(400.0, 200.0) - 40.0, 200.0);
    let cam = over(eye_xz.x, eye_xz.y, 25.0, target);
    let frame = rig.draw(&cam, None);
    let view = TerrainView::from_camera(&cam, SIZE);
    let cpu = rig.terrain.cpu();
    let ranges = Ranges::new(&rig.terrain.geometry, &rig.terrain.settings, view.focal_px);
    let mut want = Vec::new();
    let stats = Selector {
        geometry: &rig.terrain.geometry,
        pyramid: &cpu.pyramid,
        ranges: &ranges,
        eye: cam.position,
        frustum: &CullView::clip(view.view_proj),
        capacity: MAX_PATCHES,
    }
    .select(&mut want);
    let got = rig.terrain.read_patches(ctx(), 0).expect("patches");
    // The list the GPU draws is the twin's, entry by entry.
    assert_eq!(got, want);
    assert_eq!(stats, frame.stats.camera);
    let levels = stats.per_level.iter().filter(|&&n| n > 0).count();
    eprintln!(
        "twin: {} patches ({} triangles) over {levels} levels {:?}, {} nodes visited, ranges {:?}",
        got.len(),
        frame.stats.triangles(),
        &stats.per_level[..ranges.levels as usize],
        stats.visited,
        &ranges.range[..ranges.levels as usize]
    );
    assert!(levels >= 4, "only {levels} levels in view");
    assert_eq!(stats.dropped, 0);

    // Depth at every 6th pixel against a ray cast of the twin's morphed mesh.
    let mesh = Mesh::new(&cpu.heights, &ranges, cam.position, &want);
    let (mut n, mut close, mut worst, mut coverage_mismatch) = (0, 0, 0.0f32, 0);
    for y in (3..SIZE.1).step_by(6) {
        for x in (3..SIZE.0).step_by(6) {
            let dir = ray(frame.view_proj, cam.position, x, y);
            let gpu = frame.depth[(y * SIZE.0 + x) as usize];
            let cpu_hit = mesh.cast(cam.position, dir).map(|t| {
                let c = frame.view_proj * (cam.position + dir * t).extend(1.0);
                c.z / c.w
            });
            match cpu_hit {
                Some(want) if gpu > 0.0 => {
                    let rel = (gpu - want).abs() / want;
                    n += 1;
                    close += usize::from(rel < 1e-3);
                    worst = worst.max(rel);
                }
                None if gpu == 0.0 => {}
                _ => coverage_mismatch += 1,
            }
        }
    }
    eprintln!(
        "depth: {n} samples, {close} within 1e-3 relative, worst {worst:.2e}; {coverage_mismatch} coverage mismatches"
    );
    assert!(n > 800, "{n} samples on the terrain");
    // Pixel centres on a triangle edge may fall either way (f32, FMA).
    assert!(close as f32 >= 0.995 * n as f32, "{close} of {n} close");
    assert!(
        coverage_mismatch <= 3,
        "{coverage_mismatch} coverage mismatches"
    );
}
