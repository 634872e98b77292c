//! `vegetation.simulate` (V2, issue #18): the trees' bones simulated on
//! the GPU, one thread per tree: a damped spring per bone driven by the
//! scene's wind field (`scene/wind.rs`), then the bones' world transforms
//! written once per tree into their records in the objects buffer, which
//! every pass's vertex stage reads (`shaders/object_vertex.wgsl`,
//! `tree_world`). No per-tree CPU work per frame: the CPU writes one
//! uniform. Deterministic: the steps follow from the frame times alone
//! (fixed steps of at most [`STEP`] s; a reset starts from the wind's
//! equilibrium [`WARM_UP`] s early). CPU twin: [`reference`].
//! docs/techniques/V2.md.

pub mod reference;
pub mod ripple;

use bytemuck::{Pod, Zeroable};

use crate::gpu::pipeline::Program;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::SceneGpu;
use crate::graph::FrameGraph;
use crate::scene::wind::{WindField, WindGpu};

/// Threads per workgroup of `simulate.wgsl`.
const GROUP: u32 = 64;
/// Longest simulation step (s).
pub const STEP: f32 = 1.0 / 60.0;
/// Most steps in one frame (a longer gap is simulated in longer steps).
pub const MAX_STEPS: u32 = 16;
/// A gap between frames beyond this (s), or time going back, resets.
pub const MAX_GAP: f32 = 0.5;
/// Simulated time before the first frame after a reset (s).
pub const WARM_UP: f32 = 2.0;

/// What moves the trees (`FrameSettings::vegetation_motion`,
/// `--vegetation-motion`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VegetationMotion {
    /// At rest.
    Off,
    /// V2's bones alone.
    Bones,
    /// The bones, V5's branch waves and leaf flutter.
    #[default]
    On,
}

impl std::str::FromStr for VegetationMotion {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "off" => Ok(Self::Off),
            "bones" => Ok(Self::Bones),
            "on" => Ok(Self::On),
            _ => Err(format!("\"{s}\": expected on, bones or off")),
        }
    }
}

/// Twin of `Sim` in `simulate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SimGpu {
    /// Slots, steps, reset (1: from the equilibrium), V5 waves (1: on).
    pub counts: [u32; 4],
    /// Time at the start of the steps (s), step (s), 0, 0.
    pub time: [f32; 4],
    /// The wind field for these steps.
    pub wind: WindGpu,
}

/// One frame's steps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimFrame {
    /// Steps to run.
    pub steps: u32,
    /// Step length (s).
    pub h: f32,
    /// Time at the start of the steps (s).
    pub t0: f32,
    /// Start from the equilibrium (and no motion vectors).
    pub reset: bool,
}

impl SimFrame {
    /// The steps from the last simulated time `last` to `t`.
    pub fn advance(last: Option<f32>, t: f32) -> SimFrame {
        match last {
            Some(l) if t >= l && t - l <= MAX_GAP => {
                let dt = t - l;
                let steps = ((dt / STEP).ceil() as u32).min(MAX_STEPS);
                SimFrame {
                    steps,
                    h: if steps > 0 { dt / steps as f32 } else { 0.0 },
                    t0: l,
                    reset: false,
                }
            }
            _ => {
                let steps = (WARM_UP / STEP).round() as u32;
                SimFrame {
                    steps,
                    h: STEP,
                    t0: t - steps as f32 * STEP,
                    reset: true,
                }
            }
        }
    }

    /// The uniform for `slots` trees in `wind`, V5's waves on or off.
    pub fn gpu(&self, slots: u32, wind: &WindField, waves: bool) -> SimGpu {
        let t1 = self.t0 + self.steps as f32 * self.h;
        SimGpu {
            counts: [slots, self.steps, self.reset as u32, waves as u32],
            time: [self.t0, self.h, 0.0, 0.0],
            wind: wind.gpu(self.t0, t1),
        }
    }
}

/// The tree simulation: its pipeline, uniform, and the clock it follows.
pub struct VegetationPass {
    program: Program,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// The wind the trees feel (the scene's field, `--wind` applied).
    pub wind: WindField,
    /// The last simulated time (s); `None`: the next frame resets.
    last: Option<f32>,
    /// This frame's steps (`None`: not simulated this frame).
    pub frame: Option<SimFrame>,
    ripple_program: Program,
    ripple_pipeline: wgpu::ComputePipeline,
    ripple_params: wgpu::Buffer,
    /// The half of the ripple grid the next step reads, and its last time.
    ripple_state: (i32, Option<f32>),
    /// This frame's ripple step (`None`: none), as written.
    pub ripple: Option<(ripple::RippleHeader, ripple::RippleStepGpu)>,
}

