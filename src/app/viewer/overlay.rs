//! The viewer's overlay (docs/viewer.md "The overlay"): a panel over the frame with each stage's GPU ms as a stacked
//! graph over the last frames, what the frame traced (photons, level, method, photon sets, the energy account) and
//! buttons for what the keys do. egui builds it from the window's input (egui-winit); the frame's command buffer
//! draws it (caustics::overlay::OverlayPainter, through the presenter), so that it is in the presented image and
//! in its screenshots. `F1` toggles it, and `view --overlay off` starts without it.

use crate::app::profiler::STAGE_COLORS;
use crate::app::viewer::controls::Action;
use caustics::overlay::{OverlayMesh, OverlayPainter, OverlayVertex};
use caustics::{FrameReport, ACCOUNT_TERMS};
use egui::{Color32, Pos2, Rect, Sense, Stroke, Vec2};
use std::collections::VecDeque;
use std::time::Instant;
use winit::window::Window;

/// Frames the graph shows, one pixel column each.
const HISTORY: usize = 300;
/// Width and height of the graph, in points.
const GRAPH: Vec2 = Vec2::new(HISTORY as f32, 64.0);

/// What the overlay shows of one completed frame.
struct Sample {
    gpu_ms: f64,
    stages: Vec<(&'static str, f64)>,
}

/// What the overlay reads of the viewer when it is built: the settings' one-line description and the last frame.
pub struct Shown<'a> {
    pub scene: &'a str,
    pub settings: String,
    pub last: Option<&'a FrameReport>,
    pub playing: Option<bool>,
    pub fps: f64,
    /// The first light's position (m).
    pub light: glam::Vec3,
    /// Under the flux-error metric, its target error: the rel-L1 at 64² that merging photons may add.
    pub target_error: Option<f32>,
}

/// What the panel's controls asked for this frame: the keys' actions, and a new position for the first light.
#[derive(Default)]
pub struct Asked {
    pub actions: Vec<Action>,
    pub light: Option<glam::Vec3>,
}

/// A built overlay, ready to draw: its meshes (in points) and the window's pixels per point.
#[derive(Default)]
pub struct Drawn {
    pub meshes: Vec<(Rect, u64, Vec<OverlayVertex>, Vec<u32>)>,
    pub pixels_per_point: f32,
}

impl Drawn {
    /// The meshes as the painter takes them.
    pub fn meshes(&self) -> Vec<OverlayMesh<'_>> {
        self.meshes
            .iter()
            .map(|(clip, texture, vertices, indices)| OverlayMesh {
                clip: [clip.min.x, clip.min.y, clip.max.x, clip.max.y],
                texture: *texture,
                vertices,
                indices,
            })
            .collect()
    }
}

pub struct Overlay {
    ctx: egui::Context,
    state: egui_winit::State,
    pub visible: bool,
    history: VecDeque<Sample>,
    /// The stages in the order first seen (their colors stay put as stages come and go).
    stage_order: Vec<&'static str>,
    /// Host milliseconds the last build took (egui's layout and tessellation).
    pub build_ms: f64,
    /// Triangles the last build drew.
    pub triangles: usize,
    /// Each button of the last build: its label and rectangle (points), for the stats.
    pub buttons: Vec<(String, Rect)>,
    /// The panel's rectangle in the last build (points).
    pub panel: Option<Rect>,
    /// The graph's texture and full scale (ms).
    graph: Option<(egui::TextureHandle, f64)>,
}

/// egui's texture ids as the painter's.
fn texture_key(id: egui::TextureId) -> u64 {
    match id {
        egui::TextureId::Managed(n) => n << 1,
        egui::TextureId::User(n) => (n << 1) | 1,
    }
}

/// A stage's color in the graph and its legend: `profile --plot`'s palette, by the order stages were first seen.
fn stage_color(i: usize) -> Color32 {
    let (r, g, b) = STAGE_COLORS[i % STAGE_COLORS.len()];
    Color32::from_rgb(r, g, b)
}

/// The smallest of 1, 2, 5 × 10^k ms at or above `ms`: the graph's full scale.
fn nice_scale(ms: f64) -> f64 {
    let ms = ms.max(1e-3);
    let decade = 10f64.powf(ms.log10().floor());
    [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * decade).find(|&s| s >= ms).unwrap_or(10.0 * decade)
}

