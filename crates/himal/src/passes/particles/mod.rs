//! Particles lit like the world (TECHNIQUES E4, issue #21).
//!
//! `particles.simulate`: every emitter's particles live in a fixed ring of
//! `capacity` slots in one buffer; each frame one compute thread per slot
//! runs the frame's steps (births into the ring at the emitter's rate,
//! semi-implicit Euler under gravity and wind, death by age). Births are a
//! function of the clock alone: particle number n is born at n / rate, in
//! slot n mod capacity, its velocity spread hashed from (emitter, n, tick)
//! — no random state, the same bytes on every run. A reset (the first
//! frame, the clock going back or jumping past the longest lifetime)
//! pre-warms: the steps of the last lifetime at 30 Hz run in the same
//! dispatch, so a single offline frame shows a settled plume.
//!
//! `particles.light` (Ryse "Particle Shading"): once per particle, the
//! sun (shadowed by the static map, else its cascade, with R2's 4 x 4
//! gather filter) and the local lights summed as illuminance with the
//! intensity-weighted mean direction. `forward.particles` draws
//! camera-facing quads premultiplied over the HDR target after the
//! forward surfaces, shading that light with a per-pixel sprite normal,
//! the world's diffuse ambient (sky SH; or, `PROBE_AMBIENT`, Ryse's
//! environment cube's lowest specular mip used as diffuse) and a soft
//! depth fade; its `PER_PIXEL` permutation evaluates the same
//! sums per pixel (the reference of `--particle-lighting pixel`), its
//! `CASCADED_SHADOWS` one with the world's per-pixel cascaded sun shadow
//! (the reference of `--particle-shadows cascaded`).
//! CPU twins: [`reference`]. Math and measurements: `docs/techniques/E4.md`.

pub mod reference;
pub mod sprite;

use glam::Vec3;

use crate::gpu::pipeline::{Program, RenderSpec, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{BufferHandle, Fallback, FrameGraph, TextureHandle};
use crate::passes::envmap::EnvMapPass;
use crate::passes::lighting::HDR_FORMAT;
use crate::passes::shadows::SunMaps;
use crate::scene::{EmitterDesc, Motion, Object, Scene};

/// The simulation's step when it pre-warms (s): the CLI's frame clock.
pub const TICK_S: f64 = 1.0 / 30.0;
/// Standard gravity (m/s²): an emitter's `gravity` multiplies it.
pub const GRAVITY: f32 = 9.81;

/// `particles.light`'s records per slot (shaders/particles.wgsl
/// `PARTICLE_RECORDS`): at the quad's centre, then at its four corners.
pub const LIGHT_RECORDS: u32 = 5;

/// Slots `particles.sort` orders in one workgroup's memory before it merges
/// a ring's chunks (sort.wgsl `CHUNK`).
pub const SORT_CHUNK: u32 = 1024;

/// The particles' coverage (`forward.particles`' second target), the TAA's
/// reactive mask.
pub const REACTIVE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

/// One particle slot (shaders/particles.wgsl `Particle`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ParticleGpu {
    /// Position (m), age (s).
    pub pos_age: [f32; 4],
    /// Velocity (m/s), 1 alive / 0 dead.
    pub vel_alive: [f32; 4],
}

/// One emitter (`ParticleEmitter`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EmitterGpu {
    /// Position at time 0 (m; the steps carry where it is), births per
    /// second.
    pub position_rate: [f32; 4],
    /// Initial velocity (m/s), spread (m/s per axis).
    pub velocity_spread: [f32; 4],
    /// Lifetime (s), downward acceleration (m/s²), wind response (1/s).
    pub motion: [f32; 4],
    /// Size at birth and at death (m), sprite layer (−1: the disc;
    /// [`sprite::sprite_layers`]).
    pub size: [f32; 4],
    /// Linear RGBA at birth.
    pub color_start: [f32; 4],
    /// Linear RGBA at death.
    pub color_end: [f32; 4],
    /// First slot, capacity.
    pub slots: [u32; 4],
}

