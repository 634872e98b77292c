//! `himal view`: an interactive window on a scene (X11). The frame is
//! rendered by the same `Renderer` as `himal render` and presented through a
//! wgpu swapchain (`himal::present`: no read-back), or through the CPU
//! (softbuffer) where the adapter cannot present to the window. A HUD with
//! the state and per-pass GPU times is blended over the frame. Keys are
//! listed in [`HELP`].

use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use glam::{Quat, Vec3};
use himal::passes::aa::AaMode;
use himal::passes::ao::AoMode;
use himal::present::{Hud, Overlay, Presenter};
use himal::scene::Camera;
use himal::{FrameSettings, Renderer, ViewBuffer};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::orbit::Orbit;
use crate::render::RenderArgs;

pub const HELP: &str = "Orbit (models): left drag turn, middle drag pan, wheel zoom, F frame, O fly; \
fly: WASD move, Q/E down/up, Shift fast, right mouse drag look, O orbit; \
T/G time +-30 min, V next view, 1 AO, 2 bloom, 3 shadows, 4 AA mode, 5 env specular, 6 sky occlusion, \
7 TAA on AO and motion, 8 sky model, 9 tone mapper, -/= exposure, B studio/sky light, F fly the world's path (worlds), H HUD, P screenshot, Esc quit";

#[derive(Args, Clone, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    pub render: RenderArgs,
    /// How frames reach the window: a wgpu swapchain (`gpu`), a CPU copy
    /// (`cpu`), or the swapchain where the adapter supports the window (`auto`).
    #[arg(long, value_enum, default_value_t = PresentMode::Auto)]
    pub present: PresentMode,
    /// Start with the HUD (state and per-pass GPU times) hidden.
    #[arg(long)]
    pub no_hud: bool,
    /// With --frames N: also write the last image the window showed (frame
    /// and HUD, read back from the swapchain or the CPU buffer) to FILE.
    #[arg(long, value_name = "FILE")]
    pub window_out: Option<std::path::PathBuf>,
    /// Start flying the world's named path (`--scene world --path across`;
    /// F toggles flying).
    #[arg(long, value_name = "NAME", allow_hyphen_values = true)]
    pub path: Option<String>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum PresentMode {
    Auto,
    Gpu,
    Cpu,
}

/// Where frames go: a swapchain, or a CPU buffer (softbuffer).
enum Presentation {
    Gpu {
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
        presenter: Box<Presenter>,
    },
    Cpu(softbuffer::Surface<Arc<Window>, Arc<Window>>),
}

/// Lost devices the viewer recreates before it gives up.
const MAX_RECOVERIES: u32 = 3;

/// Movement keys held down.
#[derive(Default)]
struct Held {
    forward: f32,
    right: f32,
    up: f32,
    fast: bool,
    looking: bool,
    orbiting: bool,
    panning: bool,
}

/// Longest simulation step (camera, clock, flight path): a stall must not
/// throw the camera across the world. The HUD's rate is not clamped.
const MAX_STEP_S: f32 = 0.25;

fn sim_step(interval_s: f32) -> f32 {
    interval_s.min(MAX_STEP_S)
}

/// The HUD's frame rate: an exponential average of the real frame
/// intervals (not of their reciprocals, which over-weights fast frames).
#[derive(Default)]
struct FrameRate {
    interval_s: Option<f32>,
}

impl FrameRate {
    fn record(&mut self, interval_s: f32) {
        self.interval_s = Some(match self.interval_s {
            None => interval_s,
            Some(avg) => 0.9 * avg + 0.1 * interval_s,
        });
    }

    fn fps(&self) -> f32 {
        self.interval_s.map_or(0.0, |s| 1.0 / s.max(1e-6))
    }

    fn frame_ms(&self) -> f32 {
        self.interval_s.map_or(0.0, |s| 1e3 * s)
    }
}

