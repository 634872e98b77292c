//! Computing the tables on the GPU (L1): transmittance, direct irradiance,
//! single scattering, then per order the scattering density, indirect
//! irradiance and multiple scattering, as one graph of compute steps or one
//! step at a time for a progress bar (`himal bake`).

use super::{
    AtmosphereConfig, BrunetonTables, MAX_SCATTERING_ORDER, TRANSMITTANCE_FORMAT, TableSizes,
    table_sampler, table_texture, table_texture_format, tex, view,
};
use crate::gpu::pipeline::{Program, uniform_buffer};
use crate::gpu::{GpuContext, GpuError};
use crate::graph::{FrameGraph, PassTimer, PassTiming};

/// One compute step: program, pipeline, bind group and dispatch size.
struct Step {
    id: String,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    groups: [u32; 3],
}

/// `progress(done, steps, next step's id)` of [`BrunetonTables::compute_with_progress`].
pub type TableProgress<'a> = dyn FnMut(usize, usize, &str) + 'a;

impl BrunetonTables {
    /// Earth tables at [`TableSizes::DEFAULT`].
    pub fn compute(ctx: &GpuContext) -> Result<Self, GpuError> {
        Ok(Self::compute_with(ctx, AtmosphereConfig::earth(TableSizes::DEFAULT), None)?.0)
    }

    /// Computes the tables for `config`; with a `timer`, also the GPU time of
    /// each step (rows `sky.tables.*`).
    pub fn compute_with(
        ctx: &GpuContext,
        config: AtmosphereConfig,
        timer: Option<&mut PassTimer>,
    ) -> Result<(Self, Vec<PassTiming>), GpuError> {
        Self::compute_steps(ctx, config, timer, None)
    }

    /// Computes the tables for `config` one step at a time, waiting for
    /// each, and calls `progress(done, steps, next step's id)` before every
    /// step and once at the end (`himal bake`'s progress bar).
    pub fn compute_with_progress(
        ctx: &GpuContext,
        config: AtmosphereConfig,
        progress: &mut TableProgress<'_>,
    ) -> Result<Self, GpuError> {
        Ok(Self::compute_steps(ctx, config, None, Some(progress))?.0)
    }