impl EmitterGpu {
    /// The record of `e`, its ring starting at slot `first`, its sprite
    /// in layer `sprite` of the sprite array (−1: the disc).
    pub fn new(e: &EmitterDesc, first: u32, sprite: i32) -> Self {
        Self {
            position_rate: e.position.extend(e.rate).to_array(),
            velocity_spread: e.velocity.extend(e.spread).to_array(),
            motion: [e.lifetime, e.gravity * GRAVITY, e.wind, 0.0],
            size: [e.size[0], e.size[1], sprite as f32, 0.0],
            color_start: e.color_start.to_array(),
            color_end: e.color_end.to_array(),
            slots: [first, e.capacity, 0, 0],
        }
    }
}

/// One emitter's births in one step (`ParticleStep`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct StepGpu {
    /// Ring slot of the first birth, births, number of the first birth
    /// (mod 2³²), tick.
    pub spawn: [u32; 4],
    /// Age of the first birth at the step's end (s), step length (s).
    pub time: [f32; 4],
    /// The emitter's position at the step's end (m): a birth of age a
    /// starts at `origin - drift * a`.
    pub origin: [f32; 4],
    /// The emitter's mean velocity over the step (m/s; 0 unless it rides
    /// a moving object).
    pub drift: [f32; 4],
}

/// One particle's light (`ParticleLight`, written by `particles.light`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ParticleLightGpu {
    /// Illuminance summed over the lights (klux), sum of their luminances.
    pub e: [f32; 4],
    /// Luminance-weighted sum of the unit directions to the lights, the
    /// sun's visibility.
    pub d: [f32; 4],
}

/// `SimParams` of simulate.wgsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct SimParamsGpu {
    counts: [u32; 4],
    wind: [f32; 4],
    field: crate::scene::wind::WindGpu,
}

/// The births of emitter `e` (ring of `capacity`) in the step (t_a, t_b]:
/// numbers n with t_a < n / rate <= t_b; a burst larger than the ring
/// keeps its last `capacity` births. Born at `e.position` (a moving
/// emitter's: [`Simulation::advance`]).
pub fn births(e: &EmitterDesc, t_a: f64, t_b: f64) -> StepGpu {
    let rate = e.rate as f64;
    let (na, nb) = ((rate * t_a).floor() as i64, (rate * t_b).floor() as i64);
    let cap = e.capacity as i64;
    let count = (nb - na).clamp(0, cap);
    let n0 = nb - count + 1;
    StepGpu {
        spawn: [
            n0.rem_euclid(cap) as u32,
            count as u32,
            n0 as u32,
            (t_b / TICK_S).round() as i64 as u32,
        ],
        time: [
            (t_b - n0 as f64 / rate) as f32,
            (t_b - t_a) as f32,
            0.0,
            0.0,
        ],
        origin: e.position.extend(0.0).to_array(),
        drift: [0.0; 4],
    }
}

/// The steps from `last` (the previous frame's clock) to `t`: one, or a
/// pre-warm of 30 Hz steps over `lifetime` after a reset. True: reset.
pub fn step_times(last: Option<f64>, t: f64, lifetime: f32) -> (bool, Vec<(f64, f64)>) {
    let life = lifetime as f64;
    match last {
        Some(l) if t >= l && t - l <= life => (false, vec![(l, t)]),
        _ => {
            let m = (life / TICK_S).ceil() as i64 + 1;
            let at = |j: i64| t - (m - j) as f64 * TICK_S;
            (true, (1..=m).map(|j| (at(j - 1), at(j))).collect())
        }
    }
}

/// Most steps one frame runs for emitters living at most `lifetime` s.
pub fn max_steps(lifetime: f32) -> usize {
    (lifetime as f64 / TICK_S).ceil() as usize + 1
}

/// One frame of the simulation: what `particles.simulate` is given.
#[derive(Clone, Debug, Default)]
pub struct SimFrame {
    /// The emitters' records.
    pub emitters: Vec<EmitterGpu>,
    /// Step-major: steps[s * emitters + e].
    pub steps: Vec<StepGpu>,
    /// Start from empty slots (a reset).
    pub reset: bool,
    /// Wind velocity (m/s).
    pub wind: Vec3,
    /// V2: the local wind sources over the steps (global zero).
    pub field: crate::scene::wind::WindGpu,
}

impl SimFrame {
    /// Steps this frame.
    pub fn steps_count(&self) -> usize {
        self.steps.len() / self.emitters.len().max(1)
    }
}

