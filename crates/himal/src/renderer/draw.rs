//! One frame: [`Renderer::draw`] (prepare size-dependent resources,
//! upload the frame's uniforms, build, execute and submit the frame graph)
//! and [`Renderer::render`] (the same, read back).

use glam::{Mat4, Vec3, Vec4};

use super::*;
use crate::settings::Culling;

/// One rendered frame read back to the CPU.
pub struct RenderedFrame {
    /// The output texture's texels: the display image (`DISPLAY_FORMAT`),
    /// or with `FrameSettings::raw` a debug view's raw values (`RAW_FORMAT`).
    pub image: TextureData,
    /// CPU time of the frame's halves (planning and culling, graph build
    /// and recording, submit), without waiting for the GPU.
    pub cpu: CpuTimes,
    /// G-buffer draw calls (V6: one per run of one mesh's objects, or per
    /// GPU-culled list).
    pub gbuffer_draws: u32,
    /// The culling that ran (`Gpu` falls back to `Cpu` where it cannot).
    pub culling: crate::settings::Culling,
    /// GPU time per pass (empty where the adapter has no timestamps).
    pub timings: Vec<PassTiming>,
    /// With [`Renderer::set_isolated_timing`]: each pass's wall time when
    /// submitted alone (bench; `None` otherwise).
    pub isolated: Option<crate::graph::IsolatedTimings>,
    /// Shadow draw calls and what the shadow passes rendered.
    pub shadows: ShadowStats,
    /// Sky occlusion sectors wanted, rendered this frame, resident (L2).
    pub sky_occlusion: crate::passes::skyocc::SkyOccStats,
    /// The streamed world's frame: streaming and terrain (`None`: a plain scene).
    pub world: Option<super::world::WorldFrame>,
}

/// CPU milliseconds of one frame's phases, timed on the render thread.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CpuTimes {
    /// `plan_frame`: uniforms, shadow and sky-occlusion planning, culling.
    pub plan_ms: f64,
    /// Of `plan_ms`: culling (the camera's lists, shadow fits and caster
    /// lists, the GPU culling's plan).
    pub cull_ms: f64,
    /// Of `plan_ms`: uploads of the objects' transforms and the view and
    /// lighting uniforms (`Queue::write_buffer`).
    pub upload_ms: f64,
    /// Frame-graph build, compile and command recording.
    pub record_ms: f64,
    /// `Queue::submit`.
    pub submit_ms: f64,
    /// The render thread's own CPU time over the three ([`crate::clock`]):
    /// the wall times less what the scheduler gave to other threads.
    pub thread_ms: f64,
}

impl CpuTimes {
    /// The frame's whole CPU time (ms): plan + record + submit.
    pub fn total_ms(&self) -> f64 {
        self.plan_ms + self.record_ms + self.submit_ms
    }
}

/// Fetches the pipeline that draws `view` into `format` into the cache
/// (none for `Final`): pre-warming.
pub(super) fn prepare_view(
    ctx: &GpuContext,
    passes: &Passes,
    view: ViewBuffer,
    format: wgpu::TextureFormat,
) -> Result<(), GpuError> {
    match view {
        ViewBuffer::Debug(v) => passes.debug.pipeline(ctx, v, format).map(drop),
        ViewBuffer::Ao(v) => passes.ao.view_pipeline(ctx, v, format).map(drop),
        ViewBuffer::Shadow(v) => passes.shadows.view_pipeline(ctx, v, format).map(drop),
        ViewBuffer::Env(v) => passes.env_view.pipeline(ctx, v, format).map(drop),
        ViewBuffer::SkyOcc(v) => passes.skyocc.view_pipeline(ctx, v, format).map(drop),
        ViewBuffer::Indirect(_) => (passes.debug)
            .pipeline(ctx, crate::passes::debug::DebugView::Lighting, format)
            .map(drop),
        ViewBuffer::TreeAo => passes.tree_ao.view_pipeline(ctx, format).map(drop),
        ViewBuffer::Final | ViewBuffer::ParticleLighting => Ok(()),
    }
}

