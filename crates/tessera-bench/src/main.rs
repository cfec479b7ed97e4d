//! `cargo xtask bench`: Bézier CPU results as in the paper's Table 2, plus the comparison
//! with uniform tessellation at equal measured max error. Writes `OUT/bezier_cpu.json`
//! and `OUT/bezier_cpu.md`. Medians of repeated runs; no assertions.

mod cc;
mod cc_creased;
mod cc_gpu;
mod cc_view;
mod gpu;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;
use tessera_core::bezier::search::threshold_for_triangles;
use tessera_core::bezier::{
    tessellate_uniform, AdaptiveParams, BezierModel, EdgeTest, PreparedBezier, Tessellation,
};
use tessera_core::measure::{
    bezier_surface_samples, measure_error, ErrorStats, DEFAULT_SAMPLES_PER_SIDE,
};

#[derive(Serialize, Clone)]
struct Row {
    model: String,
    method: String,
    max_depth: Option<u32>,
    threshold: Option<f32>,
    segments: Option<u32>,
    target_triangles: Option<usize>,
    triangles: usize,
    vertices: usize,
    evaluations: u64,
    max_error: f64,
    mean_error: f64,
    p99_error: f64,
    /// Median tessellation time over the repeats, ms.
    time_ms: f64,
    /// Fewest uniform triangles with max error at or under this row's (any segment count).
    uniform_triangles_at_equal_error: Option<usize>,
    /// `triangles / uniform_triangles_at_equal_error`.
    ratio_to_uniform: Option<f64>,
}

impl Row {
    /// A row for one measured tessellation; method parameters are filled in by the caller.
    fn measured(model: &str, method: &str, t: &Tessellation, e: &ErrorStats, time_ms: f64) -> Row {
        Row {
            model: model.into(),
            method: method.into(),
            max_depth: None,
            threshold: None,
            segments: None,
            target_triangles: None,
            triangles: t.mesh.triangle_count(),
            vertices: t.mesh.vertices.len(),
            evaluations: t.evaluations,
            max_error: e.max_error,
            mean_error: e.mean_error,
            p99_error: e.p99_error,
            time_ms,
            uniform_triangles_at_equal_error: None,
            ratio_to_uniform: None,
        }
    }
}

/// The median of some timings.
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median time in ms of `repeats` runs of `f`, and the last run's result.
pub(crate) fn median_time<T>(repeats: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut times = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let out = f();
        times.push(t.elapsed().as_secs_f64() * 1e3);
        last = Some(out);
    }
    (median(times), last.expect("repeats > 0"))
}