/// The CPU side of the simulation: the emitters and the last clock.
#[derive(Clone, Debug)]
pub struct Simulation {
    /// The scene's emitters.
    pub emitters: Vec<EmitterDesc>,
    records: Vec<EmitterGpu>,
    /// The clock of the last simulated frame (`None`: the next resets).
    pub last: Option<f64>,
    /// Wind velocity (m/s): the scene's `[wind]`.
    pub wind: Vec3,
    /// V2: the scene's local wind sources.
    pub sources: Vec<crate::scene::wind::WindSource>,
    /// Per emitter riding a moving object: the object's motion (a copy,
    /// as `SceneGpu::animated` keeps one) and the point in its frame.
    paths: Vec<Option<(Motion, Vec3)>>,
}

impl Simulation {
    /// The emitters' rings laid out one after another, in `wind` (m/s);
    /// `objects`: the scene's, which emitters may ride.
    pub fn new(emitters: &[EmitterDesc], wind: Vec3, objects: &[Object]) -> Self {
        let paths = (emitters.iter())
            .map(|e| {
                let f = e.follow?;
                Some((objects.get(f.object)?.motion.clone()?, f.local))
            })
            .collect();
        let mut first = 0u32;
        let (layers, _) = sprite::sprite_layers(emitters);
        let records = (emitters.iter().zip(layers))
            .map(|(e, layer)| {
                let r = EmitterGpu::new(e, first, layer);
                first += e.capacity;
                r
            })
            .collect();
        Self {
            emitters: emitters.to_vec(),
            records,
            last: None,
            wind,
            sources: Vec::new(),
            paths,
        }
    }

    /// Where emitter `i` is at clock `t` (s): its position, or the point it
    /// rides on its moving object.
    pub fn position_at(&self, i: usize, t: f64) -> Vec3 {
        match &self.paths[i] {
            Some((m, local)) => m.transform_at(t as f32).transform_point3(*local),
            None => self.emitters[i].position,
        }
    }

    /// Plays glTF animation `name` on the objects emitters ride (as
    /// `Scene::set_animation` does on the scene's).
    pub fn set_animation(&mut self, name: Option<&str>) {
        for (m, _) in self.paths.iter_mut().flatten() {
            if let Some(a) = &mut m.animated {
                a.play(name);
            }
        }
    }

    /// Slots of every ring.
    pub fn slots(&self) -> u32 {
        self.emitters.iter().map(|e| e.capacity).sum()
    }

    /// The longest lifetime (s).
    pub fn lifetime(&self) -> f32 {
        self.emitters.iter().map(|e| e.lifetime).fold(0.0, f32::max)
    }

    /// The emitters' records.
    pub fn records(&self) -> &[EmitterGpu] {
        &self.records
    }

    /// The frame at clock `t` (s), and the clock moved to it.
    pub fn advance(&mut self, t: f64) -> SimFrame {
        let (reset, times) = step_times(self.last, t, self.lifetime());
        self.last = Some(t);
        let mut steps = Vec::with_capacity(times.len() * self.emitters.len());
        for &(a, b) in &times {
            for (i, e) in self.emitters.iter().enumerate() {
                let mut s = births(e, a, b);
                // Riding: born along the chord of the step (frames are short).
                if self.paths[i].is_some() {
                    let (pa, pb) = (self.position_at(i, a), self.position_at(i, b));
                    s.origin = pb.extend(0.0).to_array();
                    if b > a {
                        s.drift = ((pb - pa) / (b - a) as f32).extend(0.0).to_array();
                    }
                }
                steps.push(s);
            }
        }
        let field = crate::scene::wind::WindField {
            global: Vec3::ZERO,
            sources: self.sources.clone(),
        };
        let (t0, t1) = match (times.first(), times.last()) {
            (Some(a), Some(b)) => (a.0 as f32, b.1 as f32),
            _ => (t as f32, t as f32),
        };
        SimFrame {
            emitters: self.records.clone(),
            steps,
            reset,
            wind: self.wind,
            field: field.gpu(t0, t1),
        }
    }
}

