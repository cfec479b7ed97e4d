//! `tessera tessellate` and `tessera info`.

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use tessera_core::bezier::search::{segments_for_triangles, threshold_for_triangles};
use tessera_core::bezier::{
    tessellate_adaptive, tessellate_adaptive_in_view, tessellate_uniform, AdaptiveParams,
    BezierModel, BezierView, EdgeTest, PreparedBezier, Tessellation,
};
use tessera_core::io::export::{commit_all, stage, stage_mesh, MeshFormat, StagedFile};
use tessera_core::measure::{bezier_surface_samples, measure_error, ErrorStats};
use tessera_core::Error as CoreError;
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::Error;

use crate::cli::{Backend, Cli, Command, Method, TessellateArgs};
use crate::gpu::GpuTimings;

/// Default threshold as a fraction of the bounding-box diagonal.
const DEFAULT_THRESHOLD_REL: f32 = 0.002;

/// Per-stage times in ms, as `--stats` writes them (shared by both surface kinds).
#[derive(Serialize, Default)]
pub(crate) struct Timings {
    pub load: f64,
    pub prepare: f64,
    pub tessellate: f64,
    pub measure: f64,
    pub write: f64,
    pub total: f64,
    /// `--target-triangles`: the search for the threshold or segment count (CPU runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub search: Option<f64>,
    /// The GPU backend's stages (`tessellate` above is its timed run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu: Option<GpuTimings>,
}

#[derive(Serialize)]
struct Stats {
    input: String,
    method: &'static str,
    backend: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    adapter: Option<String>,
    threshold: Option<f32>,
    /// In a view: the threshold in pixels each patch's is scaled to.
    #[serde(skip_serializing_if = "Option::is_none")]
    tolerance_px: Option<f64>,
    /// In a view: patches whose control points lie wholly outside the frustum (nothing
    /// emitted).
    #[serde(skip_serializing_if = "Option::is_none")]
    culled_patches: Option<usize>,
    /// In a view, with `--measure`: over the samples in the frustum, the largest
    /// distance in pixels from a sample's projection to its nearest mesh point's.
    #[serde(skip_serializing_if = "Option::is_none")]
    max_error_px: Option<f64>,
    max_depth: Option<u32>,
    segments: Option<u32>,
    target_triangles: Option<usize>,
    triangles: usize,
    vertices: usize,
    /// What each vertex's `face` is.
    vertex_face: &'static str,
    /// What each vertex's `u v` is.
    vertex_uv: &'static str,
    patches: usize,
    /// Surface evaluations: the flat test's (3 per tested chord) plus one per vertex.
    evaluations: u64,
    upload_bytes: usize,
    upload_bytes_per_patch: f64,
    timings_ms: Timings,
    #[serde(flatten)]
    error: Option<ErrorStats>,
    measure_samples: Option<usize>,
}

pub(crate) fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// With `measure`, the error of `mesh` against `samples()`; then `mesh` written under a
/// temporary name beside `output` if given ([`finish_outputs`] puts it in place). Both
/// timed into `timings`. Returns the samples too (empty without `measure`), for a
/// caller that measures more on them.
pub(crate) fn measure_and_write(
    mesh: &tessera_core::Mesh,
    measure: bool,
    samples: impl FnOnce() -> Vec<tessera_wgpu::glam::DVec3>,
    bbox_diag: f64,
    output: Option<&Path>,
    timings: &mut Timings,
) -> Result<MeasuredAndStaged, CoreError> {
    let (error, samples) = if measure {
        let t = Instant::now();
        let samples = samples();
        let e = measure_error(&samples, mesh, bbox_diag);
        timings.measure = ms(t);
        (Some(e), samples)
    } else {
        (None, Vec::new())
    };
    let t = Instant::now();
    let staged = output.map(|o| stage_mesh(o, mesh)).transpose()?;
    timings.write = ms(t);
    Ok((error, staged, samples))
}

