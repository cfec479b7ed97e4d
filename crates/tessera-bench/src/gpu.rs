//! The GPU stage against the CPU reference: 1, 32 and 1024 patches (one teapot patch, a
//! teapot, 32 teapots side by side) at several thresholds. Tessellation time is the GPU
//! work to completion (record, submit, wait), after a first run that grows the buffers;
//! the CPU reference runs the same stages on one thread. Medians of repeated runs.

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use serde::Serialize;

use crate::median;
use tessera_core::bezier::tessellate::{tessellate_adaptive_timed, StageTimes};
use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::Kernels;

#[derive(Serialize, Clone)]
pub struct GpuRow {
    patches: usize,
    test: String,
    threshold: f32,
    triangles: u32,
    vertices: u32,
    cpu_ms: f64,
    gpu_ms: f64,
    /// `cpu_ms / gpu_ms`.
    speedup: f64,
    gpu_triangles_per_s: f64,
    cpu_triangles_per_s: f64,
    /// Each kernel on its own submission (ms): where the GPU time goes.
    kernels_ms: Vec<(String, f64)>,
    /// The CPU reference's stages (ms, medians), to set beside the kernels.
    cpu_stages_ms: Vec<(String, f64)>,
}

#[derive(Serialize)]
pub struct GpuReport {
    adapter: String,
    repeats: usize,
    rows: Vec<GpuRow>,
}

fn single_patch(base: &BezierModel) -> BezierModel {
    // A body patch: no collapsed side, curved in both directions.
    let net = base.nets[4];
    let points: Vec<Vec3> = net.iter().map(|&i| base.points[i as usize]).collect();
    BezierModel::from_nets(points, vec![std::array::from_fn(|k| k as u32)])
}

pub fn run(assets: &Path, out_dir: &Path, quick: bool) {
    let gpu = match Gpu::new() {
        Ok(g) => g,
        Err(e) => {
            eprintln!("bench: no GPU adapter ({e}); skipping the GPU bench");
            return;
        }
    };
    let kernels = Kernels::new(&gpu.device);
    let teapot = BezierModel::load(&assets.join("teapot")).unwrap_or_else(|e| panic!("{e}"));
    let (lo, hi) = teapot.bounds();
    let diag = (hi - lo).length();
    let repeats = if quick { 3 } else { 7 };
    let thresholds: &[f32] = if quick {
        &[0.004, 0.001]
    } else {
        &[0.008, 0.004, 0.002, 0.001, 0.0005]
    };
    let models = [
        (1, single_patch(&teapot)),
        (32, teapot.clone()),
        (1024, teapot.grid_of_copies(32, 1.2 * diag)),
    ];
    let mut rows = Vec::new();
    for (patches, model) in &models {
        let prep = PreparedBezier::new(model);
        let first = AdaptiveParams {
            test: EdgeTest::Map4p,
            threshold: thresholds[0] * diag,
            max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
        };
        let l = prep.layout;
        let mut stage = BezierStage::with_capacity(
            &gpu.device,
            &gpu.queue,
            &kernels,
            &prep,
            &first,
            (4 * l.coarse_vertices, 24 * l.coarse_triangles),
        )
        .expect("stage");
        for &rel in thresholds {
            let params = AdaptiveParams {
                threshold: rel * diag,
                ..first
            };
            stage
                .set_params(&gpu.device, &gpu.queue, &params)
                .expect("params");
            let status = stage
                .run_blocking(&gpu.device, &gpu.queue)
                .expect("first run");
            // The GPU and the CPU reference run in turns, one run each per round, so that
            // both see the same state of this shared machine: timed in two bursts, the
            // ratio moved with whatever the machine did between them.
            let mut gpu_runs = Vec::new();
            let mut cpu_runs = Vec::new();
            let mut cpu_triangles = 0;
            let mut stages = Vec::new();
            for _ in 0..repeats {
                gpu_runs.push(gpu_run_ms(&gpu, |e| {
                    stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
                }));
                let t = Instant::now();
                let (out, s) = tessellate_adaptive_timed(&prep, &params).expect("cpu");
                cpu_runs.push(t.elapsed().as_secs_f64() * 1e3);
                cpu_triangles = out.mesh.triangle_count();
                stages.push(s);
            }
            gpu.check().expect("no wgpu errors");
            let gpu_ms = median(gpu_runs);
            let cpu_ms = median(cpu_runs);
            // One kernel per submission, for the per-kernel column (not the timed run).
            let kernels_ms = stage
                .profile_kernels(&gpu.device, &gpu.queue)
                .expect("profile");
            let stage_median = |f: fn(&StageTimes) -> f64| median(stages.iter().map(f).collect());
            let cpu_stages_ms = vec![
                ("edge_decide".to_string(), stage_median(|s| s.edge_decide)),
                ("tri_mark".to_string(), stage_median(|s| s.tri_mark)),
                ("emit".to_string(), stage_median(|s| s.emit)),
                ("vertex_eval".to_string(), stage_median(|s| s.vertex_eval)),
            ];
            let triangles = status.indices / 3;
            assert_eq!(
                cpu_triangles, triangles as usize,
                "GPU and CPU triangle counts differ at {patches} patches, threshold {rel}"
            );
            eprintln!(
                "bench gpu: {patches} patches, th {rel}: {triangles} triangles, GPU {gpu_ms:.2} ms, CPU {cpu_ms:.2} ms"
            );
            rows.push(GpuRow {
                patches: *patches,
                test: "map4p".into(),
                threshold: params.threshold,
                triangles,
                vertices: status.vertices,
                cpu_ms,
                gpu_ms,
                speedup: cpu_ms / gpu_ms,
                gpu_triangles_per_s: triangles as f64 / (gpu_ms * 1e-3),
                cpu_triangles_per_s: triangles as f64 / (cpu_ms * 1e-3),
                kernels_ms: kernels_ms
                    .into_iter()
                    .map(|(k, t)| (k.to_string(), t))
                    .collect(),
                cpu_stages_ms,
            });
        }
    }
    let report = GpuReport {
        adapter: gpu.adapter_name(),
        repeats,
        rows,
    };
    crate::write_results(out_dir, "bezier_gpu", &report, table(&report));
}

