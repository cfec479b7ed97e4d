//! How loose the flatness bound is: against the true largest distance from the surface
//! (33×33 exact samples) to a cell's two triangles (the worse of the two diagonals),
//! - for some irregular patches of a mesh, the bound of the cell `[0, 2^-k]²` at the
//!   extraordinary vertex;
//! - over every patch, the bound of the whole patch (quantiles);
//! - with a tolerance R (relative to the control mesh's diagonal, as the CLI and the
//!   bench take it): how many whole patches pass the bound, and how many would pass by
//!   the sampled error of the worse and of the better diagonal.
//!
//! `cargo run --release -p tessera-core --example cc_bound_slack -- assets/catmull_clark/spot_control_mesh.obj [R]`
use std::path::Path;
use tessera_core::catmull_clark::*;
use tessera_core::measure::closest_point_on_triangle;

/// The bound of box `b = [u0, u1, v0, v1]` of patch `p`, and the sampled distances to
/// the worse and to the better of its two triangulations.
fn bound_and_truth(model: &SurfaceModel, p: usize, b: [f64; 4]) -> (f64, f64, f64) {
    let bound = adaptive::flatness_bound(model, p, b);
    let c = [(b[0], b[2]), (b[1], b[2]), (b[1], b[3]), (b[0], b[3])]
        .map(|(u, v)| model.eval(p, u, v).position);
    let diagonals = [
        [[c[0], c[1], c[2]], [c[0], c[2], c[3]]],
        [[c[0], c[1], c[3]], [c[1], c[2], c[3]]],
    ];
    let mut worst = [0f64; 2];
    for j in 0..=32 {
        for i in 0..=32 {
            let (u, v) = (i as f64 / 32.0, j as f64 / 32.0);
            let x = model
                .eval(p, b[0] + (b[1] - b[0]) * u, b[2] + (b[3] - b[2]) * v)
                .position;
            for (w, tris) in worst.iter_mut().zip(&diagonals) {
                let d = tris
                    .iter()
                    .map(|t| (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length())
                    .fold(f64::INFINITY, f64::min);
                *w = w.max(d);
            }
        }
    }
    (bound, worst[0].max(worst[1]), worst[0].min(worst[1]))
}

fn main() {
    let path = std::env::args().nth(1).unwrap();
    let model = load_surface(Path::new(&path)).unwrap();
    for p in (0..model.patches.len())
        .filter(|&p| !model.patches[p].is_regular())
        .step_by(37)
        .take(8)
    {
        let mut line = format!("patch {p:4}:");
        for k in [1, 3, 5, 7, 9] {
            let s = 2f64.powi(-k);
            let (bound, worst, _) = bound_and_truth(&model, p, [0.0, s, 0.0, s]);
            line += &format!("  k{k} {bound:.1e}/{worst:.1e}={:.1}", bound / worst);
        }
        println!("{line}");
    }
    let whole: Vec<(f64, f64, f64)> = model
        .mesh
        .surface_patches()
        .map(|p| bound_and_truth(&model, p, [0.0, 1.0, 0.0, 1.0]))
        .collect();
    let mut ratios: Vec<f64> = whole
        .iter()
        .map(|(bound, worst, _)| bound / worst)
        .collect();
    ratios.sort_by(f64::total_cmp);
    let q = |f: f64| ratios[((ratios.len() - 1) as f64 * f).round() as usize];
    println!(
        "whole patches ({}): bound / true min {:.2}, p10 {:.2}, median {:.2}, p90 {:.2}, max {:.2}",
        ratios.len(),
        q(0.0),
        q(0.1),
        q(0.5),
        q(0.9),
        q(1.0)
    );
    if let Some(rel) = std::env::args().nth(2) {
        let rel: f64 = rel.parse().expect("a relative tolerance");
        let control = tessera_core::io::load_control_mesh(Path::new(&path)).unwrap();
        let eps = rel * control.bbox_diag();
        let pass = |k: usize| whole.iter().filter(|w| [w.0, w.1, w.2][k] <= eps).count();
        println!(
            "whole patches within {eps:.4e}: by the bound {}, by the sampled error of the worse diagonal {}, of the better {}",
            pass(0),
            pass(1),
            pass(2)
        );
    }
}