impl Overlay {
    pub fn new(window: &Window, visible: bool, max_texture_side: usize) -> Self {
        let ctx = egui::Context::default();
        ctx.set_visuals(egui::Visuals::dark());
        let state = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_texture_side),
        );
        Overlay {
            ctx,
            state,
            visible,
            history: VecDeque::new(),
            stage_order: Vec::new(),
            build_ms: 0.0,
            triangles: 0,
            buttons: Vec::new(),
            panel: None,
            graph: None,
        }
    }

    /// Pass a window event to the overlay. Returns whether it took the event (a click on a button, a drag over
    /// the panel): then the viewer does not act on it too.
    pub fn on_window_event(&mut self, window: &Window, event: &winit::event::WindowEvent) -> bool {
        let response = self.state.on_window_event(window, event);
        self.visible && response.consumed
    }

    /// A scripted left click at `pos` (pixels): whether the panel takes it (it lies on the panel as last built),
    /// which then sees the pointer move there, press and release before its next build.
    pub fn click(&mut self, pos: (f64, f64), pixels_per_point: f32) -> bool {
        let p = Pos2::new(pos.0 as f32, pos.1 as f32) / pixels_per_point;
        if !self.visible || !self.panel.is_some_and(|r| r.contains(p)) {
            return false;
        }
        let events = &mut self.state.egui_input_mut().events;
        events.push(egui::Event::PointerMoved(p));
        for pressed in [true, false] {
            let button = egui::PointerButton::Primary;
            events.push(egui::Event::PointerButton { pos: p, button, pressed, modifiers: Default::default() });
        }
        true
    }

    /// Take in a completed frame's timings.
    pub fn add_frame(&mut self, report: &FrameReport) {
        for (name, _) in &report.stages {
            if !self.stage_order.contains(name) {
                self.stage_order.push(name);
            }
        }
        if self.history.len() == HISTORY {
            self.history.pop_front();
        }
        self.history.push_back(Sample { gpu_ms: report.gpu_ms, stages: report.stages.clone() });
    }

    /// Build this frame's overlay: egui lays it out from the input since the last build, the painter gets the
    /// textures that changed, and the actions its buttons asked for are returned. Nothing is built while hidden.
    pub fn build(&mut self, window: &Window, shown: &Shown, painter: &mut OverlayPainter) -> (Drawn, Asked) {
        let input = self.state.take_egui_input(window);
        if !self.visible {
            return (Drawn::default(), Asked::default());
        }
        let start = Instant::now();
        let (image, scale) = self.graph_image();
        match &mut self.graph {
            Some((texture, s)) => {
                texture.set(image, egui::TextureOptions::NEAREST);
                *s = scale;
            }
            None => self.graph = Some((self.ctx.load_texture("stages", image, egui::TextureOptions::NEAREST), scale)),
        }
        let mut actions = Asked::default();
        let (mut buttons, mut panel) = (Vec::new(), None);
        let output = self.ctx.run(input, |ctx| panel = self.panel(ctx, shown, &mut actions, &mut buttons));
        (self.buttons, self.panel) = (buttons, panel);
        self.state.handle_platform_output(window, output.platform_output);
        for (id, delta) in output.textures_delta.set {
            let egui::ImageData::Color(image) = &delta.image;
            let rgba: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
            let size = [image.size[0] as u32, image.size[1] as u32];
            let linear = delta.options.magnification == egui::TextureFilter::Linear;
            let pos = delta.pos.map(|[x, y]| [x as u32, y as u32]);
            painter.set_texture(texture_key(id), pos, size, linear, rgba);
        }
        for id in output.textures_delta.free {
            painter.free_texture(texture_key(id));
        }
        let ppp = output.pixels_per_point;
        let mut drawn = Drawn { meshes: Vec::new(), pixels_per_point: ppp };
        for clipped in self.ctx.tessellate(output.shapes, ppp) {
            if let egui::epaint::Primitive::Mesh(mesh) = clipped.primitive {
                let vertices = mesh
                    .vertices
                    .iter()
                    .map(|v| OverlayVertex { pos: [v.pos.x, v.pos.y], uv: [v.uv.x, v.uv.y], color: v.color.to_array() })
                    .collect();
                drawn.meshes.push((clipped.clip_rect, texture_key(mesh.texture_id), vertices, mesh.indices));
            }
        }
        self.triangles = drawn.meshes.iter().map(|m| m.3.len() / 3).sum();
        self.build_ms = start.elapsed().as_secs_f64() * 1e3;
        (drawn, actions)
    }

    /// The panel; returns its rectangle.
    fn panel(
        &self,
        ctx: &egui::Context,
        shown: &Shown,
        actions: &mut Asked,
        buttons: &mut Vec<(String, Rect)>,
    ) -> Option<Rect> {
        let frame = egui::Frame::window(&ctx.style()).fill(Color32::from_black_alpha(200));
        // A window shorter than the panel scrolls it (80 px: the title bar, the frame's margins and the panel's
        // place below the window's top, with as much below it).
        let max_height = (ctx.content_rect().height() - 80.0).max(80.0);
        let window = egui::Window::new("caustics").frame(frame).default_pos(Pos2::new(8.0, 8.0)).resizable(false).show(
            ctx,
            |ui| {
                egui::ScrollArea::vertical().max_height(max_height).show(ui, |ui| {
                    self.contents(ui, shown, actions, buttons);
                });
            },
        );
        window.map(|w| w.response.rect)
    }

    fn contents(&self, ui: &mut egui::Ui, shown: &Shown, actions: &mut Asked, buttons: &mut Vec<(String, Rect)>) {
        ui.label(format!("{} — {:.1} fps", shown.scene, shown.fps));
        ui.label(egui::RichText::new(&shown.settings).small());
        ui.separator();
        // The buttons first: their places do not move as the stages below come and go.
        controls(ui, shown, actions, buttons);
        ui.separator();
        self.graph(ui);
        self.legend(ui);
        if let Some(r) = shown.last {
            ui.separator();
            frame_facts(ui, r, shown.target_error);
        }
    }

    /// The graph's image: each frame a column of pixels (the newest at the right), its stages stacked bottom up,
    /// against a full scale of 1, 2 or 5 × 10^k ms, which it returns. One textured quad draws it: the thousands of
    /// rectangles it holds would cost lavapipe milliseconds a frame as triangles.
    fn graph_image(&self) -> (egui::ColorImage, f64) {
        let (w, h) = (HISTORY, GRAPH.y as usize);
        let scale = nice_scale(self.history.iter().map(|s| s.gpu_ms).fold(0.0, f64::max));
        let mut pixels = vec![Color32::from_black_alpha(160); w * h];
        let start = w - self.history.len();
        for (i, s) in self.history.iter().enumerate() {
            let mut bottom = 0.0;
            for (name, ms) in &s.stages {
                let top = bottom + ms / scale * h as f64;
                let color = stage_color(self.stage_order.iter().position(|n| n == name).unwrap_or(0));
                for row in (bottom.round() as usize)..(top.round() as usize).min(h) {
                    pixels[(h - 1 - row) * w + start + i] = color;
                }
                bottom = top;
            }
        }
        (egui::ColorImage { size: [w, h], source_size: Vec2::new(w as f32, h as f32), pixels }, scale)
    }

    fn graph(&self, ui: &mut egui::Ui) {
        let (rect, _) = ui.allocate_exact_size(GRAPH, Sense::hover());
        let Some((texture, scale)) = &self.graph else {
            return;
        };
        let painter = ui.painter_at(rect);
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(texture.id(), rect, uv, Color32::WHITE);
        let text = format!("{scale} ms");
        let font = egui::FontId::monospace(11.0);
        painter.text(rect.left_top() + Vec2::new(4.0, 2.0), egui::Align2::LEFT_TOP, text, font, Color32::WHITE);
        painter.line_segment([rect.left_top(), rect.right_top()], Stroke::new(1.0, Color32::from_gray(90)));
    }

    /// Each stage's color, name and GPU ms averaged over the last 30 frames.
    fn legend(&self, ui: &mut egui::Ui) {
        let recent: Vec<&Sample> = self.history.iter().rev().take(30).collect();
        if recent.is_empty() {
            return;
        }
        let n = recent.len() as f64;
        let mean = |name: &str| {
            recent
                .iter()
                .map(|s| s.stages.iter().filter(|(l, _)| *l == name).map(|(_, ms)| ms).sum::<f64>())
                .sum::<f64>()
                / n
        };
        let total = recent.iter().map(|s| s.gpu_ms).sum::<f64>() / n;
        let mut rows: Vec<(Option<usize>, &str, f64)> = self
            .stage_order
            .iter()
            .enumerate()
            .map(|(k, name)| (Some(k), *name, mean(name)))
            .filter(|r| r.2 >= 0.05)
            .collect();
        rows.push((None, "GPU", total));
        // Two stages a row, so that the panel stays short.
        egui::Grid::new("stages").num_columns(6).spacing([6.0, 0.0]).show(ui, |ui| {
            for pair in rows.chunks(2) {
                for (k, name, ms) in pair {
                    let (r, _) = ui.allocate_exact_size(Vec2::splat(9.0), Sense::hover());
                    if let Some(k) = k {
                        ui.painter().rect_filled(r, 1.0, stage_color(*k));
                    }
                    ui.label(egui::RichText::new(*name).monospace().small());
                    ui.label(egui::RichText::new(format!("{ms:7.1}")).monospace().small());
                }
                ui.end_row();
            }
        });
    }
}

