//! Catmull-Clark in a view: a tolerance in pixels against the same view culled at the
//! one world tolerance that guarantees the same pixel error everywhere in view, `p` times
//! the nearest visible depth over the focal length in pixels.
//! - Close-ups of the car and Spot: triangles, time on the CPU reference and the GPU
//!   stage, the measured `max_error_px` of both meshes, and the view's depth range.
//! - A scene of 64 cars in a grid, one control mesh, seen from ground level.
//! - Camera motion: the car's stage re-tessellated per frame as the view moves along a
//!   path (the view written through the queue, nothing else).
//!
//! Writes `OUT/catmull_clark_view.{json,md}`.

use std::path::Path;

use glam::DVec3;
use serde::Serialize;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive_in_view, CcParams, FirstSplit, PatchMesh, SurfaceModel,
    ViewTolerance, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::io::load_control_mesh;
use tessera_core::measure::max_error_px;
use tessera_core::{Tolerance, View};
use tessera_wgpu::catmull_clark::CcStage;
use tessera_wgpu::headless::Gpu;
use tessera_wgpu::Kernels;

use crate::gpu::gpu_median_ms;
use crate::{median, median_time};

#[derive(Serialize)]
struct Row {
    model: String,
    patches: usize,
    pixels: f64,
    /// Farthest over nearest depth of the surface samples in view.
    depth_range: f64,
    px_triangles: usize,
    px_ms: f64,
    /// The GPU stage in the same view: a run recorded, submitted and waited for.
    px_gpu_ms: f64,
    px_gpu_triangles: u32,
    px_max_error_px: f64,
    px_unmet: usize,
    culled_patches: usize,
    /// `p · nearest visible depth / focal length in pixels`.
    world_tolerance: f64,
    world_triangles: usize,
    world_ms: f64,
    world_max_error_px: f64,
    triangles_ratio: f64,
    time_ratio: f64,
    /// In pixels with the patches facing away culled too (outside the guarantee).
    backfaces_triangles: usize,
    backfaces_culled_patches: usize,
    backfaces_ms: f64,
    /// In pixels with face leaves: the CPU reference, and the GPU stage in the same view.
    faces_triangles: usize,
    faces_ms: f64,
    faces_gpu_triangles: u32,
    faces_gpu_ms: f64,
}

/// Vertical field of view, viewport and the sampling of the measurement.
const FOVY_DEG: f64 = 40.0;
const VIEWPORT: (u32, u32) = (800, 600);
const SAMPLES: usize = 16;

/// A view from just off one end of the model's longest side, a little above, looking
/// along it: the near end large on screen, the far end small.
/// The model as a renderer holds it after its first frame: each patch's root bound
/// computed ([`SurfaceModel::root_bound`]), and each face's
/// ([`SurfaceModel::face_bound`]) for the face leaves, so that every run timed, in
/// pixels or at the world ε, is a frame of a moving view and not the first.
fn warmed(model: SurfaceModel) -> SurfaceModel {
    for p in model.mesh.surface_patches() {
        model.root_bound(p);
    }
    for f in 0..model.mesh.control_faces.len() {
        model.face_bound(f);
    }
    model
}

fn close_up(model: &SurfaceModel) -> View {
    let samples = surface_samples(model, 2);
    let lo = samples.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = samples.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let (c, size) = ((lo + hi) / 2.0, hi - lo);
    let long = size.max_element();
    let axis = if size.x == long {
        DVec3::X
    } else if size.y == long {
        DVec3::Y
    } else {
        DVec3::Z
    };
    let up = if axis == DVec3::Z { DVec3::Y } else { DVec3::Z };
    let height = size.dot(up);
    let eye = c - axis * 0.505 * long + up * 0.2 * height;
    let target = c + axis * 0.5 * long;
    View::look_at(
        eye,
        target,
        up,
        FOVY_DEG.to_radians(),
        VIEWPORT,
        0.01 * long,
    )
    .expect("view")
}

