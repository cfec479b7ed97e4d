//! `tessera tessellate` and `tessera info` for Catmull-Clark control meshes: the CPU
//! reference, or the adaptive stage on the GPU (`--backend gpu`).

use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive, tessellate_adaptive_in_view, tessellate_uniform,
    CcParams, CcTessellation, SurfaceModel, ViewTolerance, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::export::MeshFormat;
use tessera_core::io::load_control_mesh;
use tessera_core::measure::{max_error_px, ErrorStats};
use tessera_core::Error as CoreError;
use tessera_core::{Pose, Tolerance};
use tessera_wgpu::catmull_clark::{CcStage, CcUniformStage, UniformParams};
use tessera_wgpu::Error;
use tessera_wgpu::Kernels;

use crate::cli::{Axis, Backend, Method, TessellateArgs, ViewArgs};
use crate::gpu::GpuTimings;
use crate::tessellate::{check_measure_args, finish_outputs, measure_and_write, ms, Timings};

/// Default tolerance as a fraction of the bounding-box diagonal.
pub const DEFAULT_TOLERANCE_REL: f64 = 1e-3;
/// Default surface samples per patch side for `--measure` (the least allowed).
pub const DEFAULT_MEASURE_SAMPLES: usize = 32;

/// The stats' words for a vertex's `face` and `u v` (as in `--help` and docs/cli.md).
const VERTEX_FACE: &str = "the control face, by its index in the input (0-based)";
const VERTEX_UV: &str = "the point's (u, v) on that face, in OpenSubdiv Bfr's parameterisation: for a quad Ptex's, (0, 0) at its first vertex, u toward its second, v toward its last; a face of n != 4 sides is n half-unit sub-faces, one per vertex (tiles 2 per row for triangles, 3 for 5 to 9 sides, 1 + floor(sqrt(n - 1)) above)";

#[derive(Serialize)]
struct Stats {
    input: String,
    method: &'static str,
    backend: &'static str,
    boundary: tessera_core::catmull_clark::BoundaryRule,
    tolerance: Option<f64>,
    max_depth: Option<u32>,
    /// Adaptive: how each patch was first split.
    first_split: Option<tessera_core::catmull_clark::FirstSplit>,
    /// Adaptive: which bound accepts a leaf.
    leaf_bound: Option<tessera_core::catmull_clark::LeafBound>,
    segments: Option<u32>,
    triangles: usize,
    /// Output vertices: a point on an edge between faces (or between the sub-faces of a
    /// face that is not a quad) is one vertex per face, so that each carries its own.
    vertices: usize,
    /// Distinct vertex positions: the surface points, seam copies counted once.
    positions: usize,
    /// What each vertex's `face` is.
    vertex_face: &'static str,
    /// What each vertex's `u v` is.
    vertex_uv: &'static str,
    /// Control faces tessellated (holes left out).
    faces: usize,
    /// Level-1 patches tessellated: one per corner of each face, after the first
    /// subdivision step.
    patches: usize,
    /// Patches with an extraordinary corner (evaluated through their quadtree).
    irregular_patches: usize,
    evaluations: u64,
    /// GPU backend: what the stage uploaded when it was made (the adaptive stage's
    /// stencil tables and control points, the uniform stage's quadtrees); null on the
    /// CPU, which uploads nothing.
    upload_bytes: Option<usize>,
    leaves: usize,
    /// Adaptive: the largest guaranteed bound of any leaf (≤ tolerance when `unmet` is 0).
    guaranteed_error: Option<f64>,
    /// Adaptive: leaves stopped by --max-depth above the tolerance.
    unmet: Option<usize>,
    /// Adaptive: flatness bounds computed, the first-split search's trials included.
    flatness_bounds: Option<u64>,
    /// Adaptive: cells at a vertex split on the split proof alone, without a bound.
    split_proofs: Option<u64>,
    /// Adaptive with `--leaf-bound triangles`: distance bounds to a cell's own
    /// triangles computed.
    triangle_bounds: Option<u64>,
    /// Adaptive on the GPU: dispatches recorded per run, the same for every model and
    /// tolerance.
    dispatches: Option<u32>,
    /// With a view: the pixel tolerance asked for (`--tolerance-px`).
    tolerance_px: Option<f64>,
    /// With a view: the pixel tolerance the output meets, coarser than asked where
    /// `--max-triangles` made it so.
    achieved_tolerance_px: Option<f64>,
    /// With a view: patches all of whose cells lie outside the frustum (nothing emitted).
    culled_patches: Option<usize>,
    /// With a view: leaf cells outside the frustum.
    culled_leaves: Option<usize>,
    /// With a view and --measure: over the surface samples inside the frustum, the
    /// largest distance in pixels between a sample's projection and its nearest mesh
    /// point's.
    max_error_px: Option<f64>,
    warnings: Vec<String>,
    timings_ms: Timings,
    #[serde(flatten)]
    error: Option<ErrorStats>,
    measure_samples: Option<usize>,
}