/// What the last frame traced: photons, level, photon sets, reuse, the flux-error metric's target error, and exact
/// transport's energy account (each term as a share of the emitted flux).
fn frame_facts(ui: &mut egui::Ui, r: &FrameReport, target_error: Option<f32>) {
    let mut line = format!("{} photons, level {}", r.photons(), r.level);
    if r.photon_sets > 1 {
        line += &format!(", {} photon sets", r.photon_sets);
    }
    if r.reused {
        line += ", maps reused";
    }
    if r.preview {
        line += ", preview";
    }
    ui.monospace(line);
    if let Some(e) = target_error {
        let text = format!("target error {:.2}% (rel-L1 at 64² that merging photons may add)", 100.0 * e);
        ui.label(egui::RichText::new(text).small());
    }
    if let Some(t) = &r.transport {
        let account = t.account();
        let emitted = account[0];
        if emitted > 0.0 {
            let shares: Vec<String> = ACCOUNT_TERMS
                .iter()
                .zip(account)
                .skip(1)
                .filter(|(name, x)| *x > 1e-4 * emitted && **name != "caustics_one_interaction")
                .map(|(name, x)| format!("{name} {:.1}%", 100.0 * x / emitted))
                .collect();
            ui.label(egui::RichText::new(format!("energy: {}", shares.join(", "))).small());
        }
    }
}