pub fn run(assets: &Path, out_dir: &Path, quick: bool) {
    let models: &[&str] = if quick {
        &["catmull_clark/spot_control_mesh.obj"]
    } else {
        &[
            "opensubdiv/catmark_car.obj",
            "catmull_clark/spot_control_mesh.obj",
        ]
    };
    let repeats = if quick { 1 } else { 3 };
    let gpu = Gpu::new().expect("a wgpu adapter");
    let kernels = Kernels::new(&gpu.device);
    let mut rows = Vec::new();
    let mut motion = None;
    for rel in models {
        let control = load_control_mesh(&assets.join(rel)).expect("mesh");
        let model = warmed(SurfaceModel::new(
            PatchMesh::new(&control).expect("valid"),
            TREE_DEPTH,
        ));
        let name = Path::new(rel)
            .file_stem()
            .unwrap()
            .to_string_lossy()
            .to_string();
        let view = close_up(&model);
        let samples = surface_samples(&model, SAMPLES);
        let (nearest, farthest) = depth_range(&view, &samples);
        for pixels in [1.0, 0.5] {
            let run =
                |tolerance, px| cpu_in_view(&model, view, tolerance, px, false, false, repeats);
            let (px_ms, px) = run(Tolerance::Relative(1.0), Some(pixels));
            let (backfaces_ms, backfaces) = cpu_in_view(
                &model,
                view,
                Tolerance::Relative(1.0),
                Some(pixels),
                true,
                false,
                repeats,
            );
            let on_gpu = |face_leaves| {
                let at = ViewTolerance {
                    view,
                    pixels: Some(pixels),
                    cull: true,
                    cull_backfaces: false,
                    max_triangles: None,
                    face_leaves,
                };
                gpu_in_view(&gpu, &kernels, &model, &at, repeats)
                    .expect("the close-up fits the device")
            };
            let (px_gpu_ms, px_gpu_triangles) = on_gpu(false);
            let (faces_ms, faces) = cpu_in_view(
                &model,
                view,
                Tolerance::Relative(1.0),
                Some(pixels),
                false,
                true,
                repeats,
            );
            let (faces_gpu_ms, faces_gpu_triangles) = on_gpu(true);
            let world_tolerance = pixels * nearest / focal();
            let (world_ms, world) = run(Tolerance::Absolute(world_tolerance), None);
            let err = |m| max_error_px(&samples, m, &view).unwrap_or(0.0);
            let row = Row {
                model: name.clone(),
                patches: model.mesh.surface_patches().count(),
                pixels,
                depth_range: farthest / nearest,
                px_triangles: px.mesh.triangle_count(),
                px_ms,
                px_gpu_ms,
                px_gpu_triangles,
                px_max_error_px: err(&px.mesh),
                px_unmet: px.unmet,
                culled_patches: px.culled_patches,
                world_tolerance,
                world_triangles: world.mesh.triangle_count(),
                world_ms,
                world_max_error_px: err(&world.mesh),
                triangles_ratio: px.mesh.triangle_count() as f64
                    / world.mesh.triangle_count().max(1) as f64,
                time_ratio: px_ms / world_ms,
                backfaces_triangles: backfaces.mesh.triangle_count(),
                backfaces_culled_patches: backfaces.culled_patches,
                backfaces_ms,
                faces_triangles: faces.mesh.triangle_count(),
                faces_ms,
                faces_gpu_triangles,
                faces_gpu_ms,
            };
            eprintln!(
                "cc view {name} {pixels} px: {} tris ({:.0} ms) against {} ({:.0} ms) at {world_tolerance:.2e}",
                row.px_triangles, px_ms, row.world_triangles, world_ms
            );
            rows.push(row);
        }
        if rel.contains("car") || quick {
            motion = Some(camera_motion(&gpu, &kernels, &name, &model, repeats));
        }
    }
    let scene = (!quick).then(|| scene(&gpu, &kernels, assets));
    let mut s = format!(
        "Close-ups ({}×{} pixels, {FOVY_DEG}° vertical field of view, from just off one end of the model's longest side, looking along it; midpoint splits, medians of {repeats}; the CPU reference, on a model that kept its patches' root bounds from an earlier frame, and the GPU stage in the pixels' view on {adapter}): the tolerance in pixels against the same view culled at the world tolerance that guarantees the same pixel error everywhere in view (p × nearest visible depth / focal length). Measured pixel errors over {SAMPLES}×{SAMPLES} samples per patch inside the frustum (the target: at most 0.5× the triangles):\n\n",
        VIEWPORT.0,
        VIEWPORT.1,
        adapter = gpu.adapter_name()
    );
    s += "| model | patches | p (px) | depth range | triangles in pixels | CPU ms | GPU ms | measured px | unmet | culled patches | world ε | triangles at world ε | CPU ms | measured px | **triangles ratio** | CPU time ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in &rows {
        s += &format!(
            "| {} | {} | {} | {:.1}:1 | {} | {:.0} | {:.1} | {:.3} | {} | {} | {:.2e} | {} | {:.0} | {:.3} | **{:.2}** | {:.2} |\n",
            r.model,
            r.patches,
            r.pixels,
            r.depth_range,
            r.px_triangles,
            r.px_ms,
            r.px_gpu_ms,
            r.px_max_error_px,
            r.px_unmet,
            r.culled_patches,
            r.world_tolerance,
            r.world_triangles,
            r.world_ms,
            r.world_max_error_px,
            r.triangles_ratio,
            r.time_ratio
        );
    }
    s += "\nThe same close-ups in pixels with the patches facing away from the eye culled too (`cull_backfaces`, outside the guarantee, which then holds for the surface facing the eye); CPU reference:\n\n| model | p (px) | triangles | culled patches | CPU ms | against pixels alone | against world ε |\n|---|---|---|---|---|---|---|\n";
    for r in &rows {
        s += &format!(
            "| {} | {} | {} | {} | {:.0} | {:.2} | {:.2} |\n",
            r.model,
            r.pixels,
            r.backfaces_triangles,
            r.backfaces_culled_patches,
            r.backfaces_ms,
            r.backfaces_triangles as f64 / r.px_triangles.max(1) as f64,
            r.backfaces_triangles as f64 / r.world_triangles.max(1) as f64,
        );
    }
    s += "\nThe same close-ups in pixels with face leaves (a quad control face whose bound taken whole meets its tolerance is one leaf), on the CPU reference and on the GPU stage in the same view:\n\n| model | p (px) | triangles, CPU | CPU ms | triangles, GPU | GPU ms | against pixels alone | against world ε |\n|---|---|---|---|---|---|---|---|\n";
    for r in &rows {
        s += &format!(
            "| {} | {} | {} | {:.0} | {} | {:.1} | {:.2} | {:.2} |\n",
            r.model,
            r.pixels,
            r.faces_triangles,
            r.faces_ms,
            r.faces_gpu_triangles,
            r.faces_gpu_ms,
            r.faces_triangles as f64 / r.px_triangles.max(1) as f64,
            r.faces_triangles as f64 / r.world_triangles.max(1) as f64,
        );
    }
    if let Some(m) = &motion {
        s += &format!(
            "\nCamera motion on {} ({} patches, p = {} px, midpoint splits): {} views along a path from far to close and past, each written with `set_view` and run (the GPU stage), against the CPU reference in the same views; medians per frame:\n\n| frames | triangles (min–max) | culled patches (min–max) | **GPU ms per frame** | CPU ms per frame | GPU / CPU |\n|---|---|---|---|---|---|\n| {} | {}–{} | {}–{} | **{:.1}** | {:.0} | {:.2} |\n",
            m.model,
            m.patches,
            m.pixels,
            m.frames,
            m.frames,
            m.triangles.0,
            m.triangles.1,
            m.culled_patches.0,
            m.culled_patches.1,
            m.gpu_ms,
            m.cpu_ms,
            m.gpu_ms / m.cpu_ms
        );
    }
    if let Some(sc) = &scene {
        s += &format!(
            "\nA scene: {} copies of the car in an {}×{} grid, one control mesh ({} patches), seen from ground level off one corner, looking across it to the far corner ({}×{} pixels, p = {} px, midpoint splits, depth range {:.0}:1), against the same view culled at the world tolerance that guarantees the same pixel error ({:.2e}); CPU reference, on a model that kept its patches' root bounds from an earlier frame, medians of {}:\n\n| | triangles | culled patches | CPU ms |\n|---|---|---|---|\n| pixels | {} | {} | {:.0} |\n| world ε | {} | {} | {:.0} |\n| **ratio** | **{:.3}** | | **{:.3}** |\n| pixels, back faces culled | {} | {} | {:.0} |\n| world ε, back faces culled | {} | {} | {:.0} |\n| **ratio**, back faces culled | **{:.3}** | | **{:.3}** |\n| pixels, back faces culled, against world ε | {:.3} | | {:.3} |\n| pixels, face leaves | {} | | {:.0} |\n| world ε, face leaves | {} | | {:.0} |\n| **ratio**, face leaves | **{:.3}** | | **{:.3}** |\n| pixels, face leaves, against world ε | {:.3} | | {:.3} |\n\nWith face leaves a quad control face whose bound taken whole meets its tolerance is one leaf ({} leaves for the pixels' {} patches in view).\n\n{}",
            sc.copies,
            sc.side,
            sc.side,
            sc.patches,
            VIEWPORT.0,
            VIEWPORT.1,
            sc.pixels,
            sc.depth_range,
            sc.world_tolerance,
            sc.repeats,
            sc.px_triangles,
            sc.px_culled_patches,
            sc.px_ms,
            sc.world_triangles,
            sc.world_culled_patches,
            sc.world_ms,
            sc.px_triangles as f64 / sc.world_triangles.max(1) as f64,
            sc.px_ms / sc.world_ms,
            sc.px_backfaces_triangles,
            sc.px_backfaces_culled_patches,
            sc.px_backfaces_ms,
            sc.world_backfaces_triangles,
            sc.world_backfaces_culled_patches,
            sc.world_backfaces_ms,
            sc.px_backfaces_triangles as f64 / sc.world_backfaces_triangles.max(1) as f64,
            sc.px_backfaces_ms / sc.world_backfaces_ms,
            sc.px_backfaces_triangles as f64 / sc.world_triangles.max(1) as f64,
            sc.px_backfaces_ms / sc.world_ms,
            sc.px_faces_triangles,
            sc.px_faces_ms,
            sc.world_faces_triangles,
            sc.world_faces_ms,
            sc.px_faces_triangles as f64 / sc.world_faces_triangles.max(1) as f64,
            sc.px_faces_ms / sc.world_faces_ms,
            sc.px_faces_triangles as f64 / sc.world_triangles.max(1) as f64,
            sc.px_faces_ms / sc.world_ms,
            sc.px_faces_leaves,
            sc.patches - sc.px_culled_patches,
            scene_gpu_table(&sc.gpu, sc.repeats, &gpu.adapter_name())
        );
    }
    let json = Results {
        adapter: gpu.adapter_name(),
        close_ups: rows,
        camera_motion: motion,
        scene,
    };
    crate::write_results(out_dir, "catmull_clark_view", &json, s);
}