pub fn tessellate(args: TessellateArgs) -> Result<(), Error> {
    let t_total = Instant::now();
    let mut timings = Timings::default();
    if let Some(o) = &args.output {
        MeshFormat::from_path(o)?;
    }
    let method = args.method.unwrap_or(Method::Adaptive);
    if !matches!(method, Method::Adaptive | Method::Uniform) {
        return Err(CoreError::Param(
            "Catmull-Clark meshes take --method adaptive or uniform; map2p, map4p, map8p and flat are Bézier methods".into(),
        )
        .into());
    }
    let on_gpu = args.backend == Some(Backend::Gpu);
    if args.threshold.is_some() || args.target_triangles.is_some() {
        return Err(CoreError::Param(
            "--threshold and --target-triangles are Bézier options; Catmull-Clark meshes take --tolerance or --tolerance-rel".into(),
        )
        .into());
    }
    if method == Method::Uniform && (args.tolerance.is_some() || args.tolerance_rel.is_some()) {
        return Err(CoreError::Param(
            "--method uniform takes --level or --segments, not a tolerance".into(),
        )
        .into());
    }
    if method == Method::Uniform && (args.first_split.is_some() || args.leaf_bound.is_some()) {
        return Err(CoreError::Param(
            "--first-split and --leaf-bound are for --method adaptive".into(),
        )
        .into());
    }
    let first_split = args.first_split.unwrap_or_default().into();
    let leaf_bound = args.leaf_bound.unwrap_or_default().into();
    if on_gpu && leaf_bound != tessera_core::catmull_clark::LeafBound::Flatness {
        return Err(CoreError::Param(
            "--leaf-bound triangles runs on the CPU only (--backend cpu)".into(),
        )
        .into());
    }
    if method == Method::Adaptive && (args.level.is_some() || args.segments.is_some()) {
        return Err(
            CoreError::Param("--level and --segments are for --method uniform".into()).into(),
        );
    }
    let max_depth = args.max_depth.unwrap_or(MAX_DEPTH);
    if max_depth > MAX_DEPTH {
        return Err(CoreError::Param(format!(
            "--max-depth {max_depth}: at most {MAX_DEPTH} for Catmull-Clark meshes"
        ))
        .into());
    }

    let t = Instant::now();
    let mut control = load_control_mesh(&args.input)?;
    if args.no_creases {
        control.drop_creases("--no-creases");
    }
    for w in &control.warnings {
        eprintln!("warning: {w}");
    }
    timings.load = ms(t);
    let t = Instant::now();
    let model = SurfaceModel::new(
        tessera_core::catmull_clark::patch_mesh(&mut control, args.split_non_manifold)?,
        TREE_DEPTH,
    );
    timings.prepare = ms(t);
    let measure_samples = args.measure_samples.unwrap_or(DEFAULT_MEASURE_SAMPLES);
    check_measure_args(&args, measure_samples, model.mesh.surface_patches().count())?;
    let view = if args.view.given() {
        if method != Method::Adaptive {
            return Err(CoreError::Param(
                "a view (--eye, --tolerance-px, ...) is for --method adaptive".into(),
            )
            .into());
        }
        let (lo, hi) = control.positions.iter().fold(
            (
                tessera_wgpu::glam::Vec3::INFINITY,
                tessera_wgpu::glam::Vec3::NEG_INFINITY,
            ),
            |(lo, hi), p| (lo.min(p.as_vec3()), hi.max(p.as_vec3())),
        );
        let size = args.size.unwrap_or((800, 600));
        let up = args.up.unwrap_or(Axis::Z);
        Some(view_tolerance(&args.view, size, up, (lo, hi))?)
    } else {
        None
    };

    let t = Instant::now();
    let mut dispatches = None;
    let mut upload_bytes = None;
    let (out, tolerance, segments) = match method {
        Method::Uniform => {
            let n = match args.level {
                Some(l) if l > 12 => {
                    return Err(CoreError::Param(format!("--level {l}: at most 12")).into())
                }
                Some(l) => 1 << l,
                None => args.segments.unwrap_or(8),
            };
            let out = if on_gpu {
                let mut gpu_timings = GpuTimings::default();
                let (out, uploaded) = run_gpu_uniform(&model, n, &mut gpu_timings)?;
                timings.gpu = Some(gpu_timings);
                upload_bytes = Some(uploaded);
                out
            } else {
                tessellate_uniform(&model, n)?
            };
            (out, None, Some(n))
        }
        _ => {
            let params = CcParams {
                tolerance: world_tolerance(
                    &args.view,
                    match (args.tolerance, args.tolerance_rel) {
                        (Some(t), _) => Some(Tolerance::Absolute(t)),
                        (None, r) => r.map(Tolerance::Relative),
                    },
                ),
                max_depth,
                first_split,
                leaf_bound,
            };
            params.validate(&model)?;
            let tolerance = params.epsilon(&model);
            if on_gpu {
                let mut gpu_timings = GpuTimings::default();
                let (out, recorded, uploaded) =
                    run_gpu(&model, &params, view.as_ref(), &mut gpu_timings)?;
                timings.gpu = Some(gpu_timings);
                dispatches = Some(recorded);
                upload_bytes = Some(uploaded);
                (out, Some(tolerance), None)
            } else if let Some(view) = &view {
                (
                    tessellate_adaptive_in_view(&model, &params, view)?,
                    Some(tolerance),
                    None,
                )
            } else {
                (tessellate_adaptive(&model, &params)?, Some(tolerance), None)
            }
        }
    };
    timings.tessellate = match &timings.gpu {
        // The tessellation alone (GPU work to completion), as for Bézier inputs.
        Some(g) => g.tessellate,
        None => ms(t),
    };
    let mut warnings = control.warnings.clone();
    if out.unmet > 0 {
        let w = format!(
            "{} leaves reached --max-depth {max_depth} above the tolerance: the bound there is {:.3e}",
            out.unmet, out.max_bound
        );
        eprintln!("warning: {w}");
        warnings.push(w);
    }

    let (error, staged_mesh, samples) = measure_and_write(
        &out.mesh,
        args.measure,
        || surface_samples(&model, measure_samples),
        model.mesh.control_diag,
        args.output.as_deref(),
        &mut timings,
    )?;
    // On the same samples as the error in model units.
    let max_error_px = match &view {
        Some(v) if args.measure => {
            let t = Instant::now();
            let px = max_error_px(&samples, &out.mesh, &v.view);
            timings.measure += ms(t);
            px
        }
        _ => None,
    };
    timings.total = ms(t_total);

    let stats = Stats {
        input: args.input.display().to_string(),
        method: if method == Method::Uniform {
            "uniform"
        } else {
            "adaptive"
        },
        backend: if on_gpu { "gpu" } else { "cpu" },
        boundary: model.mesh.boundary(),
        tolerance,
        max_depth: tolerance.map(|_| max_depth),
        first_split: tolerance.map(|_| first_split),
        leaf_bound: tolerance.map(|_| leaf_bound),
        segments,
        triangles: out.mesh.triangle_count(),
        vertices: out.mesh.vertices.len(),
        positions: out.mesh.distinct_positions(),
        vertex_face: VERTEX_FACE,
        vertex_uv: VERTEX_UV,
        faces: (0..model.mesh.control_faces.len())
            .filter(|&f| !model.mesh.hole[model.mesh.first_patch[f] as usize])
            .count(),
        patches: model.mesh.surface_patches().count(),
        irregular_patches: model.patches.iter().filter(|p| !p.is_regular()).count(),
        evaluations: out.evaluations,
        upload_bytes,
        leaves: out.leaves,
        guaranteed_error: tolerance.map(|_| out.max_bound),
        unmet: tolerance.map(|_| out.unmet),
        flatness_bounds: tolerance.map(|_| out.bounds),
        split_proofs: tolerance.map(|_| out.proven),
        triangle_bounds: tolerance.map(|_| out.triangle_bounds),
        dispatches,
        tolerance_px: view.and_then(|v| v.pixels),
        achieved_tolerance_px: out.tolerance_px,
        culled_patches: view.map(|_| out.culled_patches),
        culled_leaves: view.map(|_| out.culled_leaves),
        max_error_px,
        warnings,
        timings_ms: timings,
        error,
        measure_samples: args.measure.then_some(measure_samples),
    };
    finish_outputs(staged_mesh, args.stats.as_deref(), &stats)?;
    let mut line = format!(
        "{}: {} ({}) {} triangles, {} vertices, {} patches ({} irregular), {} evaluations, tessellate {:.2} ms",
        stats.input,
        stats.method,
        stats.backend,
        stats.triangles,
        stats.vertices,
        stats.patches,
        stats.irregular_patches,
        stats.evaluations,
        stats.timings_ms.tessellate
    );
    let pixels_only = args.view.tolerance_px.is_some()
        && args.tolerance.is_none()
        && args.tolerance_rel.is_none();
    if let Some(t) = tolerance.filter(|_| !pixels_only) {
        line += &format!(", tolerance {t:.6} (guaranteed bound {:.6})", out.max_bound);
    }
    if let Some(n) = segments {
        line += &format!(", segments {n}");
    }
    if let Some(v) = &view {
        match (v.pixels, out.tolerance_px) {
            (Some(asked), Some(got)) if got > asked => {
                // Without a cap only the device's loop limit coarsens (the GPU stage).
                let why = match v.max_triangles {
                    Some(_) => "to fit --max-triangles",
                    None => "by the device's loop limit; --backend cpu keeps them",
                };
                line += &format!(", {got:.4} px (coarsened from {asked} {why})")
            }
            (Some(px), _) => line += &format!(", {px} px"),
            _ => {}
        }
        line += &format!(", {} patches culled", out.culled_patches);
    }
    if let Some(px) = max_error_px {
        line += &format!(", measured {px:.3} px");
    }
    println!("{line}");
    if let Some(e) = &stats.error {
        println!(
            "error vs exact surface: max {:.6} ({:.3e} of diagonal {:.4}), mean {:.6}, p99 {:.6} over {} samples",
            e.max_error, e.max_error_rel, e.bbox_diag, e.mean_error, e.p99_error, e.samples
        );
    }
    Ok(())
}