/// Buttons for what the keys do (docs/viewer.md's table): each asks for the key's action.
fn controls(ui: &mut egui::Ui, shown: &Shown, actions: &mut Asked, buttons: &mut Vec<(String, Rect)>) {
    let mut button = |ui: &mut egui::Ui, text: &str, hint: &str, action: Action| {
        let r = ui.button(text).on_hover_text(hint);
        buttons.push((format!("{action:?}"), r.rect));
        if r.clicked() {
            actions.actions.push(action);
        }
    };
    ui.horizontal(|ui| {
        ui.label("method");
        button(ui, "dense", "1", Action::Dense);
        button(ui, "max-level", "2", Action::AdaptiveMaxLevel);
        button(ui, "max-error", "3", Action::AdaptiveMaxError);
        button(ui, "flux-error", "4", Action::AdaptiveFluxError);
        button(ui, "transport", "X: exact or two-interface", Action::Transport);
        button(ui, "refine", "C: flux-error by the light's map or by the camera's image", Action::Refine);
    });
    ui.horizontal(|ui| {
        ui.label("level");
        button(ui, "−", "-", Action::LevelDown);
        button(ui, "+", "=", Action::LevelUp);
        ui.label("map");
        button(ui, "½", ",", Action::ResolutionDown);
        button(ui, "2×", ".", Action::ResolutionUp);
        ui.label("IOR");
        button(ui, "−", "[", Action::IorDown);
        button(ui, "+", "]", Action::IorUp);
    });
    ui.horizontal(|ui| {
        ui.label("light (m)");
        let mut p = shown.light;
        let mut changed = false;
        for v in [&mut p.x, &mut p.y, &mut p.z] {
            changed |= ui.add(egui::DragValue::new(v).speed(0.01).max_decimals(2)).changed();
        }
        if changed {
            actions.light = Some(p);
        }
    });
    ui.horizontal(|ui| {
        button(ui, "orbit light", "Space", Action::Animate);
        if let Some(playing) = shown.playing {
            button(ui, if playing { "pause scene" } else { "play scene" }, "A", Action::PlayScene);
            button(ui, "next animation", "N", Action::NextAnimation);
        }
        button(ui, "reset", "R", Action::Reset);
    });
    ui.horizontal(|ui| {
        button(ui, "screenshot", "S", Action::Screenshot);
        button(ui, "print timings", "P", Action::Profile);
        button(ui, "trace", "T: Chrome trace", Action::Trace);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_graph_scale_is_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(nice_scale(3.2), 5.0);
        assert_eq!(nice_scale(5.0), 5.0);
        assert_eq!(nice_scale(17.0), 20.0);
        assert_eq!(nice_scale(101.0), 200.0);
        assert!((nice_scale(0.04) - 0.05).abs() < 1e-12);
    }

    #[test]
    fn managed_and_user_textures_get_distinct_keys() {
        assert_ne!(texture_key(egui::TextureId::Managed(3)), texture_key(egui::TextureId::User(3)));
        assert_eq!(texture_key(egui::TextureId::Managed(0)), 0);
    }
}
