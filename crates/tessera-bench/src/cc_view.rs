//! Catmull-Clark close-ups (CPU reference): a tolerance in pixels against the same view
//! culled at the one world tolerance that guarantees the same pixel error everywhere in
//! view, `p` times the nearest visible depth over the focal length in pixels. Per model
//! and `p`: triangles, time, the measured `max_error_px` of both, and the view's depth
//! range. Writes `OUT/catmull_clark_view.{json,md}`.

use std::path::Path;

use glam::DVec3;
use serde::Serialize;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive_in_view, CcParams, FirstSplit, PatchMesh, SurfaceModel,
    ViewTolerance, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::max_error_px;
use tessera_core::{Tolerance, View};

use crate::median_time;

#[derive(Serialize)]
struct Row {
    model: String,
    patches: usize,
    pixels: f64,
    /// Farthest over nearest depth of the surface samples in view.
    depth_range: f64,
    px_triangles: usize,
    px_ms: f64,
    px_max_error_px: f64,
    px_unmet: usize,
    culled_patches: usize,
    /// `p · nearest visible depth / focal length in pixels`.
    world_tolerance: f64,
    world_triangles: usize,
    world_ms: f64,
    world_max_error_px: f64,
    triangles_ratio: f64,
    time_ratio: f64,
}

/// Vertical field of view, viewport and the sampling of the measurement.
const FOVY_DEG: f64 = 40.0;
const VIEWPORT: (u32, u32) = (800, 600);
const SAMPLES: usize = 16;

/// A view from just off one end of the model's longest side, a little above, looking
/// along it: the near end large on screen, the far end small.
fn close_up(model: &SurfaceModel) -> View {
    let samples = surface_samples(model, 2);
    let lo = samples.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = samples.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let (c, size) = ((lo + hi) / 2.0, hi - lo);
    let long = size.max_element();
    let axis = if size.x == long {
        DVec3::X
    } else if size.y == long {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let up = if axis == DVec3::Z { DVec3::Y } else { DVec3::Z };
    let height = size.dot(up);
    let eye = c - axis * 0.505 * long + up * 0.2 * height;
    let target = c + axis * 0.5 * long;
    View::look_at(
        eye,
        target,
        up,
        FOVY_DEG.to_radians(),
        VIEWPORT,
        0.01 * long,
    )
    .expect("view")
}

pub fn run(assets: &Path, out_dir: &Path, quick: bool) {
    let models: &[&str] = if quick {
        &["catmull_clark/spot_control_mesh.obj"]
    } else {
        &[
            "opensubdiv/catmark_car.obj",
            "catmull_clark/spot_control_mesh.obj",
        ]
    };
    let repeats = if quick { 1 } else { 3 };
    let mut rows = Vec::new();
    for rel in models {
        let control = load_control_mesh(&assets.join(rel)).expect("mesh");
        let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
        let name = Path::new(rel)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let view = close_up(&model);
        let samples = surface_samples(&model, SAMPLES);
        let depths: Vec<f64> = samples
            .iter()
            .filter(|&&p| view.contains(p))
            .map(|&p| view.clip_of(p).w)
            .collect();
        let nearest = depths.iter().copied().fold(f64::INFINITY, f64::min);
        let farthest = depths.iter().copied().fold(0.0, f64::max);
        let focal = 0.5 * VIEWPORT.1 as f64 / (0.5 * FOVY_DEG.to_radians()).tan();
        for pixels in [1.0, 0.5] {
            let run = |tolerance: Tolerance, px: Option<f64>| {
                let params = CcParams {
                    tolerance,
                    max_depth: MAX_DEPTH,
                    first_split: FirstSplit::Midpoint,
                    leaf_bound: Default::default(),
                };
                let vt = ViewTolerance {
                    view,
                    pixels: px,
                    cull: true,
                    max_triangles: None,
                };
                median_time(repeats, || {
                    tessellate_adaptive_in_view(&model, &params, &vt).expect("tessellate")
                })
            };
            let (px_ms, px) = run(Tolerance::Relative(1.0), Some(pixels));
            let world_tolerance = pixels * nearest / focal;
            let (world_ms, world) = run(Tolerance::Absolute(world_tolerance), None);
            let err = |m| max_error_px(&samples, m, &view).unwrap_or(0.0);
            let row = Row {
                model: name.clone(),
                patches: model.mesh.surface_patches().count(),
                pixels,
                depth_range: farthest / nearest,
                px_triangles: px.mesh.triangle_count(),
                px_ms,
                px_max_error_px: err(&px.mesh),
                px_unmet: px.unmet,
                culled_patches: px.culled_patches,
                world_tolerance,
                world_triangles: world.mesh.triangle_count(),
                world_ms,
                world_max_error_px: err(&world.mesh),
                triangles_ratio: px.mesh.triangle_count() as f64
                    / world.mesh.triangle_count().max(1) as f64,
                time_ratio: px_ms / world_ms,
            };
            eprintln!(
                "cc view {name} {pixels} px: {} tris ({:.0} ms) against {} ({:.0} ms) at {world_tolerance:.2e}",
                row.px_triangles, px_ms, row.world_triangles, world_ms
            );
            rows.push(row);
        }
    }
    let mut s = format!(
        "Close-ups ({}×{} pixels, {FOVY_DEG}° vertical field of view, from just off one end of the model's longest side, looking along it; CPU reference, midpoint splits, medians of {repeats}): the tolerance in pixels against the same view culled at the world tolerance that guarantees the same pixel error everywhere in view (p × nearest visible depth / focal length). Measured pixel errors over {SAMPLES}×{SAMPLES} samples per patch inside the frustum (the target: at most 0.5× the triangles):\n\n",
        VIEWPORT.0, VIEWPORT.1
    );
    s += "| model | patches | p (px) | depth range | triangles in pixels | ms | measured px | unmet | culled patches | world ε | triangles at world ε | ms | measured px | **triangles ratio** | time ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in &rows {
        s += &format!(
            "| {} | {} | {} | {:.1}:1 | {} | {:.0} | {:.3} | {} | {} | {:.2e} | {} | {:.0} | {:.3} | **{:.2}** | {:.2} |\n",
            r.model,
            r.patches,
            r.pixels,
            r.depth_range,
            r.px_triangles,
            r.px_ms,
            r.px_max_error_px,
            r.px_unmet,
            r.culled_patches,
            r.world_tolerance,
            r.world_triangles,
            r.world_ms,
            r.world_max_error_px,
            r.triangles_ratio,
            r.time_ratio
        );
    }
    crate::write_results(out_dir, "catmull_clark_view", &rows, s);
}
