//! Helpers shared by the whole-frame GPU tests.
// Each test binary uses a subset of these helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use glam::{Vec3, Vec4};
use himal::gpu::{GpuContext, GpuOptions};
use himal::passes::lighting::reference::LightingParams;
use himal::passes::sky::SkyLight;
use himal::scene::{Camera, Scene};
use himal::{FrameSettings, Renderer};

/// `tests/scenes/`, where the shared test scenes live.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes")
}

/// Text of `tests/scenes/<name>.toml`.
pub fn scene_text(name: &str) -> String {
    let path = scenes_dir().join(format!("{name}.toml"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `tests/scenes/<name>.toml` with `overrides` applied: each `(from, to)`
/// replaces text that must occur exactly once in the file, so an override
/// that no longer matches fails instead of silently doing nothing.
pub fn scene_text_with(name: &str, overrides: &[(&str, &str)]) -> String {
    let mut text = scene_text(name);
    for (from, to) in overrides {
        let n = text.matches(from).count();
        assert_eq!(n, 1, "override {from:?} occurs {n} times in {name}.toml");
        text = text.replace(from, to);
    }
    text
}

/// Scene text parsed; `origin` names it in error messages.
pub fn parse_scene(text: &str, origin: &str) -> Scene {
    Scene::from_toml_str(text, origin, &scenes_dir()).unwrap_or_else(|e| panic!("{e}"))
}

/// `tests/scenes/<name>.toml`, parsed.
pub fn scene(name: &str) -> Scene {
    scene_with(name, &[])
}

/// `tests/scenes/<name>.toml` with `overrides` (see [`scene_text_with`]).
pub fn scene_with(name: &str, overrides: &[(&str, &str)]) -> Scene {
    parse_scene(&scene_text_with(name, overrides), &format!("{name}.toml"))
}

/// `tests/scenes/<name>.toml` and its camera `camera`.
pub fn scene_and_camera(name: &str, camera: &str) -> (Scene, Camera) {
    let scene = scene(name);
    let camera = scene.camera(camera).expect("camera").clone();
    (scene, camera)
}

/// Settings for a raw frame (no post-processing) of debug view `view`,
/// `size` pixels, lit by the scene's sun.
pub fn raw_settings(scene: &Scene, size: (u32, u32), view: &str) -> FrameSettings {
    let mut s = FrameSettings::new(size.0, size.1, scene.sun.clone());
    s.view = view.parse().expect("view");
    s.raw = true;
    s
}

/// One frame of `s` as RGBA floats.
pub fn render_rgba(r: &mut Renderer, camera: &Camera, s: &FrameSettings) -> Vec<[f32; 4]> {
    r.render(camera, s)
        .expect("frame")
        .image
        .to_rgba_f32()
        .expect("rgba")
}

/// Does the ray (or, with `t_max` 1, the segment) `p + t d`, 1e-4 <= t <=
/// `t_max`, meet the axis-aligned box `lo`..`hi`?
pub fn hits_box(p: Vec3, d: Vec3, (lo, hi): (Vec3, Vec3), t_max: f32) -> bool {
    let inv = d.recip();
    let (t0, t1) = ((lo - p) * inv, (hi - p) * inv);
    let near = t0.min(t1).max_element().max(1e-4);
    let far = t0.max(t1).min_element().min(t_max);
    far >= near
}

/// Eight points on the horizontal circle of `radius` around `p` (to ask
/// whether a pixel is away from a penumbra: all of them agree with it).
pub fn ring(p: Vec3, radius: f32) -> impl Iterator<Item = Vec3> {
    (0..8).map(move |k| {
        let a = k as f32 * std::f32::consts::TAU / 8.0;
        p + Vec3::new(a.cos(), 0.0, a.sin()) * radius
    })
}

/// Mean over `pixels` of the temporal standard deviation of channel 0
/// (R) over `frames`.
pub fn mean_temporal_std(frames: &[Vec<[f32; 4]>], pixels: &[usize]) -> f32 {
    let n = frames.len() as f32;
    let total: f32 = pixels
        .iter()
        .map(|&i| {
            let mean = frames.iter().map(|f| f[i][0]).sum::<f32>() / n;
            (frames.iter().map(|f| (f[i][0] - mean).powi(2)).sum::<f32>() / n).sqrt()
        })
        .sum();
    total / pixels.len().max(1) as f32
}

/// `<model>/glTF/<file>` of the Khronos sample models (`shared/assets/gltf`).
pub fn gltf_asset(model: &str, file: &str) -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/assets/gltf"
    ))
    .join(model)
    .join("glTF")
    .join(file)
}