/// The GPU buffers of a scene with emitters.
struct Buffers {
    params: wgpu::Buffer,
    emitters: wgpu::Buffer,
    steps: wgpu::Buffer,
    particles: wgpu::Buffer,
    counters: wgpu::Buffer,
    light: wgpu::Buffer,
    order: wgpu::Buffer,
    /// Each sort chunk's (key, slot) pairs, sorted (`particles.sort`).
    sort_keys: wgpu::Buffer,
    /// The sprite array (layer 0 the puff, then the scene's images) and
    /// its trilinear sampler.
    sprites: wgpu::Texture,
    sprites_view: wgpu::TextureView,
    sprite_sampler: wgpu::Sampler,
}

/// What the lighting and drawing of particles read from the other passes.
#[derive(Clone, Copy)]
pub struct ParticleInputs<'a> {
    /// The local lights (`ShadowPass::local_lights`).
    pub lights: &'a wgpu::Buffer,
    /// Their atlas tiles (`ShadowPass::light_tiles`), read with `sun_maps`' atlas.
    pub light_tiles: &'a wgpu::Buffer,
    /// The sun maps' matrices (`ShadowPass::mask_params`).
    pub shadow_params: &'a wgpu::Buffer,
    /// The maps' comparison sampler.
    pub shadow_sampler: &'a wgpu::Sampler,
    /// The sun's maps this frame (`None`: shadows off, particles unshadowed).
    pub sun_maps: Option<SunMaps>,
    /// The environment pass (its sampler).
    pub envmap: &'a EnvMapPass,
    /// This frame's filtered environment cube.
    pub env: TextureHandle,
    /// The ambient lights' volumes (`LightingPass::ambient_lights`).
    pub ambient_lights: &'a wgpu::Buffer,
}

/// A permutation of `forward.particles`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ParticleKey {
    /// Light each pixel (the reference) instead of each particle.
    pub per_pixel: bool,
    /// Light the quad's centre and corners and interpolate (Ryse's per
    /// vertex) instead of once at the particle's centre.
    pub corners: bool,
    /// White particles (`--view particle-lighting`).
    pub debug: bool,
    /// Ambient from the environment cube's lowest specular mip (Ryse)
    /// instead of the world's sky irradiance SH.
    pub probe_ambient: bool,
    /// Light each pixel with the world's sun shadow (cascades, S1 filter)
    /// instead of the static map's 4 x 4 gather (the reference of R2).
    pub cascaded_shadows: bool,
}

impl ParticleKey {
    /// Every permutation (pre-warm).
    pub fn all() -> impl Iterator<Item = ParticleKey> {
        (0..32u32).map(|k| ParticleKey {
            per_pixel: k & 1 != 0,
            debug: k & 2 != 0,
            probe_ambient: k & 4 != 0,
            cascaded_shadows: k & 8 != 0,
            corners: k & 16 != 0,
        })
    }
}

fn storage(ctx: &GpuContext, label: &str, size: u64, extra: wgpu::BufferUsages) -> wgpu::Buffer {
    ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
        mapped_at_creation: false,
    })
}

/// The particle passes: the simulation's state and buffers, the programs.
pub struct ParticlesPass {
    /// The CPU half (emitters, clock).
    pub sim: Simulation,
    simulate: Program,
    simulate_pipeline: wgpu::ComputePipeline,
    light: Program,
    /// `particles.light` at the centre and at the corners.
    light_pipelines: [wgpu::ComputePipeline; 2],
    draw: Program,
    sort_program: Program,
    /// `particles.sort`'s two dispatches (chunks, merge), with SORT off and on.
    sort_pipelines: [[wgpu::ComputePipeline; 2]; 2],
    buffers: Option<Buffers>,
    /// Steps this frame (0: nothing planned).
    steps: usize,
    /// The emitters' slot ranges in draw order, far to near from the
    /// camera ([`Self::sort`]).
    order: Vec<std::ops::Range<u32>>,
    /// Particles on this frame (`FrameSettings::particles`, and the scene
    /// has emitters).
    pub active: bool,
    /// This frame's permutation (per-pixel light, white, probe ambient;
    /// from `FrameSettings`).
    pub key: ParticleKey,
    /// The TAA reads the particles' coverage (`FrameSettings::particles_reactive`).
    pub reactive: bool,
    /// Particles drawn far to near inside each emitter
    /// (`FrameSettings::particles_sort`; off: ring order).
    pub sort_particles: bool,
}

