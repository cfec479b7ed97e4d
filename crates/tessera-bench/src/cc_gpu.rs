//! Catmull-Clark on the GPU: the adaptive stage against the CPU reference (time,
//! triangles per second), the time to reach a max error of 5e-4 of the diagonal against
//! uniform tessellation (at the smallest grid that reaches it: the CPU's, the GPU
//! uniform stage's on the same device, and OpenSubdiv's Bfr uniform tessellation where
//! OpenSubdiv is installed), and how the GPU time grows with the output (from
//! 3e-3 of the diagonal to the first of [`SCALING_FINE`] with 10× the triangles, as the
//! target reads: 10× the triangles in at most 11× the time); with the first-split
//! search (the default) and with midpoint splits alone (the paper's); and a frame of
//! animation (moved control points) on the car and Spot against building the stage anew;
//! the creased car, bishop and rook; triangle meshes of 5 856 and 10 000 faces.
//! Writes `OUT/catmull_clark_gpu.{json,md}`.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;

use crate::gpu::gpu_median_ms;
use crate::median;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive, tessellate_uniform, CcParams, FirstSplit, PatchMesh,
    SurfaceModel, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::measure_error;
use tessera_core::Tolerance;
use tessera_wgpu::catmull_clark::{CcStage, CcStatus, CcUniformStage, UniformParams};
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::{wgpu, Kernels};

#[derive(Serialize)]
struct Row {
    model: String,
    device: String,
    patches: usize,
    tolerance_rel: f64,
    first_split: FirstSplit,
    triangles: usize,
    /// Measured max error of the GPU output, as a fraction of the diagonal.
    max_error_rel: f64,
    gpu_ms: f64,
    cpu_ms: f64,
    gpu_over_cpu: f64,
    gpu_mtris_per_s: f64,
    cpu_mtris_per_s: f64,
    /// Smallest uniform grid (n × n per patch) whose measured max error is at or under
    /// the GPU output's, with its CPU time and triangles.
    uniform_segments: u32,
    uniform_triangles: usize,
    uniform_ms: f64,
    gpu_over_uniform: f64,
    /// The same uniform grid on the GPU uniform stage (same device as `gpu_ms`).
    uniform_gpu_ms: f64,
    gpu_over_uniform_gpu: f64,
    /// OpenSubdiv's Bfr uniform tessellation (CPU) at the smallest rate per face edge
    /// whose measured max error is at or under the GPU output's: its rate, triangles
    /// and time (median, measured by the helper: the surfaces built from the control
    /// points and evaluated, the topology built once). Absent without OpenSubdiv.
    osd_rate: Option<u32>,
    osd_triangles: Option<usize>,
    osd_ms: Option<f64>,
    gpu_over_osd: Option<f64>,
    /// Against the fastest of the uniform peers (CPU, GPU, OpenSubdiv).
    gpu_over_fastest_uniform: f64,
    /// Where the GPU time goes (timestamps after each phase, one run), if the adapter
    /// has timestamp queries: (phase, ms).
    phases: Vec<(String, f64)>,
    /// Flatness bounds computed per output leaf, the search's trials included: the GPU
    /// runs a patch's trials side by side and stops one once a finished trial beats it,
    /// the CPU tries them in turn and stops one as soon as it reaches the best so far.
    gpu_bounds_per_leaf: f64,
    cpu_bounds_per_leaf: f64,
}

/// From the coarse tolerance (3e-3) to the first of these that gives 10× its triangles
/// (the last if none does).
const SCALING_FINE: [f64; 2] = [1e-4, 5e-5];

/// How the GPU time grows with the output, per model and first split.
#[derive(Serialize)]
struct Scaling {
    model: String,
    first_split: FirstSplit,
    coarse_tolerance_rel: f64,
    coarse_triangles: usize,
    coarse_gpu_ms: f64,
    fine_tolerance_rel: f64,
    fine_triangles: usize,
    fine_gpu_ms: f64,
    /// Leaves of the fine run stopped by the depth limit above the tolerance.
    fine_unmet: u32,
    triangles_ratio: f64,
    time_ratio: f64,
    time_per_triangle_ratio: f64,
}

/// The script's fixed cost: the stage on the cube with ε the whole diagonal, one leaf per
/// patch. What a mode costs before any work.
#[derive(Serialize)]
struct Overhead {
    first_split: FirstSplit,
    patches: usize,
    triangles: usize,
    /// GPU time by timestamp queries, median of 9 runs (`None` without timestamps).
    timestamp_ms: Option<f64>,
    /// Wall time of a run (record, submit, wait), median of 9.
    wall_ms: f64,
    /// Where the GPU time goes (timestamps after each phase, one run): (phase, ms).
    phases: Vec<(String, f64)>,
}