/// The `.gltf` file of sample model `model`.
pub fn gltf_sample(model: &str) -> PathBuf {
    gltf_asset(model, &format!("{model}.gltf"))
}

/// A `.gltf` file's JSON and buffers read by hand, independently of the
/// loader, for tests that check what it read.
pub struct GltfFile {
    pub json: serde_json::Value,
    buffers: Vec<Vec<u8>>,
}

impl GltfFile {
    /// Reads `path` and its `.bin` buffers (file URIs only).
    pub fn open(path: &Path) -> Self {
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let buffers = (json["buffers"].as_array().unwrap().iter())
            .map(|b| std::fs::read(path.with_file_name(b["uri"].as_str().unwrap())).unwrap())
            .collect();
        GltfFile { json, buffers }
    }

    /// Elements in accessor `accessor`.
    pub fn count(&self, accessor: usize) -> usize {
        self.json["accessors"][accessor]["count"].as_u64().unwrap() as usize
    }

    /// Element `i` of accessor `accessor` (`n` components of float, unsigned
    /// byte or unsigned short, not normalised), as f32.
    pub fn element(&self, accessor: usize, i: usize, n: usize) -> Vec<f32> {
        let a = &self.json["accessors"][accessor];
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let bin = &self.buffers[view["buffer"].as_u64().unwrap() as usize];
        let size = match a["componentType"].as_u64().unwrap() {
            5126 => 4,
            5123 => 2,
            5121 => 1,
            t => panic!("component type {t}"),
        };
        let base = view["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
        let stride = view["byteStride"].as_u64().unwrap_or((size * n) as u64);
        (0..n)
            .map(|c| {
                let at = (base + stride * i as u64) as usize + size * c;
                match size {
                    4 => f32::from_le_bytes(bin[at..at + 4].try_into().unwrap()),
                    2 => u16::from_le_bytes(bin[at..at + 2].try_into().unwrap()) as f32,
                    _ => bin[at] as f32,
                }
            })
            .collect()
    }

    /// Element `i` of a VEC3 float accessor.
    pub fn vec3(&self, accessor: usize, i: usize) -> Vec3 {
        Vec3::from_slice(&self.element(accessor, i, 3))
    }
}

/// Standard base64 with padding (for `data:` URIs in generated glTF files).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            out.push(if k <= c.len() {
                A[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// A GLB container of `json` and `bin`: header, JSON chunk (space-padded),
/// BIN chunk (zero-padded).
pub fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Deterministic pseudo-random numbers in [0, 1).
pub struct Lcg(pub u64);
impl Lcg {
    pub fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A new context on the adapter present (lavapipe in CI), as a new process
/// would have it.
pub fn context() -> GpuContext {
    GpuContext::new(&GpuOptions::default()).expect("a GPU adapter (lavapipe in CI)")
}

/// A renderer on a new context.
pub fn renderer(scene: &Scene) -> Renderer {
    Renderer::new(context(), scene).expect("renderer")
}

/// A fresh, empty directory `himal-<name>-<pid>` under the system temp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("himal-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Raw debug views (`lighting`, `normal`, `tangent`, `depth`, ...) of
/// `scene` from `camera`, `size` square, no anti-aliasing: RGBA f32 per view.
pub fn raw_views(scene: &Scene, camera: &Camera, size: u32, names: &[&str]) -> Vec<Vec<[f32; 4]>> {
    let mut r = renderer(scene);
    names
        .iter()
        .map(|name| {
            let mut s = raw_settings(scene, (size, size), name);
            s.aa = himal::passes::aa::AaMode::None;
            render_rgba(&mut r, camera, &s)
        })
        .collect()
}

/// Sun and sky of the scene's time of day, as the lighting pass gets them.
pub fn lighting_params(scene: &Scene) -> LightingParams {
    let sun = &scene.sun;
    let sky = SkyLight::new(
        sun.time_hours,
        sun.latitude_deg,
        sun.day_of_year,
        sun.turbidity,
    );
    LightingParams {
        sun_direction: sky.sun_direction,
        sun_illuminance: sky.sun_illuminance,
        sky_irradiance: sky.irradiance_sh,
        environment: None,
        visibility_remap: false,
    }
}

/// Unit direction of the camera ray through the centre of pixel (x, y).
pub fn pixel_ray(camera: &Camera, size: (u32, u32), x: u32, y: u32) -> Vec3 {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let inv = camera.view_projection(w / h).inverse();
    let ndc = Vec4::new(
        (x as f32 + 0.5) / w * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / h * 2.0,
        1.0,
        1.0,
    );
    let p = inv * ndc;
    (p.truncate() / p.w - camera.position).normalize()
}

/// Origin (on the near plane) and unit direction of the ray through pixel
/// (x, y): perspective and orthographic cameras alike.
#[allow(dead_code)]
pub fn pixel_ray_from(camera: &Camera, size: (u32, u32), x: u32, y: u32) -> (Vec3, Vec3) {
    let (w, h) = (size.0 as f32, size.1 as f32);
    let inv = camera.view_projection(w / h).inverse();
    let at = |depth: f32| {
        let p = inv
            * Vec4::new(
                (x as f32 + 0.5) / w * 2.0 - 1.0,
                1.0 - (y as f32 + 0.5) / h * 2.0,
                depth,
                1.0,
            );
        p.truncate() / p.w
    };
    let near = at(1.0);
    (near, (at(0.5) - near).normalize())
}

/// The renderer's filtered environment cube and DFG table read back, for
/// the lighting twin's `ENV_SPECULAR` path.
pub fn environment_specular(
    r: &Renderer,
) -> himal::passes::lighting::reference::EnvironmentSpecular {
    use himal::passes::envmap::reference::CubeMip;
    let env = r.envmap();
    let ctx = r.context();
    let read = |texture: &wgpu::Texture, mip: u32, layer: u32| {
        himal::gpu::read_texture(ctx, texture, mip, layer)
            .expect("read back")
            .to_rgba_f32()
            .expect("float texels")
    };
    let filtered = (0..env.filtered().mip_level_count())
        .map(|mip| {
            let faces: [Vec<Vec3>; 6] = std::array::from_fn(|face| {
                read(env.filtered(), mip, face as u32)
                    .iter()
                    .map(|t| Vec3::new(t[0], t[1], t[2]))
                    .collect()
            });
            CubeMip {
                size: (env.size >> mip) as usize,
                faces,
            }
        })
        .collect();
    let dfg = read(&env.dfg, 0, 0)
        .iter()
        .map(|t| glam::Vec2::new(t[0], t[1]))
        .collect();
    himal::passes::lighting::reference::EnvironmentSpecular {
        filtered,
        dfg,
        dfg_size: env.dfg.width() as usize,
    }
}

/// Byte ranges of the numbers (digits and dots) in `text`, for mutations.
pub fn number_runs(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut runs = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            runs.push((start, i));
        } else {
            i += 1;
        }
    }
    runs
}

/// A .gltf of one unit cube (-0.5..0.5, 24 vertices with face normals, CCW
/// outward) under one node with the extra JSON members `node` (e.g.
/// `"scale":[2,6,2]`) and the material `material` (JSON); written to a
/// temporary file named after `name`.
pub fn cube_gltf(name: &str, node: &str, material: &str) -> PathBuf {
    let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut n = [0.0f32; 3];
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u16;
            // (u, v) corners in CCW order seen from outside: the normal is u x v
            // for the + face; the - face walks them the other way.
            let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
            for (a, b) in corners {
                let mut p = [0.0f32; 3];
                p[axis] = 0.5 * sign;
                p[u] = a;
                p[v] = b * sign;
                positions.push(p);
                normals.push(n);
            }
            indices.extend([0, 1, 2, 0, 2, 3].map(|i| base + i));
        }
    }
    let mut bin: Vec<u8> = Vec::new();
    bin.extend(positions.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bin.extend(normals.iter().flatten().flat_map(|c| c.to_le_bytes()));
    bin.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let (pn, ib) = (24 * 12, indices.len() * 2);
    let b64 = base64(&bin);
    let node = if node.is_empty() {
        String::new()
    } else {
        format!(",{node}")
    };
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0{node}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"material":0}}]}}],"materials":[{material}],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pn}}},{{"buffer":0,"byteOffset":{pn},"byteLength":{pn}}},{{"buffer":0,"byteOffset":{},"byteLength":{ib}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":24,"type":"VEC3","min":[-0.5,-0.5,-0.5],"max":[0.5,0.5,0.5]}},
{{"bufferView":1,"componentType":5126,"count":24,"type":"VEC3"}},{{"bufferView":2,"componentType":5123,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        2 * pn,
        indices.len()
    );
    let path = std::env::temp_dir().join(format!("himal-{}-{name}.gltf", std::process::id()));
    std::fs::write(&path, json).expect("write temporary glTF");
    path
}

/// Ray `o + t d` against triangle `v` (Möller–Trumbore, both sides): the
/// distance t > 0 and the barycentric weights of v\[0\], v\[1\], v\[2\].
#[allow(dead_code)]
pub fn ray_triangle(o: Vec3, d: Vec3, v: [Vec3; 3]) -> Option<(f32, Vec3)> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = o - v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let w = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > 0.0).then(|| (t, Vec3::new(1.0 - u - w, u, w)))
}