/// What the CPU half of a frame hands to its GPU half.
pub(super) struct FramePlan {
    pub(super) format: wgpu::TextureFormat,
    /// Projection jitter (px) of this frame.
    jitter: [f32; 2],
    view_proj: Mat4,
    shadows: ShadowStats,
    sky_occlusion: crate::passes::skyocc::SkyOccStats,
    terrain: Option<crate::passes::terrain::TerrainStats>,
    cull_ms: f64,
    upload_ms: f64,
}

/// One frame drawn into [`Renderer::output`], left on the GPU (a viewer
/// presents it without a read-back).
pub struct DrawnFrame {
    /// CPU time of the frame's halves (planning and culling, graph build
    /// and recording, submit), without waiting for the GPU.
    pub cpu: CpuTimes,
    /// G-buffer draw calls (V6: one per run of one mesh's objects, or per
    /// GPU-culled list).
    pub gbuffer_draws: u32,
    /// The culling that ran (`Gpu` falls back to `Cpu` where it cannot).
    pub culling: crate::settings::Culling,
    /// GPU time per pass (empty where the adapter has no timestamps).
    pub timings: Vec<PassTiming>,
    /// With [`Renderer::set_isolated_timing`]: each pass's wall time when
    /// submitted alone (bench; `None` otherwise).
    pub isolated: Option<crate::graph::IsolatedTimings>,
    /// Shadow draw calls and what the shadow passes rendered.
    pub shadows: ShadowStats,
    /// Sky occlusion sectors wanted, rendered this frame, resident (L2).
    pub sky_occlusion: crate::passes::skyocc::SkyOccStats,
    /// The streamed world's frame: streaming and terrain (`None`: a plain scene).
    pub world: Option<super::world::WorldFrame>,
}

impl Renderer {
    fn output_format(settings: &FrameSettings) -> wgpu::TextureFormat {
        match settings.view {
            v if v.is_final() => DISPLAY_FORMAT,
            _ if settings.raw => RAW_FORMAT,
            _ => DISPLAY_FORMAT,
        }
    }