/// The nearest and farthest clip `w` of the samples inside the view's frustum.
fn depth_range(view: &View, samples: &[DVec3]) -> (f64, f64) {
    let depths: Vec<f64> = samples
        .iter()
        .filter(|&&p| view.contains(p))
        .map(|&p| view.clip_of(p).w)
        .collect();
    let nearest = depths.iter().copied().fold(f64::INFINITY, f64::min);
    let farthest = depths.iter().copied().fold(0.0, f64::max);
    (nearest, farthest)
}

/// The focal length in pixels of the bench's views.
fn focal() -> f64 {
    0.5 * VIEWPORT.1 as f64 / (0.5 * FOVY_DEG.to_radians()).tan()
}

/// The CPU reference in `view`, culled, at `tolerance` and (if given) `pixels`: the
/// median time (ms) and the tessellation.
fn cpu_in_view(
    model: &SurfaceModel,
    view: View,
    tolerance: Tolerance,
    pixels: Option<f64>,
    backfaces: bool,
    face_leaves: bool,
    repeats: usize,
) -> (f64, tessera_core::catmull_clark::CcTessellation) {
    let params = CcParams {
        tolerance,
        max_depth: MAX_DEPTH,
        first_split: FirstSplit::Midpoint,
        leaf_bound: Default::default(),
    };
    let vt = ViewTolerance {
        view,
        pixels,
        cull: true,
        cull_backfaces: backfaces,
        max_triangles: None,
        face_leaves,
    };
    median_time(repeats, || {
        tessellate_adaptive_in_view(model, &params, &vt).expect("tessellate")
    })
}

