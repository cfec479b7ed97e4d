//! Catmull-Clark: adaptive (Lai–Cheng, guaranteed bound) against uniform tessellation
//! at equal measured max error, any segment count per patch, and the paper's own
//! subdivision (midpoint splits alone, [`FirstSplit::Midpoint`]) against uniform the same
//! way. Writes
//! `OUT/catmull_clark_cpu.{json,md}`. Creases and corners are dropped (`--no-creases`):
//! [`super::cc_creased`] measures the creased surfaces.

use std::path::Path;

use serde::Serialize;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive, tessellate_uniform, CcParams, FirstSplit, LeafBound,
    PatchMesh, SurfaceModel, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::{measure_error, ErrorStats};
use tessera_core::Tolerance;

#[derive(Serialize)]
struct Row {
    model: String,
    /// Detailed models carry the ≤ 0.5× target; every model the ≤ 1.25× one.
    detailed: bool,
    patches: usize,
    tolerance_rel: f64,
    tolerance: f64,
    triangles: usize,
    guaranteed_error: f64,
    max_error: f64,
    mean_error: f64,
    time_ms: f64,
    /// Flatness bounds computed per leaf, the first-split search's trials included.
    bounds_per_leaf: f64,
    /// Fewest triangles of a uniform grid (n × n per patch, any n) whose measured max
    /// error is at or under this row's.
    uniform_segments: u32,
    uniform_triangles: usize,
    uniform_max_error: f64,
    uniform_time_ms: f64,
    ratio_to_uniform: f64,
    /// The same against uniform at max error ≤ the tolerance (what a user asking for ε
    /// would pick with a uniform grid, knowing its error).
    uniform_triangles_at_tolerance: usize,
    ratio_at_tolerance: f64,
    /// The paper's subdivision (midpoint splits alone) at the same tolerance: its
    /// triangles, time, and ratio to the uniform grid at or under its measured max error.
    midpoint_triangles: usize,
    midpoint_time_ms: f64,
    midpoint_ratio_to_uniform: f64,
    /// The CPU's leaf bound for a cell's own triangles ([`LeafBound::Triangles`], the
    /// search's first splits) at the same tolerance, likewise.
    own_triangles: usize,
    own_max_error: f64,
    own_time_ms: f64,
    own_ratio_to_uniform: f64,
}

/// (file, detailed)
const MODELS: [(&str, bool); 11] = [
    ("opensubdiv/catmark_car.obj", true),
    ("opensubdiv/catmark_bishop.obj", true),
    ("opensubdiv/catmark_rook.obj", true),
    ("catmull_clark/spot_control_mesh.obj", true),
    ("catmull_clark/blub_control_mesh.obj", true),
    ("catmull_clark/penguin_control_mesh.obj", true),
    // Non-manifold: cut into its three sheets (`ControlMesh::split_non_manifold`).
    ("opensubdiv/catmark_fan.obj", true),
    ("opensubdiv/catmark_cube.obj", false),
    ("opensubdiv/catmark_torus.obj", false),
    ("opensubdiv/catmark_pyramid.obj", false),
    ("opensubdiv/catmark_xord_interior.obj", false),
];

/// Uniform tessellation by segment count: triangles, measured error (against `samples`)
/// and median time of each grid `n × n` per patch, each measured once, when first asked.
pub struct UniformLadder<'a> {
    model: &'a SurfaceModel,
    samples: &'a [glam::DVec3],
    repeats: usize,
    grids: Vec<(usize, ErrorStats, f64)>,
}

impl<'a> UniformLadder<'a> {
    pub fn new(model: &'a SurfaceModel, samples: &'a [glam::DVec3], repeats: usize) -> Self {
        UniformLadder {
            model,
            samples,
            repeats,
            grids: Vec::new(),
        }
    }

    /// The grid of `n` segments per patch side.
    pub fn at(&mut self, n: u32) -> (usize, ErrorStats, f64) {
        while self.grids.len() < n as usize {
            let k = self.grids.len() as u32 + 1;
            let (ms, t) = crate::median_time(self.repeats, || {
                tessellate_uniform(self.model, k).expect("uniform")
            });
            self.grids.push((
                t.mesh.triangle_count(),
                measure_error(self.samples, &t.mesh, self.model.mesh.control_diag),
                ms,
            ));
        }
        self.grids[n as usize - 1]
    }

    /// The fewest segments (at most 256) whose measured max error is at or under `error`.
    pub fn segments_within(&mut self, error: f64) -> u32 {
        let mut n = 1;
        while self.at(n).1.max_error > error && n < 256 {
            n += 1;
        }
        n
    }
}