/// What [`measure_and_write`] returns: the error, the staged mesh and the samples.
pub(crate) type MeasuredAndStaged = (
    Option<ErrorStats>,
    Option<StagedFile>,
    Vec<tessera_wgpu::glam::DVec3>,
);

/// Writes the stats JSON (if asked), then puts the mesh and the stats in place together:
/// if either cannot be written, neither is left behind.
pub(crate) fn finish_outputs(
    mesh: Option<StagedFile>,
    stats_path: Option<&Path>,
    stats: &impl Serialize,
) -> Result<(), CoreError> {
    let mut files: Vec<StagedFile> = mesh.into_iter().collect();
    if let Some(path) = stats_path {
        let json = serde_json::to_string_pretty(stats).expect("stats serialize");
        files.push(stage(path, |w| writeln!(w, "{json}"))?);
    }
    commit_all(files)
}

/// A warning when a `--target-triangles` search ended outside ±2% of its target.
fn warn_if_missed(target: usize, mesh: &tessera_core::Mesh, setting: &str, hit: bool) {
    if !hit {
        eprintln!(
            "warning: nothing gives {target} triangles ±2%; closest: {} at {setting}",
            mesh.triangle_count()
        );
    }
}

/// `--measure-samples` only with `--measure`, and within the measurement's limits.
pub(crate) fn check_measure_args(
    args: &TessellateArgs,
    per_side: usize,
    patches: usize,
) -> Result<(), CoreError> {
    if args.measure_samples.is_some() && !args.measure {
        return Err(CoreError::Param(
            "--measure-samples sets the sampling of --measure; add --measure".into(),
        ));
    }
    if args.measure {
        tessera_core::measure::check_sampling(per_side, patches)?;
    }
    Ok(())
}

pub fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Tessellate(args) => tessellate(args),
        Command::Render(args) => crate::render::render(args),
        Command::Info { input } => info(&input),
    }
}

/// Loads a Newell teaset file (callers send control meshes, by extension, to
/// `catmull_clark` first).
pub fn load(input: &Path) -> Result<BezierModel, CoreError> {
    BezierModel::load(input)
}

fn info(input: &Path) -> Result<(), Error> {
    if tessera_core::io::is_control_mesh(input) {
        return crate::catmull_clark::info(input);
    }
    let model = load(input)?;
    let t = &model.topology;
    let (lo, hi) = model.bounds();
    println!(
        "{}: Newell teaset, {} bicubic Bézier patches",
        input.display(),
        model.patches.len()
    );
    println!("  control points (welded): {}", model.points.len());
    println!(
        "  boundary curves: {} ({} shared, {} open, {} collapsed to a point)",
        t.curves.len(),
        t.curves.iter().filter(|c| c.users > 1).count(),
        t.curves
            .iter()
            .filter(|c| c.users == 1 && !c.collapsed)
            .count(),
        t.curves.iter().filter(|c| c.collapsed).count()
    );
    println!(
        "  patches flipped to orient consistently: {}",
        t.flip.iter().filter(|&&f| f).count()
    );
    println!("  bounds: {lo} .. {hi} (diagonal {})", (hi - lo).length());
    Ok(())
}