#[derive(Serialize)]
struct Results {
    /// The GPU stage's adapter.
    adapter: String,
    close_ups: Vec<Row>,
    camera_motion: Option<Motion>,
    scene: Option<Scene>,
}

/// The GPU stage of `model` in `view`: the median run (ms) and its triangles, or why the
/// device cannot hold it.
fn gpu_in_view(
    gpu: &Gpu,
    kernels: &Kernels,
    model: &SurfaceModel,
    view: &ViewTolerance,
    repeats: usize,
) -> Result<(f64, u32), String> {
    let params = CcParams {
        tolerance: Tolerance::Relative(1.0),
        max_depth: MAX_DEPTH,
        first_split: FirstSplit::Midpoint,
        leaf_bound: Default::default(),
    };
    let mut stage = CcStage::new(&gpu.device, &gpu.queue, kernels, model, &params)
        .map_err(|e| e.to_string())?;
    stage.set_view(&gpu.queue, Some(view)).expect("view");
    let status = stage
        .run_blocking(&gpu.device, &gpu.queue)
        .map_err(|e| e.to_string())?;
    let ms = gpu_median_ms(gpu, repeats, |e| {
        stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
    });
    gpu.check().expect("no wgpu errors");
    Ok((ms, status.indices / 3))
}

#[derive(Serialize)]
struct Motion {
    model: String,
    patches: usize,
    pixels: f64,
    frames: usize,
    triangles: (u32, u32),
    culled_patches: (u32, u32),
    gpu_ms: f64,
    cpu_ms: f64,
}