/// The world tolerance given, if any; else none beyond the whole model where pixels set
/// the tolerance, and the default without them.
pub(crate) fn world_tolerance(view: &ViewArgs, given: Option<Tolerance>) -> Tolerance {
    match given {
        Some(t) => t,
        None if view.tolerance_px.is_some() => Tolerance::Relative(1.0),
        None => Tolerance::Relative(DEFAULT_TOLERANCE_REL),
    }
}

/// The view of `args` for a viewport of `size` pixels and the model's `up` axis: its
/// camera (or `render`'s default framing of the box `lo..hi`), with a far plane past the
/// box (the renderer draws it too), the pixel tolerance and culling.
pub(crate) fn view_tolerance(
    args: &ViewArgs,
    size: (u32, u32),
    up: Axis,
    (lo, hi): (tessera_wgpu::glam::Vec3, tessera_wgpu::glam::Vec3),
) -> Result<ViewTolerance, Error> {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let framing = crate::render::default_framing(lo, hi, size, up);
    let (eye, target) = match (args.eye, args.target) {
        (Some(e), Some(t)) => (
            tessera_wgpu::glam::DVec3::from(e),
            tessera_wgpu::glam::DVec3::from(t),
        ),
        _ => (framing.eye, framing.target),
    };
    let fovy = args.fov.map_or(framing.fovy, f64::to_radians);
    // The framing's near plane is in front of the model from its own eye; from another
    // eye, a hundredth of the model's size.
    let near = match (args.near, args.eye) {
        (Some(n), _) => n,
        (None, Some(_)) => 0.01 * (hi - lo).length(),
        (None, None) => framing.near,
    };
    // The far plane past the farthest corner of the box: nothing of the model beyond it.
    let far = tessera_core::view::box_corners(lo, hi)
        .iter()
        .map(|c| (*c - eye).length())
        .fold(near, f64::max)
        * 1.05
        + near;
    let pose = Pose {
        eye,
        target,
        fovy,
        near,
        far,
        ..framing
    };
    Ok(ViewTolerance {
        view: pose.view(size)?,
        pixels: args.tolerance_px,
        cull: !args.no_cull,
        cull_backfaces: args.cull_backfaces,
        max_triangles: args.max_triangles,
        face_leaves: args.face_leaves,
    })
}

