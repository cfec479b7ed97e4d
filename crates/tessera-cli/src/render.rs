//! `tessera render`: tessellate on the GPU (Bézier or Catmull-Clark, or a Catmull-Clark
//! mesh with the CPU reference) and draw the result headless into a PNG.

use std::time::Instant;

use tessera_core::bezier::{AdaptiveParams, EdgeTest, PreparedBezier};
use tessera_core::Error as CoreError;
use tessera_wgpu::image_out::{render_view_to_rgba, save_png};
use tessera_wgpu::{Error, RenderOptions};
use tessera_wgpu::{Kernels, Pose, View};

use tessera_core::catmull_clark::{CcParams, SurfaceModel, MAX_DEPTH, TREE_DEPTH};
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::catmull_clark::{CcStage, CcUniformStage, UniformParams};
use tessera_wgpu::glam::DVec3;
use tessera_wgpu::MeshBuffers;

use crate::cli::{Axis, Backend, Method, RenderArgs};
use crate::gpu::GpuTimings;

/// The stage whose output buffers are drawn.
enum StageOutput {
    Bezier(Box<BezierStage>),
    Cc(Box<CcStage>),
    CcUniform(Box<CcUniformStage>),
    /// A mesh tessellated by the CPU reference, uploaded to be drawn.
    Cpu(Box<MeshBuffers>),
}

impl StageOutput {
    fn mesh(&self) -> &MeshBuffers {
        match self {
            StageOutput::Bezier(s) => s.output(),
            StageOutput::Cc(s) => s.output(),
            StageOutput::CcUniform(s) => s.output(),
            StageOutput::Cpu(m) => m,
        }
    }
}