/// Views along a path past `model`: from far in front, in close along its side, and
/// out past its end.
fn path(model: &SurfaceModel, frames: usize) -> Vec<View> {
    let samples = surface_samples(model, 2);
    let lo = samples.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = samples.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let (c, d) = ((lo + hi) / 2.0, (hi - lo).length());
    (0..frames)
        .map(|k| {
            let t = k as f64 / (frames - 1) as f64;
            // Around the model at a shrinking then growing distance.
            let angle = -1.2 + 2.4 * t;
            let distance = d * (0.45 + 1.6 * (2.0 * t - 1.0).powi(2));
            let eye = c + DVec3::new(angle.sin(), -angle.cos(), 0.25) * distance;
            View::look_at(eye, c, DVec3::Z, FOVY_DEG.to_radians(), VIEWPORT, 0.01 * d)
                .expect("view")
        })
        .collect()
}

/// [`Motion`] of `model`: one stage, its view written per frame.
fn camera_motion(
    gpu: &Gpu,
    kernels: &Kernels,
    name: &str,
    model: &SurfaceModel,
    repeats: usize,
) -> Motion {
    const PIXELS: f64 = 1.0;
    let frames = 12;
    let views = path(model, frames);
    let params = CcParams {
        tolerance: Tolerance::Relative(1.0),
        max_depth: MAX_DEPTH,
        first_split: FirstSplit::Midpoint,
        leaf_bound: Default::default(),
    };
    let at = |v: &View| ViewTolerance {
        view: *v,
        pixels: Some(PIXELS),
        cull: true,
        cull_backfaces: false,
        max_triangles: None,
        face_leaves: false,
    };
    let mut stage = CcStage::new(&gpu.device, &gpu.queue, kernels, model, &params).expect("stage");
    // Every view once to completion: the buffers grown for the largest.
    let (mut triangles, mut culled) = ((u32::MAX, 0), (u32::MAX, 0));
    for v in &views {
        stage.set_view(&gpu.queue, Some(&at(v))).expect("view");
        let status = stage.run_blocking(&gpu.device, &gpu.queue).expect("run");
        let t = status.indices / 3;
        triangles = (triangles.0.min(t), triangles.1.max(t));
        let c = status.state.culled_patches;
        culled = (culled.0.min(c), culled.1.max(c));
    }
    let mut k = 0;
    let gpu_ms = gpu_median_ms(gpu, repeats * frames, |e| {
        stage
            .set_view(&gpu.queue, Some(&at(&views[k % frames])))
            .expect("view");
        k += 1;
        stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
    });
    gpu.check().expect("no wgpu errors");
    let cpu_ms = median(
        views
            .iter()
            .map(|v| {
                median_time(1, || {
                    tessellate_adaptive_in_view(model, &params, &at(v)).expect("tessellate")
                })
                .0
            })
            .collect(),
    );
    eprintln!("cc view motion {name}: GPU {gpu_ms:.1} ms, CPU {cpu_ms:.0} ms per frame");
    Motion {
        model: name.to_string(),
        patches: model.mesh.surface_patches().count(),
        pixels: PIXELS,
        frames,
        triangles,
        culled_patches: culled,
        gpu_ms,
        cpu_ms,
    }
}

