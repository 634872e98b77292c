//! The viewer's settings panel (Tab): egui, fed by the window's winit
//! events, drawn by egui-wgpu into a copy of the frame's final LDR image
//! before that copy is presented (swapchain) or read back (softbuffer), so
//! both paths show the same pixels. `--out` stays the clean frame.

use anyhow::Result;
use egui::{Color32, ComboBox, Slider};
use himal::ViewBuffer;
use himal::gpu::GpuContext;
use himal::passes::aa::AaMode;
use himal::passes::ao::AoMode;
use himal::passes::post::Tonemapper;
use himal::passes::sky::SkyModel;
use himal::settings::Occlusion;
use winit::event::WindowEvent;
use winit::keyboard::KeyCode;
use winit::window::Window;

use super::Viewer;
use super::hud::{timing_groups, view_name};

/// The panel's width (points), on the window's right edge.
pub(super) const WIDTH: f32 = 210.0;

/// The AA modes key 4 steps through, in its order.
const AA_MODES: [&str; 6] = ["none", "smaa", "smaa-t2x", "tfq", "taa", "hraa"];

/// egui's state and its painter on the renderer's device (rebuilt with the
/// device: egui's textures live there).
pub(super) struct Panel {
    ctx: egui::Context,
    input: egui_winit::State,
    painter: egui_wgpu::Renderer,
    /// The copy of the frame the panel is drawn into.
    target: Option<wgpu::Texture>,
    /// The last UI pass, tessellated (and its pixels per point), until painted.
    jobs: Option<(Vec<egui::ClippedPrimitive>, f32)>,
    /// Texture changes not yet uploaded (kept across frames that were not
    /// painted: the font atlas arrives once).
    textures: egui::TexturesDelta,
}

impl Panel {
    pub(super) fn new(gpu: &GpuContext, window: &Window) -> Self {
        let ctx = egui::Context::default();
        let max_side = gpu.device.limits().max_texture_dimension_2d as usize;
        let input = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_side),
        );
        // The frame's non-sRGB view: egui blends in display space, as it is designed to.
        let painter = egui_wgpu::Renderer::new(
            &gpu.device,
            wgpu::TextureFormat::Rgba8Unorm,
            egui_wgpu::RendererOptions::PREDICTABLE,
        );
        Self {
            ctx,
            input,
            painter,
            target: None,
            jobs: None,
            textures: Default::default(),
        }
    }

    /// Hands `event` to egui; true when egui takes it (the pointer is over
    /// the panel, a widget has the keyboard).
    pub(super) fn on_window_event(&mut self, window: &Window, event: &WindowEvent) -> bool {
        self.input.on_window_event(window, event).consumed
    }

    /// egui is using the pointer or it hovers the panel.
    pub(super) fn wants_pointer(&self) -> bool {
        self.ctx.egui_wants_pointer_input()
    }

    /// A panel widget has the keyboard focus.
    pub(super) fn wants_keyboard(&self) -> bool {
        self.ctx.egui_wants_keyboard_input()
    }

    /// Copies `frame` (the renderer's `Rgba8UnormSrgb` output) and draws the
    /// last UI pass over the copy; `None` when no pass is waiting.
    pub(super) fn paint(
        &mut self,
        gpu: &GpuContext,
        frame: &wgpu::Texture,
    ) -> Result<Option<&wgpu::Texture>> {
        let Some((jobs, pixels_per_point)) = self.jobs.take() else {
            return Ok(None);
        };
        let size = frame.size();
        let linear = frame.format().remove_srgb_suffix();
        let target = match self.target.take() {
            Some(t) if t.size() == size && t.format() == frame.format() => t,
            _ => gpu.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("view.panel"),
                size,
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: frame.format(),
                // COPY_SRC: the CPU path and --window-out read it back;
                // TEXTURE_BINDING: the presenter samples it as the frame.
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::COPY_DST
                    | wgpu::TextureUsages::COPY_SRC
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[linear],
            }),
        };
        let target = self.target.insert(target);
        let textures = std::mem::take(&mut self.textures);
        for (id, deltas) in &textures.set {
            for delta in deltas {
                self.painter
                    .update_texture(&gpu.device, &gpu.queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [size.width, size.height],
            pixels_per_point,
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view.panel"),
            });
        encoder.copy_texture_to_texture(frame.as_image_copy(), target.as_image_copy(), size);
        let mut commands =
            self.painter
                .update_buffers(&gpu.device, &gpu.queue, &mut encoder, &jobs, &screen);
        let view = target.create_view(&wgpu::TextureViewDescriptor {
            format: Some(linear),
            ..Default::default()
        });
        {
            let mut pass = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("view.panel"),
                    color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                        view: &view,
                        depth_slice: None,
                        resolve_target: None,
                        ops: wgpu::Operations {
                            load: wgpu::LoadOp::Load,
                            store: wgpu::StoreOp::Store,
                        },
                    })],
                    depth_stencil_attachment: None,
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                })
                .forget_lifetime();
            self.painter.render(&mut pass, &jobs, &screen);
        }
        commands.push(encoder.finish());
        gpu.queue.submit(commands);
        for id in &textures.free {
            self.painter.free_texture(id);
        }
        gpu.check("settings panel")?;
        Ok(Some(target))
    }
}