pub fn render(args: RenderArgs) -> Result<(), Error> {
    let t_total = Instant::now();
    let cc = tessera_core::io::is_control_mesh(&args.input);
    let test = match (cc, args.method) {
        (false, None | Some(Method::Map4p)) => EdgeTest::Map4p,
        (false, Some(Method::Map2p)) => EdgeTest::Map2p,
        (false, Some(Method::Map8p)) => EdgeTest::Map8p,
        (false, Some(Method::Flat)) => EdgeTest::Flat,
        // (Unused for Catmull-Clark meshes.)
        (true, None | Some(Method::Adaptive | Method::Uniform)) => EdgeTest::Map4p,
        (false, _) => return Err(CoreError::Param(
            "tessera render takes the GPU methods map2p, map4p, map8p or flat for Bézier surfaces"
                .into(),
        )
        .into()),
        (true, _) => {
            return Err(CoreError::Param(
                "tessera render takes --method adaptive or uniform for Catmull-Clark meshes".into(),
            )
            .into())
        }
    };
    if cc && args.threshold.is_some() {
        return Err(CoreError::Param(
            "--threshold is a Bézier option; Catmull-Clark meshes take --tolerance-rel".into(),
        )
        .into());
    }
    let uniform = cc && args.method == Some(Method::Uniform);
    if args.segments.is_some() && !uniform {
        return Err(CoreError::Param(
            "--segments is for Catmull-Clark meshes with --method uniform".into(),
        )
        .into());
    }
    if uniform && (args.tolerance_rel.is_some() || args.first_split.is_some()) {
        return Err(CoreError::Param(
            "--method uniform takes --segments, not a tolerance or --first-split".into(),
        )
        .into());
    }
    if !cc
        && (args.tolerance_rel.is_some()
            || args.first_split.is_some()
            || args.split_non_manifold
            || args.no_creases
            || args.backend.is_some())
    {
        return Err(CoreError::Param(
            "--tolerance-rel, --first-split, --split-non-manifold, --no-creases and --backend are Catmull-Clark options; Bézier surfaces take --threshold and are tessellated on the GPU".into(),
        )
        .into());
    }
    if args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        != Some("png".into())
    {
        return Err(CoreError::Param(format!(
            "{}: the render output must be a .png file",
            args.output.display()
        ))
        .into());
    }
    if args.view.given() && uniform {
        return Err(CoreError::Param(
            "a view (--eye, --tolerance-px, ...) is for the adaptive methods".into(),
        )
        .into());
    }
    if !cc && args.view.given() && args.view.tolerance_px.is_none() {
        return Err(CoreError::Param(
            "a view of a Bézier surface sets its threshold in pixels: give --tolerance-px".into(),
        )
        .into());
    }
    if !cc && (args.view.max_triangles.is_some()) {
        return Err(CoreError::Param("--max-triangles is for Catmull-Clark meshes".into()).into());
    }
    if !cc && args.view.face_leaves {
        return Err(CoreError::Param("--face-leaves is for Catmull-Clark meshes".into()).into());
    }
    let mut drawn_view = None;
    let mut timings = GpuTimings::default();
    let (gpu, output, (lo, hi), what, (triangles, vertices)) = if cc {
        let mut control = tessera_core::io::load_control_mesh(&args.input)?;
        if args.no_creases {
            control.drop_creases("--no-creases");
        }
        for w in &control.warnings {
            eprintln!("warning: {w}");
        }
        let on_cpu = args.backend == Some(Backend::Cpu);
        let mesh = tessera_core::catmull_clark::patch_mesh(&mut control, args.split_non_manifold)?;
        let model = SurfaceModel::new(mesh, TREE_DEPTH);
        let (lo, hi) = control.positions.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let rel = args
            .tolerance_rel
            .unwrap_or(crate::catmull_clark::DEFAULT_TOLERANCE_REL);
        let params = CcParams {
            tolerance: tessera_core::Tolerance::Relative(rel),
            max_depth: args.max_depth.unwrap_or(MAX_DEPTH),
            first_split: args.first_split.unwrap_or_default().into(),
            leaf_bound: Default::default(),
        };
        params.validate(&model)?;
        let gpu = crate::gpu::open(&mut timings)?;
        let kernels = Kernels::new(&gpu.device);
        let bounds = (lo.as_vec3(), hi.as_vec3());
        // The camera drawn is the one tessellated for, and the world tolerance only caps
        // the pixels' unless given.
        let view = if args.view.given() {
            let view =
                crate::catmull_clark::view_tolerance(&args.view, args.size, args.up, bounds)?;
            drawn_view = Some(view.view);
            Some(view)
        } else {
            None
        };
        let params = CcParams {
            tolerance: match view {
                Some(_) => crate::catmull_clark::world_tolerance(
                    &args.view,
                    args.tolerance_rel.map(tessera_core::Tolerance::Relative),
                ),
                None => params.tolerance,
            },
            ..params
        };
        if on_cpu {
            let t = Instant::now();
            let out = if uniform {
                tessera_core::catmull_clark::tessellate_uniform(&model, args.segments.unwrap_or(8))?
            } else if let Some(view) = &view {
                tessera_core::catmull_clark::tessellate_adaptive_in_view(&model, &params, view)?
            } else {
                tessera_core::catmull_clark::tessellate_adaptive(&model, &params)?
            };
            timings.tessellate = t.elapsed().as_secs_f64() * 1e3;
            let counts = (
                out.mesh.triangle_count() as u32,
                out.mesh.vertices.len() as u32,
            );
            let buffers = MeshBuffers::from_mesh(&gpu.device, &out.mesh);
            let what = if uniform {
                "uniform (cpu)"
            } else {
                "adaptive (cpu)"
            };
            (
                gpu,
                StageOutput::Cpu(Box::new(buffers)),
                bounds,
                what,
                counts,
            )
        } else if uniform {
            let n = args.segments.unwrap_or(8);
            let (stage, ()) = crate::gpu::run(&gpu, &mut timings, || {
                CcUniformStage::new(
                    &gpu.device,
                    &gpu.queue,
                    &kernels,
                    &model,
                    &UniformParams { segments: n },
                )
            })?;
            let counts = (stage.index_count() / 3, stage.vertex_count());
            let output = StageOutput::CcUniform(Box::new(stage));
            (gpu, output, bounds, "uniform", counts)
        } else {
            let (stage, status) = crate::gpu::run(&gpu, &mut timings, || {
                let mut stage = CcStage::new(&gpu.device, &gpu.queue, &kernels, &model, &params)?;
                stage.set_view(&gpu.queue, view.as_ref())?;
                Ok(stage)
            })?;
            let counts = (status.indices / 3, status.vertices());
            let output = StageOutput::Cc(Box::new(stage));
            (gpu, output, bounds, "adaptive", counts)
        }
    } else {
        let model = crate::tessellate::load(&args.input)?;
        let prep = PreparedBezier::new(&model);
        let (lo, hi) = model.bounds();
        // In pixels, the threshold in model units only caps them; the view drawn is the
        // one tessellated for.
        let view = if args.view.given() {
            let v = crate::catmull_clark::view_tolerance(&args.view, args.size, args.up, (lo, hi))?;
            drawn_view = Some(v.view);
            Some(tessera_core::bezier::BezierView {
                view: v.view,
                pixels: v.pixels.expect("checked"),
                cull: v.cull,
                cull_backfaces: v.cull_backfaces,
            })
        } else {
            None
        };
        let default_threshold = match view {
            Some(_) => (hi - lo).length(),
            None => 0.002 * (hi - lo).length(),
        };
        let params = AdaptiveParams {
            test,
            threshold: args.threshold.unwrap_or(default_threshold),
            max_depth: args.max_depth.unwrap_or(6),
        };
        params.validate()?;
        let gpu = crate::gpu::open(&mut timings)?;
        let kernels = Kernels::new(&gpu.device);
        let (stage, status) = crate::gpu::run(&gpu, &mut timings, || {
            let mut stage = BezierStage::new(&gpu.device, &gpu.queue, &kernels, &prep, &params)?;
            stage.set_view(&gpu.queue, view.as_ref())?;
            Ok(stage)
        })?;
        let counts = (status.indices / 3, status.vertices);
        (
            gpu,
            StageOutput::Bezier(Box::new(stage)),
            (lo, hi),
            test.name(),
            counts,
        )
    };
    let options = RenderOptions {
        wireframe: args.wireframe,
        patch_tint: args.patch_tint,
        ..RenderOptions::default()
    };
    let t = Instant::now();
    let (w, h) = args.size;
    let view = match drawn_view {
        Some(v) => v,
        None => default_framing(lo.as_dvec3(), hi.as_dvec3(), (w, h), args.up).view((w, h))?,
    };
    let image = render_view_to_rgba(&gpu, output.mesh(), &view, w, h, &options)?;
    let render_ms = t.elapsed().as_secs_f64() * 1e3;
    save_png(&image, &args.output)?;
    println!(
        "{}: {} {} triangles, {} vertices on {}; tessellate {:.2} ms, render {:.1} ms, total {:.0} ms -> {}",
        args.input.display(),
        what,
        triangles,
        vertices,
        gpu.adapter_name(),
        timings.tessellate,
        render_ms,
        t_total.elapsed().as_secs_f64() * 1e3,
        args.output.display()
    );
    Ok(())
}

/// The default view (front-right, above) of the box `lo..hi`, for the model's up axis:
/// `render`'s camera, and the view `tessellate` takes without `--eye`.
pub(crate) fn default_framing(lo: DVec3, hi: DVec3, size: (u32, u32), up: Axis) -> Pose {
    let d = View::FRAMING_DIRECTION;
    let (direction, up) = match up {
        Axis::Z => (d, DVec3::Z),
        Axis::Y => (DVec3::new(d.x, d.z, -d.y), DVec3::Y),
        Axis::X => (DVec3::new(d.z, d.x, d.y), DVec3::X),
    };
    Pose::framing(lo, hi, size, direction, up)
}
