//! The Bézier stage at 1024 patches (32 teapots) and one threshold, run in a loop: for
//! comparing two builds of the kernels in interleaved runs (this machine's speed drifts
//! more than most changes gain), and for `perf record -p PID` while it runs.
//!
//! ```sh
//! cargo run --release -p tessera-bench --example stage_profile -- 0.002 5
//! ```
//! Arguments: the threshold relative to the teapot's diagonal (default 0.002, the bench's
//! 0.0166) and the number of runs (default 5). Prints the stage's minimum and median time
//! (record, submit, wait) and each kernel's minimum (one kernel per submission).

use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::Kernels;

fn main() {
    let mut args = std::env::args().skip(1);
    let rel: f32 = args.next().map_or(0.002, |s| s.parse().expect("threshold"));
    let runs: usize = args.next().map_or(5, |s| s.parse().expect("runs"));
    let gpu = Gpu::new().expect("a wgpu adapter");
    let teapot = BezierModel::load(std::path::Path::new("assets/teaset/teapot")).expect("teapot");
    let (lo, hi) = teapot.bounds();
    let diag = (hi - lo).length();
    let prep = PreparedBezier::new(&teapot.grid_of_copies(32, 1.2 * diag));
    let params = AdaptiveParams {
        test: EdgeTest::Map4p,
        threshold: rel * diag,
        max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
    };
    let kernels = Kernels::new(&gpu.device);
    let mut stage =
        BezierStage::new(&gpu.device, &gpu.queue, &kernels, &prep, &params).expect("stage");
    stage
        .run_blocking(&gpu.device, &gpu.queue)
        .expect("first run");
    let mut kernel_min: Vec<(&str, f64)> = Vec::new();
    let mut totals = Vec::new();
    for _ in 0..runs.max(1) {
        let k = stage
            .profile_kernels(&gpu.device, &gpu.queue)
            .expect("profile");
        if kernel_min.is_empty() {
            kernel_min = k.clone();
        }
        for (m, x) in kernel_min.iter_mut().zip(&k) {
            m.1 = m.1.min(x.1);
        }
        let t = std::time::Instant::now();
        stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        totals.push(t.elapsed().as_secs_f64() * 1e3);
    }
    gpu.check().expect("no wgpu errors");
    totals.sort_by(f64::total_cmp);
    let kernels: Vec<String> = kernel_min
        .iter()
        .map(|(k, v)| format!("{k} {v:.1}"))
        .collect();
    println!(
        "total min {:.1} med {:.1} | {}",
        totals[0],
        totals[totals.len() / 2],
        kernels.join(", ")
    );
}