struct Viewer {
    args: RenderArgs,
    /// Kept to rebuild the renderer when the device is lost.
    scene: himal::scene::Scene,
    renderer: Renderer,
    /// Devices recreated after a loss (more than MAX_RECOVERIES ends the run).
    recoveries: u32,
    /// Test hook ($HIMAL_VIEW_LOSE_DEVICE_AT): destroy the device before this frame.
    lose_device_at: Option<u32>,
    /// Test hook ($HIMAL_VIEW_OPEN_AT=FRAME:FILE): open FILE before that
    /// frame as a dropped file would be.
    open_at: Option<(u32, std::path::PathBuf)>,
    /// A model was opened in the window: the scene is no longer the
    /// command line's.
    opened: bool,
    /// The scene's environment changed (B): rebuild before the next frame.
    rebuild_pending: bool,
    camera: Camera,
    settings: FrameSettings,
    present: PresentMode,
    window_out: Option<std::path::PathBuf>,
    window: Option<(Arc<Window>, Presentation)>,
    hud: bool,
    held: Held,
    last: Instant,
    frames: u32,
    clock: f32,
    rate: FrameRate,
    screenshot: bool,
    error: Option<anyhow::Error>,
    /// The orbit camera (models; O toggles it), `None` when flying.
    orbit: Option<Orbit>,
    /// The world's flight path F flies, and whether it is flying and where (s).
    path: Option<himal::scene::world::FlightPath>,
    flying: bool,
    path_t: f32,
}

impl Viewer {
    fn toggle(&mut self, key: KeyCode) {
        let s = &mut self.settings;
        match key {
            KeyCode::Equal => s.exposure_ev = (s.exposure_ev + 0.5).min(10.0),
            KeyCode::Minus => s.exposure_ev = (s.exposure_ev - 0.5).max(-10.0),
            // Studio light or the physical sky: the environment is part of
            // the renderer's resources, rebuilt before the next frame.
            KeyCode::KeyB if self.renderer.world().is_none() => {
                self.scene.environment = match self.scene.environment {
                    Some(_) => None,
                    None => Some(himal::scene::EnvironmentDesc::new(himal::scene::STUDIO)),
                };
                self.rebuild_pending = true;
            }
            KeyCode::KeyT => s.sun.time_hours = (s.sun.time_hours + 0.5).rem_euclid(24.0),
            KeyCode::KeyG => s.sun.time_hours = (s.sun.time_hours - 0.5).rem_euclid(24.0),
            KeyCode::KeyV => {
                let names = ViewBuffer::NAMES;
                let now = names
                    .iter()
                    .position(|n| n.parse::<ViewBuffer>().ok() == Some(s.view))
                    .unwrap_or(0);
                if let Ok(v) = names[(now + 1) % names.len()].parse() {
                    s.view = v;
                }
            }
            KeyCode::Digit1 => {
                s.ao.mode = match s.ao.mode {
                    AoMode::Off => AoMode::HbaoStf,
                    _ => AoMode::Off,
                }
            }
            KeyCode::Digit2 => s.bloom.enabled = !s.bloom.enabled,
            KeyCode::Digit3 => {
                s.shadow_resolution = if s.shadow_resolution > 0 {
                    0
                } else {
                    himal::renderer::DEFAULT_SHADOW_RESOLUTION
                }
            }
            KeyCode::Digit4 => {
                let modes = ["none", "smaa", "smaa-t2x", "tfq", "taa", "hraa"];
                let now = modes
                    .iter()
                    .position(|m| AaMode::parse(m).ok() == Some(s.aa))
                    .unwrap_or(0);
                if let Ok(m) = AaMode::parse(modes[(now + 1) % modes.len()]) {
                    s.aa = m;
                }
            }
            KeyCode::Digit5 => s.environment_specular = !s.environment_specular,
            KeyCode::Digit6 => s.sky_occlusion = !s.sky_occlusion,
            KeyCode::Digit7 => {
                let on = !s.aa_buffers.any();
                s.aa_buffers = himal::passes::aa::AaBuffers { ao: on, motion: on };
            }
            KeyCode::Digit8 => {
                use himal::passes::sky::SkyModel;
                s.sky_model = match s.sky_model {
                    SkyModel::Bruneton => SkyModel::Preetham,
                    SkyModel::Preetham => SkyModel::Bruneton,
                };
            }
            KeyCode::Digit9 => {
                s.tonemapper = s.tonemapper.next();
                // The white point is Reinhard's: kept for it, dropped for the others.
                s.white_point = (s.tonemapper == himal::passes::post::Tonemapper::Reinhard)
                    .then_some(self.args.post.white_point)
                    .flatten();
            }
            KeyCode::KeyP | KeyCode::F12 => self.screenshot = true,
            KeyCode::KeyH => self.hud = !self.hud,
            // A world flies its path; anything else is framed.
            KeyCode::KeyF if self.path.is_some() => self.flying = !self.flying,
            KeyCode::KeyF => {
                self.orbit = Some(Orbit::framing(&self.scene.bounds, self.camera.fov_y_deg))
            }
            KeyCode::KeyO => {
                self.orbit = match self.orbit {
                    Some(_) => None,
                    None => Some(Orbit::around(&self.camera, &self.scene.bounds)),
                }
            }
            _ => {}
        }
    }

