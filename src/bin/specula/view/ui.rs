//! The viewer's overlay (egui): the device and frame time, the plan with each specular
//! object's method to switch, the knobs the plan's methods read, the per-pass GPU timings
//! of the last completed frame, the camera and a screenshot button. It changes nothing
//! itself: it returns the same actions a script gives (`script::Action`), which the viewer
//! applies as it applies a script's.

use specula::plan::{Choice, Method, Plan};
use specula::quality::{knob::Range, Quality, KNOBS};
use specula::vk::PassTiming;

use super::camera::Mode;
use super::script::Action;

/// What the overlay shows, borrowed from the viewer each frame.
pub struct Shown<'a> {
    pub device: &'a str,
    pub size: (u32, u32),
    pub fps: f64,
    pub timings: &'a [PassTiming],
    pub plan: &'a Plan,
    pub choice: Choice,
    pub quality: &'a Quality,
    pub messages: &'a [String],
    pub mode: Mode,
    /// `None`: the scene has no animations.
    pub paused: Option<bool>,
    pub camera_args: &'a str,
}

/// The overlay's own state across frames.
#[derive(Default)]
pub struct Overlay {
    pub hidden: bool,
    screenshots: u32,
}

/// Frame-wide knobs every method's frame reads, shown before the plan's methods' own.
const FRAME_KNOBS: &[&str] = &["depth", "aa", "shadows", "fresnel", "map_updates"];

impl Overlay {
    pub fn draw(&mut self, ctx: &egui::Context, s: &Shown) -> Vec<Action> {
        let mut actions = Vec::new();
        if self.hidden {
            return actions;
        }
        egui::Window::new("specula").default_pos([8.0, 8.0]).default_width(330.0).resizable(true).show(ctx, |ui| {
            let gpu: f64 = s.timings.iter().map(|t| t.gpu_ms).sum();
            ui.label(format!("{} · {}×{}", s.device, s.size.0, s.size.1));
            ui.label(format!("{:.1} fps · GPU {gpu:.2} ms a frame", s.fps));
            ui.label("F1 overlay · WASD/QE move · right drag look · O orbit · Space pause · F12 screenshot · Esc quit");
            egui::CollapsingHeader::new("Plan").default_open(true).show(ui, |ui| self.plan(ui, s, &mut actions));
            egui::CollapsingHeader::new("Knobs").default_open(false).show(ui, |ui| knobs(ui, s, &mut actions));
            egui::CollapsingHeader::new(format!("Passes ({gpu:.2} ms)"))
                .id_salt("passes")
                .default_open(true)
                .show(ui, |ui| passes(ui, s.timings));
            ui.separator();
            ui.horizontal(|ui| {
                let mode = if s.mode == Mode::Fly { "fly" } else { "orbit" };
                if ui.button(format!("camera: {mode}")).clicked() {
                    actions.push(Action::Orbit);
                }
                if let Some(paused) = s.paused {
                    if ui.button(if paused { "play" } else { "pause" }).clicked() {
                        actions.push(Action::Pause);
                    }
                }
                if ui.button("screenshot").clicked() {
                    self.screenshots += 1;
                    actions.push(Action::Screenshot(format!("shot{:03}", self.screenshots)));
                }
            });
            ui.label(egui::RichText::new(s.camera_args).small().monospace());
            for m in s.messages.iter().rev().take(4) {
                ui.colored_label(egui::Color32::from_rgb(255, 170, 90), m);
            }
        });
        actions
    }

    fn plan(&mut self, ui: &mut egui::Ui, s: &Shown, actions: &mut Vec<Action>) {
        let gpu_methods = || Method::ALL.iter().copied().filter(|m| m.is_gpu());
        let mut whole = s.choice.name().to_string();
        egui::ComboBox::from_label("whole scene").selected_text(&whole).show_ui(ui, |ui| {
            for name in std::iter::once("auto").chain(gpu_methods().map(|m| m.name())) {
                ui.selectable_value(&mut whole, name.to_string(), name);
            }
        });
        if whole != s.choice.name() {
            actions.push(Action::Method(None, whole));
        }
        egui::Grid::new("objects").striped(true).show(ui, |ui| {
            for o in &s.plan.objects {
                ui.label(&o.name).on_hover_text(&o.reason);
                let mut chosen = o.method.name().to_string();
                egui::ComboBox::from_id_salt(("method", o.mesh)).selected_text(&chosen).show_ui(ui, |ui| {
                    for m in gpu_methods().filter(|m| m.can_serve(o.class)) {
                        ui.selectable_value(&mut chosen, m.name().to_string(), m.name());
                    }
                });
                if chosen != o.method.name() {
                    actions.push(Action::Method(Some(o.name.clone()), chosen));
                }
                ui.end_row();
            }
        });
    }
}

/// The frame's knobs and those of the methods in the plan, each edited by its range:
/// options as a list, counts and reals by dragging, the rest as text.
fn knobs(ui: &mut egui::Ui, s: &Shown, actions: &mut Vec<Action>) {
    let mut names: Vec<&str> = FRAME_KNOBS.to_vec();
    for o in &s.plan.objects {
        for k in o.method.knobs {
            if !names.contains(k) {
                names.push(k);
            }
        }
    }
    egui::Grid::new("knobs").striped(true).show(ui, |ui| {
        for k in KNOBS.iter().filter(|k| names.contains(&k.name)) {
            let now = s.quality.get(k.name);
            ui.label(k.name).on_hover_text(format!("{} ({})", k.doc, k.values));
            let mut value = now.clone();
            match k.range {
                Range::Options(options) => {
                    egui::ComboBox::from_id_salt(("knob", k.name)).selected_text(&value).show_ui(ui, |ui| {
                        for o in options {
                            ui.selectable_value(&mut value, o.to_string(), *o);
                        }
                    });
                }
                Range::Count(lo, hi) => {
                    let mut n: u32 = now.parse().unwrap_or(lo);
                    if ui.add(egui::DragValue::new(&mut n).range(lo..=hi)).changed() {
                        value = n.to_string();
                    }
                }
                Range::Real(lo, hi) => {
                    let mut x: f32 = now.parse().unwrap_or(lo);
                    if ui.add(egui::DragValue::new(&mut x).range(lo..=hi).speed(0.01 * (hi - lo).min(10.0))).changed() {
                        value = x.to_string();
                    }
                }
                _ => {
                    let r = ui.text_edit_singleline(&mut value);
                    if !(r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter))) {
                        value = now.clone();
                    }
                }
            }
            if value != now {
                actions.push(Action::Knob(format!("{}={value}", k.name)));
            }
            ui.end_row();
        }
    });
}

/// The last completed frame's passes in recording order, each with its share as a bar.
fn passes(ui: &mut egui::Ui, timings: &[PassTiming]) {
    let total: f64 = timings.iter().map(|t| t.gpu_ms).sum::<f64>().max(1e-9);
    egui::ScrollArea::vertical().max_height(260.0).show(ui, |ui| {
        egui::Grid::new("passes").striped(true).show(ui, |ui| {
            for t in timings {
                ui.label(egui::RichText::new(&t.name).monospace());
                ui.label(format!("{:8.3} ms", t.gpu_ms));
                ui.add(egui::ProgressBar::new((t.gpu_ms / total) as f32).desired_width(80.0));
                ui.end_row();
            }
        });
    });
}