impl ParticlesPass {
    /// Programs, and the buffers of the scene's emitters (none without);
    /// particles drift in the scene's wind.
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Result<Self, GpuError> {
        let emitters = &scene.emitters;
        let simulate = Program::new(ctx, "passes/particles/simulate.wgsl")?;
        let simulate_pipeline = simulate.compute_pipeline(ctx, "cs_main", &[])?;
        let light = Program::new(ctx, "passes/particles/light.wgsl")?;
        let light_pipelines = [
            light.compute_pipeline(ctx, "cs_main", &[("CORNERS", 0.0)])?,
            light.compute_pipeline(ctx, "cs_main", &[("CORNERS", 1.0)])?,
        ];
        let draw = Program::new(ctx, "passes/particles/draw.wgsl")?;
        let sort_program = Program::new(ctx, "passes/particles/sort.wgsl")?;
        let sort_pair = |on: f64| -> Result<_, GpuError> {
            Ok([
                sort_program.compute_pipeline(ctx, "cs_chunks", &[("SORT", on)])?,
                sort_program.compute_pipeline(ctx, "cs_merge", &[("SORT", on)])?,
            ])
        };
        let sort_pipelines = [sort_pair(0.0)?, sort_pair(1.0)?];
        let mut sim = Simulation::new(emitters, scene.wind, &scene.objects);
        sim.sources = scene.wind_sources.clone();
        let buffers = (!emitters.is_empty()).then(|| {
            let ne = emitters.len() as u64;
            let slots = sim.slots() as u64;
            let steps = max_steps(sim.lifetime()) as u64 * ne;
            let step_bytes = std::mem::size_of::<StepGpu>() as u64;
            let none = wgpu::BufferUsages::empty();
            let src = wgpu::BufferUsages::COPY_SRC;
            let emitters_buf = storage(ctx, "particles.emitters", ne * 112, none);
            let (_, images) = sprite::sprite_layers(emitters);
            let images: Vec<&[u8]> = images.iter().map(|i| &i.rgba[..]).collect();
            let sprites = sprite::create_sprites(ctx, &images);
            ctx.queue
                .write_buffer(&emitters_buf, 0, bytemuck::cast_slice(sim.records()));
            Buffers {
                params: uniform_buffer(ctx, "particles.params", &SimParamsGpu::default()),
                emitters: emitters_buf,
                steps: storage(ctx, "particles.steps", steps * step_bytes, none),
                particles: storage(ctx, "particles.state", slots * 32, src),
                counters: storage(ctx, "particles.counters", ne * 8, src),
                light: storage(
                    ctx,
                    "particles.light",
                    slots * u64::from(LIGHT_RECORDS) * 32,
                    src,
                ),
                order: storage(ctx, "particles.order", slots * 4, src),
                sort_keys: storage(ctx, "particles.sort_keys", slots * 8, none),
                sprites_view: sprites.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    ..Default::default()
                }),
                sprites,
                sprite_sampler: ctx.device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("particles.sprites"),
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                }),
            }
        });
        Ok(Self {
            sim,
            simulate,
            simulate_pipeline,
            light,
            light_pipelines,
            draw,
            sort_program,
            sort_pipelines,
            buffers,
            steps: 0,
            order: Vec::new(),
            active: false,
            key: ParticleKey::default(),
            reactive: true,
            sort_particles: true,
        })
    }

    /// Orders the emitters far to near from `eye` (premultiplied "over"
    /// composes back to front; inside an emitter the ring's order stays),
    /// each where it is at the last planned clock.
    pub fn sort(&mut self, eye: Vec3) {
        let mut first = 0u32;
        let t = self.sim.last.unwrap_or(0.0);
        let mut ranges: Vec<(f32, std::ops::Range<u32>)> = (self.sim.emitters.iter())
            .enumerate()
            .map(|(i, e)| {
                let r = first..first + e.capacity;
                first += e.capacity;
                (self.sim.position_at(i, t).distance_squared(eye), r)
            })
            .collect();
        ranges.sort_by(|a, b| b.0.total_cmp(&a.0));
        self.order = ranges.into_iter().map(|(_, r)| r).collect();
    }

    /// GPU bytes that outlive a frame, by buffer group (none without
    /// emitters): state and light 32 B a slot, the draw order 4 B a slot,
    /// (and its sort's keys, 8 B a slot),
    /// and the emitter records, a frame's steps (pre-warm: every 30 Hz
    /// step of the longest lifetime), counters and parameters.
    pub fn memory(&self) -> Vec<(String, u64)> {
        let Some(b) = &self.buffers else {
            return Vec::new();
        };
        let (slots, ne) = (self.sim.slots(), self.sim.emitters.len());
        let params = [&b.params, &b.emitters, &b.steps, &b.counters];
        vec![
            (
                format!("particles.state ({slots} slots)"),
                b.particles.size(),
            ),
            ("particles.light".to_string(), b.light.size()),
            (
                "particles.order (and sort keys)".to_string(),
                b.order.size() + b.sort_keys.size(),
            ),
            (
                format!("particles.params ({ne} emitters, steps, counters)"),
                params.iter().map(|x| x.size()).sum(),
            ),
            (
                format!(
                    "particles.sprites ({} layers)",
                    b.sprites.depth_or_array_layers()
                ),
                sprite::sprite_bytes(b.sprites.depth_or_array_layers()),
            ),
        ]
    }

    /// The emitters' slot ranges in this frame's draw order.
    pub fn draw_order(&self) -> &[std::ops::Range<u32>] {
        &self.order
    }

    /// This frame's simulation at clock `time_s`: steps and parameters
    /// uploaded, counters cleared. `on`: `FrameSettings::particles`. Off,
    /// the clock is forgotten (turning them on again pre-warms).
    pub fn plan(&mut self, ctx: &GpuContext, time_s: f32, on: bool) -> Option<SimFrame> {
        self.active = on && self.buffers.is_some();
        self.steps = 0;
        if !self.active {
            self.sim.last = None;
            return None;
        }
        let b = self.buffers.as_ref()?;
        let frame = self.sim.advance(time_s as f64);
        let ne = frame.emitters.len();
        self.steps = frame.steps_count();
        let params = SimParamsGpu {
            counts: [
                ne as u32,
                self.steps as u32,
                self.sim.slots(),
                frame.reset as u32,
            ],
            wind: frame.wind.extend(0.0).to_array(),
            field: frame.field,
        };
        ctx.queue
            .write_buffer(&b.params, 0, bytemuck::bytes_of(&params));
        ctx.queue
            .write_buffer(&b.steps, 0, bytemuck::cast_slice(&frame.steps));
        ctx.queue.write_buffer(&b.counters, 0, &vec![0u8; ne * 8]);
        Some(frame)
    }

    /// `particles.simulate`: this frame's steps over every slot; returns
    /// the particle buffer's new version (`None` when inactive). The
    /// state outlives the frame, so the node always runs.
    pub fn add_simulate<'a>(&'a self, g: &mut FrameGraph<'a>) -> Option<BufferHandle> {
        let b = self.buffers.as_ref().filter(|_| self.active)?;
        let particles = g.import_buffer("particles.state", &b.particles);
        let counters = g.import_buffer("particles.counters", &b.counters);
        let groups = self.sim.slots().div_ceil(64);
        let written = g
            .compute("particles.simulate", &self.simulate)
            .compute_pipeline(Ok(self.simulate_pipeline.clone()))
            .uniform("sim", &b.params)
            .uniform("emitters", &b.emitters)
            .uniform("steps", &b.steps)
            .write_buffer("particles", particles)
            .write_buffer("counters", counters)
            .side_effect()
            .dispatch([groups, 1, 1]);
        Some(written.buffer(particles))
    }

    /// `particles.light`: each live particle's light from the sun (its
    /// shadow) and the local lights; returns the light buffer's version.
    pub fn add_light<'a>(
        &'a self,
        g: &mut FrameGraph<'a>,
        particles: BufferHandle,
        inputs: ParticleInputs<'a>,
    ) -> Option<BufferHandle> {
        let b = self.buffers.as_ref().filter(|_| self.active)?;
        let light = g.import_buffer("particles.light", &b.light);
        let maps = inputs.sun_maps;
        let far = Fallback::DepthFar;
        let corners = self.key.corners;
        let longest = (self.sim.emitters.iter()).map(|e| e.capacity).max()?;
        let threads = longest * if corners { LIGHT_RECORDS } else { 1 };
        let written = g
            .compute("particles.light", &self.light)
            .compute_pipeline(Ok(self.light_pipelines[usize::from(corners)].clone()))
            .read_buffer(
                "particles",
                particles,
                crate::graph::BufferAccess::StorageRead,
            )
            .uniform("lights", inputs.lights)
            .uniform("shadow_params", inputs.shadow_params)
            .optional_array("cascades", maps.and_then(|m| m.cascades), far)
            .optional_array("static_map", maps.and_then(|m| m.static_map), far)
            .optional_array("atlas", maps.and_then(|m| m.atlas), far)
            .uniform("light_tiles", inputs.light_tiles)
            .sampler("shadow_sampler", inputs.shadow_sampler)
            .uniform("emitters", &b.emitters)
            .write_buffer("particle_light", light)
            .dispatch([threads.div_ceil(64), self.sim.emitters.len() as u32, 1]);
        Some(written.buffer(light))
    }

    /// `particles.sort`: each emitter's slots far to near along the view
    /// direction (ring order when `sort_particles` is off): chunks of
    /// [`SORT_CHUNK`] sorted in workgroup memory, then every slot's rank
    /// in its ring; returns the order buffer's version.
    pub fn add_sort<'a>(
        &'a self,
        g: &mut FrameGraph<'a>,
        particles: BufferHandle,
    ) -> Option<BufferHandle> {
        let b = self.buffers.as_ref().filter(|_| self.active)?;
        let order = g.import_buffer("particles.order", &b.order);
        let keys = g.import_buffer("particles.sort_keys", &b.sort_keys);
        let [chunks, merge] = &self.sort_pipelines[usize::from(self.sort_particles)];
        let ne = self.sim.emitters.len() as u32;
        let longest = (self.sim.emitters.iter()).map(|e| e.capacity).max()?;
        let written = g
            .compute("particles.sort", &self.sort_program)
            .compute_pipeline(Ok(chunks.clone()))
            .read_buffer(
                "particles",
                particles,
                crate::graph::BufferAccess::StorageRead,
            )
            .uniform("emitters", &b.emitters)
            .write_buffer("order", order)
            .write_buffer("sorted", keys)
            .dispatch_with(move |cp| {
                cp.dispatch_workgroups(longest.div_ceil(SORT_CHUNK), ne, 1);
                cp.set_pipeline(merge);
                cp.dispatch_workgroups(longest.div_ceil(256), ne, 1);
            });
        Some(written.buffer(order))
    }

    /// The draw order read back (tests): the slot drawn at each instance.
    pub fn read_order(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let b = self
            .buffers
            .as_ref()
            .ok_or_else(|| GpuError::Other("no emitters".into()))?;
        let bytes = crate::gpu::read_buffer(ctx, &b.order)?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[..self.sim.slots() as usize * 4],
        ))
    }

    /// The draw pipeline of permutation `key`.
    pub fn draw_pipeline(
        &self,
        ctx: &GpuContext,
        key: ParticleKey,
    ) -> Result<wgpu::RenderPipeline, GpuError> {
        let blended = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let targets = [blended(HDR_FORMAT), blended(REACTIVE_FORMAT)];
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        let constants = [
            ("PER_PIXEL", flag(key.per_pixel)),
            ("CORNERS", flag(key.corners)),
            ("DEBUG", flag(key.debug)),
            ("PROBE_AMBIENT", flag(key.probe_ambient)),
            ("CASCADED_SHADOWS", flag(key.cascaded_shadows)),
        ];
        let mut spec = RenderSpec::fullscreen("forward.particles", &targets);
        spec.constants = &constants;
        self.draw.render_pipeline(ctx, &spec)
    }

    /// `forward.particles`: the live particles' quads over `hdr` (scene
    /// `depth` read for the soft fade); returns the new HDR version and
    /// the particles' coverage (the TAA's reactive mask; `None` when
    /// nothing is drawn).
    pub fn add_draw<'a>(
        &'a self,
        ctx: &GpuContext,
        g: &mut FrameGraph<'a>,
        hdr: TextureHandle,
        depth: TextureHandle,
        (particles, light, sorted): (BufferHandle, BufferHandle, BufferHandle),
        inputs: ParticleInputs<'a>,
    ) -> (TextureHandle, Option<TextureHandle>) {
        let Some(b) = self.buffers.as_ref().filter(|_| self.active) else {
            return (hdr, None);
        };
        let size = g.texture_desc(hdr).map_or((1, 1), |d| (d.width, d.height));
        let reactive = g.create_texture(
            "particles.reactive",
            crate::graph::TextureDesc::new_2d(size.0, size.1, REACTIVE_FORMAT),
        );
        let maps = inputs.sun_maps;
        let far = Fallback::DepthFar;
        let order = &self.order;
        let storage_read = crate::graph::BufferAccess::StorageRead;
        let written = g
            .raster("forward.particles", &self.draw)
            .pipeline(self.draw_pipeline(ctx, self.key))
            .read_buffer("particles", particles, storage_read)
            .uniform("emitters", &b.emitters)
            .read_buffer("particle_light", light, storage_read)
            .read_buffer("order", sorted, storage_read)
            .read("depth", depth)
            .read_cube("env_specular", inputs.env)
            .sampler("env_sampler", &inputs.envmap.sampler)
            .uniform("lights", inputs.lights)
            .uniform("shadow_params", inputs.shadow_params)
            .optional_array("cascades", maps.and_then(|m| m.cascades), far)
            .optional_array("static_map", maps.and_then(|m| m.static_map), far)
            .sampler("shadow_sampler", inputs.shadow_sampler)
            .uniform("ambient_lights", inputs.ambient_lights)
            .external("sprites", &b.sprites_view)
            .sampler("sprite_sampler", &b.sprite_sampler)
            .color(hdr, wgpu::LoadOp::Load)
            .color(reactive, wgpu::LoadOp::Clear(wgpu::Color::BLACK))
            .record(move |_, rp| {
                for r in order {
                    rp.draw(0..12, r.clone());
                }
                Ok(())
            });
        (written.colors[0], Some(written.colors[1]))
    }

    /// The light buffer read back (tests): per slot, the records of its
    /// quad's centre and corners (`ParticleKey::corners`; else the first
    /// alone is written).
    pub fn read_light(
        &self,
        ctx: &GpuContext,
    ) -> Result<Vec<[ParticleLightGpu; LIGHT_RECORDS as usize]>, GpuError> {
        let b = self
            .buffers
            .as_ref()
            .ok_or_else(|| GpuError::Other("no emitters".into()))?;
        let bytes = crate::gpu::read_buffer(ctx, &b.light)?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[..self.sim.slots() as usize * LIGHT_RECORDS as usize * 32],
        ))
    }

    /// Runs this frame's simulation at `time_s` outside a frame (tests,
    /// tools); returns the planned frame.
    pub fn run_simulation(&mut self, ctx: &GpuContext, time_s: f32) -> Result<SimFrame, GpuError> {
        let frame = self
            .plan(ctx, time_s, true)
            .ok_or_else(|| GpuError::Other("particles: the scene has no emitters".into()))?;
        let mut g = FrameGraph::new();
        self.add_simulate(&mut g);
        crate::graph::run(ctx, g, None, "particles.simulate")?;
        Ok(frame)
    }

    /// The particle buffer read back (tests).
    pub fn read_particles(&self, ctx: &GpuContext) -> Result<Vec<ParticleGpu>, GpuError> {
        let b = self
            .buffers
            .as_ref()
            .ok_or_else(|| GpuError::Other("no emitters".into()))?;
        let bytes = crate::gpu::read_buffer(ctx, &b.particles)?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[..self.sim.slots() as usize * 32],
        ))
    }

    /// Per emitter (alive, births this frame), read back (tests).
    pub fn read_counters(&self, ctx: &GpuContext) -> Result<Vec<[u32; 2]>, GpuError> {
        let b = self
            .buffers
            .as_ref()
            .ok_or_else(|| GpuError::Other("no emitters".into()))?;
        let bytes = crate::gpu::read_buffer(ctx, &b.counters)?;
        Ok(bytemuck::pod_collect_to_vec(
            &bytes[..self.sim.emitters.len() * 8],
        ))
    }
}
