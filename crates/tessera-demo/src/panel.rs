//! The egui panel: file, method and parameters, drawing options, animation, live stats
//! and every error. It edits copies of the settings; the app compares them with the
//! previous frame's to decide whether to tessellate again.

use std::path::PathBuf;

use tessera_core::catmull_clark::FirstSplit;

use crate::camera::Axis;
use crate::scene::{Backend, Kind, Method, Model, Params};
use crate::stats::FrameStats;

/// Drawing and view options (no new tessellation when they change, but animation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub wireframe: bool,
    pub patch_tint: bool,
    pub up: Axis,
    pub animate: bool,
    pub split_non_manifold: bool,
}

/// What the panel shows besides what it edits.
pub struct Shown<'a> {
    pub model: &'a Model,
    pub stats: &'a FrameStats,
    pub fps: Option<f64>,
    pub wireframe_available: bool,
    pub timestamps: bool,
    pub adapter: &'a str,
    pub assets: &'a [PathBuf],
    /// The last file that failed to load, and why (the CLI's line).
    pub load_error: Option<&'a str>,
    /// The last run's error (parameters the stage refused, buffers too large).
    pub run_error: Option<&'a str>,
    /// Every wgpu error the device reported.
    pub wgpu_errors: &'a [String],
}

/// What the panel asks the app to do.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    Load(PathBuf),
    Frame,
    ResetAnimation,
}

const ERROR: egui::Color32 = egui::Color32::from_rgb(200, 40, 30);

/// The panel's contents.
pub fn contents(
    ui: &mut egui::Ui,
    shown: &Shown,
    params: &mut Params,
    view: &mut View,
) -> Vec<Request> {
    let mut requests = Vec::new();
    egui::ScrollArea::vertical().show(ui, |ui| {
        ui.heading("tessera");
        file(ui, shown, view, &mut requests);
        ui.separator();
        tessellation(ui, shown, params);
        ui.separator();
        stats(ui, shown, params);
        ui.separator();
        drawing(ui, shown, view, &mut requests);
        errors(ui, shown);
    });
    requests
}

fn file(ui: &mut egui::Ui, shown: &Shown, view: &mut View, requests: &mut Vec<Request>) {
    let model = shown.model;
    ui.label(format!(
        "{}: {}, {} patches",
        model.name(),
        match model.kind() {
            Kind::Bezier => "Bézier",
            Kind::CatmullClark => "Catmull-Clark",
        },
        model.patches
    ));
    egui::ComboBox::from_id_salt("open")
        .selected_text("Open a shipped model…")
        .show_ui(ui, |ui| {
            for path in shown.assets {
                let label = asset_label(path);
                if ui.selectable_label(*path == model.path, label).clicked() {
                    requests.push(Request::Load(path.clone()));
                }
            }
        });
    ui.small("or drop a file on the window");
    if model.kind() == Kind::CatmullClark
        && ui
            .checkbox(&mut view.split_non_manifold, "split non-manifold edges")
            .changed()
    {
        requests.push(Request::Load(model.path.clone()));
    }
    for w in &model.warnings {
        ui.small(format!("warning: {w}"));
    }
    if let Some(e) = shown.load_error {
        ui.colored_label(ERROR, format!("error: {e}"));
    }
}

/// `teaset/teapot`, `opensubdiv/catmark_car.obj`: the folder and the file.
fn asset_label(path: &std::path::Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    match path.parent().and_then(|p| p.file_name()) {
        Some(dir) => format!("{}/{name}", dir.to_string_lossy()),
        None => name.into_owned(),
    }
}

fn tessellation(ui: &mut egui::Ui, shown: &Shown, params: &mut Params) {
    let kind = shown.model.kind();
    ui.strong("Tessellation");
    egui::ComboBox::from_label("method")
        .selected_text(params.method.name())
        .show_ui(ui, |ui| {
            for &m in Method::of(kind) {
                ui.selectable_value(&mut params.method, m, m.name());
            }
        });
    let diag = shown.model.diagonal() as f64;
    match (kind, params.method) {
        (_, Method::Uniform) => {
            ui.add(egui::Slider::new(&mut params.segments, 1..=64).text("segments per side"));
        }
        (Kind::Bezier, _) => {
            let mut th = params.threshold as f64;
            let range = (1e-4 * diag).max(f64::MIN_POSITIVE)..=(0.05 * diag).max(1e-30);
            let slider = egui::Slider::new(&mut th, range)
                .logarithmic(true)
                .text("threshold")
                .custom_formatter(|v, _| format!("{v:.3e}"))
                .custom_parser(|s| s.trim().parse().ok());
            if ui.add(slider).changed() {
                params.threshold = th as f32;
            }
            ui.small(format!(
                "model units; {:.2e} of the diagonal",
                th / diag.max(1e-30)
            ));
        }
        (Kind::CatmullClark, _) => {
            let mut in_pixels = params.pixels.is_some();
            ui.horizontal(|ui| {
                ui.label("tolerance in");
                ui.radio_value(&mut in_pixels, true, "pixels");
                ui.radio_value(&mut in_pixels, false, "model units");
            });
            if in_pixels != params.pixels.is_some() {
                params.pixels = in_pixels.then_some(crate::scene::DEFAULT_PIXELS);
            }
            if let Some(px) = &mut params.pixels {
                let slider = egui::Slider::new(px, 0.25..=16.0)
                    .logarithmic(true)
                    .text("pixels")
                    .custom_formatter(|v, _| format!("{v:.2}"))
                    .custom_parser(|s| s.trim().parse().ok());
                ui.add(slider);
                ui.small("guaranteed in the view drawn; moving it tessellates again, and patches out of view are culled");
                ui.checkbox(&mut params.cull_backfaces, "cull back faces")
                    .on_hover_text("patches facing away from the eye everywhere emit nothing");
            } else {
                let slider = egui::Slider::new(&mut params.tolerance_rel, 1e-5..=3e-2)
                    .logarithmic(true)
                    .text("tolerance")
                    .custom_formatter(|v, _| format!("{v:.2e}"))
                    .custom_parser(|s| s.trim().parse().ok());
                ui.add(slider);
                ui.small(format!(
                    "fraction of the diagonal: {:.3e} model units",
                    shown.model.tolerance(params.tolerance_rel)
                ));
            }
        }
    }
    if params.method != Method::Uniform {
        let limit = Params::depth_limit(kind);
        let depth = match kind {
            Kind::Bezier => &mut params.bezier_depth,
            Kind::CatmullClark => &mut params.cc_depth,
        };
        ui.add(egui::Slider::new(depth, 0..=limit).text("max depth"));
    }
    if kind == Kind::CatmullClark && params.method == Method::Adaptive {
        ui.horizontal(|ui| {
            ui.label("first split");
            ui.radio_value(&mut params.first_split, FirstSplit::Search, "search");
            ui.radio_value(&mut params.first_split, FirstSplit::Midpoint, "midpoint");
        });
    }
    ui.horizontal(|ui| {
        ui.label("backend");
        ui.radio_value(&mut params.backend, Backend::Gpu, "GPU");
        ui.radio_value(&mut params.backend, Backend::Cpu, "CPU reference");
    });
    if !params.method.on_gpu(kind) {
        ui.small(format!(
            "{} runs on the CPU only (the reference, uploaded for drawing)",
            params.method.name()
        ));
    }
}