pub fn info(input: &Path) -> Result<(), Error> {
    let mut control = load_control_mesh(input)?;
    let mesh = tessera_core::catmull_clark::patch_mesh(&mut control, false)?;
    let mut sizes = std::collections::BTreeMap::new();
    for f in &control.faces {
        *sizes.entry(f.len()).or_insert(0usize) += 1;
    }
    let sizes: Vec<String> = sizes.iter().map(|(k, n)| format!("{k}:{n}")).collect();
    println!(
        "{}: Catmull-Clark control mesh, {} vertices ({} unused), {} faces (sizes {}), {} holes",
        input.display(),
        control.positions.len(),
        mesh.unreferenced_vertices,
        control.faces.len(),
        sizes.join(" "),
        control.holes.iter().filter(|&&h| h).count()
    );
    let boundary_edges = mesh.edge_uses.iter().filter(|&&u| u == 1).count();
    println!(
        "  patches: {} (one per face corner), boundary rule {:?}, {} boundary edges after one step",
        mesh.patch_count(),
        mesh.boundary(),
        boundary_edges
    );
    let sharp = &mesh.control_sharpness;
    let infinite = |s: &f32| *s >= tessera_core::catmull_clark::SHARPNESS_INFINITE;
    println!(
        "  creases: {} sharp edges ({} infinitely sharp), {} sharp vertices, {:?} crease method, smooth triangles {}",
        sharp.edges.len(),
        sharp.edges.values().filter(|s| infinite(s)).count(),
        sharp.vertices.len(),
        mesh.scheme.creasing,
        if mesh.scheme.smooth_triangles { "on" } else { "off" }
    );
    let (lo, hi) = control.bounds();
    println!("  bounds: {lo} .. {hi} (diagonal {})", (hi - lo).length());
    for w in &control.warnings {
        println!("  warning: {w}");
    }
    Ok(())
}

