//! What any per-patch split could reach at a given max error, for judging the adaptive
//! tessellation's triangle counts: per patch, the smallest grid (nu × nv cells, two
//! triangles each, the better diagonal per cell) whose triangles lie within E of the
//! patch's 32 × 32 exact surface samples (distance to the patch's own triangles),
//! summed over the patches. Optimistic: it knows the true errors, where a tessellator
//! must bound them, and it leaves out the triangles that fit neighbours' points.
//!
//! `cargo run --release -p tessera-core --example cc_split_oracle -- assets/catmull_clark/spot_control_mesh.obj 6.69e-3 7.24e-3`
//!
//! Arguments: the mesh, then one or more max errors E in model units.
use glam::DVec3;
use tessera_core::catmull_clark::TREE_DEPTH;
use tessera_core::catmull_clark::{PatchMesh, SurfaceModel};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::closest_point_on_triangle;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("obj");
    let errors: Vec<f64> = args.map(|s| s.parse().unwrap()).collect();
    let control = load_control_mesh(std::path::Path::new(&path)).expect("mesh");
    let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
    let grids = [
        (1, 1),
        (1, 2),
        (2, 1),
        (2, 2),
        (1, 3),
        (3, 1),
        (2, 3),
        (3, 2),
        (3, 3),
        (4, 4),
    ];
    let n = 32;
    let mut per_patch = Vec::new();
    for p in model.mesh.surface_patches() {
        // (u, v) and position of each sample.
        let samples: Vec<(f64, f64, DVec3)> = (0..n * n)
            .map(|k| {
                let (u, v) = (
                    (k % n) as f64 / (n - 1) as f64,
                    (k / n) as f64 / (n - 1) as f64,
                );
                (u, v, model.eval(p, u, v).position)
            })
            .collect();
        let errs: Vec<f64> = grids
            .iter()
            .map(|&(nu, nv)| {
                let q = |a: usize, b: usize| {
                    model
                        .eval(p, a as f64 / nu as f64, b as f64 / nv as f64)
                        .position
                };
                // Each cell's two triangulations: diagonal 0–2, then 1–3.
                let mut cells = Vec::new();
                for b in 0..nv {
                    for a in 0..nu {
                        let (c00, c10, c01, c11) =
                            (q(a, b), q(a + 1, b), q(a, b + 1), q(a + 1, b + 1));
                        cells.push([
                            [c00, c10, c11],
                            [c00, c11, c01],
                            [c00, c10, c01],
                            [c10, c11, c01],
                        ]);
                    }
                }
                // Each cell keeps the triangulation nearer its own samples.
                let d = |s: DVec3, t: &[DVec3; 3]| {
                    (closest_point_on_triangle(s, t[0], t[1], t[2]) - s).length()
                };
                let mut tris: Vec<[DVec3; 3]> = Vec::new();
                for (ci, cell) in cells.iter().enumerate() {
                    let (a, b) = ((ci % nu) as f64, (ci / nu) as f64);
                    let inside = |t: f64, lo: f64| t >= lo - 1e-9 && t <= lo + 1.0 + 1e-9;
                    let own: Vec<DVec3> = samples
                        .iter()
                        .filter(|(u, v, _)| inside(u * nu as f64, a) && inside(v * nv as f64, b))
                        .map(|&(_, _, s)| s)
                        .collect();
                    let e = |t0: &[DVec3; 3], t1: &[DVec3; 3]| {
                        own.iter()
                            .map(|&s| d(s, t0).min(d(s, t1)))
                            .fold(0.0, f64::max)
                    };
                    if e(&cell[0], &cell[1]) <= e(&cell[2], &cell[3]) {
                        tris.extend([cell[0], cell[1]]);
                    } else {
                        tris.extend([cell[2], cell[3]]);
                    }
                }
                samples
                    .iter()
                    .map(|&(_, _, s)| tris.iter().map(|t| d(s, t)).fold(f64::MAX, f64::min))
                    .fold(0.0, f64::max)
            })
            .collect();
        per_patch.push(errs);
    }
    let patches = per_patch.len();
    for &e in &errors {
        // Patches by the triangles their smallest grid makes (none: no grid up to 4 × 4
        // is within E; counted as 32 triangles).
        let mut by_triangles = std::collections::BTreeMap::<usize, usize>::new();
        for errs in &per_patch {
            let t = grids
                .iter()
                .zip(errs)
                .filter(|(_, &x)| x <= e)
                .map(|(&(a, b), _)| 2 * a * b)
                .min()
                .unwrap_or(32);
            *by_triangles.entry(t).or_default() += 1;
        }
        let tris: usize = by_triangles.iter().map(|(t, n)| t * n).sum();
        println!(
            "E {e:.3e}: {patches} patches, {tris} triangles at best (patches by triangles: {by_triangles:?})"
        );
    }
}