#[derive(Serialize)]
struct Scene {
    copies: usize,
    side: usize,
    patches: usize,
    pixels: f64,
    depth_range: f64,
    world_tolerance: f64,
    repeats: usize,
    px_triangles: usize,
    px_culled_patches: usize,
    px_ms: f64,
    /// The GPU stage's runs, or why the device cannot hold the scene.
    gpu: Result<SceneGpu, String>,
    world_triangles: usize,
    world_culled_patches: usize,
    world_ms: f64,
    /// Both runs again with the patches facing away culled too.
    px_backfaces_triangles: usize,
    px_backfaces_culled_patches: usize,
    px_backfaces_ms: f64,
    world_backfaces_triangles: usize,
    world_backfaces_culled_patches: usize,
    world_backfaces_ms: f64,
    /// Both runs again with face leaves: a quad control face within its tolerance taken
    /// whole is one leaf.
    px_faces_triangles: usize,
    px_faces_leaves: usize,
    px_faces_ms: f64,
    world_faces_triangles: usize,
    world_faces_ms: f64,
}

/// The scene's table on the GPU stage, or why it did not run.
fn scene_gpu_table(on_gpu: &Result<SceneGpu, String>, repeats: usize, adapter: &str) -> String {
    let g = match on_gpu {
        Ok(g) => g,
        Err(e) => {
            return format!("The GPU stage: not run, the device cannot hold the scene ({e}).\n")
        }
    };
    let row = |name: &str, r: &Result<SceneGpuRun, String>| match r {
        Ok(r) => format!(
            "| {name} | {} | {} | {:.0} |\n",
            r.triangles, r.culled_patches, r.ms
        ),
        Err(e) => format!("| {name} | not run: {e} | | |\n"),
    };
    let ratio =
        |name: &str, a: &Result<SceneGpuRun, String>, b: &Result<SceneGpuRun, String>| match (a, b)
        {
            (Ok(a), Ok(b)) => format!(
                "| {name} | {:.3} | | {:.3} |\n",
                a.triangles as f64 / b.triangles.max(1) as f64,
                a.ms / b.ms
            ),
            _ => String::new(),
        };
    let pixels = Ok(g.pixels.clone());
    let mut s = format!(
        "The same runs on the GPU stage ({adapter}; one stage, built in {:.0} s, its tolerance and view set for each run; time per frame, medians of {repeats}):\n\n| | triangles | culled patches | GPU ms |\n|---|---|---|---|\n",
        g.build_s
    );
    s += &row("pixels", &pixels);
    s += &row("world ε", &g.world);
    s += &ratio("**ratio**", &pixels, &g.world);
    s += &row("pixels, face leaves", &g.pixels_faces);
    s += &row("world ε, face leaves", &g.world_faces);
    s += &ratio("**ratio**, face leaves", &g.pixels_faces, &g.world_faces);
    s += &ratio(
        "pixels, face leaves, against world ε",
        &g.pixels_faces,
        &g.world,
    );
    s
}

/// The scene on the GPU stage: one stage, its tolerance and view set for each run.
#[derive(Serialize)]
struct SceneGpu {
    /// Building the stage: its stencil tables, buffers and first run (s).
    build_s: f64,
    pixels: SceneGpuRun,
    /// The others, or why the device could not run them.
    world: Result<SceneGpuRun, String>,
    pixels_faces: Result<SceneGpuRun, String>,
    world_faces: Result<SceneGpuRun, String>,
}

