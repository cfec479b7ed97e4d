use std::path::Path;
use tessera_core::catmull_clark::*;
use tessera_core::measure::measure_error;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let tol: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(1e-3);
    let t = std::time::Instant::now();
    let model = load_surface(Path::new(&path)).unwrap();
    let diag = {
        let m = tessera_core::io::load_control_mesh(Path::new(&path)).unwrap();
        m.bbox_diag()
    };
    println!(
        "build {:?}, patches {}, irregular {}",
        t.elapsed(),
        model.patches.len(),
        model.patches.iter().filter(|p| !p.is_regular()).count()
    );
    let tol = tol * diag;
    let t = std::time::Instant::now();
    let out = tessellate_adaptive(
        &model,
        &CcParams {
            tolerance: tol,
            max_depth: 10,
        },
    )
    .unwrap();
    println!(
        "adaptive {:?}: tris {} unmet {} max_bound {:.3e} tol {:.3e}",
        t.elapsed(),
        out.mesh.triangle_count(),
        out.unmet,
        out.max_bound,
        tol
    );
    let samples = surface_samples(&model, 32);
    let e = measure_error(&samples, &out.mesh);
    println!("measured max {:.3e} mean {:.3e}", e.max_error, e.mean_error);
    for n in 1..40 {
        let u = tessellate_uniform(&model, n).unwrap();
        let eu = measure_error(&samples, &u.mesh);
        println!(
            "uniform n={n}: tris {} max {:.3e}",
            u.mesh.triangle_count(),
            eu.max_error
        );
        if eu.max_error <= e.max_error {
            println!(
                "ratio {:.3}",
                out.mesh.triangle_count() as f64 / u.mesh.triangle_count() as f64
            );
            break;
        }
    }
}