fn tessellate(args: TessellateArgs) -> Result<(), Error> {
    if tessera_core::io::is_control_mesh(&args.input) {
        return crate::catmull_clark::tessellate(args);
    }
    let in_view = args.view.given() || args.size.is_some() || args.up.is_some();
    if in_view && args.view.tolerance_px.is_none() {
        return Err(CoreError::Param(
            "a view of a Bézier surface sets its threshold in pixels: give --tolerance-px".into(),
        )
        .into());
    }
    if args.view.max_triangles.is_some() {
        return Err(CoreError::Param("--max-triangles is for Catmull-Clark meshes".into()).into());
    }
    if args.view.face_leaves {
        return Err(CoreError::Param("--face-leaves is for Catmull-Clark meshes".into()).into());
    }
    if in_view && (args.target_triangles.is_some() || args.method == Some(Method::Uniform)) {
        return Err(CoreError::Param(
            "--tolerance-px is for the adaptive methods, without --target-triangles".into(),
        )
        .into());
    }
    if args.tolerance.is_some()
        || args.tolerance_rel.is_some()
        || args.level.is_some()
        || args.first_split.is_some()
        || args.leaf_bound.is_some()
        || args.split_non_manifold
        || args.no_creases
    {
        return Err(CoreError::Param(
            "--tolerance, --tolerance-rel, --level, --first-split, --leaf-bound, --split-non-manifold and --no-creases are Catmull-Clark options; Bézier inputs take --threshold and --segments".into(),
        )
        .into());
    }
    let max_depth = args.max_depth.unwrap_or(6);
    let segments = args.segments.unwrap_or(8);
    let measure_samples = args
        .measure_samples
        .unwrap_or(tessera_core::measure::DEFAULT_SAMPLES_PER_SIDE);
    let t_total = Instant::now();
    let mut timings = Timings::default();
    // Reject bad output paths before doing any work.
    if let Some(o) = &args.output {
        MeshFormat::from_path(o)?;
    }
    let method = args.method.unwrap_or(Method::Map4p);
    let test = match method {
        Method::Map2p => Some(EdgeTest::Map2p),
        Method::Map4p => Some(EdgeTest::Map4p),
        Method::Map8p => Some(EdgeTest::Map8p),
        Method::Flat => Some(EdgeTest::Flat),
        Method::Uniform => None,
        Method::Adaptive => {
            return Err(CoreError::Param(
                "--method adaptive is the Catmull-Clark method; Bézier inputs take map2p, map4p, map8p, flat or uniform".into(),
            )
            .into())
        }
    };

    // Options that would be silently ignored are refused instead.
    if test.is_some() && args.segments.is_some() {
        return Err(CoreError::Param(
            "--segments is for --method uniform; the adaptive methods take --threshold".into(),
        )
        .into());
    }
    if test.is_none() && (args.threshold.is_some() || args.max_depth.is_some()) {
        return Err(CoreError::Param(
            "--threshold and --max-depth are for the adaptive methods; --method uniform takes --segments".into(),
        )
        .into());
    }
    if test.is_none() && args.target_triangles.is_some() && args.segments.is_some() {
        return Err(CoreError::Param(
            "--target-triangles searches the segment count; drop --segments".into(),
        )
        .into());
    }

    let t = Instant::now();
    let model = load(&args.input)?;
    timings.load = ms(t);
    let t = Instant::now();
    let prep = PreparedBezier::new(&model);
    timings.prepare = ms(t);
    let (lo, hi) = model.bounds();
    let diag = (hi - lo).length();
    check_measure_args(&args, measure_samples, model.patches.len())?;
    // Parameters are checked before a device is opened. In pixels, the threshold in
    // model units only caps them.
    let view = match in_view {
        true => {
            let size = args.size.unwrap_or((800, 600));
            let up = args.up.unwrap_or(crate::cli::Axis::Z);
            let v = crate::catmull_clark::view_tolerance(&args.view, size, up, (lo, hi))?;
            Some(BezierView {
                view: v.view,
                pixels: v.pixels.expect("checked"),
                cull: v.cull,
                cull_backfaces: v.cull_backfaces,
            })
        }
        false => None,
    };
    let default_threshold = match view {
        Some(_) => diag,
        None => DEFAULT_THRESHOLD_REL * diag,
    };
    let adaptive = test.map(|test| AdaptiveParams {
        test,
        threshold: args.threshold.unwrap_or(default_threshold),
        max_depth,
    });
    if let Some(a) = &adaptive {
        a.validate()?;
    }

    // The GPU runs the adaptive methods; uniform tessellation is CPU only. Without
    // --backend, the GPU is used when an adapter exists.
    let mut gpu_timings = GpuTimings::default();
    let gpu = match (args.backend, test) {
        (Some(Backend::Cpu), _) | (None, None) => None,
        (Some(Backend::Gpu), None) => {
            return Err(CoreError::Param(
                "--method uniform runs on the CPU only; use --backend cpu".into(),
            )
            .into())
        }
        (Some(Backend::Gpu), Some(_)) => Some(crate::gpu::open(&mut gpu_timings)?),
        (None, Some(_)) => match crate::gpu::open(&mut gpu_timings) {
            Ok(g) => Some(g),
            Err(e) => {
                eprintln!("note: no GPU adapter ({e}); tessellating on the CPU");
                None
            }
        },
    };
    let mut adapter = None;

    // On the CPU a --target-triangles search's last run is the output: its time is
    // reported as `search`, and `tessellate` is one more run at the found setting.
    let mut search = false;
    let t = Instant::now();
    let (out, threshold, segments) = match (test, args.target_triangles) {
        (Some(_), target) if gpu.is_some() => {
            let gpu = gpu.as_ref().expect("checked");
            adapter = Some(gpu.adapter_name());
            let mut params = adaptive.expect("adaptive method");
            if let Some(n) = target {
                // The search runs the CPU twin, which makes the same mesh as the kernels.
                let t = Instant::now();
                let r = threshold_for_triangles(&prep, params, diag, n)?;
                timings.search = Some(ms(t));
                warn_if_missed(
                    n,
                    &r.tessellation.mesh,
                    &format!("threshold {}", r.threshold),
                    r.within_tolerance,
                );
                params.threshold = r.threshold;
            }
            let kernels = tessera_wgpu::Kernels::new(&gpu.device);
            let (stage, status) = crate::gpu::run(gpu, &mut gpu_timings, || {
                let mut stage =
                    BezierStage::new(&gpu.device, &gpu.queue, &kernels, &prep, &params)?;
                stage.set_view(&gpu.queue, view.as_ref())?;
                Ok(stage)
            })?;
            let t = Instant::now();
            let mesh = stage.read_mesh(&gpu.device, &gpu.queue, &status)?;
            gpu_timings.readback = ms(t);
            let evaluations = status.evaluations as u64;
            (
                Tessellation {
                    mesh,
                    evaluations,
                    culled_patches: status.culled_patches as usize,
                },
                Some(params.threshold),
                None,
            )
        }
        (Some(_), target) => {
            let base = adaptive.expect("adaptive method");
            match target {
                Some(n) => {
                    let r = threshold_for_triangles(&prep, base, diag, n)?;
                    warn_if_missed(
                        n,
                        &r.tessellation.mesh,
                        &format!("threshold {}", r.threshold),
                        r.within_tolerance,
                    );
                    search = true;
                    (r.tessellation, Some(r.threshold), None)
                }
                None => (
                    match &view {
                        Some(v) => tessellate_adaptive_in_view(&prep, &base, v)?,
                        None => tessellate_adaptive(&prep, &base)?,
                    },
                    Some(base.threshold),
                    None,
                ),
            }
        }
        (None, Some(n)) => {
            let (segments, t) = segments_for_triangles(&model, &prep, n)?;
            let hit = t.mesh.triangle_count().abs_diff(n) as f64 <= 0.02 * n as f64;
            warn_if_missed(n, &t.mesh, &format!("{segments} segments"), hit);
            search = true;
            (t, None, Some(segments))
        }
        (None, None) => (
            tessellate_uniform(&model, &prep, segments)?,
            None,
            Some(segments),
        ),
    };
    timings.tessellate = if gpu.is_some() {
        gpu_timings.tessellate
    } else if search {
        timings.search = Some(ms(t));
        // The tessellation alone, as the GPU backend reports it: one run at the setting
        // the search found (the same mesh).
        let t = Instant::now();
        let again = match (test, threshold) {
            (Some(_), Some(th)) => tessellate_adaptive(
                &prep,
                &AdaptiveParams {
                    threshold: th,
                    ..adaptive.expect("adaptive method")
                },
            )?,
            _ => tessellate_uniform(&model, &prep, segments.expect("uniform"))?,
        };
        debug_assert_eq!(again.mesh, out.mesh);
        ms(t)
    } else {
        ms(t)
    };
    timings.gpu = gpu.as_ref().map(|_| gpu_timings);

    let (error, staged_mesh, samples) = measure_and_write(
        &out.mesh,
        args.measure,
        || bezier_surface_samples(&model, measure_samples),
        model.bbox_diag(),
        args.output.as_deref(),
        &mut timings,
    )?;
    // Measured, not guaranteed: the Bézier tests are heuristics.
    let max_error_px = match &view {
        Some(v) if args.measure => {
            tessera_core::measure::max_error_px(&samples, &out.mesh, &v.view)
        }
        _ => None,
    };
    timings.total = ms(t_total);

    let upload = match test {
        Some(_) => prep.upload_bytes(),
        // The uniform peer uploads control points and topology only.
        None => {
            prep.upload_bytes()
                - tessera_core::gpu_types::MapHalves::bytes(prep.maps.len()) as usize
        }
    };
    let stats = Stats {
        input: args.input.display().to_string(),
        method: test.map_or("uniform", EdgeTest::name),
        backend: if gpu.is_some() { "gpu" } else { "cpu" },
        adapter,
        threshold,
        tolerance_px: view.map(|v| v.pixels),
        culled_patches: view.map(|_| out.culled_patches),
        max_error_px,
        max_depth: test.map(|_| max_depth),
        segments,
        target_triangles: args.target_triangles,
        triangles: out.mesh.triangle_count(),
        vertices: out.mesh.vertices.len(),
        vertex_face: "the Bézier patch, by its index in the file (0-based)",
        vertex_uv: "the point's (u, v) on that patch",
        patches: model.patches.len(),
        evaluations: out.evaluations,
        upload_bytes: upload,
        upload_bytes_per_patch: upload as f64 / model.patches.len() as f64,
        timings_ms: timings,
        error,
        measure_samples: args.measure.then_some(measure_samples),
    };
    finish_outputs(staged_mesh, args.stats.as_deref(), &stats)?;
    print_summary(&stats);
    Ok(())
}