/// One material reading `image` (texture 0, default sampler, UV set 0)
/// through the slots `set` fills in, uploaded on the shared context.
pub fn upload_one_image_material(
    image: &himal::scene::gltf::ImageData,
    set: impl FnOnce(&mut himal::scene::gltf::PbrMaterial, himal::scene::gltf::TextureRef),
) -> himal::gpu_scene::textures::MaterialTextures {
    use himal::scene::gltf::{PbrMaterial, PbrSet, SamplerDesc, TextureRef, TextureSlot};
    let mut material = PbrMaterial::default();
    let texture = TextureRef {
        texture: 0,
        tex_coord: 0,
        transform: None,
    };
    set(&mut material, texture);
    let pbr = PbrSet {
        materials: vec![material],
        textures: vec![TextureSlot {
            image: 0,
            sampler: SamplerDesc::default(),
        }],
        images: vec![image.clone()],
        mesh_material: Vec::new(),
    };
    let ctx = himal::gpu::testing::shared_context().expect("GPU (lavapipe in CI)");
    himal::gpu_scene::textures::MaterialTextures::upload(ctx, &pbr).expect("upload")
}

/// Runs compute `kernel` (entry `main`; bindings `input` queries, `output`,
/// `map` an `n`x`n` Depth16Unorm array layer holding `stored`, `cmp` a
/// LessEqual bilinear comparison sampler) over `queries`, 64 per workgroup,
/// and reads back `out_bytes` of output: the harness of the shadow-filter
/// kernels' GPU-vs-twin tests.
pub fn run_depth_map_kernel(
    kernel: &str,
    stored: &[u16],
    n: u32,
    queries: &[[f32; 4]],
    out_bytes: u64,
) -> Vec<u8> {
    use wgpu::util::DeviceExt;
    let ctx = himal::gpu::testing::shared_context().expect("GPU");
    let texture = himal::gpu::texture_2d(
        &ctx.device,
        "test.depth",
        (n, n),
        1,
        wgpu::TextureFormat::Depth16Unorm,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(stored),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(2 * n),
            rows_per_image: Some(n),
        },
        texture.size(),
    );
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    let sampler = ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        compare: Some(wgpu::CompareFunction::LessEqual),
        ..Default::default()
    });
    let input = ctx
        .device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("test.queries"),
            contents: bytemuck::cast_slice(queries),
            usage: wgpu::BufferUsages::STORAGE,
        });
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("test.out"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let program = himal::gpu::pipeline::Program::from_source(ctx, "depth-map-kernel", kernel)
        .expect("kernel");
    let pipeline = program
        .compute_pipeline(ctx, "main", &[])
        .expect("pipeline");
    let bg = program
        .bind_group(
            ctx,
            0,
            &[
                ("input", input.as_entire_binding()),
                ("output", output.as_entire_binding()),
                ("map", wgpu::BindingResource::TextureView(&view)),
                ("cmp", wgpu::BindingResource::Sampler(&sampler)),
            ],
        )
        .expect("bind group");
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bg, &[]);
        pass.dispatch_workgroups((queries.len() as u32).div_ceil(64), 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    himal::gpu::read_buffer(ctx, &output).expect("read back")
}