/// Writes `OUT/NAME.json` and `OUT/NAME.md` (the table `cargo xtask bench` pastes).
pub(crate) fn write_results(
    out_dir: &Path,
    name: &str,
    rows: &impl serde::Serialize,
    table: String,
) {
    let json = serde_json::to_string_pretty(rows).expect("rows serialize");
    std::fs::write(out_dir.join(format!("{name}.json")), json).expect("write json");
    std::fs::write(out_dir.join(format!("{name}.md")), table).expect("write md");
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out_dir = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("bench"));
    let quick = args.iter().any(|a| a == "--quick");
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/teaset");
    let only = args
        .iter()
        .position(|a| a == "--only")
        .and_then(|i| args.get(i + 1))
        .cloned();
    // `--model NAME`: only the Catmull-Clark GPU models whose file name contains NAME.
    let model = args
        .iter()
        .position(|a| a == "--model")
        .and_then(|i| args.get(i + 1))
        .cloned();
    std::fs::create_dir_all(&out_dir).expect("create bench output folder");
    // `--only gpu|cpu|cc|creased|ccgpu|view`: one part of the bench (cpu is the Bézier CPU table).
    let part = |name: &str| only.as_deref().is_none_or(|o| o == name);
    if part("gpu") {
        gpu::run(&assets, &out_dir, quick);
    }
    if part("cc") {
        cc::run(&assets.join(".."), &out_dir, quick);
    }
    if part("creased") {
        cc_creased::run(&assets.join(".."), &out_dir, quick, model.as_deref());
    }
    if part("ccgpu") {
        cc_gpu::run(&assets.join(".."), &out_dir, quick, model.as_deref());
    }
    if part("view") {
        cc_view::run(&assets.join(".."), &out_dir, quick);
    }
    if !part("cpu") {
        return;
    }
    let repeats = if quick { 3 } else { 7 };
    let targets: &[usize] = if quick {
        &[2000, 8000]
    } else {
        &[2000, 5000, 10000, 20000, 40000]
    };
    let mut rows = Vec::new();
    for name in ["teapot", "teacup"] {
        let model = BezierModel::load(&assets.join(name)).unwrap_or_else(|e| panic!("{e}"));
        let prep = PreparedBezier::new(&model);
        let samples = bezier_surface_samples(&model, DEFAULT_SAMPLES_PER_SIDE);
        let (lo, hi) = model.bounds();
        let diag = (hi - lo).length();
        // Uniform at every segment count up to well past the finest adaptive result.
        let mut uniform: Vec<Row> = Vec::new();
        for n in 1..=if quick { 24 } else { 56 } {
            let (time_ms, t) = median_time(repeats, || {
                tessellate_uniform(&model, &prep, n).expect("uniform")
            });
            let e = measure_error(&samples, &t.mesh, model.bbox_diag());
            uniform.push(Row {
                segments: Some(n),
                ..Row::measured(name, "uniform", &t, &e, time_ms)
            });
        }
        let uniform_at = |err: f64| {
            uniform
                .iter()
                .filter(|r| r.max_error <= err)
                .map(|r| r.triangles)
                .min()
        };
        for test in [
            EdgeTest::Map2p,
            EdgeTest::Map4p,
            EdgeTest::Map8p,
            EdgeTest::Flat,
        ] {
            for depth in [AdaptiveParams::DEFAULT_MAX_DEPTH, 3] {
                for &target in targets {
                    let base = AdaptiveParams {
                        test,
                        threshold: diag * 1e-3,
                        max_depth: depth,
                    };
                    let Ok(found) = threshold_for_triangles(&prep, base, diag, target) else {
                        continue;
                    };
                    if !found.within_tolerance {
                        continue;
                    }
                    let params = AdaptiveParams {
                        threshold: found.threshold,
                        ..base
                    };
                    let (time_ms, t) = median_time(repeats, || tessellate_adaptive(&prep, &params));
                    let e = measure_error(&samples, &t.mesh, model.bbox_diag());
                    let u = uniform_at(e.max_error);
                    rows.push(Row {
                        max_depth: Some(depth),
                        threshold: Some(found.threshold),
                        target_triangles: Some(target),
                        uniform_triangles_at_equal_error: u,
                        ratio_to_uniform: u.map(|u| t.mesh.triangle_count() as f64 / u as f64),
                        ..Row::measured(name, test.name(), &t, &e, time_ms)
                    });
                }
            }
        }
        rows.extend(uniform);
    }
    std::fs::create_dir_all(&out_dir).expect("create bench output folder");
    write_results(&out_dir, "bezier_cpu", &rows, table(&rows));
    println!("{}", table(&rows));
}

fn tessellate_adaptive(prep: &PreparedBezier, p: &AdaptiveParams) -> Tessellation {
    tessera_core::bezier::tessellate_adaptive(prep, p).expect("adaptive")
}

fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    s += "Measured by `cargo xtask bench` (CPU reference, one thread; error: 64×64 exact samples per patch).\n";
    s += "`vs uniform` = triangles / fewest uniform triangles (any segment count) with max error at or under this row's.\n\n";
    s += "| model | method | depth | triangles | max error | mean error | time (ms) | uniform at equal error | vs uniform |\n";
    s += "|---|---|---|---:|---:|---:|---:|---:|---:|\n";
    for r in rows.iter().filter(|r| r.method != "uniform") {
        s += &format!(
            "| {} | {} | {} | {} | {:.5} | {:.5} | {:.2} | {} | {} |\n",
            r.model,
            r.method,
            r.max_depth.map_or("-".into(), |d| d.to_string()),
            r.triangles,
            r.max_error,
            r.mean_error,
            r.time_ms,
            r.uniform_triangles_at_equal_error
                .map_or("> max swept".into(), |u| u.to_string()),
            r.ratio_to_uniform
                .map_or("-".into(), |x| format!("{x:.2}×")),
        );
    }
    s += "\nUniform peer (selected segment counts):\n\n| model | segments | triangles | max error | mean error | time (ms) |\n|---|---:|---:|---:|---:|---:|\n";
    for r in rows.iter().filter(|r| {
        r.method == "uniform" && matches!(r.segments, Some(4 | 8 | 12 | 16 | 24 | 32 | 48))
    }) {
        s += &format!(
            "| {} | {} | {} | {:.5} | {:.5} | {:.2} |\n",
            r.model,
            r.segments.unwrap_or(0),
            r.triangles,
            r.max_error,
            r.mean_error,
            r.time_ms
        );
    }
    s
}
