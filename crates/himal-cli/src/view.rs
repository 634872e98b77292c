//! `himal view`: an interactive window on a scene (X11). The frame is
//! rendered by the same `Renderer` as `himal render` and presented through
//! the CPU (softbuffer): simple and portable, at the cost of a read-back per
//! frame. Keys are listed in [`HELP`]; the title shows the frame rate and the
//! costliest passes.

use std::num::NonZeroU32;
use std::rc::Rc;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::{Quat, Vec3};
use himal::passes::aa::AaMode;
use himal::passes::ao::AoMode;
use himal::scene::Camera;
use himal::{FrameSettings, Renderer, ViewBuffer};
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use crate::render::RenderArgs;

pub const HELP: &str = "WASD move, Q/E down/up, Shift fast, right mouse drag look, \
T/G time +-30 min, V next view, 1 AO, 2 bloom, 3 shadows, 4 AA mode, 5 env specular, \
P screenshot, Esc quit";

/// The window's CPU-presented surface.
type WindowSurface = softbuffer::Surface<Rc<Window>, Rc<Window>>;

/// Movement keys held down.
#[derive(Default)]
struct Held {
    forward: f32,
    right: f32,
    up: f32,
    fast: bool,
    looking: bool,
}

struct Viewer {
    args: RenderArgs,
    renderer: Renderer,
    camera: Camera,
    settings: FrameSettings,
    window: Option<(Rc<Window>, WindowSurface)>,
    held: Held,
    last: Instant,
    frames: u32,
    clock: f32,
    fps: f32,
    screenshot: bool,
    error: Option<anyhow::Error>,
}

impl Viewer {
    fn toggle(&mut self, key: KeyCode) {
        let s = &mut self.settings;
        match key {
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
            KeyCode::KeyP | KeyCode::F12 => self.screenshot = true,
            _ => {}
        }
    }

    fn step_camera(&mut self, dt: f32) {
        let speed = if self.held.fast { 20.0 } else { 4.0 } * dt;
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

    /// Renders a frame, presents it, and updates the title.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let Some((window, surface)) = &mut self.window else {
            return Ok(());
        };
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f32().min(0.25);
        self.last = now;
        self.fps = 0.9 * self.fps + 0.1 / dt.max(1e-3);
        self.clock += dt;
        let mut settings = self.settings.clone();
        settings.width = w;
        settings.height = h;
        settings.raw = false;
        settings.time_s = self.clock;
        let frame = self.renderer.render(&self.camera, &settings)?;
        let rgba = frame.image.to_rgba_f32()?;
        surface
            .resize(
                NonZeroU32::new(w).context("zero width")?,
                NonZeroU32::new(h).context("zero height")?,
            )
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        let mut buffer = surface
            .buffer_mut()
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        let byte = |c: f32| (c.clamp(0.0, 1.0) * 255.0 + 0.5) as u32;
        for (dst, p) in buffer.iter_mut().zip(&rgba) {
            *dst = (byte(p[0]) << 16) | (byte(p[1]) << 8) | byte(p[2]);
        }
        buffer
            .present()
            .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
        let mut passes = frame.timings.clone();
        passes.sort_by(|a, b| b.gpu_ms.total_cmp(&a.gpu_ms));
        let top: Vec<String> = passes
            .iter()
            .take(4)
            .map(|t| format!("{} {:.1}", t.id, t.gpu_ms))
            .collect();
        let total: f64 = frame.timings.iter().map(|t| t.gpu_ms).sum();
        window.set_title(&format!(
            "himal {:.1} fps | {:02}:{:02} | GPU {total:.1} ms: {}",
            self.fps,
            settings.sun.time_hours as u32,
            (settings.sun.time_hours.fract() * 60.0) as u32,
            top.join(", ")
        ));
        self.frames += 1;
        let last = self.args.frames > 1 && self.frames >= self.args.frames;
        if self.screenshot || last {
            himal::image_io::save(&self.args.out, &frame.image)?;
            println!("wrote {} ({w}x{h})", self.args.out.display());
            self.screenshot = false;
        }
        if last {
            event_loop.exit();
        }
        Ok(())
    }
}

impl ApplicationHandler for Viewer {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title("himal")
            .with_inner_size(winit::dpi::PhysicalSize::new(
                self.settings.width,
                self.settings.height,
            ));
        let made = event_loop
            .create_window(attributes)
            .map_err(|e| anyhow::anyhow!("cannot open a window: {e}"))
            .and_then(|w| {
                let w = Rc::new(w);
                let context = softbuffer::Context::new(w.clone())
                    .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
                let surface = softbuffer::Surface::new(&context, w.clone())
                    .map_err(|e| anyhow::anyhow!("window surface: {e}"))?;
                Ok((w, surface))
            });
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
            WindowEvent::RedrawRequested => {
                let dt = (Instant::now() - self.last).as_secs_f32().min(0.25);
                self.step_camera(dt);
                if let Err(e) = self.redraw(event_loop) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Right,
                ..
            } => {
                self.held.looking = state == ElementState::Pressed;
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
        if let DeviceEvent::MouseMotion { delta } = event
            && self.held.looking
        {
            self.look(delta.0 as f32, delta.1 as f32);
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
pub fn run(args: &RenderArgs) -> Result<()> {
    let (scene, camera, settings) = crate::render::setup(args)?;
    let mut renderer = Renderer::new(args.gpu.context()?, &scene)?;
    renderer.set_sky_table_cache(args.gpu.cache_dir());
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow::anyhow!("himal view needs a display (X11; e.g. xvfb-run for automated runs): {e}")
    })?;
    event_loop.set_control_flow(ControlFlow::Poll);
    println!("{HELP}");
    let mut viewer = Viewer {
        args: args.clone(),
        renderer,
        camera,
        settings,
        window: None,
        held: Held::default(),
        last: Instant::now(),
        frames: 0,
        clock: 0.0,
        fps: 0.0,
        screenshot: false,
        error: None,
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
