//! The Catmull-Clark adaptive stage on one shipped mesh, run in a loop: for interleaved
//! A/B runs of two builds and for `perf record -p PID`.
//!
//! ```sh
//! cargo run --release -p tessera-bench --example cc_stage_profile -- catmark_rook 5e-4 5 search
//! ```
//! Arguments: an OpenSubdiv shape's name (default catmark_rook), the tolerance relative
//! to the diagonal (default 5e-4), the number of runs (default 5) and the first split
//! (`search`, the default, or `midpoint`). Prints the stage's minimum and median time
//! (record, submit, wait), and how many leaves have no marked point on their sides.

use tessera_core::catmull_clark::{
    CcParams, FirstSplit, PatchMesh, SurfaceModel, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::Tolerance;
use tessera_wgpu::catmull_clark::CcStage;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::Kernels;

fn main() {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "catmark_rook".into());
    let rel: f64 = args.next().map_or(5e-4, |s| s.parse().expect("tolerance"));
    let runs: usize = args.next().map_or(5, |s| s.parse().expect("runs"));
    let first_split = match args.next().as_deref() {
        None | Some("search") => FirstSplit::Search,
        Some("midpoint") => FirstSplit::Midpoint,
        Some(other) => panic!("first split: search or midpoint, not {other}"),
    };
    let path = std::path::Path::new("assets/opensubdiv").join(format!("{name}.obj"));
    let control = load_control_mesh(&path).expect("mesh");
    let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
    let params = CcParams {
        tolerance: Tolerance::Relative(rel),
        max_depth: MAX_DEPTH,
        first_split,
        leaf_bound: Default::default(),
    };
    let gpu = Gpu::new().expect("a wgpu adapter");
    let kernels = Kernels::new(&gpu.device);
    let mut stage =
        CcStage::new(&gpu.device, &gpu.queue, &kernels, &model, &params).expect("stage");
    stage
        .run_blocking(&gpu.device, &gpu.queue)
        .expect("first run");
    let mut totals = Vec::new();
    for _ in 0..runs.max(1) {
        let t = std::time::Instant::now();
        stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        totals.push(t.elapsed().as_secs_f64() * 1e3);
    }
    // Leaves whose sides hold no marked point: `cc_polygon`'s emit walks none of their
    // sides again.
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let polygons = stage
        .read_polygons(&gpu.device, &gpu.queue, &status)
        .expect("polygons");
    let plain = polygons
        .side_counts
        .iter()
        .filter(|c| c.iter().all(|&k| k == 0))
        .count();
    println!(
        "leaves without side points {plain} of {}",
        polygons.side_counts.len()
    );
    gpu.check().expect("no wgpu errors");
    totals.sort_by(f64::total_cmp);
    println!(
        "total min {:.1} med {:.1}",
        totals[0],
        totals[totals.len() / 2]
    );
}