    /// Creates size-dependent resources and the debug pipeline if needed.
    pub(super) fn prepare_output(
        &mut self,
        settings: &FrameSettings,
    ) -> Result<wgpu::TextureFormat, Error> {
        let size = (settings.width, settings.height);
        let format = Self::output_format(settings);
        let (device, history) = (&self.ctx.device, &mut self.res.history);
        if settings.aa.temporal() {
            crate::passes::aa::temporal::declare_history(history, device, size, DISPLAY_FORMAT);
        }
        if settings.aa_buffers.any() {
            crate::passes::aa::temporal::buffers::declare_history(history, device, size);
        }
        if settings.ao.mode.temporal() {
            crate::passes::ao::declare_history(history, device, size, settings.ao.mode);
        }
        if self.res.luminance.as_ref().is_none_or(|(s, _)| *s != size) {
            self.res.luminance = Some((size, LuminanceBuffers::new(&self.ctx.device, size)));
        }
        let device = &self.ctx.device;
        self.res
            .outputs
            .entry((size.0, size.1, format))
            .or_insert_with(|| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("output"),
                    size: wgpu::Extent3d {
                        width: size.0,
                        height: size.1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::COPY_SRC
                        | wgpu::TextureUsages::TEXTURE_BINDING,
                    // himal::present reads the display-encoded bytes as they are
                    view_formats: if format.is_srgb() {
                        &[wgpu::TextureFormat::Rgba8Unorm]
                    } else {
                        &[]
                    },
                })
            });
        Ok(format)
    }

    /// Restarts the AA history on a mode change and uploads the temporal
    /// passes' parameters for a frame sampled at `jitter`.
    fn prepare_aa_history(&mut self, settings: &FrameSettings, jitter: [f32; 2]) {
        use crate::passes::aa::temporal;
        if self.aa_last != Some(settings.aa) {
            temporal::reset_history(&mut self.res.history);
            self.aa_last = Some(settings.aa);
        }
        if settings.aa.temporal() {
            let params = crate::passes::aa::AaParams::new(
                jitter,
                self.aa_last_jitter,
                self.res.history.frames(temporal::RAW_HISTORY),
                (self.frame_index % 2) as u32,
                &settings.aa_tuning,
            );
            self.res.passes.temporal.update(&self.ctx.queue, &params);
        }
    }

    /// Renders one frame from `camera` and reads the output back.
    pub fn render(
        &mut self,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> Result<RenderedFrame, Error> {
        let DrawnFrame {
            cpu,
            gbuffer_draws,
            culling,
            timings,
            isolated,
            shadows,
            sky_occlusion,
            world,
        } = self.draw(camera, settings)?;
        let output = self
            .output(settings)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        Ok(RenderedFrame {
            image: read_texture(&self.ctx, output, 0, 0)?,
            cpu,
            gbuffer_draws,
            culling,
            timings,
            isolated,
            shadows,
            sky_occlusion,
            world,
        })
    }

    /// The texture the last [`Renderer::draw`] with these settings' size and
    /// output format wrote (display frames: `Rgba8UnormSrgb`).
    pub fn output(&self, settings: &FrameSettings) -> Option<&wgpu::Texture> {
        let format = Self::output_format(settings);
        self.res
            .outputs
            .get(&(settings.width, settings.height, format))
    }

    /// The CPU half of a frame, in order: output and history declarations,
    /// sky light, probe choice, uniforms, and each technique's planning
    /// (AO and buffer TAA parameters, shadow fits and culled draws, sky
    /// occlusion sectors, forward sorting). [`Renderer::draw`] and
    /// [`Renderer::describe_graph`] both run it.
    pub(super) fn plan_frame(
        &mut self,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> Result<FramePlan, Error> {
        let size = (settings.width, settings.height);
        let format = self.prepare_output(settings)?;
        self.update_sky(&settings.sun, settings.sky_model)?;
        self.stream_world(camera)?;
        let probe = if settings.environment_probes && self.res.environment.is_none() {
            (self.res.passes.probes).select(camera.position, self.res.active_probe)
        } else {
            None
        };
        if probe != self.res.active_probe {
            self.res.active_probe = probe;
            self.res.passes.envmap.dirty = true;
        }
        if settings.envmap_every_frame {
            self.res.passes.envmap.dirty = true;
        }
        self.res.post.update(&self.ctx.queue, settings);
        let aspect = size.0 as f32 / size.1 as f32;
        let (view, proj) = (camera.view(), camera.projection(aspect));
        // Projection jitter (A2, A3): the matrices carry it, so passes that
        // reconstruct positions from depth stay exact; View.jitter.xy repeats
        // it in clip units. Sample offset j (px, y down) = image shifted by -j.
        // Debug views show the G-buffer as rasterised: no jitter there; the
        // AO views show the AO that lighting gets, jittered like the frame,
        // and the motion view the stabilised motion of `--aa-buffers motion`.
        let stable_motion_view = settings.aa_buffers.motion
            && settings.view == ViewBuffer::Debug(crate::passes::debug::DebugView::Motion);
        let jitter = match settings.view {
            v if v.is_final() => settings.aa.jitter(self.frame_index),
            ViewBuffer::Ao(_) => settings.aa.jitter(self.frame_index),
            _ if stable_motion_view => settings.aa.jitter(self.frame_index),
            _ => [0.0, 0.0],
        };
        let jitter_clip = Vec3::new(
            -2.0 * jitter[0] / size.0 as f32,
            2.0 * jitter[1] / size.1 as f32,
            0.0,
        );
        let proj = Mat4::from_translation(jitter_clip) * proj;
        self.prepare_aa_history(settings, jitter);
        let view_proj = proj * view;
        let prev = self.prev_view_proj.unwrap_or(view_proj);
        let prev_time = self.prev_time.unwrap_or(settings.time_s);
        let uniform = ViewUniform::new(
            view,
            proj,
            prev,
            camera.position,
            camera.near,
            size,
            self.frame_index,
            settings.exposure_ev,
        )
        .with_times(settings.time_s, prev_time)
        .with_jitter(jitter_clip.x, jitter_clip.y)
        .with_orthographic(camera.orthographic.map(|o| o.far));
        let t_upload = std::time::Instant::now();
        self.res
            .scene
            .update_objects(&self.ctx.queue, settings.time_s, prev_time);
        self.ctx
            .queue
            .write_buffer(&self.res.view_buffer, 0, bytemuck::bytes_of(&uniform));
        let prev_jitter = if self.prev_view_proj.is_some() {
            self.prev_jitter
        } else {
            jitter
        };
        let upload_ms = t_upload.elapsed().as_secs_f64() * 1e3;
        let Some((_, _, light)) = &self.sky_light else {
            return Err(Error::InvalidSettings("sky light missing".into()));
        };
        let (sun_illuminance, sky_irradiance) = match &self.res.environment {
            Some(env) => (
                if env.sun {
                    light.sun_illuminance
                } else {
                    glam::Vec3::ZERO
                },
                Sh9Gpu::from(&env.irradiance_sh),
            ),
            None => (light.sun_illuminance, Sh9Gpu::from(&light.irradiance_sh)),
        };
        let lighting = LightingUniform::new(
            light.sun_direction,
            sun_illuminance,
            sky_irradiance,
            Vec4::new(
                settings.aerial_extinction,
                if settings.aerial_extinction > 0.0 {
                    1.0
                } else {
                    0.0
                },
                // fog colour from the sky SH under the Bruneton sky (deferred.wgsl)
                if self.res.passes.sky.draws_bruneton() {
                    1.0
                } else {
                    0.0
                },
                if settings.bent_normals { 1.0 } else { 0.0 },
            ),
        )
        .with_visibility_remap(settings.visibility_remap)
        .with_leaf_shading(settings.leaf_shading);
        let t_lighting = std::time::Instant::now();
        self.ctx
            .queue
            .write_buffer(&self.res.lighting_buffer, 0, bytemuck::bytes_of(&lighting));
        let upload_ms = upload_ms + t_lighting.elapsed().as_secs_f64() * 1e3;
        let sun_direction = light.sun_direction;
        // E3: the permutations the G-buffer and forward draws pick.
        self.res.passes.gbuffer.specular_aa = settings.specular_aa;
        self.res.passes.gbuffer.deform_motion = settings.deform_motion;
        self.res.passes.forward.specular_aa = settings.specular_aa;
        self.res.passes.forward.fog =
            super::lighting_key(settings, self.res.environment.is_some()).fog;
        self.res.passes.wet.amount = settings.wetness;
        self.res.passes.wet.specular_aa = settings.specular_aa;
        self.res.passes.particles.key = crate::passes::particles::ParticleKey {
            per_pixel: settings.particles_per_pixel,
            corners: settings.particles_light_corners,
            debug: settings.view == ViewBuffer::ParticleLighting,
            probe_ambient: settings.particles_probe_ambient,
            cascaded_shadows: settings.particles_cascaded_shadows,
        };
        self.res.passes.particles.reactive = settings.particles_reactive;
        self.res.passes.particles.sort_particles = settings.particles_sort;
        let planned = frame::plan(
            &mut self.res.passes,
            frame::PlanInputs {
                ctx: &self.ctx,
                scene: &self.res.scene,
                settings,
                camera,
                proj,
                jitter,
                prev_jitter,
                sun_direction,
                history: &self.res.history,
            },
        );
        Ok(FramePlan {
            format,
            jitter,
            view_proj,
            shadows: planned.shadows,
            sky_occlusion: planned.sky_occlusion,
            terrain: planned.terrain,
            cull_ms: planned.cull_ms,
            upload_ms,
        })
    }

    /// Renders one frame from `camera` into [`Renderer::output`] and waits for
    /// the GPU timings; the image stays on the GPU.
    pub fn draw(&mut self, camera: &Camera, settings: &FrameSettings) -> Result<DrawnFrame, Error> {
        self.validate(settings)?;
        let size = (settings.width, settings.height);
        let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
        let thread = crate::clock::Stopwatch::start();
        let t_plan = std::time::Instant::now();
        let FramePlan {
            format,
            jitter,
            view_proj,
            shadows: shadow_stats,
            sky_occlusion: skyocc_stats,
            terrain,
            cull_ms,
            upload_ms,
        } = self.plan_frame(camera, settings)?;
        let plan_ms = ms(t_plan);
        let t_record = std::time::Instant::now();
        let Self {
            ctx,
            res,
            pool,
            timer,
            frame_index,
            sky_timings,
            isolate_passes,
            ..
        } = self;
        let inputs = res
            .inputs(ctx, settings, format, *frame_index)
            .ok_or_else(|| Error::InvalidSettings("output not prepared".into()))?;
        let recorded = frame::build(inputs, size, settings.view)
            .map_err(Error::from)
            .and_then(|g| Ok(g.compile()?))
            .and_then(|c| {
                Ok(match isolate_passes {
                    true => c
                        .execute_isolated(&ctx.device, &ctx.queue, pool, timer.as_mut())
                        .map(|(c, i)| (c, Some(i)))?,
                    false => (c.execute(&ctx.device, pool, timer.as_mut())?, None),
                })
            });
        let (commands, isolated) = match recorded {
            Ok(c) => c,
            Err(e) => {
                res.history.discard();
                res.passes.cull.hiz.reset();
                return Err(e);
            }
        };
        let record_ms = ms(t_record);
        let t_submit = std::time::Instant::now();
        ctx.queue.submit([commands]);
        let submit_ms = ms(t_submit);
        let thread_ms = thread.span().cpu_ms;
        res.history.swap();
        // A failed frame leaves no Hi-Z pyramid to trust.
        ctx.check("frame")
            .inspect_err(|_| res.passes.cull.hiz.reset())?;
        let mut timings = std::mem::take(sky_timings);
        if let Some(t) = timer.as_mut() {
            timings.extend(t.read_timings(&ctx.device)?);
        }
        self.prev_view_proj = Some(view_proj);
        // V6 Hi-Z: the pyramid now holds this frame's depth.
        self.res.passes.cull.hiz.frame_done(view_proj);
        self.prev_jitter = jitter;
        self.prev_time = Some(settings.time_s);
        self.res.post.frame_done(settings);
        if self.res.passes.envmap.dirty
            && let Some(p) = self.res.active_probe
        {
            self.res.passes.probes.probes[p].captured = true;
        }
        self.res.passes.envmap.dirty = false;
        self.frame_index += 1;
        if settings.aa.temporal() && settings.view.is_final() {
            self.aa_last_jitter = jitter;
        }
        Ok(DrawnFrame {
            cpu: CpuTimes {
                plan_ms,
                cull_ms,
                upload_ms,
                record_ms,
                submit_ms,
                thread_ms,
            },
            gbuffer_draws: (self.res.passes.gbuffer.visible).draw_calls(&self.res.scene),
            culling: match settings.culling {
                Culling::Gpu if self.res.passes.cull.planned() == 0 => Culling::Cpu,
                c => c,
            },
            timings,
            isolated,
            shadows: shadow_stats,
            sky_occlusion: skyocc_stats,
            world: self.world.as_ref().map(|w| world::WorldFrame {
                stream: w.stats,
                stream_ms: w.stream_ms,
                stream_times: w.stream_times,
                terrain,
            }),
        })
    }
}

/// What the camera's culled lists draw (V6, E2): instances and triangles
/// per LOD level, a level in transition counted in both lists.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrawnCounts {
    /// Instances drawn, indexed by LOD level (0: the finest).
    pub instances: [u64; crate::scene::lod::MAX_LODS],
    /// Triangles drawn (index count / 3 × instances), by LOD level.
    pub triangles: [u64; crate::scene::lod::MAX_LODS],
    /// Of those, triangles expected under one pixel (E2): each instance's
    /// level's areas at `(s f / d)^2` pixels per unit area (`s` its linear
    /// scale, `d` the eye's distance to its box centre) foreshortened by a
    /// uniform `|cos|` ([`crate::scene::lod::AreaHistogram::below`]).
    pub subpixel: [f64; crate::scene::lod::MAX_LODS],
}