/// Median GPU time of 9 runs of `stage` by timestamp queries, where the device has them.
fn timestamp_median_ms(gpu: &Gpu, stage: &mut CcStage) -> Option<f64> {
    let mut timer = tessera_wgpu::GpuTimer::new(&gpu.device, &gpu.queue)?;
    let runs = (0..9)
        .map(|_| {
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            stage
                .prepare_timed(&gpu.device, &gpu.queue, &mut encoder, timer.timestamps())
                .expect("prepare");
            timer.resolve(&gpu.device, &mut encoder);
            gpu.queue.submit([encoder.finish()]);
            timer.read_ms(&gpu.device).expect("timestamps")
        })
        .collect();
    Some(median(runs))
}

/// A frame of animation: moved control points written with `update_points` and the run
/// that follows, against building the stage anew for them (the patches rebuilt on the
/// CPU, the stage made and run to completion), at 3e-3 with the default first split.
#[derive(Serialize)]
struct Animation {
    model: String,
    patches: usize,
    control_points: usize,
    /// Bytes `update_points` writes per frame.
    upload_bytes_per_frame: usize,
    /// Bytes a stage made anew uploads.
    anew_upload_bytes: usize,
    /// Median of a frame: the points moved, then the run.
    frame_ms: f64,
    /// Median of a run whose points did not move (the stencil step skipped).
    still_ms: f64,
    /// Median of building the stage anew for moved points and running it to completion.
    anew_ms: f64,
    frame_over_anew: f64,
}

/// Ten copies of the car as one control mesh against the car alone, at 3e-3: how the GPU
/// time grows with the patches (the target: at most 11× the time).
#[derive(Serialize)]
struct Copies {
    first_split: FirstSplit,
    copies: usize,
    patches: usize,
    triangles: usize,
    one_ms: f64,
    copies_ms: f64,
    patches_ratio: f64,
    time_ratio: f64,
}

/// `control` repeated `n` times in a row along x, one control mesh (smooth).
fn copies_of(
    control: &tessera_core::catmull_clark::ControlMesh,
    n: usize,
) -> tessera_core::catmull_clark::ControlMesh {
    let step = 1.1 * control.bbox_diag();
    let count = control.positions.len() as u32;
    let mut out = tessera_core::catmull_clark::ControlMesh::new(Vec::new(), Vec::new());
    out.boundary = control.boundary;
    for k in 0..n {
        let shift = glam::DVec3::new(step * k as f64, 0.0, 0.0);
        out.positions
            .extend(control.positions.iter().map(|p| *p + shift));
        let base = k as u32 * count;
        out.faces.extend(
            control
                .faces
                .iter()
                .map(|f| f.iter().map(|v| v + base).collect()),
        );
        out.face_lines.extend(&control.face_lines);
        out.holes.extend(&control.holes);
    }
    out
}

/// A creased surface (the shipped tags) on the GPU stage against the CPU reference.
#[derive(Serialize)]
struct Creased {
    model: String,
    tolerance_rel: f64,
    first_split: FirstSplit,
    triangles: usize,
    /// The GPU's guaranteed bound and the measured error against the creased surface, as
    /// fractions of the diagonal.
    max_bound_rel: f64,
    max_error_rel: f64,
    unmet: u32,
    gpu_ms: f64,
    cpu_ms: f64,
    gpu_over_cpu: f64,
    /// What the stage uploads when made, with and without the creases, and the
    /// difference per patch whose one-ring holds a sharp edge or vertex.
    upload_bytes: usize,
    smooth_upload_bytes: usize,
    creased_patches: usize,
    extra_bytes_per_creased_patch: f64,
}

/// A triangle mesh (every patch with two extraordinary corners) on the GPU stage against
/// the CPU reference: Spot's published triangulation and a generated torus of 10 000
/// triangles, whose derived nets are more than one page holds at WebGPU's default limits.
#[derive(Serialize)]
struct TriangleMesh {
    model: String,
    faces: usize,
    patches: usize,
    tolerance_rel: f64,
    first_split: FirstSplit,
    triangles: usize,
    unmet: u32,
    gpu_ms: f64,
    cpu_ms: f64,
    gpu_over_cpu: f64,
    upload_bytes: usize,
    /// Nets the stencil step derives into the nets' pages (12 texels of 16 bytes each).
    derived_nets: usize,
}

#[derive(Serialize)]
struct Results<'a> {
    rows: &'a [Row],
    scaling: &'a [Scaling],
    overhead: &'a [Overhead],
    animation: &'a [Animation],
    copies: &'a [Copies],
    creased: &'a [Creased],
    triangle_meshes: &'a [TriangleMesh],
}

/// The control points of `model` moved for frame `k`: each by a wave of 1% of `diag`.
fn wave(model: &SurfaceModel, diag: f64, k: usize) -> Vec<glam::DVec3> {
    model
        .mesh
        .control_points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let phase = 0.7 * k as f64 + 0.1 * i as f64;
            *p + 0.01 * diag * glam::DVec3::new(phase.sin(), phase.cos(), (2.0 * phase).sin())
        })
        .collect()
}

