//! Catmull-Clark with creases: every shipped OpenSubdiv shape with crease or corner tags,
//! tessellated adaptively with its creases. Per shape: the measured max error against
//! the exact (creased) surface beside the tolerance it must stay under, and the triangles
//! against uniform tessellation at equal measured max error; on car, bishop and rook at
//! three tolerances. With `TESSERA_OSD_EVAL` set (as `cargo xtask bench` sets it), also
//! the largest distance from OpenSubdiv's own limit surface (Bfr) at random `(face, u, v)`.
//! Writes `OUT/catmull_clark_creased.{json,md}`.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use tessera_core::catmull_clark::{
    patch_mesh, surface_samples, tessellate_adaptive, CcParams, SurfaceModel, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::measure_error;
use tessera_core::Tolerance;

#[derive(Serialize)]
struct Row {
    model: String,
    patches: usize,
    sharp_edges: usize,
    sharp_vertices: usize,
    prepare_ms: f64,
    tolerance_rel: f64,
    tolerance: f64,
    triangles: usize,
    unmet: usize,
    guaranteed_error: f64,
    max_error: f64,
    /// `max_error ≤ tolerance`.
    within_tolerance: bool,
    time_ms: f64,
    uniform_segments: u32,
    uniform_triangles: usize,
    uniform_max_error: f64,
    ratio_to_uniform: f64,
    /// The same shape with `--no-creases`, same tolerance: its triangles.
    smooth_triangles: usize,
    /// Largest distance from OpenSubdiv's limit surface at random `(face, u, v)`,
    /// relative to the bounding-box diagonal (when the OpenSubdiv helper is available).
    opensubdiv_max_rel: Option<f64>,
    opensubdiv_points: usize,
    /// Bfr, or Far where Bfr departs from it.
    opensubdiv_reference: Option<&'static str>,
}

/// Shapes with many patches, measured at three tolerances.
const DETAILED: [&str; 3] = ["catmark_car", "catmark_bishop", "catmark_rook"];

pub fn run(assets: &Path, out_dir: &Path, quick: bool, filter: Option<&str>) {
    let mut rows = Vec::new();
    let mut refused = Vec::new();
    for rel in tessera_tests::osd::sharp_shapes() {
        let path = assets.join(rel);
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        if filter.is_some_and(|f| !name.contains(f)) {
            continue;
        }
        let mut control = load_control_mesh(&path).expect("shipped mesh");
        let t = Instant::now();
        let mesh = match patch_mesh(&mut control, true) {
            Ok(mesh) => mesh,
            Err(e) => {
                eprintln!("creased {name}: refused: {e}");
                refused.push(Refused {
                    model: name,
                    error: e.to_string(),
                });
                continue;
            }
        };
        let model = SurfaceModel::new(mesh, TREE_DEPTH);
        let prepare_ms = t.elapsed().as_secs_f64() * 1e3;
        let mut smooth_control = control.clone();
        smooth_control.drop_creases("--no-creases");
        let smooth = SurfaceModel::new(
            patch_mesh(&mut smooth_control, true).expect("valid mesh"),
            TREE_DEPTH,
        );
        let detailed = DETAILED.contains(&name.as_str());
        let tolerances: &[f64] = match (detailed, quick) {
            (true, false) => &[3e-3, 1e-3, 3e-4],
            _ => &[1e-3],
        };
        let osd = opensubdiv_agreement(&name, &control, &model, if quick { 100 } else { 400 });
        let samples = surface_samples(&model, 32);
        // The grids are only counted and measured here: one run each.
        let mut uniform = crate::cc::UniformLadder::new(&model, &samples, 1);
        for &rel in tolerances {
            let params = CcParams {
                tolerance: Tolerance::Relative(rel),
                max_depth: MAX_DEPTH,
                first_split: Default::default(),
                leaf_bound: Default::default(),
            };
            let tolerance = params.epsilon(&model);
            let (ms, out) = crate::median_time(if quick { 1 } else { 3 }, || {
                tessellate_adaptive(&model, &params).expect("adaptive")
            });
            let e = measure_error(&samples, &out.mesh, model.mesh.control_diag);
            let n = uniform.segments_within(e.max_error);
            let (ut, ue, _) = uniform.at(n);
            let smooth_out = tessellate_adaptive(&smooth, &params).expect("smooth");
            let row = Row {
                model: name.clone(),
                patches: model.mesh.surface_patches().count(),
                sharp_edges: model.mesh.control_sharpness.edges.len(),
                sharp_vertices: model.mesh.control_sharpness.vertices.len(),
                prepare_ms,
                tolerance_rel: rel,
                tolerance,
                triangles: out.mesh.triangle_count(),
                unmet: out.unmet,
                guaranteed_error: out.max_bound,
                max_error: e.max_error,
                within_tolerance: e.max_error <= tolerance,
                time_ms: ms,
                uniform_segments: n,
                uniform_triangles: ut,
                uniform_max_error: ue.max_error,
                ratio_to_uniform: out.mesh.triangle_count() as f64 / ut as f64,
                smooth_triangles: smooth_out.mesh.triangle_count(),
                opensubdiv_max_rel: osd.map(|o| o.0),
                opensubdiv_points: osd.map_or(0, |o| o.1),
                opensubdiv_reference: osd.map(|o| o.2),
            };
            eprintln!(
                "creased {} {rel:e}: {} tris, max {:.3e} ≤ ε {:.3e}: {}, uniform n={n} {} tris: {:.3}×; OpenSubdiv {:?}",
                row.model,
                row.triangles,
                row.max_error,
                row.tolerance,
                row.within_tolerance,
                row.uniform_triangles,
                row.ratio_to_uniform,
                row.opensubdiv_max_rel
            );
            rows.push(row);
        }
    }
    let mut md = table(&rows);
    for r in &refused {
        md += &format!(
            "\nRefused: `{}` ({}; the topology check turns it away before anything is tessellated).\n",
            r.model,
            r.error.rsplit(": ").next().unwrap_or(&r.error)
        );
    }
    crate::write_results(
        out_dir,
        "catmull_clark_creased",
        &Results { rows, refused },
        md,
    );
}