impl VegetationPass {
    /// Compiles `simulate.wgsl`; `wind`: the scene's field.
    pub fn new(ctx: &GpuContext, wind: WindField) -> Result<Self, GpuError> {
        let program = Program::new(ctx, "passes/vegetation/simulate.wgsl")?;
        let pipeline = program.compute_pipeline(ctx, "cs_main", &[])?;
        let params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vegetation.sim"),
            size: std::mem::size_of::<SimGpu>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let ripple_program = Program::new(ctx, "passes/vegetation/ripple.wgsl")?;
        let ripple_pipeline = ripple_program.compute_pipeline(ctx, "cs_step", &[])?;
        let ripple_params = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("vegetation.ripple_step"),
            size: std::mem::size_of::<ripple::RippleStepGpu>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Self {
            program,
            pipeline,
            params,
            wind,
            last: None,
            frame: None,
            ripple_program,
            ripple_pipeline,
            ripple_params,
            ripple_state: (0, None),
            ripple: None,
        })
    }

    /// The next frame starts from the equilibrium again (the ripple flat).
    pub fn reset(&mut self) {
        self.last = None;
        self.ripple_state.1 = None;
    }

    /// Plans this frame's grass ripple step (scenes with grass, `on`): the
    /// window around `camera`, one step to `time_s` (at most
    /// [`ripple::RIPPLE_MAX_STEP`]; a reset starts flat), the sources where
    /// they are at `time_s`.
    pub fn plan_ripple(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        time_s: f32,
        camera: glam::Vec3,
        on: bool,
    ) {
        self.ripple = None;
        if !on || scene.ripple_n <= 1 {
            self.ripple_state.1 = None;
            return;
        }
        let (half, last) = self.ripple_state;
        let (dt, reset) = match last {
            Some(l) if time_s >= l && time_s - l <= MAX_GAP => {
                ((time_s - l).min(ripple::RIPPLE_MAX_STEP), false)
            }
            _ => (0.0, true),
        };
        let header = ripple::header(scene.ripple_n, camera, half, dt);
        let step = ripple::RippleStepGpu {
            time: [time_s, reset as u32 as f32, 0.0, 0.0],
            wind: self.wind.gpu(time_s, time_s),
        };
        ctx.queue
            .write_buffer(&scene.ripple, 0, bytemuck::bytes_of(&header));
        ctx.queue
            .write_buffer(&self.ripple_params, 0, bytemuck::bytes_of(&step));
        self.ripple_state = (1 - half, Some(time_s));
        self.ripple = Some((header, step));
    }

    /// Plans this frame's steps to `time_s` and writes the uniform. `on`
    /// false or no trees: nothing runs. `motion` false: the bones are set
    /// at rest (one reset without wind or steps). `global`: the global wind
    /// in place of the scene's (`--wind`).
    pub fn plan(
        &mut self,
        ctx: &GpuContext,
        scene: &SceneGpu,
        time_s: f32,
        (on, motion): (bool, VegetationMotion),
        global: Option<glam::Vec3>,
    ) {
        self.frame = None;
        if !on || scene.tree_buffers.is_none() {
            self.last = None;
            return;
        }
        let slots = scene.tree_layout.slots.len() as u32;
        let (f, wind) = if motion != VegetationMotion::Off {
            let f = SimFrame::advance(self.last, time_s);
            self.last = Some(time_s);
            let mut wind = self.wind.clone();
            if let Some(g) = global {
                wind.global = g;
            }
            (f, wind)
        } else {
            self.last = None;
            let rest = SimFrame {
                steps: 0,
                h: 0.0,
                t0: time_s,
                reset: true,
            };
            (rest, WindField::new(glam::Vec3::ZERO))
        };
        let waves = motion == VegetationMotion::On;
        ctx.queue.write_buffer(
            &self.params,
            0,
            bytemuck::bytes_of(&f.gpu(slots, &wind, waves)),
        );
        self.frame = Some(f);
    }

    /// `vegetation.simulate`: this frame's steps for every tree; its
    /// bones land in the scene's objects buffer, which the draws bind
    /// outside the graph (a side effect, before them in the encoder).
    pub fn add<'a>(&'a self, g: &mut FrameGraph<'a>, scene: &'a SceneGpu) {
        if self.ripple.is_some() {
            let groups = (scene.ripple_n as u32).div_ceil(8);
            g.compute("vegetation.ripple", &self.ripple_program)
                .compute_pipeline(Ok(self.ripple_pipeline.clone()))
                .uniform("step", &self.ripple_params)
                .uniform("ripple", &scene.ripple)
                .side_effect()
                .dispatch([groups, groups, 1]);
        }
        let (Some(_), Some(t)) = (self.frame, &scene.tree_buffers) else {
            return;
        };
        let slots = scene.tree_layout.slots.len() as u32;
        g.compute("vegetation.simulate", &self.program)
            .compute_pipeline(Ok(self.pipeline.clone()))
            .uniform("sim", &self.params)
            .uniform("slots", &t.slots)
            .uniform("rigs", &t.rigs)
            .uniform("state", &t.state)
            .uniform("objects", &scene.objects)
            .side_effect()
            .dispatch([slots.div_ceil(GROUP), 1, 1]);
    }

    /// Runs this frame's ripple step now, outside a frame (tests).
    pub fn run_ripple_now(&self, ctx: &GpuContext, scene: &SceneGpu) -> Result<(), GpuError> {
        if self.ripple.is_none() {
            return Ok(());
        }
        let bind = self.ripple_program.bind(
            &ctx.device,
            0,
            &[
                ("step", self.ripple_params.as_entire_binding()),
                ("ripple", scene.ripple.as_entire_binding()),
            ],
        )?;
        let groups = (scene.ripple_n as u32).div_ceil(8);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("vegetation.ripple"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vegetation.ripple"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.ripple_pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(groups, groups, 1);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.check("vegetation.ripple")
    }

    /// Runs this frame's steps now, outside a frame (tests).
    pub fn run_now(&self, ctx: &GpuContext, scene: &SceneGpu) -> Result<(), GpuError> {
        let (Some(_), Some(t)) = (self.frame, &scene.tree_buffers) else {
            return Ok(());
        };
        let bind = self.program.bind(
            &ctx.device,
            0,
            &[
                ("sim", self.params.as_entire_binding()),
                ("slots", t.slots.as_entire_binding()),
                ("rigs", t.rigs.as_entire_binding()),
                ("state", t.state.as_entire_binding()),
                ("objects", scene.objects.as_entire_binding()),
            ],
        )?;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("vegetation.simulate"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("vegetation.simulate"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            let slots = scene.tree_layout.slots.len() as u32;
            pass.dispatch_workgroups(slots.div_ceil(GROUP), 1, 1);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.check("vegetation.simulate")
    }
}