/// One configuration of the scene on the GPU stage.
#[derive(Clone, Serialize)]
struct SceneGpuRun {
    triangles: u32,
    culled_patches: u32,
    /// Median time per frame (ms).
    ms: f64,
}

/// The scene on the GPU stage in `view`: pixels and world ε, by patches and with face
/// leaves.
fn scene_on_gpu(
    gpu: &Gpu,
    kernels: &Kernels,
    model: &SurfaceModel,
    view: View,
    (pixels, world_tolerance): (f64, f64),
    repeats: usize,
) -> Result<SceneGpu, String> {
    let started = std::time::Instant::now();
    let params = |tolerance| CcParams {
        tolerance,
        max_depth: MAX_DEPTH,
        first_split: FirstSplit::Midpoint,
        leaf_bound: Default::default(),
    };
    let mut stage = CcStage::new(
        &gpu.device,
        &gpu.queue,
        kernels,
        model,
        &params(Tolerance::Relative(1.0)),
    )
    .map_err(|e| e.to_string())?;
    let mut build_s = None;
    let mut run = |px: Option<f64>, face_leaves| -> Result<SceneGpuRun, String> {
        let tolerance = match px {
            Some(_) => Tolerance::Relative(1.0),
            None => Tolerance::Absolute(world_tolerance),
        };
        let at = ViewTolerance {
            view,
            pixels: px,
            cull: true,
            cull_backfaces: false,
            max_triangles: None,
            face_leaves,
        };
        let e = |e: tessera_wgpu::Error| e.to_string();
        stage
            .set_params(&gpu.device, &gpu.queue, &params(tolerance))
            .map_err(e)?;
        stage.set_view(&gpu.queue, Some(&at)).map_err(e)?;
        let status = stage.run_blocking(&gpu.device, &gpu.queue).map_err(e)?;
        build_s.get_or_insert(started.elapsed().as_secs_f64());
        let ms = gpu_median_ms(gpu, repeats, |e| {
            stage.prepare(&gpu.device, &gpu.queue, e).expect("prepare")
        });
        gpu.check().map_err(e)?;
        eprintln!(
            "cc view scene on the GPU, {px:?} px, face leaves {face_leaves}: {} tris, {ms:.0} ms",
            status.indices / 3
        );
        Ok(SceneGpuRun {
            triangles: status.indices / 3,
            culled_patches: status.state.culled_patches,
            ms,
        })
    };
    let pixels_run = run(Some(pixels), false)?;
    let world = run(None, false);
    let pixels_faces = run(Some(pixels), true);
    let world_faces = run(None, true);
    Ok(SceneGpu {
        build_s: build_s.unwrap_or_default(),
        pixels: pixels_run,
        world,
        pixels_faces,
        world_faces,
    })
}