impl DrawnCounts {
    /// Sums draw arguments `[index_count, instance_count, ..]` in
    /// `reference::cull`'s order (lists of each batch, level = list % levels).
    pub fn from_args(args: &[[u32; 5]]) -> Self {
        use crate::scene::lod::MAX_LODS;
        let mut c = Self::default();
        for (j, a) in args.iter().enumerate() {
            let l = j % crate::passes::cull::LISTS % MAX_LODS;
            c.instances[l] += u64::from(a[1]);
            c.triangles[l] += u64::from(a[0] / 3) * u64::from(a[1]);
        }
        c
    }

    /// Instances over all levels.
    pub fn total_instances(&self) -> u64 {
        self.instances.iter().sum()
    }

    /// Triangles over all levels.
    pub fn total_triangles(&self) -> u64 {
        self.triangles.iter().sum()
    }

    /// The share of drawn triangles under one pixel.
    pub fn subpixel_share(&self) -> f64 {
        self.subpixel.iter().sum::<f64>() / self.total_triangles().max(1) as f64
    }
}

impl Renderer {
    /// Runs the camera's culling alone and counts what its G-buffer lists
    /// draw (the GPU's lists read back; the CPU twin's where the GPU path
    /// cannot run). With Hi-Z occlusion on, against the pyramid the last
    /// frame culled with, so after a frame it counts what that frame drew.
    /// Statistics only: it stalls for the read-back.
    pub fn count_drawn(
        &mut self,
        camera: &Camera,
        settings: &FrameSettings,
    ) -> Result<DrawnCounts, Error> {
        use crate::passes::cull::{CullView, reference};
        let aspect = settings.width as f32 / settings.height as f32;
        let view = CullView::clip(camera.projection(aspect) * camera.view());
        let lod = frame::lod_view(camera, settings);
        let cull = &mut self.res.passes.cull;
        let result = if cull.supported().is_ok() {
            cull.read_back(&self.ctx, &[view], lod)?
        } else {
            reference::cull(&cull.layout, &[view], &lod)
        };
        let mut counts = DrawnCounts::from_args(&result.args);
        let (l, scene) = (&cull.layout, &self.res.scene);
        let focal = crate::scene::lod::focal_px(camera.fov_y_deg, settings.height);
        let lists = crate::passes::cull::LISTS;
        let levels = crate::scene::lod::MAX_LODS;
        for (k, list) in result.instances.iter().enumerate() {
            let (batch, level) = (k / lists, k % lists % levels);
            let mesh = l.batch_mesh.get(batch).copied().unwrap_or(0) as usize;
            let Some(h) = scene.area_histograms.get(mesh).and_then(|m| m.get(level)) else {
                continue;
            };
            for &e in list {
                let Some(b) = l.bounds.get((e & 0x00ff_ffff) as usize) else {
                    continue;
                };
                let d = camera.position.distance(b.center()).max(1e-3);
                counts.subpixel[level] += h.below((b.half_extent[3] * focal / d).powi(2));
            }
        }
        Ok(counts)
    }
}