    fn step_camera(&mut self, dt: f32) {
        if let Some(o) = &self.orbit {
            self.camera = o.camera(self.camera.fov_y_deg);
            return;
        }
        // A 10 km world is crossed at flying speed, a valley at walking speed.
        let base = if self.path.is_some() { 40.0 } else { 4.0 };
        let speed = if self.held.fast { 5.0 * base } else { base } * dt;
        let c = &mut self.camera;
        let right = c.forward.cross(Vec3::Y).normalize_or(Vec3::X);
        c.position += (c.forward * self.held.forward + right * self.held.right) * speed
            + Vec3::Y * self.held.up * speed;
    }

    fn look(&mut self, dx: f32, dy: f32) {
        let c = &mut self.camera;
        let right = c.forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let yaw = Quat::from_axis_angle(Vec3::Y, -dx * 0.003);
        let pitched = Quat::from_axis_angle(right, -dy * 0.003) * c.forward;
        // Stop short of the poles, where yaw would flip.
        let forward = if pitched.y.abs() < 0.98 {
            pitched
        } else {
            c.forward
        };
        c.forward = (yaw * forward).normalize();
        c.up = Vec3::Y;
    }

    /// The HUD's text: state, then the GPU time of every pass in frame order.
    fn hud_text(
        &self,
        settings: &FrameSettings,
        timings: &[himal::graph::PassTiming],
        world: Option<&himal::WorldFrame>,
    ) -> Hud {
        let s = settings;
        let on = |b: bool| if b { "on" } else { "off" };
        let total: f64 = timings.iter().map(|t| t.gpu_ms).sum();
        let mut lines = vec![
            format!(
                "himal {:5.1} fps ({:.1} ms)  {}x{}  {:02}:{:02}  GPU {total:.2} ms",
                self.rate.fps(),
                self.rate.frame_ms(),
                s.width,
                s.height,
                s.sun.time_hours as u32,
                (s.sun.time_hours.fract() * 60.0) as u32
            ),
            format!(
                "[1] AO {}  [2] bloom {}  [3] shadows {}",
                on(s.ao.mode != AoMode::Off),
                on(s.bloom.enabled),
                on(s.shadow_resolution > 0)
            ),
            format!(
                "[4] AA {}  [5] env specular {}  [6] sky occlusion {}",
                s.aa.name(),
                on(s.environment_specular),
                on(s.sky_occlusion)
            ),
            format!(
                "[7] TAA on AO+motion {}  [8] sky {:?}  [V] {}",
                on(s.aa_buffers.any()),
                s.sky_model,
                view_name(s.view)
            ),
            format!(
                "[9] tone {}  [-/=] {:+.1} EV  [B] light {}",
                s.tonemapper.name(),
                s.exposure_ev,
                match &self.scene.environment {
                    None => "sky".to_string(),
                    Some(e) if e.path.as_os_str() == himal::scene::STUDIO => "studio".to_string(),
                    Some(e) => e.path.display().to_string(),
                }
            ),
        ];
        if let Some(w) = world {
            let s = &w.stream;
            lines.push(format!(
                "world {} sectors +{}  tiles {}/{}  inst {}k/{}k",
                s.resident,
                s.missing,
                s.tiles_used,
                s.tiles_total,
                s.instances / 1000,
                s.instances_total / 1000
            ));
            lines.push(format!(
                "stream {:.1} ms {:.0} KiB  terrain {}k tris  [F] fly {}",
                w.stream_ms,
                s.upload_bytes as f64 / 1024.0,
                w.terrain.as_ref().map_or(0, |t| t.triangles() / 1000),
                on(self.flying)
            ));
        }
        if timings.is_empty() {
            lines.push("no GPU timestamps on this adapter".into());
        }
        // One row per pass group (the id before the first '.'), in frame order:
        // a full list of steps does not fit a small window.
        let mut groups: Vec<(String, f64)> = Vec::new();
        for t in timings {
            let group = t.id.split('.').next().unwrap_or(&t.id);
            match groups.iter_mut().find(|(g, _)| g == group) {
                Some((_, ms)) => *ms += t.gpu_ms,
                None => groups.push((group.to_string(), t.gpu_ms)),
            }
        }
        Hud {
            lines,
            timings: groups,
        }
    }