    fn compute_steps(
        ctx: &GpuContext,
        config: AtmosphereConfig,
        timer: Option<&mut PassTimer>,
        progress: Option<&mut TableProgress<'_>>,
    ) -> Result<(Self, Vec<PassTiming>), GpuError> {
        let s = config.sizes;
        let params = uniform_buffer(ctx, "sky.atmosphere", &config.gpu_params());
        let t_size = (s.transmittance.0, s.transmittance.1, 1);
        let e_size = (s.irradiance.0, s.irradiance.1, 1);
        let s_size = s.scattering_extent();
        let transmittance = table_texture_format(
            ctx,
            "sky.transmittance",
            t_size,
            false,
            TRANSMITTANCE_FORMAT,
        );
        let delta_irradiance = table_texture(ctx, "sky.delta_irradiance", e_size, false);
        // Ping-pong sums; freshly created textures are zero (order 1 has no irradiance).
        let irradiance = [
            table_texture(ctx, "sky.irradiance.a", e_size, false),
            table_texture(ctx, "sky.irradiance.b", e_size, false),
        ];
        let single_rayleigh = table_texture(ctx, "sky.single_rayleigh", s_size, true);
        let single_mie = table_texture(ctx, "sky.single_mie", s_size, true);
        let density = table_texture(ctx, "sky.density", s_size, true);
        let delta_multiple = table_texture(ctx, "sky.delta_multiple", s_size, true);
        let scattering = [
            table_texture(ctx, "sky.scattering.a", s_size, true),
            table_texture(ctx, "sky.scattering.b", s_size, true),
        ];
        let sampler = table_sampler(ctx);
        let v_t = view(&transmittance);
        let v_de = view(&delta_irradiance);
        let v_e = [view(&irradiance[0]), view(&irradiance[1])];
        let v_sr = view(&single_rayleigh);
        let v_sm = view(&single_mie);
        let v_j = view(&density);
        let v_dm = view(&delta_multiple);
        let v_s = [view(&scattering[0]), view(&scattering[1])];
        let ub = params.as_entire_binding();
        let smp = wgpu::BindingResource::Sampler(&sampler);
        let g2 = |size: (u32, u32, u32)| [size.0.div_ceil(8), size.1.div_ceil(8), 1];
        let g3 = [s_size.0.div_ceil(8), s_size.1.div_ceil(8), s_size.2];
        let program = |name: &str| Program::new(ctx, &format!("passes/sky/bruneton/{name}.wgsl"));

        let mut steps = Vec::new();
        let p = program("transmittance")?;
        steps.push(Step {
            id: "sky.tables.transmittance".into(),
            pipeline: p.compute_pipeline(ctx, "cs_transmittance", &[])?,
            bind_group: p.bind_group(
                ctx,
                0,
                &[("atmosphere", ub.clone()), ("out_transmittance", tex(&v_t))],
            )?,
            groups: g2(t_size),
        });
        let p = program("direct_irradiance")?;
        steps.push(Step {
            id: "sky.tables.direct_irradiance".into(),
            pipeline: p.compute_pipeline(ctx, "cs_direct_irradiance", &[])?,
            bind_group: p.bind_group(
                ctx,
                0,
                &[
                    ("atmosphere", ub.clone()),
                    ("transmittance_load", tex(&v_t)),
                    ("table_sampler", smp.clone()),
                    ("out_delta_irradiance", tex(&v_de)),
                ],
            )?,
            groups: g2(e_size),
        });
        let p = program("single_scattering")?;
        steps.push(Step {
            id: "sky.tables.single".into(),
            pipeline: p.compute_pipeline(ctx, "cs_single_scattering", &[])?,
            bind_group: p.bind_group(
                ctx,
                0,
                &[
                    ("atmosphere", ub.clone()),
                    ("transmittance_load", tex(&v_t)),
                    ("table_sampler", smp.clone()),
                    ("out_rayleigh", tex(&v_sr)),
                    ("out_mie", tex(&v_sm)),
                ],
            )?,
            groups: g3,
        });
        let p_density = program("scattering_density")?;
        let p_irradiance = program("indirect_irradiance")?;
        let p_multiple = program("multiple_scattering")?;
        // Scattering sum: order 1 is the single Rayleigh table itself, then
        // a -> b -> a; irradiance sum: a (zero) -> b -> a -> b.
        let mut scattering_prev: &wgpu::TextureView = &v_sr;
        let mut scattering_out = 0usize;
        let mut irradiance_prev = 0usize;
        for order in 2..=MAX_SCATTERING_ORDER {
            let density_constants = [
                ("SCATTERING_ORDER", f64::from(order)),
                ("DENSITY_SAMPLES", f64::from(s.density_samples)),
            ];
            steps.push(Step {
                id: format!("sky.tables.density{order}"),
                pipeline: p_density.compute_pipeline(
                    ctx,
                    "cs_scattering_density",
                    &density_constants,
                )?,
                bind_group: p_density.bind_group(
                    ctx,
                    0,
                    &[
                        ("atmosphere", ub.clone()),
                        ("transmittance_load", tex(&v_t)),
                        ("single_rayleigh", tex(&v_sr)),
                        ("single_mie", tex(&v_sm)),
                        ("multiple", tex(&v_dm)),
                        ("delta_irradiance", tex(&v_de)),
                        ("table_sampler", smp.clone()),
                        ("out_density", tex(&v_j)),
                    ],
                )?,
                groups: g3,
            });
            let irradiance_constants = [("SCATTERING_ORDER", f64::from(order - 1))];
            steps.push(Step {
                id: format!("sky.tables.irradiance{}", order - 1),
                pipeline: p_irradiance.compute_pipeline(
                    ctx,
                    "cs_indirect_irradiance",
                    &irradiance_constants,
                )?,
                bind_group: p_irradiance.bind_group(
                    ctx,
                    0,
                    &[
                        ("atmosphere", ub.clone()),
                        ("single_rayleigh", tex(&v_sr)),
                        ("single_mie", tex(&v_sm)),
                        ("multiple", tex(&v_dm)),
                        ("previous_irradiance_load", tex(&v_e[irradiance_prev])),
                        ("table_sampler", smp.clone()),
                        ("out_delta_irradiance", tex(&v_de)),
                        ("out_irradiance", tex(&v_e[1 - irradiance_prev])),
                    ],
                )?,
                groups: g2(e_size),
            });
            irradiance_prev = 1 - irradiance_prev;
            steps.push(Step {
                id: format!("sky.tables.multiple{order}"),
                pipeline: p_multiple.compute_pipeline(ctx, "cs_multiple_scattering", &[])?,
                bind_group: p_multiple.bind_group(
                    ctx,
                    0,
                    &[
                        ("atmosphere", ub.clone()),
                        ("transmittance_load", tex(&v_t)),
                        ("density", tex(&v_j)),
                        ("previous_scattering_load", tex(scattering_prev)),
                        ("table_sampler", smp.clone()),
                        ("out_delta_multiple", tex(&v_dm)),
                        ("out_scattering", tex(&v_s[scattering_out])),
                    ],
                )?,
                groups: g3,
            });
            scattering_prev = &v_s[scattering_out];
            scattering_out = 1 - scattering_out;
        }
        let final_scattering = 1 - scattering_out;
        let final_irradiance = irradiance_prev;

        let timings = match progress {
            None => run_steps(ctx, &steps, timer)?,
            Some(progress) => {
                for (i, step) in steps.iter().enumerate() {
                    progress(i, steps.len(), &step.id);
                    run_steps(ctx, std::slice::from_ref(step), None)?;
                    ctx.wait(&step.id)?;
                }
                progress(steps.len(), steps.len(), "done");
                Vec::new()
            }
        };
        let [s0, s1] = scattering;
        let [e0, e1] = irradiance;
        Ok((
            BrunetonTables {
                config,
                params,
                transmittance,
                irradiance: if final_irradiance == 0 { e0 } else { e1 },
                scattering: if final_scattering == 0 { s0 } else { s1 },
                single_rayleigh,
                single_mie,
                sampler,
            },
            timings,
        ))
    }
}

/// Runs `steps` as side-effect passes of one graph (timed with `timer`).
fn run_steps(
    ctx: &GpuContext,
    steps: &[Step],
    timer: Option<&mut PassTimer>,
) -> Result<Vec<PassTiming>, GpuError> {
    let mut graph = FrameGraph::new();
    for step in steps {
        let mut pass = graph.add_pass(&step.id);
        pass.side_effect();
        pass.execute(move |pc| {
            let timestamp_writes = pc.compute_timestamp_writes();
            let mut cp = pc.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&step.id),
                timestamp_writes,
            });
            cp.set_pipeline(&step.pipeline);
            cp.set_bind_group(0, &step.bind_group, &[]);
            cp.dispatch_workgroups(step.groups[0], step.groups[1], step.groups[2]);
            Ok(())
        });
    }
    crate::graph::run(ctx, graph, timer, "sky.tables")
}