fn print_summary(s: &Stats) {
    let mut line = format!(
        "{}: {} ({}) {} triangles, {} vertices, {} patches, {} evaluations, upload {} B ({:.0} B/patch), tessellate {:.2} ms",
        s.input,
        s.method,
        s.backend,
        s.triangles,
        s.vertices,
        s.patches,
        s.evaluations,
        s.upload_bytes,
        s.upload_bytes_per_patch,
        s.timings_ms.tessellate
    );
    if let Some(th) = s.threshold {
        line += &format!(", threshold {th:.6}");
    }
    if let Some(n) = s.segments {
        line += &format!(", segments {n}");
    }
    if let Some(n) = s.culled_patches {
        line += &format!(", {n} patches culled");
    }
    println!("{line}");
    if let Some(a) = &s.adapter {
        println!("adapter: {a}");
    }
    if let Some(e) = &s.error {
        println!(
            "error vs exact surface: max {:.6} ({:.3e} of diagonal {:.4}), mean {:.6}, p99 {:.6} over {} samples",
            e.max_error, e.max_error_rel, e.bbox_diag, e.mean_error, e.p99_error, e.samples
        );
        if let Some(n) = s.measure_samples {
            let (p, k) = (e.worst_sample / (n * n), e.worst_sample % (n * n));
            let (u, v) = (
                (k % n) as f64 / (n - 1) as f64,
                (k / n) as f64 / (n - 1) as f64,
            );
            println!("largest error at patch {p}, (u, v) = ({u:.3}, {v:.3})");
        }
    }
}
