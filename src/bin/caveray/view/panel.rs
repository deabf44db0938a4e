//! The controls (a side panel) and the overlay of per-wall figures, drawn
//! with egui. They change `Controls`; the viewer sees what changed.

use anari_library_caveray::data::PRESETS;
use anari_library_caveray::render::warp::WarpMode;
use anari_library_caveray::render::{Backend, Shading};

use super::controls::{Controls, Look, Stereo};
use super::live::PaneStats;

/// What the overlay shows of one wall.
pub struct WallFigures<'a> {
    pub name: &'a str,
    /// The eyes rendered (left, then right), each its figures.
    pub eyes: Vec<PaneStats>,
}

/// What the window reports besides the walls.
pub struct Figures<'a> {
    pub fps: f64,
    pub frame_ms: f64,
    pub walls: Vec<WallFigures<'a>>,
    pub converged: bool,
    pub renderer: &'a str,
    pub notes: Vec<String>,
    /// The path's length in seconds (0: the rig has no path).
    pub path_seconds: f64,
    /// Views of a multi-view display (0: a rig).
    pub display_views: u32,
}

/// Width of the side panel in points.
pub const PANEL_WIDTH: f32 = 250.0;

const SHADINGS: [Shading; 5] = [
    Shading::None,
    Shading::Shadows,
    Shading::Ao,
    Shading::ShadowsAo,
    Shading::Directional(4),
];

/// Draws the panel and the overlay; returns the rectangle (in points)
/// left for the rig.
pub fn draw(ui: &mut egui::Ui, c: &mut Controls, figures: &Figures) -> egui::Rect {
    if c.show_panel {
        egui::Panel::left("controls")
            .exact_size(PANEL_WIDTH)
            .resizable(false)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| controls(ui, c, figures));
            });
    }
    let rect = ui.available_rect_before_wrap();
    if !c.show_figures {
        return rect;
    }
    egui::Area::new(ui.scope_id().with("figures"))
        .anchor(egui::Align2::LEFT_BOTTOM, [rect.min.x + 6.0, -6.0])
        .interactable(false)
        .show(ui.ctx(), |ui| {
            egui::Frame::popup(ui.style())
                .fill(egui::Color32::from_black_alpha(190))
                .show(ui, |ui| overlay(ui, figures));
        });
    rect
}

fn controls(ui: &mut egui::Ui, c: &mut Controls, figures: &Figures) {
    ui.spacing_mut().slider_width = 110.0;
    ui.heading("caveray view");
    ui.label(figures.renderer);
    ui.separator();
    ui.horizontal(|ui| {
        ui.label("View (V)");
        for look in Look::ALL {
            ui.selectable_value(&mut c.look, look, look.name());
        }
    });
    if figures.display_views > 0 {
        // A display renders from its own eye line: no head, no volume
        // controls; its panel above, the chosen view below.
        ui.label("The interleaved panel, then one view (an isosurface per view, on the CPU).");
        ui.add(egui::Slider::new(&mut c.display_view, 0..=figures.display_views - 1).text("view"));
        notes(ui, figures);
        return;
    }
    ui.separator();
    ui.label("Head (WASD, Q/E, drag)");
    ui.horizontal(|ui| {
        for (v, label) in c.head.as_mut().iter_mut().zip(["x", "y", "z"]) {
            ui.add(egui::DragValue::new(v).speed(5.0).prefix(label));
        }
    });
    ui.horizontal(|ui| {
        ui.add(
            egui::DragValue::new(&mut c.ypr.x)
                .speed(0.5)
                .suffix("° yaw"),
        );
        ui.add(
            egui::DragValue::new(&mut c.ypr.y)
                .speed(0.5)
                .range(-85.0..=85.0)
                .suffix("° pitch"),
        );
    });
    if figures.path_seconds > 0.0 {
        ui.horizontal(|ui| {
            let label = if c.playing { "Pause (P)" } else { "Play (P)" };
            if ui.button(label).clicked() {
                c.playing = !c.playing;
            }
            ui.add(egui::Slider::new(&mut c.time, 0.0..=figures.path_seconds).suffix(" s"));
        });
    }
    ui.separator();
    ui.label("Volume (arrows, PgUp/PgDn, shift-drag)");
    let r = &mut c.rendering;
    ui.horizontal(|ui| {
        for (v, label) in r.volume_offset.as_mut().iter_mut().zip(["x", "y", "z"]) {
            ui.add(egui::DragValue::new(v).speed(5.0).prefix(label));
        }
    });
    ui.add(egui::Slider::new(&mut r.volume_yaw, 0.0..=360.0).text("yaw"));
    ui.add(egui::Slider::new(&mut r.volume_pitch, -90.0..=90.0).text("pitch"));
    egui::ComboBox::from_label("transfer function")
        .selected_text(r.tf.as_str())
        .show_ui(ui, |ui| {
            for p in PRESETS {
                ui.selectable_value(&mut r.tf, p.to_string(), p);
            }
        });
    ui.add(egui::Slider::new(&mut r.opacity_gain, 0.0..=4.0).text("opacity"));
    ui.add(egui::Slider::new(&mut r.opacity_floor, 0.0..=1.0).text("cut below"));
    curve(ui, r.opacity_gain, r.opacity_floor);
    ui.separator();
    ui.label("Renderer");
    ui.add(
        egui::Slider::new(&mut r.step_factor, 0.25..=8.0)
            .logarithmic(true)
            .text("step factor"),
    );
    egui::ComboBox::from_label("shading")
        .selected_text(r.shading.to_string())
        .show_ui(ui, |ui| {
            for s in SHADINGS {
                ui.selectable_value(&mut r.shading, s, s.to_string());
            }
        });
    egui::ComboBox::from_label("backend")
        .selected_text(r.backend.name())
        .show_ui(ui, |ui| {
            for b in [Backend::Auto, Backend::Gpu, Backend::Cpu] {
                ui.selectable_value(&mut r.backend, b, b.name());
            }
        });
    egui::ComboBox::from_label("stereo (M)")
        .selected_text(c.stereo.name())
        .show_ui(ui, |ui| {
            for s in Stereo::ALL {
                ui.selectable_value(&mut c.stereo, s, s.name());
            }
        });
    egui::ComboBox::from_label("warp")
        .selected_text(c.warp.name())
        .show_ui(ui, |ui| {
            for w in WarpMode::ALL {
                ui.selectable_value(&mut c.warp, w, w.name());
            }
        });
    ui.add(
        egui::Slider::new(&mut c.deadline_ms, 1.0..=200.0)
            .logarithmic(true)
            .suffix(" ms")
            .text("deadline"),
    );
    notes(ui, figures);
}