pub fn run(assets: &Path, out_dir: &Path, quick: bool) {
    let tolerances: &[f64] = if quick { &[3e-3] } else { &[3e-3, 1e-3, 3e-4] };
    let repeats = if quick { 1 } else { 3 };
    let mut rows = Vec::new();
    for (file, detailed) in MODELS {
        let path = assets.join(file);
        let mut control = load_control_mesh(&path).expect("shipped mesh");
        // The smooth surfaces (`--no-creases`), comparable across the tables and with
        // the GPU stage; the creased ones have their own table.
        control.drop_creases("--no-creases");
        let cut = control.split_non_manifold().expect("sheets that meet");
        let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid mesh"), TREE_DEPTH);
        let samples = surface_samples(&model, 32);
        let mut uniform = UniformLadder::new(&model, &samples, repeats);
        for &rel in tolerances {
            let params = CcParams {
                tolerance: Tolerance::Relative(rel),
                max_depth: MAX_DEPTH,
                first_split: Default::default(),
                leaf_bound: Default::default(),
            };
            let tolerance = params.epsilon(&model);
            let (ms, out) = crate::median_time(repeats, || {
                tessellate_adaptive(&model, &params).expect("adaptive")
            });
            let e = measure_error(&samples, &out.mesh, model.mesh.control_diag);
            let n = uniform.segments_within(e.max_error);
            let (ut, ue, ums) = uniform.at(n);
            let m = uniform.segments_within(tolerance);
            let ut_tol = uniform.at(m).0;
            let midpoint = CcParams {
                first_split: FirstSplit::Midpoint,
                leaf_bound: Default::default(),
                ..params
            };
            let (midpoint_ms, paper) = crate::median_time(repeats, || {
                tessellate_adaptive(&model, &midpoint).expect("midpoint")
            });
            let paper_error =
                measure_error(&samples, &paper.mesh, model.mesh.control_diag).max_error;
            let k = uniform.segments_within(paper_error);
            let paper_triangles = paper.mesh.triangle_count();
            let own_params = CcParams {
                leaf_bound: LeafBound::Triangles,
                ..params
            };
            let (own_ms, own) = crate::median_time(repeats, || {
                tessellate_adaptive(&model, &own_params).expect("own triangles")
            });
            let own_error = measure_error(&samples, &own.mesh, model.mesh.control_diag).max_error;
            let j = uniform.segments_within(own_error);
            let row = Row {
                model: format!(
                    "{}{}",
                    Path::new(file).file_stem().unwrap().to_string_lossy(),
                    if cut > 0 { " (sheets cut apart)" } else { "" }
                ),
                detailed,
                patches: model.mesh.surface_patches().count(),
                tolerance_rel: rel,
                tolerance,
                triangles: out.mesh.triangle_count(),
                guaranteed_error: out.max_bound,
                max_error: e.max_error,
                mean_error: e.mean_error,
                time_ms: ms,
                bounds_per_leaf: out.bounds as f64 / out.leaves.max(1) as f64,
                uniform_segments: n,
                uniform_triangles: ut,
                uniform_max_error: ue.max_error,
                uniform_time_ms: ums,
                ratio_to_uniform: out.mesh.triangle_count() as f64 / ut as f64,
                uniform_triangles_at_tolerance: ut_tol,
                ratio_at_tolerance: out.mesh.triangle_count() as f64 / ut_tol as f64,
                midpoint_triangles: paper_triangles,
                midpoint_time_ms: midpoint_ms,
                midpoint_ratio_to_uniform: paper_triangles as f64 / uniform.at(k).0 as f64,
                own_triangles: own.mesh.triangle_count(),
                own_max_error: own_error,
                own_time_ms: own_ms,
                own_ratio_to_uniform: own.mesh.triangle_count() as f64 / uniform.at(j).0 as f64,
            };
            eprintln!(
                "cc {} {rel:e}: {} tris (max {:.3e}), uniform n={n} {} tris (max {:.3e}): {:.3}×; own triangles {} ({:.3}×)",
                row.model,
                row.triangles,
                row.max_error,
                row.uniform_triangles,
                row.uniform_max_error,
                row.ratio_to_uniform,
                row.own_triangles,
                row.own_ratio_to_uniform
            );
            rows.push(row);
        }
    }
    crate::write_results(out_dir, "catmull_clark_cpu", &rows, table(&rows));
}

fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| model | patches | ε (of diagonal) | adaptive tris | guaranteed bound (model units) | measured max (model units) | mean | time ms | bounds per leaf | uniform n | uniform tris | uniform max | **ratio** | ratio at ε | midpoint (paper) tris | midpoint ms | midpoint ratio | own-triangles tris | own max | own ms | **own ratio** |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {}{} | {} | {:.0e} | {} | {:.2e} | {:.2e} | {:.2e} | {:.1} | {:.2} | {} | {} | {:.2e} | **{:.2}** | {:.2} | {} | {:.1} | {:.2} | {} | {:.2e} | {:.1} | **{:.2}** |\n",
            r.model,
            if r.detailed { "" } else { " (simple)" },
            r.patches,
            r.tolerance_rel,
            r.triangles,
            r.guaranteed_error,
            r.max_error,
            r.mean_error,
            r.time_ms,
            r.bounds_per_leaf,
            r.uniform_segments,
            r.uniform_triangles,
            r.uniform_max_error,
            r.ratio_to_uniform,
            r.ratio_at_tolerance,
            r.midpoint_triangles,
            r.midpoint_time_ms,
            r.midpoint_ratio_to_uniform,
            r.own_triangles,
            r.own_max_error,
            r.own_time_ms,
            r.own_ratio_to_uniform
        );
    }
    s
}