/// [`Animation`] of `model`.
fn animation(
    gpu: &Gpu,
    kernels: &Kernels,
    name: &str,
    model: &SurfaceModel,
    repeats: usize,
) -> Animation {
    let diag = model.mesh.control_diag;
    let params = CcParams {
        tolerance: Tolerance::Relative(3e-3),
        max_depth: MAX_DEPTH,
        first_split: Default::default(),
        leaf_bound: Default::default(),
    };
    let (mut stage, _, still_ms) = timed_stage(gpu, kernels, model, &params, repeats);
    let frames: Vec<Vec<glam::Vec3>> = (0..4)
        .map(|k| wave(model, diag, k).iter().map(|p| p.as_vec3()).collect())
        .collect();
    let mut k = 0;
    let frame_ms = gpu_median_ms(gpu, repeats, |e| {
        stage
            .update_points(&gpu.queue, &frames[k % frames.len()])
            .expect("same topology");
        k += 1;
        stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
    });
    let mut anew_upload_bytes = 0;
    let anew_ms = median(
        (0..repeats)
            .map(|k| {
                let moved = wave(model, diag, k);
                let t = Instant::now();
                let rebuilt = model.with_control_points(&moved).expect("same topology");
                let mut anew = CcStage::new(&gpu.device, &gpu.queue, kernels, &rebuilt, &params)
                    .expect("stage");
                anew.run_blocking(&gpu.device, &gpu.queue).expect("run");
                anew_upload_bytes = anew.upload_bytes();
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    );
    gpu.check().expect("no wgpu errors");
    let row = Animation {
        model: name.to_string(),
        patches: model.mesh.surface_patches().count(),
        control_points: model.mesh.control_vertices,
        upload_bytes_per_frame: stage.update_bytes(),
        anew_upload_bytes,
        frame_ms,
        still_ms,
        anew_ms,
        frame_over_anew: frame_ms / anew_ms,
    };
    eprintln!(
        "cc gpu animation {name}: frame {frame_ms:.1} ms ({} B), still {still_ms:.1} ms, anew {anew_ms:.1} ms ({} B)",
        row.upload_bytes_per_frame, row.anew_upload_bytes
    );
    row
}

/// One run with a timestamp after each phase of the stage script: (phase, ms). Empty
/// without timestamp queries.
fn gpu_phases(gpu: &Gpu, stage: &mut CcStage) -> Vec<(String, f64)> {
    let needed = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
    if !gpu.device.features().contains(needed) {
        return Vec::new();
    }
    let slots = CcStage::TIMED_PHASES + 1;
    let set = gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("tessera bench phases"),
        ty: wgpu::QueryType::Timestamp,
        count: slots,
    });
    let buffer = |usage| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("tessera bench timestamps"),
            size: 8 * slots as u64,
            usage,
            mapped_at_creation: false,
        })
    };
    let resolve = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
    let read = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    let names = stage.profile_phases(&gpu.device, &mut encoder, &set);
    let n = names.len() as u32 + 1;
    encoder.resolve_query_set(&set, 0..n, &resolve, 0);
    encoder.copy_buffer_to_buffer(&resolve, 0, &read, 0, 8 * n as u64);
    gpu.queue.submit([encoder.finish()]);
    let bytes = gpu.map_and_copy(&read).expect("timestamps");
    let ticks: Vec<u64> = bytes[..8 * n as usize]
        .chunks_exact(8)
        .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let period = gpu.queue.get_timestamp_period() as f64;
    names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let ms = ticks[k + 1].saturating_sub(ticks[k]) as f64 * period / 1e6;
            (name.clone(), ms)
        })
        .collect()
}

/// A stage run to completion once (growing its buffers), then timed: the stage, what
/// the run needed and the median time of the recorded run.
fn timed_stage(
    gpu: &Gpu,
    kernels: &Kernels,
    model: &SurfaceModel,
    params: &CcParams,
    repeats: usize,
) -> (CcStage, CcStatus, f64) {
    let mut stage = CcStage::new(&gpu.device, &gpu.queue, kernels, model, params).expect("stage");
    let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
    let ms = gpu_median_ms(gpu, repeats, |e| {
        stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
    });
    gpu.check().expect("no wgpu errors");
    (stage, status, ms)
}

/// [`timed_stage`], with the mesh, the phases and the bounds per leaf.
fn gpu_time(
    gpu: &Gpu,
    kernels: &Kernels,
    model: &SurfaceModel,
    params: &CcParams,
    repeats: usize,
) -> (f64, tessera_core::Mesh, Vec<(String, f64)>, f64) {
    let (mut stage, status, ms) = timed_stage(gpu, kernels, model, params, repeats);
    let mesh = stage
        .read_mesh(&gpu.device, &gpu.queue, &status)
        .expect("mesh");
    let phases = gpu_phases(gpu, &mut stage);
    gpu.check().expect("no wgpu errors");
    let bounds_per_leaf = status.state.bounds as f64 / status.state.leaves.max(1) as f64;
    (ms, mesh, phases, bounds_per_leaf)
}