/// Mip `mip`, layer `layer` of a float texture, rgb per texel.
pub fn read_rgb(
    ctx: &himal::gpu::GpuContext,
    texture: &wgpu::Texture,
    mip: u32,
    layer: u32,
) -> Vec<Vec3> {
    himal::gpu::read_texture(ctx, texture, mip, layer)
        .expect("read back")
        .to_rgba_f32()
        .expect("float texels")
        .iter()
        .map(|t| Vec3::new(t[0], t[1], t[2]))
        .collect()
}

/// A 160 x 120 frame of `scene` at clock 2 s: the particle tests' settings
/// (plumes settled by the pre-warm).
pub fn particle_settings(scene: &Scene) -> FrameSettings {
    let mut s = FrameSettings::new(160, 120, scene.sun.clone());
    s.time_s = 2.0;
    s
}

/// The animation rigs of `scene`'s objects.
pub fn animated(scene: &Scene) -> Vec<&himal::scene::gltf::Animated> {
    (scene.objects.iter())
        .filter_map(|o| o.motion.as_ref()?.animated.as_ref())
        .collect()
}

/// The animated `scene`'s normals at `t` (96², raw) against `deformed`
/// (the CPU's shape at `t`, not animated) and against `scene` at t = 0:
/// mean absolute differences (same shape, moved).
pub fn frame_against(
    scene: &Scene,
    deformed: &Scene,
    camera: &himal::scene::Camera,
    t: f32,
) -> (f32, f32) {
    let image = |scene: &Scene, t: f32| {
        let mut s = raw_settings(scene, (96, 96), "normal");
        s.time_s = t;
        render_rgba(&mut renderer(scene), camera, &s)
    };
    let diff = |a: &[[f32; 4]], b: &[[f32; 4]]| {
        let sum: f32 = (a.iter().zip(b))
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).sum::<f32>() / 3.0)
            .sum();
        sum / a.len() as f32
    };
    let gpu = image(scene, t);
    (
        diff(&gpu, &image(deformed, t)),
        diff(&gpu, &image(scene, 0.0)),
    )
}

/// The streamed world's camera called `name`.
pub fn world_camera(world: &himal::scene::world::World, name: &str) -> Camera {
    let named = world.cameras.iter().find(|c| c.name == name);
    named
        .unwrap_or_else(|| panic!("no world camera {name}"))
        .camera
        .clone()
}

/// A renderer of `world` with every sector around `camera` resident and
/// none over its pool's capacity.
pub fn settled_world(
    world: &std::sync::Arc<himal::scene::world::World>,
    camera: &Camera,
) -> Renderer {
    let mut r = Renderer::with_world(context(), world.clone()).expect("renderer");
    let stats = r
        .settle_world(camera, std::time::Duration::from_secs(120))
        .expect("streaming")
        .expect("a world");
    assert_eq!((stats.missing, stats.over_capacity), (0, 0), "{stats:?}");
    r
}