    /// Renders a frame, presents it, and updates the title.
    /// After a frame failed: when the device is lost, recreate it, the
    /// renderer and the window's presentation and go on (`Ok`); otherwise,
    /// or past MAX_RECOVERIES, the error ends the viewer.
    fn recover(&mut self, error: anyhow::Error) -> Result<()> {
        let Some(reason) = self.renderer.context().lost_reason() else {
            return Err(error);
        };
        if self.recoveries >= MAX_RECOVERIES {
            return Err(error.context(format!(
                "the device was lost {} times ({reason}); giving up",
                self.recoveries + 1
            )));
        }
        self.recoveries += 1;
        eprintln!(
            "warning: GPU device lost ({reason}) at frame {}: {error:#}; recreating the device \
             and its resources",
            self.frames
        );
        self.rebuild()?;
        eprintln!("device recreated on {}", self.renderer.context().info.name);
        Ok(())
    }

    /// A new device and renderer for `self.scene`, and the window's
    /// presentation on it.
    fn rebuild(&mut self) -> Result<()> {
        // The presentation holds the old device's surface: drop it first.
        let window = self.window.take().map(|(w, _)| w);
        let mut renderer = if self.opened {
            Renderer::new(self.args.gpu.context()?, &self.scene)?
        } else {
            self.args
                .open_renderer(self.args.gpu.context()?, &self.scene)?
        };
        self.args.post.configure(&mut renderer, &self.args.gpu)?;
        self.renderer = renderer;
        if let Some(window) = window {
            let presentation = self.presentation(&window)?;
            self.window = Some((window, presentation));
        }
        Ok(())
    }

