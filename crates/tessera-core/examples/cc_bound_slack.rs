//! How loose the flatness bound is at extraordinary vertices: for some irregular patches
//! of a mesh, the bound of the cell `[0, 2^-k]²` at the vertex against the true largest
//! distance from the surface (33×33 exact samples) to the cell's two triangles.
//!
//! `cargo run --release -p tessera-core --example cc_bound_slack -- assets/catmull_clark/spot_control_mesh.obj`
use std::path::Path;
use tessera_core::catmull_clark::*;
use tessera_core::measure::closest_point_on_triangle;
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
            let b = [0.0, s, 0.0, s];
            let bound = adaptive::flatness_bound(&model, p, b);
            let c = [(b[0], b[2]), (b[1], b[2]), (b[1], b[3]), (b[0], b[3])]
                .map(|(u, v)| model.eval(p, u, v).position);
            let mut worst = 0f64;
            for j in 0..=32 {
                for i in 0..=32 {
                    let x = model
                        .eval(p, s * i as f64 / 32.0, s * j as f64 / 32.0)
                        .position;
                    let d = [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]
                        .iter()
                        .map(|t| (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length())
                        .fold(f64::INFINITY, f64::min);
                    worst = worst.max(d);
                }
            }
            line += &format!("  k{k} {:.1e}/{:.1e}={:.1}", bound, worst, bound / worst);
            // bound / true
        }
        println!("{line}");
    }
}