impl Viewer {
    /// Runs the panel's UI for this frame when it is shown: its controls
    /// change the settings before the frame is drawn, as keys do.
    pub(super) fn run_panel(&mut self) {
        if !self.panel_shown {
            return;
        }
        let (Some(panel), Some((window, _))) = (&mut self.panel, &self.window) else {
            return;
        };
        let window = window.clone();
        let mut raw = panel.input.take_egui_input(&window);
        if !self.script.is_empty() {
            // Scripted runs: a 4 fps UI clock whatever the adapter's speed, so
            // that a press and release a frame apart are a click (egui: under
            // 0.8 s) and clicks two frames apart no double click (0.3 s).
            raw.time = Some(f64::from(self.frames) / 4.0);
        }
        let ctx = panel.ctx.clone();
        let out = ctx.run_ui(raw, |ui| {
            egui::Panel::right("himal.settings")
                .resizable(false)
                .exact_size(WIDTH)
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| self.panel_ui(ui));
                });
        });
        let Some(panel) = &mut self.panel else {
            return;
        };
        panel
            .input
            .handle_platform_output(&window, out.platform_output);
        panel.textures.append(out.textures_delta);
        let jobs = ctx.tessellate(out.shapes, out.pixels_per_point);
        panel.jobs = Some((jobs, out.pixels_per_point));
    }

    /// The panel's controls. Toggles go through the keys' path
    /// ([`Viewer::toggle`]) so that a click and its key do the same.
    fn panel_ui(&mut self, ui: &mut egui::Ui) {
        ui.strong("himal settings  [Tab]");
        ui.label(format!(
            "{:.1} fps, {:.1} ms a frame",
            self.rate.fps(),
            self.rate.frame_ms()
        ));
        if let Some(notice) = &self.notice {
            ui.colored_label(Color32::from_rgb(255, 110, 100), notice);
        }
        ui.separator();
        let s = &self.settings;
        let toggles = [
            (s.ao.mode != AoMode::Off, "AO  [1]", KeyCode::Digit1),
            (s.bloom.enabled, "bloom  [2]", KeyCode::Digit2),
            (s.shadow_resolution > 0, "shadows  [3]", KeyCode::Digit3),
            (s.environment_specular, "env specular  [5]", KeyCode::Digit5),
            (s.sky_occlusion, "sky occlusion  [6]", KeyCode::Digit6),
            (s.aa_buffers.any(), "TAA on AO+motion  [7]", KeyCode::Digit7),
        ];
        for (mut on, label, key) in toggles {
            if ui.checkbox(&mut on, label).changed() {
                self.toggle(key);
            }
        }
        let mut aa = self.settings.aa;
        ComboBox::from_label("AA  [4]")
            .selected_text(aa.name())
            .show_ui(ui, |ui| {
                for m in AA_MODES.iter().filter_map(|m| AaMode::parse(m).ok()) {
                    ui.selectable_value(&mut aa, m, m.name());
                }
            });
        self.settings.aa = aa;
        let mut tone = self.settings.tonemapper;
        ComboBox::from_label("tone  [9]")
            .selected_text(tone.name())
            .show_ui(ui, |ui| {
                for t in Tonemapper::ALL {
                    ui.selectable_value(&mut tone, t, t.name());
                }
            });
        if tone != self.settings.tonemapper {
            self.set_tonemapper(tone);
        }
        // Edits only: an --exposure outside the range stays as given.
        let ev = Slider::new(&mut self.settings.exposure_ev, -10.0..=10.0)
            .clamping(egui::SliderClamping::Edits)
            .text("EV  [-/=]");
        ui.add(ev);
        let mut view = self.settings.view;
        ComboBox::from_label("view  [V]")
            .selected_text(view_name(view))
            .show_ui(ui, |ui| {
                for name in ViewBuffer::NAMES {
                    if let Ok(v) = name.parse::<ViewBuffer>() {
                        ui.selectable_value(&mut view, v, name);
                    }
                }
            });
        self.settings.view = view;
        // No key of their own (and below the controls the click test
        // finds by position): E3, a permutation, and V6's Hi-Z, whose
        // pyramids the next frame makes or frees.
        ui.checkbox(&mut self.settings.specular_aa, "specular AA (Toksvig)");
        let mut hiz = self.settings.occlusion == Occlusion::Hiz;
        if ui.checkbox(&mut hiz, "Hi-Z occlusion").changed() {
            self.settings.occlusion = if hiz { Occlusion::Hiz } else { Occlusion::Off };
        }
        // O4: the directional term needs AO on; off returns to BF3's HBAO+STF.
        let ao = &mut self.settings.ao;
        let mut ssdo = ao.mode == AoMode::Ssdo;
        let enabled = ao.mode != AoMode::Off;
        if ui
            .add_enabled(
                enabled,
                egui::Checkbox::new(&mut ssdo, "directional AO (SSDO)"),
            )
            .changed()
        {
            ao.mode = if ssdo { AoMode::Ssdo } else { AoMode::HbaoStf };
        }
        ui.checkbox(&mut ao.reflection_occlusion, "reflection occlusion");
        ui.checkbox(&mut self.settings.ao.bleed, "AO colour bleeding (O5)");
        ui.checkbox(&mut self.settings.ambient_lights, "ambient lights");
        ui.checkbox(&mut self.settings.visibility_remap, "visibility remap (R4)");
        ui.checkbox(&mut self.settings.ao.large_scale, "large-scale AO (O6)");
        ui.checkbox(&mut self.settings.vegetation, "vegetation (V1)");
        ui.checkbox(&mut self.settings.impostors, "tree impostors (V3)");
        ui.checkbox(&mut self.settings.tree_ao, "tree AO volumes (V4)");
        ui.checkbox(&mut self.settings.leaf_shading, "leaf shading (V5)");
        // L5's probes are baked when the viewer starts with --indirect on.
        let probes = self.renderer.probe_cells().is_some();
        ui.add_enabled(
            probes,
            egui::Checkbox::new(&mut self.settings.indirect, "indirect light (L5)"),
        )
        .on_disabled_hover_text("start with --indirect on: the probes are baked (or read) then");
        ui.checkbox(&mut self.settings.deform_motion, "skinned motion vectors");
        ui.checkbox(
            &mut self.settings.shadows.alpha_test,
            "alpha-tested glTF shadows",
        );
        ui.separator();
        self.environment_ui(ui);
        if !self.animations.is_empty() {
            ui.separator();
            self.animation_ui(ui);
        }
        ui.separator();
        self.timings_ui(ui);
    }

    /// Light, sky model and time of day.
    fn environment_ui(&mut self, ui: &mut egui::Ui) {
        let image = self.scene.environment.as_ref().map(|e| {
            if e.path.as_os_str() == himal::scene::STUDIO {
                "studio".to_string()
            } else {
                e.path.file_name().map_or_else(
                    || e.path.display().to_string(),
                    |n| n.to_string_lossy().into_owned(),
                )
            }
        });
        let lit = image.is_some();
        let mut want = lit;
        // A world is lit by its sky only (B does nothing there).
        ui.add_enabled_ui(self.renderer.world().is_none(), |ui| {
            ui.horizontal(|ui| {
                ui.label("light  [B]");
                ui.radio_value(&mut want, false, "sky");
                ui.radio_value(&mut want, true, image.as_deref().unwrap_or("studio"));
            });
        });
        if want != lit {
            self.toggle(KeyCode::KeyB);
        }
        let mut sky = self.settings.sky_model;
        ComboBox::from_label("sky model  [8]")
            .selected_text(format!("{sky:?}"))
            .show_ui(ui, |ui| {
                for m in [SkyModel::Bruneton, SkyModel::Preetham] {
                    ui.selectable_value(&mut sky, m, format!("{m:?}"));
                }
            });
        self.settings.sky_model = sky;
        ui.add(
            Slider::new(&mut self.settings.sun.time_hours, 0.0..=24.0)
                .text("time (h)  [T/G]")
                .fixed_decimals(1),
        );
    }

    /// Clip, play/pause and a scrubbing time slider.
    fn animation_ui(&mut self, ui: &mut egui::Ui) {
        let mut clip = self.clip;
        let name = |c: Option<usize>| c.map_or("rest pose", |c| self.animations[c].as_str());
        ComboBox::from_label("animation  [N]")
            .selected_text(name(clip))
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut clip, None, "rest pose");
                for (i, a) in self.animations.iter().enumerate() {
                    ui.selectable_value(&mut clip, Some(i), a);
                }
            });
        if clip != self.clip {
            self.set_clip(clip);
        }
        let label = if self.playing {
            "pause  [Space]"
        } else {
            "play  [Space]"
        };
        if ui.button(label).clicked() {
            self.toggle(KeyCode::Space);
        }
        let duration = self.clip_duration();
        let mut t = if duration > 0.0 {
            self.clock.rem_euclid(duration)
        } else {
            0.0
        };
        let slider = Slider::new(&mut t, 0.0..=duration.max(1e-3))
            .text("s  [ [ ] ]")
            .fixed_decimals(2);
        // Scrubbing pauses the clock, as [ and ] do.
        if ui.add_enabled(duration > 0.0, slider).changed() {
            self.clock = t;
            self.playing = false;
        }
    }

    /// The playing clip's length (s; 0 for the rest pose).
    fn clip_duration(&self) -> f32 {
        let Some(name) = self.clip.map(|c| &self.animations[c]) else {
            return 0.0;
        };
        (self.scene.objects.iter())
            .filter_map(|o| o.motion.as_ref()?.animated.as_ref())
            .flat_map(|a| &a.rig.clips)
            .filter(|c| &c.name == name)
            .map(|c| c.duration)
            .fold(0.0, f32::max)
    }

    /// The HUD's per-pass GPU times, as a table.
    fn timings_ui(&self, ui: &mut egui::Ui) {
        let groups = timing_groups(&self.timings);
        let total: f64 = groups.iter().map(|(_, ms)| ms).sum();
        ui.strong(format!("GPU {total:.2} ms"));
        if groups.is_empty() {
            ui.label("no GPU timestamps on this adapter");
            return;
        }
        egui::Grid::new("himal.timings")
            .striped(true)
            .show(ui, |ui| {
                for (pass, ms) in &groups {
                    ui.label(pass);
                    ui.label(format!("{ms:.2} ms"));
                    ui.end_row();
                }
            });
    }
}