/// Median time of the GPU uniform stage's run to completion at `n` segments (after a
/// first run), and its triangles.
fn gpu_uniform_time(
    gpu: &Gpu,
    kernels: &Kernels,
    model: &SurfaceModel,
    n: u32,
    repeats: usize,
) -> (f64, usize) {
    let mut stage = CcUniformStage::new(
        &gpu.device,
        &gpu.queue,
        kernels,
        model,
        &UniformParams { segments: n },
    )
    .expect("uniform stage");
    // The uniform stage's sizes follow from `n`: one run to completion, nothing to grow.
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    stage
        .prepare(&gpu.device, &gpu.queue, &mut encoder)
        .expect("first run");
    gpu.queue.submit([encoder.finish()]);
    gpu.wait().expect("first run");
    let ms = gpu_median_ms(gpu, repeats, |e| {
        stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
    });
    gpu.check().expect("no wgpu errors");
    (ms, stage.index_count() as usize / 3)
}

pub fn run(assets: &Path, out_dir: &Path, quick: bool, model_filter: Option<&str>) {
    // Timestamps where the adapter has them, for the phase breakdown.
    let gpu = Gpu::with_optional_features(
        wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS,
    )
    .expect("a wgpu adapter");
    let kernels = Kernels::new(&gpu.device);
    let device = gpu.adapter_name();
    let repeats = if quick { 1 } else { 3 };
    let models: &[&str] = if quick {
        &["opensubdiv/catmark_rook.obj"]
    } else {
        &[
            "opensubdiv/catmark_car.obj",
            "opensubdiv/catmark_bishop.obj",
            "opensubdiv/catmark_rook.obj",
            "catmull_clark/spot_control_mesh.obj",
        ]
    };
    // First, in a fresh process: measured after the models' runs it read 2–3× more with
    // the search on this machine (cause not found).
    let cube = load_control_mesh(&assets.join("opensubdiv/catmark_cube.obj")).expect("cube");
    let cube = SurfaceModel::new(PatchMesh::new(&cube).expect("valid"), TREE_DEPTH);
    let overhead: Vec<Overhead> = [FirstSplit::Search, FirstSplit::Midpoint]
        .into_iter()
        .map(|first_split| {
            let params = CcParams {
                tolerance: Tolerance::Relative(1.0),
                max_depth: MAX_DEPTH,
                first_split,
                leaf_bound: Default::default(),
            };
            let (mut stage, status, wall_ms) = timed_stage(&gpu, &kernels, &cube, &params, 9);
            let timestamp_ms = timestamp_median_ms(&gpu, &mut stage);
            let phases = gpu_phases(&gpu, &mut stage);
            gpu.check().expect("no wgpu errors");
            Overhead {
                first_split,
                patches: cube.mesh.surface_patches().count(),
                triangles: status.indices as usize / 3,
                timestamp_ms,
                wall_ms,
                phases,
            }
        })
        .collect();
    let mut rows = Vec::new();
    let mut scaling = Vec::new();
    let mut animated = Vec::new();
    let mut copies = Vec::new();
    for file in models
        .iter()
        .filter(|f| model_filter.is_none_or(|m| f.contains(m)))
    {
        let mut control = load_control_mesh(&assets.join(file)).expect("shipped mesh");
        // The GPU stages tessellate smooth surfaces.
        control.drop_creases("--no-creases");
        let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
        let diag = control.bbox_diag();
        let samples = surface_samples(&model, 32);
        let name: String = Path::new(file)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .into();
        if ["catmark_car", "spot_control_mesh"].contains(&name.as_str()) {
            animated.push(animation(&gpu, &kernels, &name, &model, repeats.max(5)));
        }
        if name == "catmark_car" && !quick {
            let ten = copies_of(&control, 10);
            let many = SurfaceModel::new(PatchMesh::new(&ten).expect("valid"), TREE_DEPTH);
            for first_split in [FirstSplit::Search, FirstSplit::Midpoint] {
                // ε in model units, the same for both: the copies' box is larger.
                let params = CcParams {
                    tolerance: Tolerance::Absolute(3e-3 * diag),
                    max_depth: MAX_DEPTH,
                    first_split,
                    leaf_bound: Default::default(),
                };
                let (_, _, one_ms) = timed_stage(&gpu, &kernels, &model, &params, repeats);
                let (_, status, copies_ms) = timed_stage(&gpu, &kernels, &many, &params, repeats);
                let row = Copies {
                    first_split,
                    copies: 10,
                    patches: many.mesh.surface_patches().count(),
                    triangles: status.indices as usize / 3,
                    one_ms,
                    copies_ms,
                    patches_ratio: many.mesh.surface_patches().count() as f64
                        / model.mesh.surface_patches().count() as f64,
                    time_ratio: copies_ms / one_ms,
                };
                eprintln!(
                    "cc gpu ten cars {first_split:?}: {} patches, {one_ms:.1} → {copies_ms:.1} ms",
                    row.patches
                );
                copies.push(row);
            }
        }
        for (first_split, rel) in [FirstSplit::Search, FirstSplit::Midpoint]
            .into_iter()
            .flat_map(|f| [(f, 3e-3), (f, 5e-4)])
        {
            let params = CcParams {
                tolerance: Tolerance::Relative(rel),
                max_depth: MAX_DEPTH,
                first_split,
                leaf_bound: Default::default(),
            };
            let (gpu_ms, mesh, phases, gpu_bounds_per_leaf) =
                gpu_time(&gpu, &kernels, &model, &params, repeats);
            let e = measure_error(&samples, &mesh, model.mesh.control_diag);
            let mut cpu_bounds_per_leaf = 0.0;
            let cpu_ms = median(
                (0..repeats)
                    .map(|_| {
                        let t = Instant::now();
                        let out = tessellate_adaptive(&model, &params).expect("cpu");
                        let ms = t.elapsed().as_secs_f64() * 1e3;
                        cpu_bounds_per_leaf = out.bounds as f64 / out.leaves.max(1) as f64;
                        ms
                    })
                    .collect(),
            );
            let mut n = 1;
            let (uniform_triangles, uniform_ms) = loop {
                let t = Instant::now();
                let u = tessellate_uniform(&model, n).expect("uniform");
                let first = t.elapsed().as_secs_f64() * 1e3;
                if measure_error(&samples, &u.mesh, model.mesh.control_diag).max_error
                    <= e.max_error
                    || n >= 64
                {
                    let mut times = vec![first];
                    for _ in 1..repeats {
                        let t = Instant::now();
                        tessellate_uniform(&model, n).expect("uniform");
                        times.push(t.elapsed().as_secs_f64() * 1e3);
                    }
                    break (u.mesh.triangle_count(), median(times));
                }
                n += 1;
            };
            let (uniform_gpu_ms, uniform_gpu_triangles) =
                gpu_uniform_time(&gpu, &kernels, &model, n, repeats);
            assert_eq!(uniform_gpu_triangles, uniform_triangles, "GPU uniform grid");
            // OpenSubdiv's rate is per face edge: a quad face is 2 × 2 of our patches.
            let osd = tessera_tests::osd::available().then(|| {
                let mut rate = (2 * n).saturating_sub(3).max(1);
                loop {
                    let (_, m) = tessera_tests::osd::bfr_uniform(&control, rate, 1);
                    let err = measure_error(&samples, &m, model.mesh.control_diag).max_error;
                    if err <= e.max_error || rate >= 128 {
                        let (ms, _) =
                            tessera_tests::osd::bfr_uniform(&control, rate, repeats as u32);
                        break (rate, m.triangle_count(), ms);
                    }
                    rate += 1;
                }
            });
            let fastest = osd
                .map_or(f64::INFINITY, |o| o.2)
                .min(uniform_ms)
                .min(uniform_gpu_ms);
            let tris = mesh.triangle_count();
            let row = Row {
                model: name.clone(),
                device: device.clone(),
                patches: model.mesh.surface_patches().count(),
                tolerance_rel: rel,
                first_split,
                triangles: tris,
                max_error_rel: e.max_error / diag,
                gpu_ms,
                cpu_ms,
                gpu_over_cpu: gpu_ms / cpu_ms,
                gpu_mtris_per_s: tris as f64 / gpu_ms / 1e3,
                cpu_mtris_per_s: tris as f64 / cpu_ms / 1e3,
                uniform_segments: n,
                uniform_triangles,
                uniform_ms,
                gpu_over_uniform: gpu_ms / uniform_ms,
                uniform_gpu_ms,
                gpu_over_uniform_gpu: gpu_ms / uniform_gpu_ms,
                osd_rate: osd.map(|o| o.0),
                osd_triangles: osd.map(|o| o.1),
                osd_ms: osd.map(|o| o.2),
                gpu_over_osd: osd.map(|o| gpu_ms / o.2),
                gpu_over_fastest_uniform: gpu_ms / fastest,
                phases,
                gpu_bounds_per_leaf,
                cpu_bounds_per_leaf,
            };
            eprintln!(
                "cc gpu {} {rel:e} {first_split:?}: {} tris, gpu {:.1} ms, cpu {:.1} ms, uniform n={} {:.1} ms (GPU {:.1} ms)",
                row.model, tris, gpu_ms, cpu_ms, n, uniform_ms, uniform_gpu_ms
            );
            rows.push(row);
        }
        for first_split in [FirstSplit::Search, FirstSplit::Midpoint] {
            let coarse = rows
                .iter()
                .find(|r| {
                    r.model == name && r.first_split == first_split && r.tolerance_rel == 3e-3
                })
                .expect("the coarse row");
            let fine_list = if quick {
                &SCALING_FINE[..1]
            } else {
                &SCALING_FINE[..]
            };
            let mut fine = None;
            for &rel in fine_list {
                let params = CcParams {
                    tolerance: Tolerance::Relative(rel),
                    max_depth: MAX_DEPTH,
                    first_split,
                    leaf_bound: Default::default(),
                };
                let (_, status, ms) = timed_stage(&gpu, &kernels, &model, &params, repeats);
                let (tris, unmet) = (status.indices as usize / 3, status.state.unmet);
                eprintln!(
                    "cc gpu scaling {} {rel:e} {first_split:?}: {tris} tris, gpu {ms:.1} ms",
                    coarse.model
                );
                fine = Some((rel, ms, tris, unmet));
                if tris >= 10 * coarse.triangles {
                    break;
                }
            }
            let (rel, ms, tris, unmet) = fine.expect("a fine tolerance");
            let triangles_ratio = tris as f64 / coarse.triangles as f64;
            let time_ratio = ms / coarse.gpu_ms;
            scaling.push(Scaling {
                model: coarse.model.clone(),
                first_split,
                coarse_tolerance_rel: coarse.tolerance_rel,
                coarse_triangles: coarse.triangles,
                coarse_gpu_ms: coarse.gpu_ms,
                fine_tolerance_rel: rel,
                fine_triangles: tris,
                fine_gpu_ms: ms,
                fine_unmet: unmet,
                triangles_ratio,
                time_ratio,
                time_per_triangle_ratio: time_ratio / triangles_ratio,
            });
        }
    }
    let mut creased = Vec::new();
    for name in ["catmark_car", "catmark_bishop", "catmark_rook"]
        .into_iter()
        .filter(|f| model_filter.is_none_or(|m| f.contains(m)))
    {
        let control = load_control_mesh(&assets.join(format!("opensubdiv/{name}.obj")))
            .expect("shipped mesh");
        let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
        let mut smooth_control = control.clone();
        smooth_control.drop_creases("--no-creases");
        let smooth = SurfaceModel::new(PatchMesh::new(&smooth_control).expect("valid"), TREE_DEPTH);
        let diag = control.bbox_diag();
        let samples = surface_samples(&model, 32);
        let creased_patches = model.patches.iter().filter(|s| s.creased).count();
        // What the smooth surface's stage uploads: fixed by the topology, not ε.
        let smooth_upload = CcStage::new(
            &gpu.device,
            &gpu.queue,
            &kernels,
            &smooth,
            &CcParams {
                tolerance: Tolerance::Relative(3e-3),
                max_depth: MAX_DEPTH,
                first_split: FirstSplit::default(),
                leaf_bound: Default::default(),
            },
        )
        .expect("smooth stage")
        .upload_bytes();
        let tolerances: &[f64] = if quick { &[3e-3] } else { &[3e-3, 5e-4] };
        for &rel in tolerances {
            let params = CcParams {
                tolerance: Tolerance::Relative(rel),
                max_depth: MAX_DEPTH,
                first_split: FirstSplit::default(),
                leaf_bound: Default::default(),
            };
            let (stage, status, gpu_ms) = timed_stage(&gpu, &kernels, &model, &params, repeats);
            let mesh = stage
                .read_mesh(&gpu.device, &gpu.queue, &status)
                .expect("mesh");
            let cpu_ms = median(
                (0..repeats)
                    .map(|_| {
                        let t = Instant::now();
                        tessellate_adaptive(&model, &params).expect("cpu");
                        t.elapsed().as_secs_f64() * 1e3
                    })
                    .collect(),
            );
            let e = measure_error(&samples, &mesh, model.mesh.control_diag);
            let upload = stage.upload_bytes();
            let row = Creased {
                model: name.into(),
                tolerance_rel: rel,
                first_split: params.first_split,
                triangles: mesh.triangle_count(),
                max_bound_rel: status.max_bound() as f64 / diag,
                max_error_rel: e.max_error / diag,
                unmet: status.state.unmet,
                gpu_ms,
                cpu_ms,
                gpu_over_cpu: gpu_ms / cpu_ms,
                upload_bytes: upload,
                smooth_upload_bytes: smooth_upload,
                creased_patches,
                extra_bytes_per_creased_patch: (upload as f64 - smooth_upload as f64)
                    / creased_patches.max(1) as f64,
            };
            eprintln!(
                "cc gpu creased {name} {rel:e}: {} tris, bound {:.3e}, error {:.3e}, gpu {gpu_ms:.1} ms, cpu {cpu_ms:.1} ms",
                row.triangles, row.max_bound_rel, row.max_error_rel
            );
            creased.push(row);
        }
    }
    let mut triangle_meshes = Vec::new();
    let spot = load_control_mesh(&assets.join("catmull_clark/spot_triangulated.obj"))
        .expect("shipped mesh");
    for (name, mut control, rel) in [
        ("spot_triangulated", spot, 3e-3),
        (
            "triangle_torus_10k",
            tessera_tests::triangle_torus(100, 50),
            1.5e-4,
        ),
    ] {
        if model_filter.is_some_and(|m| !name.contains(m)) || (quick && name != "spot_triangulated")
        {
            continue;
        }
        control.drop_creases("--no-creases");
        let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
        let params = CcParams {
            tolerance: Tolerance::Relative(rel),
            max_depth: 6,
            first_split: FirstSplit::Midpoint,
            leaf_bound: Default::default(),
        };
        let runs = repeats.min(3);
        let (stage, status, gpu_ms) = timed_stage(&gpu, &kernels, &model, &params, runs);
        let cpu_ms = median(
            (0..runs)
                .map(|_| {
                    let t = Instant::now();
                    tessellate_adaptive(&model, &params).expect("cpu");
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect(),
        );
        let row = TriangleMesh {
            model: name.into(),
            faces: control.faces.len(),
            patches: model.mesh.surface_patches().count(),
            tolerance_rel: rel,
            first_split: params.first_split,
            triangles: status.indices as usize / 3,
            unmet: status.state.unmet,
            gpu_ms,
            cpu_ms,
            gpu_over_cpu: gpu_ms / cpu_ms,
            upload_bytes: stage.upload_bytes(),
            derived_nets: stage.derived_nets(),
        };
        eprintln!(
            "cc gpu triangle mesh {name}: {} faces, {} tris, gpu {gpu_ms:.1} ms, cpu {cpu_ms:.1} ms",
            row.faces, row.triangles
        );
        triangle_meshes.push(row);
    }
    // A run on some models only must not replace the table of all of them.
    let name = if model_filter.is_some() {
        "catmull_clark_gpu_subset"
    } else {
        "catmull_clark_gpu"
    };
    let results = Results {
        rows: &rows,
        scaling: &scaling,
        overhead: &overhead,
        animation: &animated,
        copies: &copies,
        creased: &creased,
        triangle_meshes: &triangle_meshes,
    };
    let text = table(&rows, &scaling, &overhead, &animated)
        + &copies_table(&copies)
        + &creased_table(&creased)
        + &triangle_table(&triangle_meshes);
    crate::write_results(out_dir, name, &results, text);
}

fn table(
    rows: &[Row],
    scaling: &[Scaling],
    overhead: &[Overhead],
    animation: &[Animation],
) -> String {
    let mut s = String::from(
        "| model | device | patches | ε (of diagonal) | first split | triangles | measured max (of diag.) | GPU ms | CPU ms | GPU/CPU | GPU Mtri/s | uniform n (same error) | uniform tris | uniform CPU ms | **GPU/uniform** | uniform GPU ms | **GPU/uniform GPU** | OpenSubdiv Bfr rate | Bfr tris | Bfr ms | **GPU/Bfr** | **GPU/fastest uniform** |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.0e} | {} | {} | {:.2e} | {:.1} | {:.1} | {:.2} | {:.3} | {} | {} | {:.1} | **{:.2}** | {:.1} | **{:.2}** | {} | {} | {} | **{}** | **{:.2}** |\n",
            r.model,
            r.device,
            r.patches,
            r.tolerance_rel,
            r.first_split.name(),
            r.triangles,
            r.max_error_rel,
            r.gpu_ms,
            r.cpu_ms,
            r.gpu_over_cpu,
            r.gpu_mtris_per_s,
            r.uniform_segments,
            r.uniform_triangles,
            r.uniform_ms,
            r.gpu_over_uniform,
            r.uniform_gpu_ms,
            r.gpu_over_uniform_gpu,
            r.osd_rate.map_or("—".into(), |x| x.to_string()),
            r.osd_triangles.map_or("—".into(), |x| x.to_string()),
            r.osd_ms.map_or("—".into(), |x| format!("{x:.1}")),
            r.gpu_over_osd.map_or("—".into(), |x| format!("{x:.2}")),
            r.gpu_over_fastest_uniform
        );
    }
    if rows.iter().any(|r| !r.phases.is_empty()) {
        s += "\nWhere the GPU time goes (ms, timestamps after each phase of one run):\n\n| model | ε | first split |";
        let names: Vec<&str> = rows
            .iter()
            .find(|r| !r.phases.is_empty())
            .map(|r| r.phases.iter().map(|(n, _)| n.as_str()).collect())
            .unwrap_or_default();
        for n in &names {
            s += &format!(" {n} |");
        }
        s += " bounds per leaf (GPU / CPU) |\n|---|---|---|";
        s += &"---|".repeat(names.len() + 1);
        s += "\n";
        for r in rows.iter().filter(|r| !r.phases.is_empty()) {
            s += &format!(
                "| {} | {:.0e} | {} |",
                r.model,
                r.tolerance_rel,
                r.first_split.name()
            );
            for (_, ms) in &r.phases {
                s += &format!(" {ms:.1} |");
            }
            s += &format!(
                " {:.2} / {:.2} |\n",
                r.gpu_bounds_per_leaf, r.cpu_bounds_per_leaf
            );
        }
    }
    s += "\nThe script's fixed cost (the cube with ε the whole diagonal: one leaf per patch; medians of 9 runs; the target: at most 2 ms of GPU time):\n\n| first split | patches | triangles | **GPU ms (timestamps)** | wall ms | phases (ms, one run) |\n|---|---|---|---|---|---|\n";
    for o in overhead {
        let stamps = o
            .timestamp_ms
            .map_or("no timestamps".to_string(), |ms| format!("{ms:.2}"));
        let phases: Vec<String> = o
            .phases
            .iter()
            .map(|(name, ms)| format!("{name} {ms:.2}"))
            .collect();
        s += &format!(
            "| {} | {} | {} | **{}** | {:.2} | {} |\n",
            o.first_split.name(),
            o.patches,
            o.triangles,
            stamps,
            o.wall_ms,
            phases.join(", ")
        );
    }
    s += "\nScaling with the output (GPU), from 3e-3 to the first tolerance with 10× the triangles (the target: time per triangle ratio at most 1.1):\n\n| model | first split | triangles (3e-3 → fine) | fine ε | GPU ms | triangles ratio | GPU time ratio | **time per triangle ratio** | leaves unmet at the depth limit |\n|---|---|---|---|---|---|---|---|---|\n";
    for r in scaling {
        s += &format!(
            "| {} | {} | {} → {} | {:.0e} | {:.1} → {:.1} | {:.1}× | {:.1}× | **{:.2}** | {} |\n",
            r.model,
            r.first_split.name(),
            r.coarse_triangles,
            r.fine_triangles,
            r.fine_tolerance_rel,
            r.coarse_gpu_ms,
            r.fine_gpu_ms,
            r.triangles_ratio,
            r.time_ratio,
            r.time_per_triangle_ratio,
            r.fine_unmet
        );
    }
    if !animation.is_empty() {
        s += "\nAnimation at 3e-3, default first split: a frame writes the moved control points (`update_points`) and runs, against building the stage anew for them (patches rebuilt on the CPU, stage made, run to completion); medians of 5:\n\n| model | patches | control points | bytes per frame | frame ms | run ms, points still | anew ms | bytes anew | **frame / anew** |\n|---|---|---|---|---|---|---|---|---|\n";
        for a in animation {
            s += &format!(
                "| {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {} | **{:.3}** |\n",
                a.model,
                a.patches,
                a.control_points,
                a.upload_bytes_per_frame,
                a.frame_ms,
                a.still_ms,
                a.anew_ms,
                a.anew_upload_bytes,
                a.frame_over_anew
            );
        }
    }
    s
}

fn copies_table(copies: &[Copies]) -> String {
    if copies.is_empty() {
        return String::new();
    }
    let mut s = String::from("\nScaling with the patches (GPU): ten copies of the car as one control mesh, ε 3e-3 of one car's diagonal (the target: at most 11× the time):\n\n| first split | patches | triangles | one car ms | ten cars ms | patches ratio | **time ratio** |\n|---|---|---|---|---|---|---|\n");
    for c in copies {
        s += &format!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.1}× | **{:.1}×** |\n",
            c.first_split.name(),
            c.patches,
            c.triangles,
            c.one_ms,
            c.copies_ms,
            c.patches_ratio,
            c.time_ratio
        );
    }
    s
}