    /// Opens glTF model `path` in place of the scene (a dropped file): lit
    /// and framed as `--gltf` would be. A file that does not load is
    /// reported and the current scene kept.
    fn open_model(&mut self, path: &std::path::Path) -> Result<()> {
        let mut scene = match himal::scene::Scene::from_gltf(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e} (keeping the current scene)");
                return Ok(());
            }
        };
        crate::render::apply_environment(&self.args, &mut scene, true);
        // --gltf's field of view, not the previous scene camera's.
        self.camera.fov_y_deg = self.args.fov.unwrap_or(40.0);
        let orbit = Orbit::framing(&scene.bounds, self.camera.fov_y_deg);
        // This frame already looks at the model.
        self.camera = orbit.camera(self.camera.fov_y_deg);
        self.orbit = Some(orbit);
        // The scene's own sun and no world haze, as `--gltf` starts with.
        let fresh =
            FrameSettings::new(self.settings.width, self.settings.height, scene.sun.clone());
        self.settings.sun = fresh.sun;
        self.settings.aerial_extinction = fresh.aerial_extinction;
        self.scene = scene;
        (self.path, self.flying, self.opened) = (None, false, true);
        self.rebuild()?;
        if let Some((window, _)) = &self.window {
            window.set_title(&format!("himal — {}", path.display()));
        }
        println!("opened {}", path.display());
        Ok(())
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        if let Some((_, path)) = self.open_at.take_if(|(at, _)| *at == self.frames) {
            self.open_model(&path)?;
        }
        if std::mem::take(&mut self.rebuild_pending) {
            self.rebuild()?;
        }
        let Some((window, _)) = &self.window else {
            return Ok(());
        };
        if self.lose_device_at == Some(self.frames) {
            self.lose_device_at = None;
            self.renderer.context().device.destroy();
        }
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let now = Instant::now();
        let interval = (now - self.last).as_secs_f32();
        self.last = now;
        // The first interval runs from start-up, not from a previous frame.
        if self.frames > 0 {
            self.rate.record(interval);
        }
        let dt = sim_step(interval);
        self.clock += dt;
        let mut settings = self.settings.clone();
        settings.width = w;
        settings.height = h;
        settings.raw = false;
        settings.time_s = self.clock;
        if let Some(path) = self.path.as_ref().filter(|_| self.flying) {
            self.path_t = (self.path_t + dt) % path.duration().max(1.0);
            self.camera = path.camera_at(self.path_t, self.camera.fov_y_deg);
        }
        let drawn = self.renderer.draw(&self.camera, &settings)?;
        let overlay = self
            .hud
            .then(|| Overlay::hud(&self.hud_text(&settings, &drawn.timings, drawn.world.as_ref())));
        let overlay = overlay.as_ref().map(|o| (o, [8, 8]));
        let frame = self
            .renderer
            .output(&settings)
            .context("the renderer wrote no output")?;
        let last = self.args.frames > 1 && self.frames + 1 >= self.args.frames;
        let window_out = self.window_out.as_ref().filter(|_| last);
        let Some((window, presentation)) = &mut self.window else {
            return Ok(());
        };
        match presentation {
            Presentation::Gpu {
                surface,
                config,
                presenter,
            } => {
                let ctx = self.renderer.context();
                if (config.width, config.height) != (w, h) {
                    (config.width, config.height) = (w, h);
                    surface.configure(&ctx.device, config);
                }
                let texture = match surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(t)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
                    wgpu::CurrentSurfaceTexture::Timeout
                    | wgpu::CurrentSurfaceTexture::Occluded => return Ok(()),
                    wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                        surface.configure(&ctx.device, config);
                        return Ok(());
                    }
                    wgpu::CurrentSurfaceTexture::Validation => {
                        bail!("window surface: validation error acquiring a frame")
                    }
                };
                let view = texture.texture.create_view(&Default::default());
                presenter.present(ctx, frame, overlay, &view, config.format)?;
                if let Some(path) = window_out {
                    let shown = himal::gpu::read_texture(ctx, &texture.texture, 0, 0)?;
                    himal::image_io::save(path, &shown)?;
                    println!("wrote {} (the window)", path.display());
                }
                ctx.queue.present(texture);
            }
            Presentation::Cpu(surface) => {
                let image = himal::gpu::read_texture(self.renderer.context(), frame, 0, 0)?;
                let mut rgba: Vec<[u8; 4]> = bytemuck_rgba(&image.bytes);
                if let Some((o, origin)) = overlay {
                    rgba = himal::present::reference::compose(&rgba, w, o, origin);
                }
                if let Some(path) = window_out {
                    let shown = himal::gpu::TextureData {
                        width: w,
                        height: h,
                        format: wgpu::TextureFormat::Rgba8UnormSrgb,
                        bytes: rgba.iter().flatten().copied().collect(),
                    };
                    himal::image_io::save(path, &shown)?;
                    println!("wrote {} (the window)", path.display());
                }
                surface
                    .resize(
                        NonZeroU32::new(w).context("zero width")?,
                        NonZeroU32::new(h).context("zero height")?,
                    )
                    .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
                let mut buffer = surface
                    .buffer_mut()
                    .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
                for (dst, p) in buffer.iter_mut().zip(&rgba) {
                    *dst = (u32::from(p[0]) << 16) | (u32::from(p[1]) << 8) | u32::from(p[2]);
                }
                buffer
                    .present()
                    .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
            }
        }
        window.set_title(&format!(
            "himal {:.1} fps | {:02}:{:02}",
            self.rate.fps(),
            settings.sun.time_hours as u32,
            (settings.sun.time_hours.fract() * 60.0) as u32,
        ));
        self.frames += 1;
        if self.screenshot || last {
            let image = himal::gpu::read_texture(self.renderer.context(), frame, 0, 0)?;
            himal::image_io::save(&self.args.out, &image)?;
            println!("wrote {} ({w}x{h})", self.args.out.display());
            self.screenshot = false;
        }
        if last {
            event_loop.exit();
        }
        Ok(())
    }

    /// The swapchain for `window` when the adapter can present to it.
    fn gpu_presentation(&self, window: &Arc<Window>) -> Result<Presentation> {
        let ctx = self.renderer.context();
        let surface = ctx
            .instance
            .create_surface(window.clone())
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        let caps = surface.get_capabilities(&ctx.adapter);
        // 8-bit formats only: the presenter writes display-encoded values.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Bgra8UnormSrgb
                        | wgpu::TextureFormat::Rgba8UnormSrgb
                        | wgpu::TextureFormat::Bgra8Unorm
                        | wgpu::TextureFormat::Rgba8Unorm
                )
            })
            .with_context(|| {
                format!(
                    "adapter {} cannot present to this window (formats {:?})",
                    ctx.info.name, caps.formats
                )
            })?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            // COPY_SRC where offered: --window-out reads the swapchain image back.
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | (caps.usages & wgpu::TextureUsages::COPY_SRC),
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: wgpu::CompositeAlphaMode::Auto,
            color_space: wgpu::SurfaceColorSpace::Auto,
            view_formats: vec![],
        };
        surface.configure(&ctx.device, &config);
        ctx.check("surface configure")?;
        println!("presenting through a wgpu swapchain ({format:?})");
        Ok(Presentation::Gpu {
            surface,
            config,
            presenter: Box::new(Presenter::new(ctx)?),
        })
    }

    fn cpu_presentation(window: &Arc<Window>) -> Result<Presentation> {
        let context = softbuffer::Context::new(window.clone())
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        let surface = softbuffer::Surface::new(&context, window.clone())
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        println!("presenting through the CPU (softbuffer)");
        Ok(Presentation::Cpu(surface))
    }

    fn open(&self, event_loop: &ActiveEventLoop) -> Result<(Arc<Window>, Presentation)> {
        let attributes = Window::default_attributes()
            .with_title("himal")
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.settings.width,
                self.settings.height,
            ));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| anyhow::anyhow!("cannot open a window: {e}"))?,
        );
        let presentation = self.presentation(&window)?;
        Ok((window, presentation))
    }

    /// The presentation `--present` asks for.
    fn presentation(&self, window: &Arc<Window>) -> Result<Presentation> {
        Ok(match self.present {
            PresentMode::Cpu => Self::cpu_presentation(window)?,
            PresentMode::Gpu => self.gpu_presentation(window)?,
            PresentMode::Auto => match self.gpu_presentation(window) {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("note: {e:#}; falling back to CPU presentation");
                    Self::cpu_presentation(window)?
                }
            },
        })
    }
}

