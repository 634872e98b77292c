//! `himal view`: an interactive window on a scene (X11). The frame is
//! rendered by the same `Renderer` as `himal render` and presented through a
//! wgpu swapchain (`himal::present`: no read-back), or through the CPU
//! (softbuffer) where the adapter cannot present to the window. A HUD with
//! the state and per-pass GPU times is blended over the frame; Tab opens a
//! settings panel (egui, `panel.rs`) in its place. Keys are listed in
//! [`HELP`].

use std::num::NonZeroU32;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use himal::present::{Overlay, Presenter};
use himal::scene::Camera;
use himal::{FrameSettings, Renderer, ViewBuffer};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::orbit::Orbit;
use crate::render::RenderArgs;

mod controls;
mod hud;
mod panel;
mod x11;

use controls::{Held, Scripted};
use hud::{FrameRate, sim_step};
use panel::Panel;
use x11::check_x11_libraries;

pub const HELP: &str = "Orbit (models): left drag turn, middle drag pan, wheel zoom, F frame, O fly; \
fly: WASD move, Q/E down/up, Shift fast, right mouse drag look, O orbit; \
T/G time +-30 min, V next view, 1 AO, 2 bloom, 3 shadows, 4 AA mode, 5 env specular, 6 sky occlusion, \
7 TAA on AO and motion, 8 sky model, 9 tone mapper, -/= exposure, B studio/sky light, \
Space play/pause, [ ] step 1/30 s, N next animation, F fly the world's path (worlds), H HUD, \
Tab settings panel (in place of the HUD; the camera ignores input the panel takes), \
drop a .gltf/.glb on the window to open it, P screenshot, Esc quit";

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
    /// Test hook ($HIMAL_VIEW_KEYS=FRAME:KEY,FRAME:click:X:Y,...): keys
    /// pressed before those frames, through the same path as the
    /// keyboard's, and clicks, as winit's window events.
    script: Vec<(u32, Scripted)>,
    /// The animation clock runs (Space pauses; [ and ] step it).
    playing: bool,
    /// The scene's glTF animations and the one playing (`None`: rest pose).
    animations: Vec<String>,
    clip: Option<usize>,
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
    /// The settings panel (on the window's device), and whether Tab showed it.
    panel: Option<Panel>,
    panel_shown: bool,
    /// The last frame's GPU pass times (the panel's table).
    timings: Vec<himal::graph::PassTiming>,
    /// The last problem the user should see (a dropped file that did not
    /// open), in the HUD and the panel.
    notice: Option<String>,
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
        self.args
            .post
            .configure_live(&mut renderer, &self.args.gpu, &self.scene)?;
        self.renderer = renderer;
        if let Some(window) = window {
            let presentation = self.presentation(&window)?;
            // egui's textures lived on the old device: a new panel uploads them again.
            self.panel = Some(Panel::new(self.renderer.context(), &window));
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
                let message = format!("cannot open {}: {e}", path.display());
                eprintln!("error: {message} (keeping the current scene)");
                self.notice = Some(message);
                return Ok(());
            }
        };
        self.notice = None;
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
        self.animations = scene.animations();
        self.clip = (!self.animations.is_empty()).then_some(0);
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
        let frame = self.frames;
        let inputs: Vec<Scripted> = (self.script.iter())
            .filter(|(at, _)| *at == frame)
            .map(|(_, k)| *k)
            .collect();
        if !inputs.is_empty() {
            for input in inputs {
                self.scripted(event_loop, input);
            }
            // This frame's camera follows the keys, as after a real press.
            self.step_camera(0.0);
        }
        if std::mem::take(&mut self.rebuild_pending) {
            self.rebuild()?;
        }
        // After the rebuild: the panel it makes holds this frame's UI.
        self.run_panel();
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
        if self.playing {
            self.clock += dt;
        }
        let mut settings = self.settings.clone();
        settings.width = w;
        settings.height = h;
        settings.raw = false;
        settings.time_s = self.clock;
        if let Some(path) = self.path.as_ref().filter(|_| self.flying) {
            self.path_t = (self.path_t + dt) % path.duration().max(1.0);
            self.camera = path.camera_at(self.path_t, self.camera.fov_y_deg);
        }
        // A debug view whose inputs are off (AO views without AO, L5's
        // without probes) is reported and the final image shown instead.
        let drawn = match self.renderer.draw(&self.camera, &settings) {
            Ok(d) => d,
            Err(e) if settings.view != ViewBuffer::Final => {
                self.notice = Some(format!("--view {}: {e}", hud::view_name(settings.view)));
                self.settings.view = ViewBuffer::Final;
                settings.view = ViewBuffer::Final;
                self.renderer.draw(&self.camera, &settings)?
            }
            Err(e) => return Err(e.into()),
        };
        // The panel holds the HUD's numbers: one of the two at a time.
        let overlay = (self.hud && !self.panel_shown)
            .then(|| Overlay::hud(&self.hud_text(&settings, &drawn.timings, drawn.world.as_ref())));
        let overlay = overlay.as_ref().map(|o| (o, [8, 8]));
        self.timings = drawn.timings;
        let frame = self
            .renderer
            .output(&settings)
            .context("the renderer wrote no output")?;
        // What the window shows: the frame, with the panel drawn into a copy.
        let shown = match (&mut self.panel, self.panel_shown) {
            (Some(panel), true) => panel.paint(self.renderer.context(), frame)?,
            _ => None,
        }
        .unwrap_or(frame);
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
                presenter.present(ctx, shown, overlay, &view, config.format)?;
                if let Some(path) = window_out {
                    let shown = himal::gpu::read_texture(ctx, &texture.texture, 0, 0)?;
                    himal::image_io::save(path, &shown)?;
                    println!("wrote {} (the window)", path.display());
                }
                ctx.queue.present(texture);
            }
            Presentation::Cpu(surface) => {
                let image = himal::gpu::read_texture(self.renderer.context(), shown, 0, 0)?;
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

    /// One scripted input: a key through the keys' path, a click as the
    /// window events winit reports for one.
    fn scripted(&mut self, event_loop: &ActiveEventLoop, input: Scripted) {
        let Some(id) = self.window.as_ref().map(|(w, _)| w.id()) else {
            return;
        };
        let device_id = winit::event::DeviceId::dummy();
        let button = |state| WindowEvent::MouseInput {
            device_id,
            state,
            button: MouseButton::Left,
        };
        match input {
            Scripted::Key(key) => self.toggle(key),
            Scripted::Press(x, y) | Scripted::Move(x, y) => {
                let position = winit::dpi::PhysicalPosition::new(x, y);
                let moved = WindowEvent::CursorMoved {
                    device_id,
                    position,
                };
                self.window_event(event_loop, id, moved);
                if matches!(input, Scripted::Press(..)) {
                    self.window_event(event_loop, id, button(ElementState::Pressed));
                }
            }
            Scripted::Release => self.window_event(event_loop, id, button(ElementState::Released)),
        }
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
                self.panel = Some(Panel::new(self.renderer.context(), &window.0));
                self.window = Some(window);
            }
            Err(e) => {
                self.error = Some(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        // The panel sees the window's input first; what it takes the camera does not.
        let taken = match (&mut self.panel, &self.window) {
            (Some(panel), Some((window, _))) if self.panel_shown => {
                let consumed = panel.on_window_event(window, &event);
                match &event {
                    WindowEvent::MouseInput { .. } | WindowEvent::MouseWheel { .. } => {
                        consumed || panel.wants_pointer()
                    }
                    WindowEvent::KeyboardInput { .. } => panel.wants_keyboard(),
                    _ => false,
                }
            }
            _ => false,
        };
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
                // A release always lets go, wherever the press went.
                if down && taken {
                    return;
                }
                match button {
                    MouseButton::Right => self.held.looking = down,
                    MouseButton::Left => self.held.orbiting = down,
                    MouseButton::Middle => self.held.panning = down,
                    _ => {}
                }
            }
            WindowEvent::MouseWheel { .. } if taken => {}
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
                // Tab is the panel's own key; other presses go to a focused widget.
                if down && taken && code != KeyCode::Tab {
                    return;
                }
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

/// Opens the window; `--frames N` (N > 1) renders N frames, writes the last
/// to `--out` and exits (automated runs, e.g. under Xvfb).
pub fn run(view: &ViewArgs) -> Result<()> {
    let args = &view.render;
    let (scene, camera, mut settings) = crate::render::setup(args)?;
    let mut renderer = args.open_renderer(args.gpu.context()?, &scene)?;
    crate::render::world_haze(&renderer, &mut settings);
    args.post.configure_live(&mut renderer, &args.gpu, &scene)?;
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
    let orbit = (args.gltf.is_some() || crate::scene_source::is_gltf(&args.scene))
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
    let script = match std::env::var("HIMAL_VIEW_KEYS") {
        Ok(v) => controls::parse_script(&v)?,
        Err(_) => Vec::new(),
    };
    let animations = scene.animations();
    let clip = match args.animation.as_deref() {
        Some("none") => None,
        Some(name) => animations.iter().position(|a| a == name),
        None => (!animations.is_empty()).then_some(0),
    };
    let mut viewer = Viewer {
        script,
        playing: true,
        animations,
        clip,
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
        panel: None,
        panel_shown: false,
        timings: Vec::new(),
        notice: None,
        held: Held::default(),
        last: Instant::now(),
        frames: 0,
        clock: args.at,
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