#[derive(Serialize)]
struct Refused {
    model: String,
    error: String,
}

#[derive(Serialize)]
struct Results {
    rows: Vec<Row>,
    /// Shapes the topology check refuses (with the reason).
    refused: Vec<Refused>,
}

/// Largest distance from OpenSubdiv's surface, relative to the bounding-box diagonal,
/// how many points were compared, and the reference: Bfr at `n` random points, or, on
/// `catmark_chaikin1`, where Bfr departs from Far's own refinement, Far's limit masks at
/// the first refinement's vertices. `None` without the helper.
fn opensubdiv_agreement(
    name: &str,
    control: &tessera_core::catmull_clark::ControlMesh,
    model: &SurfaceModel,
    n: usize,
) -> Option<(f64, usize, &'static str)> {
    use tessera_tests::osd;
    std::env::var_os("TESSERA_OSD_EVAL")?;
    if name == "catmark_chaikin1" {
        let points = osd::first_level_points(control);
        let c = osd::compare_with(
            control,
            |f, u, v| model.eval_face(f, u, v).map(|p| p.position),
            &points,
            osd::far_limit_points(control, &points),
        );
        return Some((c.relative(), c.evaluated, "Far"));
    }
    let points = osd::sample_points(control, n, &mut tessera_tests::fuzz::Rng::new(0x05d_be4c));
    let c = osd::compare(control, model, &points);
    Some((c.relative(), c.evaluated, "Bfr"))
}

fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| model | patches | sharp edges | sharp vertices | prepare ms | ε (of diagonal) | tris | unmet | measured max (model units) | ≤ ε | time ms | uniform n | uniform tris | **ratio** | smooth tris | OpenSubdiv max (of diagonal) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.0} | {:.0e} | {} | {} | {:.2e} | {} | {:.1} | {} | {} | **{:.2}** | {} | {} |\n",
            r.model,
            r.patches,
            r.sharp_edges,
            r.sharp_vertices,
            r.prepare_ms,
            r.tolerance_rel,
            r.triangles,
            r.unmet,
            r.max_error,
            if r.within_tolerance { "yes" } else { "**no**" },
            r.time_ms,
            r.uniform_segments,
            r.uniform_triangles,
            r.ratio_to_uniform,
            r.smooth_triangles,
            r.opensubdiv_max_rel.map_or("—".to_string(), |e| format!(
                "{e:.1e} ({} points, {})",
                r.opensubdiv_points,
                r.opensubdiv_reference.unwrap_or("")
            )),
        );
    }
    s
}