/// The `--view` name of `v`.
fn view_name(v: ViewBuffer) -> &'static str {
    ViewBuffer::NAMES
        .iter()
        .find(|n| n.parse::<ViewBuffer>().ok() == Some(v))
        .copied()
        .unwrap_or("?")
}

/// RGBA8 texels from a tightly packed byte buffer.
fn bytemuck_rgba(bytes: &[u8]) -> Vec<[u8; 4]> {
    bytes
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect()
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let made = self.open(event_loop);
        match made {
            Ok(window) => {
                window.0.request_redraw();
                self.window = Some(window);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::DroppedFile(path) => {
                if let Err(e) = self.open_model(&path) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::RedrawRequested => {
                self.step_camera(sim_step((Instant::now() - self.last).as_secs_f32()));
                if let Err(e) = self.redraw(event_loop).or_else(|e| self.recover(e)) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Right => self.held.looking = down,
                    MouseButton::Left => self.held.orbiting = down,
                    MouseButton::Middle => self.held.panning = down,
                    _ => {}
                }
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(o) = &mut self.orbit {
                    o.zoom(steps);
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                let PhysicalKey::Code(code) = event.physical_key else {
                    return;
                };
                let down = event.state == ElementState::Pressed;
                let v = if down { 1.0 } else { 0.0 };
                match code {
                    KeyCode::Escape if down => event_loop.exit(),
                    KeyCode::KeyW => self.held.forward = v,
                    KeyCode::KeyS => self.held.forward = -v,
                    KeyCode::KeyD => self.held.right = v,
                    KeyCode::KeyA => self.held.right = -v,
                    KeyCode::KeyE => self.held.up = v,
                    KeyCode::KeyQ => self.held.up = -v,
                    KeyCode::ShiftLeft | KeyCode::ShiftRight => self.held.fast = down,
                    _ if down && !event.repeat => self.toggle(code),
                    _ => {}
                }
            }
            _ => {}
        }
    }

    fn device_event(&mut self, _: &ActiveEventLoop, _: winit::event::DeviceId, event: DeviceEvent) {
        let DeviceEvent::MouseMotion { delta } = event else {
            return;
        };
        let (dx, dy) = (delta.0 as f32, delta.1 as f32);
        let (fov, height) = (self.camera.fov_y_deg, self.settings.height);
        match &mut self.orbit {
            Some(o) if self.held.orbiting => o.rotate(dx, dy),
            Some(o) if self.held.panning => o.pan(dx, dy, fov, height),
            None if self.held.looking => self.look(dx, dy),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some((window, _)) = &self.window {
            window.request_redraw();
        }
    }
}

/// The X11 libraries winit opens at run time, with their Debian/Ubuntu
/// packages: without them winit panics or reports a display failure.
const X11_LIBRARIES: [(&str, &str); 7] = [
    ("libX11.so.6", "libx11-6"),
    ("libX11-xcb.so.1", "libx11-xcb1"),
    ("libxkbcommon.so.0", "libxkbcommon0"),
    ("libxkbcommon-x11.so.0", "libxkbcommon-x11-0"),
    ("libXi.so.6", "libxi6"),
    ("libXcursor.so.1", "libxcursor1"),
    ("libXrandr.so.2", "libxrandr2"),
];

/// Fails naming every missing library (and its package) that `opens`
/// cannot load.
fn check_x11_libraries(opens: impl Fn(&str) -> bool) -> Result<()> {
    let missing: Vec<_> = X11_LIBRARIES
        .iter()
        .filter(|(lib, _)| !opens(lib))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let libs: Vec<&str> = missing.iter().map(|(l, _)| *l).collect();
    let packages: Vec<&str> = missing.iter().map(|(_, p)| *p).collect();
    bail!(
        "himal view cannot load the X11 libraries {} (Debian/Ubuntu packages: {}; `./run view` installs them)",
        libs.join(", "),
        packages.join(" ")
    )
}

/// Opens the window; `--frames N` (N > 1) renders N frames, writes the last
/// to `--out` and exits (automated runs, e.g. under Xvfb).
pub fn run(view: &ViewArgs) -> Result<()> {
    let args = &view.render;
    let (scene, camera, mut settings) = crate::render::setup(args)?;
    let mut renderer = args.open_renderer(args.gpu.context()?, &scene)?;
    crate::render::world_haze(&renderer, &mut settings);
    args.post.configure(&mut renderer, &args.gpu)?;
    let paths = renderer
        .world()
        .map(|w| w.paths.clone())
        .unwrap_or_default();
    let path = match &view.path {
        Some(name) => Some(paths.iter().find(|p| &p.name == name).cloned().with_context(|| {
            let names: Vec<&str> = paths.iter().map(|p| p.name.as_str()).collect();
            if names.is_empty() {
                format!("--path {name}: the scene has no flight paths (a world scene has: --scene world)")
            } else {
                format!("--path {name}: no such path (this world has: {})", names.join(", "))
            }
        })?),
        None => paths.first().cloned(),
    };
    check_x11_libraries(|name| {
        let c = std::ffi::CString::new(name).expect("no NUL in a library name");
        // SAFETY: dlopen with a valid C string; the handle is closed at once.
        unsafe {
            let h = libc::dlopen(c.as_ptr(), libc::RTLD_LAZY | libc::RTLD_LOCAL);
            if !h.is_null() {
                libc::dlclose(h);
            }
            !h.is_null()
        }
    })?;
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow::anyhow!("himal view needs a display (X11; e.g. xvfb-run for automated runs): {e}")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    println!("{HELP}");
    let lose_device_at =
        match std::env::var("HIMAL_VIEW_LOSE_DEVICE_AT") {
            Ok(v) => Some(v.parse::<u32>().with_context(|| {
                format!("HIMAL_VIEW_LOSE_DEVICE_AT={v}: expected a frame number")
            })?),
            Err(_) => None,
        };
    // A model is orbited, a world or scene flown.
    let orbit = (args.gltf.is_some() || crate::render::is_gltf(&args.scene))
        .then(|| Orbit::around(&camera, &scene.bounds));
    let open_at = match std::env::var("HIMAL_VIEW_OPEN_AT") {
        Ok(v) => {
            let (frame, file) = v
                .split_once(':')
                .with_context(|| format!("HIMAL_VIEW_OPEN_AT={v}: expected FRAME:FILE"))?;
            let frame = frame
                .parse::<u32>()
                .with_context(|| format!("HIMAL_VIEW_OPEN_AT={v}: expected a frame number"))?;
            Some((frame, std::path::PathBuf::from(file)))
        }
        Err(_) => None,
    };
    let mut viewer = Viewer {
        args: args.clone(),
        scene,
        renderer,
        recoveries: 0,
        lose_device_at,
        open_at,
        opened: false,
        rebuild_pending: false,
        camera,
        settings,
        present: view.present,
        window_out: view.window_out.clone(),
        window: None,
        hud: !view.no_hud,
        held: Held::default(),
        last: Instant::now(),
        frames: 0,
        clock: 0.0,
        rate: FrameRate::default(),
        screenshot: false,
        error: None,
        flying: view.path.is_some(),
        orbit,
        path,
        path_t: 0.0,
    };
    event_loop
        .run_app(&mut viewer)
        .map_err(|e| anyhow::anyhow!("window event loop: {e}"))?;
    crate::save_cache(viewer.renderer.context());
    match viewer.error.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_x11_libraries_are_named_with_their_packages() {
        assert!(check_x11_libraries(|_| true).is_ok());
        let e = check_x11_libraries(|l| !l.starts_with("libxkbcommon-x11") && l != "libXi.so.6")
            .unwrap_err()
            .to_string();
        assert!(e.contains("libxkbcommon-x11.so.0, libXi.so.6"), "{e}");
        assert!(e.contains("libxkbcommon-x11-0 libxi6"), "{e}");
        assert!(!e.contains("display"), "{e}");
    }

    /// The HUD capped the frame time at 0.25 s (never below 4 fps): a
    /// 2-second frame on a software adapter read 4 fps.
    #[test]
    fn the_hud_rate_is_the_real_one_and_only_the_step_is_clamped() {
        let mut rate = FrameRate::default();
        assert_eq!(rate.fps(), 0.0);
        rate.record(2.0);
        assert_eq!(rate.fps(), 0.5);
        assert_eq!(rate.frame_ms(), 2000.0);
        assert_eq!(sim_step(2.0), MAX_STEP_S);
        assert_eq!(sim_step(0.016), 0.016);
        // Averaged intervals: 10 ms frames then one 1 s stall.
        let mut rate = FrameRate::default();
        for _ in 0..50 {
            rate.record(0.010);
        }
        rate.record(1.0);
        assert!((rate.frame_ms() - 109.0).abs() < 0.5, "{}", rate.frame_ms());
    }
}