fn drawing(ui: &mut egui::Ui, shown: &Shown, view: &mut View, requests: &mut Vec<Request>) {
    ui.strong("View");
    ui.add_enabled(
        shown.wireframe_available,
        egui::Checkbox::new(&mut view.wireframe, "wireframe"),
    );
    if !shown.wireframe_available {
        ui.small("the device has no POLYGON_MODE_LINE: no wireframe");
    }
    ui.checkbox(&mut view.patch_tint, "patch tint");
    ui.horizontal(|ui| {
        ui.label("up");
        for a in Axis::ALL {
            ui.radio_value(&mut view.up, a, a.name());
        }
        if ui.button("frame (F)").clicked() {
            requests.push(Request::Frame);
        }
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut view.animate, "animate control points");
        if ui.button("reset").clicked() {
            requests.push(Request::ResetAnimation);
        }
    });
    ui.small("left drag: orbit · right/middle drag: pan · wheel: zoom");
}

fn stats(ui: &mut egui::Ui, shown: &Shown, params: &Params) {
    let s = shown.stats;
    ui.strong("Stats");
    egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
        let mut row = |k: &str, v: String| {
            ui.label(k);
            ui.monospace(v);
            ui.end_row();
        };
        row("triangles", s.triangles.to_string());
        row("vertices", s.vertices.to_string());
        row("patches", s.patches.to_string());
        // Short rows: a resizable panel widens to its widest row and stays so.
        match (s.guaranteed_bound, s.tolerance_px) {
            (Some(b), None) => {
                row("guaranteed bound", format!("{b:.3e}"));
                let eps = shown.model.tolerance(params.tolerance_rel);
                row("tolerance ε", format!("{eps:.3e}"));
            }
            (_, Some(px)) => {
                match params.pixels {
                    Some(asked) if asked < px => row(
                        "tolerance",
                        format!("{px:.2} px (coarsened; {asked:.2} asked)"),
                    ),
                    _ => row("tolerance", format!("{px:.2} px")),
                }
                if let Some(c) = s.culled_patches {
                    row("culled patches", c.to_string());
                }
            }
            _ => {}
        }
        match (s.gpu_ms, s.wall_ms) {
            (Some(ms), _) => row("tessellation (GPU)", format!("{ms:.2} ms")),
            (None, Some(ms)) => row("tessellation (wall)", format!("{ms:.2} ms")),
            (None, None) => row("tessellation", "—".into()),
        }
        row(
            "frame",
            match shown.fps {
                Some(fps) => format!("{:.1} ms, {fps:.1} fps", s.frame_ms),
                None => format!("{:.1} ms", s.frame_ms),
            },
        );
        row(
            "buffer growths",
            if s.overflowed {
                format!("{} (growing)", s.growths)
            } else {
                s.growths.to_string()
            },
        );
        row(
            "tessellated",
            if s.tessellated {
                "this frame"
            } else {
                "no (still)"
            }
            .into(),
        );
    });
    if !shown.timestamps {
        ui.small("no TIMESTAMP_QUERY: times are wall times");
    }
    ui.small(shown.adapter);
}

fn errors(ui: &mut egui::Ui, shown: &Shown) {
    if let Some(e) = shown.run_error {
        ui.colored_label(ERROR, format!("error: {e}"));
    }
    if !shown.wgpu_errors.is_empty() {
        ui.colored_label(ERROR, format!("{} wgpu error(s):", shown.wgpu_errors.len()));
        for e in shown.wgpu_errors.iter().rev().take(5) {
            ui.colored_label(ERROR, e);
        }
    }
}