/// 64 cars in an 8 × 8 grid, one control mesh, from ground level off one corner,
/// looking across the grid to the far corner.
fn scene(gpu: &Gpu, kernels: &Kernels, assets: &Path) -> Scene {
    const SIDE: usize = 8;
    const PIXELS: f64 = 1.0;
    let started = std::time::Instant::now();
    let car = load_control_mesh(&assets.join("opensubdiv/catmark_car.obj")).expect("mesh");
    let lo = car.positions.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = car
        .positions
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let size = hi - lo;
    // Rows along x (the car's length), 1.6 lengths apart; columns 2 widths apart.
    let step = DVec3::new(1.6 * size.x, 2.0 * size.y, 0.0);
    let mut control = car.clone();
    control.positions.clear();
    control.faces.clear();
    control.face_lines.clear();
    control.holes.clear();
    control.creases.clear();
    control.corners.clear();
    let n = car.positions.len() as u32;
    for k in 0..SIDE * SIDE {
        let base = k as u32 * n;
        let offset = DVec3::new((k / SIDE) as f64 * step.x, (k % SIDE) as f64 * step.y, 0.0);
        control
            .positions
            .extend(car.positions.iter().map(|&p| p + offset));
        control.faces.extend(
            car.faces
                .iter()
                .map(|f| f.iter().map(|&v| v + base).collect()),
        );
        control.face_lines.extend(&car.face_lines);
        control.holes.extend(&car.holes);
        control.creases.extend(
            car.creases
                .iter()
                .map(|&([a, b], s)| ([a + base, b + base], s)),
        );
        control
            .corners
            .extend(car.corners.iter().map(|&(v, s)| (v + base, s)));
    }
    let model = warmed(SurfaceModel::new(
        PatchMesh::new(&control).expect("valid"),
        TREE_DEPTH,
    ));
    // At the height of a car's middle, off one corner of the lot, looking across it
    // to the far corner.
    let far_corner = lo + step * (SIDE - 1) as f64 + size;
    let eye = DVec3::new(
        lo.x - 0.3 * size.x,
        lo.y - 0.3 * size.x,
        lo.z + 0.5 * size.z,
    );
    let target = DVec3::new(far_corner.x, far_corner.y, eye.z);
    let view = View::look_at(
        eye,
        target,
        DVec3::Z,
        FOVY_DEG.to_radians(),
        VIEWPORT,
        0.01 * size.x,
    )
    .expect("view");
    let (nearest, farthest) = depth_range(&view, &surface_samples(&model, 2));
    let world_tolerance = PIXELS * nearest / focal();
    // The first run after another config is slower (its allocations are new): medians.
    let repeats = 3;
    let run = |tolerance, px| cpu_in_view(&model, view, tolerance, px, false, false, repeats);
    let run_backfaces =
        |tolerance, px| cpu_in_view(&model, view, tolerance, px, true, false, repeats);
    let run_faces = |tolerance, px| cpu_in_view(&model, view, tolerance, px, false, true, repeats);
    eprintln!(
        "cc view scene: built and sampled in {:.0} s",
        started.elapsed().as_secs_f64()
    );
    let (px_ms, px) = run(Tolerance::Relative(1.0), Some(PIXELS));
    eprintln!("cc view scene: pixels {px_ms:.0} ms");
    let on_gpu = scene_on_gpu(
        gpu,
        kernels,
        &model,
        view,
        (PIXELS, world_tolerance),
        repeats,
    );
    let (world_ms, world) = run(Tolerance::Absolute(world_tolerance), None);
    eprintln!(
        "cc view scene: {} tris ({px_ms:.0} ms) against {} ({world_ms:.0} ms)",
        px.mesh.triangle_count(),
        world.mesh.triangle_count()
    );
    let (px_backfaces_ms, px_backfaces) = run_backfaces(Tolerance::Relative(1.0), Some(PIXELS));
    let (world_backfaces_ms, world_backfaces) =
        run_backfaces(Tolerance::Absolute(world_tolerance), None);
    let (px_faces_ms, px_faces) = run_faces(Tolerance::Relative(1.0), Some(PIXELS));
    let (world_faces_ms, world_faces) = run_faces(Tolerance::Absolute(world_tolerance), None);
    eprintln!(
        "cc view scene, face leaves: {} tris ({px_faces_ms:.0} ms) against {} ({world_faces_ms:.0} ms)",
        px_faces.mesh.triangle_count(),
        world_faces.mesh.triangle_count()
    );
    Scene {
        copies: SIDE * SIDE,
        side: SIDE,
        patches: model.mesh.surface_patches().count(),
        pixels: PIXELS,
        depth_range: farthest / nearest,
        world_tolerance,
        repeats,
        px_triangles: px.mesh.triangle_count(),
        px_culled_patches: px.culled_patches,
        px_ms,
        gpu: on_gpu,
        world_triangles: world.mesh.triangle_count(),
        world_culled_patches: world.culled_patches,
        world_ms,
        px_backfaces_triangles: px_backfaces.mesh.triangle_count(),
        px_backfaces_culled_patches: px_backfaces.culled_patches,
        px_backfaces_ms,
        world_backfaces_triangles: world_backfaces.mesh.triangle_count(),
        world_backfaces_culled_patches: world_backfaces.culled_patches,
        world_backfaces_ms,
        px_faces_triangles: px_faces.mesh.triangle_count(),
        px_faces_leaves: px_faces.leaves,
        px_faces_ms,
        world_faces_triangles: world_faces.mesh.triangle_count(),
        world_faces_ms,
    }
}