/// The adaptive stage on the GPU: a first run that grows the buffers, then the timed run
/// and the readback; with the dispatches the run recorded and the bytes the stage
/// uploaded when it was made. Evaluations are the output
/// vertices (the GPU evaluates each once, a seam copy at its point's home like the
/// others; the cell corners its flatness test reads are not counted).
pub fn run_gpu(
    model: &SurfaceModel,
    params: &CcParams,
    view: Option<&ViewTolerance>,
    timings: &mut GpuTimings,
) -> Result<(CcTessellation, u32, usize), Error> {
    let gpu = crate::gpu::open(timings)?;
    let kernels = Kernels::new(&gpu.device);
    let (stage, status) = crate::gpu::run(&gpu, timings, || {
        let mut stage = CcStage::new(&gpu.device, &gpu.queue, &kernels, model, params)?;
        stage.set_view(&gpu.queue, view)?;
        Ok(stage)
    })?;
    let t = Instant::now();
    let mesh = stage.read_mesh(&gpu.device, &gpu.queue, &status)?;
    timings.readback = ms(t);
    let tessellation = CcTessellation {
        evaluations: mesh.vertices.len() as u64,
        mesh,
        leaves: status.state.leaves as usize,
        unmet: status.state.unmet as usize,
        max_bound: status.max_bound() as f64,
        bounds: status.state.bounds as u64,
        proven: status.state.proven as u64,
        triangle_bounds: 0,
        culled_leaves: status.state.culled_leaves as usize,
        culled_patches: status.state.culled_patches as usize,
        tolerance_px: stage.tolerance_px(),
    };
    Ok((tessellation, stage.dispatches(), stage.upload_bytes()))
}

/// The uniform stage on the GPU: a first run, the timed run and the readback; with the
/// bytes the stage uploaded.
pub fn run_gpu_uniform(
    model: &SurfaceModel,
    segments: u32,
    timings: &mut GpuTimings,
) -> Result<(CcTessellation, usize), Error> {
    let gpu = crate::gpu::open(timings)?;
    let kernels = Kernels::new(&gpu.device);
    let (stage, _) = crate::gpu::run(&gpu, timings, || {
        CcUniformStage::new(
            &gpu.device,
            &gpu.queue,
            &kernels,
            model,
            &UniformParams { segments },
        )
    })?;
    let t = Instant::now();
    let mesh = stage.read_mesh(&gpu.device, &gpu.queue)?;
    timings.readback = ms(t);
    let tessellation = CcTessellation {
        evaluations: mesh.vertices.len() as u64,
        leaves: model.mesh.surface_patches().count() * (segments as usize).pow(2),
        mesh,
        unmet: 0,
        max_bound: 0.0,
        bounds: 0,
        proven: 0,
        triangle_bounds: 0,
        culled_leaves: 0,
        culled_patches: 0,
        tolerance_px: None,
    };
    Ok((tessellation, stage.upload_bytes()))
}