/// Median over `repeats` runs of what `record` puts into an encoder, submitted and
/// waited for (ms), after runs that keep the GPU busy for [`WARM_UP_MS`].
pub(crate) fn gpu_median_ms(
    gpu: &Gpu,
    repeats: usize,
    mut record: impl FnMut(&mut tessera_wgpu::wgpu::CommandEncoder),
) -> f64 {
    let mut busy = 0.0;
    while busy < WARM_UP_MS {
        busy += gpu_run_ms(gpu, &mut record);
    }
    median((0..repeats).map(|_| gpu_run_ms(gpu, &mut record)).collect())
}

/// How long [`gpu_median_ms`] runs the work untimed first. A discrete GPU left idle
/// while the CPU reference ran drops its clocks, and the first timed runs would read
/// its ramp-up; where one run is longer than this, it costs one run.
const WARM_UP_MS: f64 = 200.0;

/// One run of what `record` puts into an encoder: recorded, submitted and waited for (ms).
fn gpu_run_ms(gpu: &Gpu, record: impl FnOnce(&mut tessera_wgpu::wgpu::CommandEncoder)) -> f64 {
    let t = Instant::now();
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    record(&mut encoder);
    gpu.queue.submit([encoder.finish()]);
    gpu.wait().expect("gpu");
    t.elapsed().as_secs_f64() * 1e3
}

fn table(r: &GpuReport) -> String {
    let mut s = format!(
        "Measured by `cargo xtask bench` on {} (map4p, max depth 6; medians of {} runs, GPU and CPU in turns; GPU time = record + submit + wait, after a first run that sizes the buffers; CPU = the reference twins, one thread).\n\n",
        r.adapter, r.repeats
    );
    s += "| patches | threshold | triangles | CPU (ms) | GPU (ms) | GPU speed-up | GPU triangles/s | GPU kernels alone (ms) | CPU stages (ms) |\n|---:|---:|---:|---:|---:|---:|---:|---|---|\n";
    let list = |times: &[(String, f64)]| {
        let parts: Vec<String> = times.iter().map(|(k, t)| format!("{k} {t:.1}")).collect();
        parts.join(", ")
    };
    for row in &r.rows {
        s += &format!(
            "| {} | {:.4} | {} | {:.2} | {:.2} | {:.2}× | {:.3e} | {} | {} |\n",
            row.patches,
            row.threshold,
            row.triangles,
            row.cpu_ms,
            row.gpu_ms,
            row.speedup,
            row.gpu_triangles_per_s,
            list(&row.kernels_ms),
            list(&row.cpu_stages_ms)
        );
    }
    // Scaling with output: the largest against the smallest output per model size.
    s += "\nScaling with output size (GPU): time ratio against triangle ratio, coarsest to finest threshold.\n\n| patches | triangles ratio | GPU time ratio | CPU time ratio |\n|---:|---:|---:|---:|\n";
    for patches in [1, 32, 1024] {
        let rows: Vec<&GpuRow> = r.rows.iter().filter(|x| x.patches == patches).collect();
        if let (Some(a), Some(b)) = (rows.first(), rows.last()) {
            s += &format!(
                "| {} | {:.1}× | {:.1}× | {:.1}× |\n",
                patches,
                b.triangles as f64 / a.triangles as f64,
                b.gpu_ms / a.gpu_ms,
                b.cpu_ms / a.cpu_ms
            );
        }
    }
    s
}