fn notes(ui: &mut egui::Ui, figures: &Figures) {
    if !figures.notes.is_empty() {
        ui.separator();
        ui.label("Engine");
        for n in &figures.notes {
            ui.small(n);
        }
    }
}

/// The opacity curve's multiplier over the value range.
fn curve(ui: &mut egui::Ui, gain: f32, floor: f32) {
    let (rect, _) =
        ui.allocate_exact_size(egui::vec2(PANEL_WIDTH - 20.0, 36.0), egui::Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_filled(rect, 2.0, egui::Color32::from_gray(30));
    let top = gain.max(1.0) * 1.15;
    let point = |t: f32, m: f32| {
        egui::pos2(
            rect.left() + t * rect.width(),
            rect.bottom() - m / top * rect.height(),
        )
    };
    let points = vec![
        point(0.0, 0.0),
        point(floor, 0.0),
        point(floor, gain),
        point(1.0, gain),
    ];
    painter.add(egui::Shape::line(
        points,
        egui::Stroke::new(1.5, egui::Color32::from_rgb(240, 200, 90)),
    ));
}

fn overlay(ui: &mut egui::Ui, f: &Figures) {
    let text = |ui: &mut egui::Ui, s: String| {
        ui.label(
            egui::RichText::new(s)
                .monospace()
                .color(egui::Color32::WHITE)
                .size(11.0),
        );
    };
    text(
        ui,
        format!(
            "{:5.1} fps {:5.1} ms/frame {}",
            f.fps,
            f.frame_ms,
            if f.converged { "converged" } else { "" }
        ),
    );
    if f.walls.is_empty() {
        return;
    }
    // One row a wall; a stereo wall's two eyes as left/right.
    text(ui, "wall        age ms   render ms  warp        Hz".into());
    for w in &f.walls {
        let each = |part: &dyn Fn(&PaneStats) -> String| {
            w.eyes.iter().map(part).collect::<Vec<_>>().join("/")
        };
        let shown = |s: &PaneStats| s.last.filter(|l| l.age_ms >= 0.0);
        let age = each(&|s| shown(s).map_or("-".into(), |l| format!("{:.0}", l.age_ms)));
        let render = each(&|s| shown(s).map_or("-".into(), |l| format!("{:.0}", l.render_ms)));
        let warp = each(&|s| {
            shown(s).map_or("-".into(), |l| {
                if l.own { "own" } else { l.warp.name() }.to_string()
            })
        });
        let hz = w
            .eyes
            .iter()
            .map(|s| s.rate_hz)
            .fold(f64::INFINITY, f64::min);
        let hz = if hz.is_finite() {
            format!("{hz:3.0}")
        } else {
            "  -".into()
        };
        text(
            ui,
            format!(
                "{:<10} {age:>9} {render:>9}  {warp:<10} {hz}",
                truncate(w.name, 10)
            ),
        );
    }
}

fn truncate(s: &str, n: usize) -> &str {
    s.char_indices().nth(n).map_or(s, |(i, _)| &s[..i])
}