fn creased_table(rows: &[Creased]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from("\nWith creases (the shipped tags, Chaikin's rule), GPU stage against its CPU reference in turns; bound and measured error as fractions of the diagonal; upload when the stage is made, with and without the creases, and the difference per patch whose one-ring is sharp:\n\n| model | ε (rel) | triangles | bound | measured | GPU ms | CPU ms | **GPU / CPU** | upload | smooth upload | sharp patches | bytes per sharp patch |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        s += &format!(
            "| {} | {:e} | {} | {:.2e}{} | {:.2e} | {:.1} | {:.1} | **{:.2}×** | {:.2} MB | {:.2} MB | {} | {:.0} |\n",
            r.model,
            r.tolerance_rel,
            r.triangles,
            r.max_bound_rel,
            if r.unmet > 0 { " (unmet)" } else { "" },
            r.max_error_rel,
            r.gpu_ms,
            r.cpu_ms,
            r.gpu_over_cpu,
            r.upload_bytes as f64 / 1e6,
            r.smooth_upload_bytes as f64 / 1e6,
            r.creased_patches,
            r.extra_bytes_per_creased_patch
        );
    }
    s
}

fn triangle_table(rows: &[TriangleMesh]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from("\nTriangle meshes (every patch with two extraordinary corners), midpoint splits, GPU stage against its CPU reference in turns; upload when the stage is made:\n\n| model | faces | patches | ε (rel) | triangles | GPU ms | CPU ms | **GPU / CPU** | upload | derived nets |\n|---|---|---|---|---|---|---|---|---|---|\n");
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:e} | {}{} | {:.1} | {:.1} | **{:.2}×** | {:.2} MB | {:.2} M ({:.0} MB) |\n",
            r.model,
            r.faces,
            r.patches,
            r.tolerance_rel,
            r.triangles,
            if r.unmet > 0 { " (unmet)" } else { "" },
            r.gpu_ms,
            r.cpu_ms,
            r.gpu_over_cpu,
            r.upload_bytes as f64 / 1e6,
            r.derived_nets as f64 / 1e6,
            r.derived_nets as f64 * 192.0 / 1e6
        );
    }
    s
}
