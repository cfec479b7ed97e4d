//! The open model and what tessellates it: the GPU stages, each made the first time its
//! method is chosen and kept while the model is open, or the CPU reference; the
//! parameters the panel and the script set; the animated control points.

use std::path::{Path, PathBuf};
use std::time::Instant;

use tessera_core::bezier::{self, AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
use tessera_core::catmull_clark::{
    self, patch_mesh, CcParams, FirstSplit, SurfaceModel, ViewTolerance, MAX_DEPTH, TREE_DEPTH,
};
use tessera_core::gpu_types::MAX_DEPTH_LIMIT;
use tessera_core::io::{is_control_mesh, load_control_mesh};
use tessera_core::Tolerance;
use tessera_wgpu::bezier::BezierStage;
use tessera_wgpu::catmull_clark::{CcStage, CcUniformStage, UniformParams};
use tessera_wgpu::glam::{DVec3, Vec3};
use tessera_wgpu::{wgpu, GpuTimer, Kernels, MeshBuffers, View};

use crate::camera::Axis;

/// How a surface is tessellated. `Uniform` is the uniform grid of either kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Map2p,
    Map4p,
    Map8p,
    Flat,
    Uniform,
    Adaptive,
}

impl Method {
    pub const BEZIER: [Method; 5] = [
        Method::Map2p,
        Method::Map4p,
        Method::Map8p,
        Method::Flat,
        Method::Uniform,
    ];
    pub const CATMULL_CLARK: [Method; 2] = [Method::Adaptive, Method::Uniform];

    pub fn parse(s: &str) -> Option<Method> {
        Some(match s {
            "map2p" => Method::Map2p,
            "map4p" => Method::Map4p,
            "map8p" => Method::Map8p,
            "flat" => Method::Flat,
            "uniform" => Method::Uniform,
            "adaptive" => Method::Adaptive,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Method::Map2p => "map2p",
            Method::Map4p => "map4p",
            Method::Map8p => "map8p",
            Method::Flat => "flat",
            Method::Uniform => "uniform",
            Method::Adaptive => "adaptive",
        }
    }

    fn edge_test(self) -> Option<EdgeTest> {
        match self {
            Method::Map2p => Some(EdgeTest::Map2p),
            Method::Map4p => Some(EdgeTest::Map4p),
            Method::Map8p => Some(EdgeTest::Map8p),
            Method::Flat => Some(EdgeTest::Flat),
            Method::Uniform | Method::Adaptive => None,
        }
    }

    /// The methods of a kind of surface.
    pub fn of(kind: Kind) -> &'static [Method] {
        match kind {
            Kind::Bezier => &Self::BEZIER,
            Kind::CatmullClark => &Self::CATMULL_CLARK,
        }
    }

    /// Whether a stage of tessera-wgpu runs it (Bézier uniform is the CPU's alone).
    pub fn on_gpu(self, kind: Kind) -> bool {
        !(kind == Kind::Bezier && self == Method::Uniform)
    }
}

/// Where the tessellation runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The stages' WGSL kernels.
    Gpu,
    /// The CPU reference (the kernels' twins), uploaded for drawing.
    Cpu,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Bezier,
    CatmullClark,
}

/// What the tessellation depends on besides the model (defaults: `tessera render`'s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    pub method: Method,
    /// Bézier edge-test threshold, model units.
    pub threshold: f32,
    /// Catmull-Clark tolerance, fraction of the control box's diagonal (where `pixels` is
    /// `None`).
    pub tolerance_rel: f64,
    /// Catmull-Clark adaptive: the tolerance in pixels of the view drawn (moving the
    /// camera tessellates again), patches out of view culled; `None`: `tolerance_rel`.
    pub pixels: Option<f64>,
    /// In pixels, the patches facing away from the eye are culled too.
    pub cull_backfaces: bool,
    pub bezier_depth: u32,
    pub cc_depth: u32,
    pub first_split: FirstSplit,
    pub segments: u32,
    pub backend: Backend,
}

/// `tessera render`'s defaults: `--threshold` 0.002 of the diagonal, `--tolerance-rel`
/// 1e-3 (the CLI's `DEFAULT_TOLERANCE_REL`), depth 6 (Bézier) or 10, search, 8 segments.
pub const DEFAULT_THRESHOLD_REL: f32 = 0.002;
pub const DEFAULT_TOLERANCE_REL: f64 = 1e-3;
/// The demo's default for Catmull-Clark surfaces: one pixel in the view drawn.
pub const DEFAULT_PIXELS: f64 = 1.0;
/// In pixels, at most this many triangles: zoomed in close, the pixels coarsen instead
/// (the panel shows those reached), so that no view exhausts memory.
pub const TRIANGLE_CAP: usize = 4_000_000;

impl Params {
    /// The defaults for `model`.
    pub fn defaults(model: &Model) -> Params {
        Params {
            method: match model.kind() {
                Kind::Bezier => Method::Map4p,
                Kind::CatmullClark => Method::Adaptive,
            },
            threshold: model.default_threshold(),
            tolerance_rel: DEFAULT_TOLERANCE_REL,
            pixels: Some(DEFAULT_PIXELS),
            cull_backfaces: false,
            bezier_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
            cc_depth: MAX_DEPTH,
            first_split: FirstSplit::Search,
            segments: 8,
            backend: Backend::Gpu,
        }
    }

    /// The same settings for another model: the method kept for a model of the same
    /// kind (else that kind's default), the threshold (model units) the new model's
    /// default.
    pub fn for_model(&self, kind: Kind, model: &Model) -> Params {
        let defaults = Params::defaults(model);
        Params {
            method: if kind == model.kind() {
                self.method
            } else {
                defaults.method
            },
            threshold: defaults.threshold,
            ..*self
        }
    }

    /// The deepest depth of a kind.
    pub fn depth_limit(kind: Kind) -> u32 {
        match kind {
            Kind::Bezier => MAX_DEPTH_LIMIT,
            Kind::CatmullClark => MAX_DEPTH,
        }
    }

    fn bezier(&self) -> Option<AdaptiveParams> {
        Some(AdaptiveParams {
            test: self.method.edge_test()?,
            threshold: self.threshold,
            max_depth: self.bezier_depth,
        })
    }

    /// Whether the mesh depends on the view: Catmull-Clark adaptive in pixels.
    pub fn follows_view(&self, kind: Kind) -> bool {
        kind == Kind::CatmullClark && self.method == Method::Adaptive && self.pixels.is_some()
    }

    /// The view's tolerance for a run in `view`, in pixels (culling too).
    fn in_view(&self, view: &View) -> Option<ViewTolerance> {
        (self.method == Method::Adaptive)
            .then_some(self.pixels)
            .flatten()
            .map(|px| ViewTolerance {
                view: *view,
                pixels: Some(px),
                cull: true,
                cull_backfaces: self.cull_backfaces,
                max_triangles: Some(TRIANGLE_CAP),
                face_leaves: false,
            })
    }

    fn cc(&self) -> CcParams {
        CcParams {
            // In pixels, the world tolerance only caps: the pixels decide.
            tolerance: Tolerance::Relative(match self.pixels {
                Some(_) => 1.0,
                None => self.tolerance_rel,
            }),
            max_depth: self.cc_depth,
            first_split: self.first_split,
            leaf_bound: Default::default(),
        }
    }
}

/// A loaded surface.
pub enum Surface {
    Bezier(BezierModel),
    CatmullClark {
        model: Box<SurfaceModel>,
        /// The control points as loaded (after any cut along non-manifold edges).
        rest: Vec<DVec3>,
    },
}

/// A file, loaded and ready to tessellate.
pub struct Model {
    pub path: PathBuf,
    pub surface: Surface,
    /// The control points' box: what the view frames (as `tessera render` does).
    pub bounds: (Vec3, Vec3),
    /// Patches tessellated (holes aside).
    pub patches: usize,
    pub warnings: Vec<String>,
}

impl Model {
    /// Loads `path` as the CLI does: a control mesh by its extension (`.obj`, `.gltf`,
    /// `.glb`), else a Newell teaset file. The error is the CLI's line. A control mesh
    /// keeps its creases and corners.
    pub fn load(path: &Path, split_non_manifold: bool) -> Result<Model, tessera_core::Error> {
        if is_control_mesh(path) {
            let mut control = load_control_mesh(path)?;
            let mesh = patch_mesh(&mut control, split_non_manifold)?;
            let model = SurfaceModel::new(mesh, TREE_DEPTH);
            // All control points, as `tessera render` frames them.
            let (lo, hi) = control.positions.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), p| (lo.min(*p), hi.max(*p)),
            );
            Ok(Model {
                path: path.to_path_buf(),
                patches: model.mesh.surface_patches().count(),
                bounds: (lo.as_vec3(), hi.as_vec3()),
                warnings: control.warnings.clone(),
                surface: Surface::CatmullClark {
                    model: Box::new(model),
                    rest: control.positions,
                },
            })
        } else {
            let model = BezierModel::load(path)?;
            Ok(Model {
                path: path.to_path_buf(),
                patches: model.patches.len(),
                bounds: model.bounds(),
                warnings: Vec::new(),
                surface: Surface::Bezier(model),
            })
        }
    }

    pub fn kind(&self) -> Kind {
        match self.surface {
            Surface::Bezier(_) => Kind::Bezier,
            Surface::CatmullClark { .. } => Kind::CatmullClark,
        }
    }

    /// `tessera render`'s threshold: 0.002 of the control box's diagonal.
    pub fn default_threshold(&self) -> f32 {
        let (lo, hi) = self.bounds;
        DEFAULT_THRESHOLD_REL * (hi - lo).length()
    }

    pub fn diagonal(&self) -> f32 {
        (self.bounds.1 - self.bounds.0).length()
    }

    /// ε of a relative tolerance `rel` in model units, as the stages resolve it
    /// (Catmull-Clark: against the control box as loaded).
    pub fn tolerance(&self, rel: f64) -> f64 {
        match &self.surface {
            Surface::CatmullClark { model, .. } => rel * model.mesh.control_diag,
            Surface::Bezier(_) => rel * self.diagonal() as f64,
        }
    }

    pub fn name(&self) -> String {
        self.path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.path.display().to_string())
    }
}

/// Seconds per period of the animation.
const PERIOD: f64 = 3.0;
/// Largest relative change of a control point's distance from the up axis.
const AMPLITUDE: f64 = 0.12;

/// The animated control points at time `t` (seconds): each point's distance from the
/// vertical line through the box's centre breathes, with a phase that climbs the up
/// axis, so the surface bulges and pinches in a wave. Smooth in time and in space.
pub fn deform(p: DVec3, t: f64, (lo, hi): (Vec3, Vec3), up: Axis) -> DVec3 {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let center = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(1e-12);
    let up = up.vector();
    let q = p - center;
    let along = up * q.dot(up);
    let phase = std::f64::consts::TAU * t / PERIOD + 3.0 * q.dot(up) / radius;
    center + along + (q - along) * (1.0 + AMPLITUDE * phase.sin())
}

/// Which output is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Drawn {
    Nothing,
    Bezier,
    Cc,
    CcUniform,
    Cpu,
}

/// A mesh made on the CPU and uploaded.
struct CpuOutput {
    buffers: MeshBuffers,
    triangles: u32,
    vertices: u32,
    bound: Option<f64>,
    culled_patches: Option<u32>,
    tolerance_px: Option<f64>,
}

/// What a run reported: counts of the drawn output, as they have arrived.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub triangles: u32,
    pub vertices: u32,
    /// Catmull-Clark adaptive: the largest leaf bound, model units.
    pub guaranteed_bound: Option<f64>,
    /// Catmull-Clark adaptive in a view: patches wholly out of view.
    pub culled_patches: Option<u32>,
    /// Catmull-Clark adaptive in pixels: the pixels reached (coarser than asked where
    /// the triangle cap needed it).
    pub tolerance_px: Option<f64>,
    /// Reallocations of the drawn stage's buffers.
    pub growths: u32,
    /// The newest status says the run overflowed (nothing drawn until the rerun).
    pub overflowed: bool,
}

/// How the run just recorded is timed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunTime {
    /// On the GPU by the timer's timestamps (read when they arrive).
    Timestamps,
    /// On the GPU without timestamps: the wall time to the submission's completion.
    Submission,
    /// On the CPU, ms, measured.
    Cpu(f64),
}

/// The model's stages and outputs.
pub struct Tessellator {
    kernels: Kernels,
    pub model: Model,
    /// The control points now (at rest until animated): Bézier welded points or
    /// Catmull-Clark control vertices.
    points: Option<Vec<DVec3>>,
    /// Bumped whenever `points` change; each output remembers the version it has.
    version: u64,
    /// The Bézier model and its CPU preparation at `points` (the stage's upload).
    bezier_at: Option<(u64, BezierModel, PreparedBezier)>,
    /// The Catmull-Clark model at `points` (the CPU reference's input).
    cc_at: Option<(u64, SurfaceModel)>,
    bezier: Option<(u64, BezierStage)>,
    cc: Option<(u64, CcStage)>,
    cc_uniform: Option<(u64, CcUniformStage)>,
    cpu: Option<CpuOutput>,
    drawn: Drawn,
}

impl Tessellator {
    pub fn new(kernels: Kernels, model: Model) -> Tessellator {
        Tessellator {
            kernels,
            model,
            points: None,
            version: 0,
            bezier_at: None,
            cc_at: None,
            bezier: None,
            cc: None,
            cc_uniform: None,
            cpu: None,
            drawn: Drawn::Nothing,
        }
    }

    /// Moves the control points to the animation at time `t`, or back to rest (`None`).
    pub fn animate(&mut self, t: Option<f64>, up: Axis) {
        self.points = t.map(|t| {
            let b = self.model.bounds;
            match &self.model.surface {
                Surface::Bezier(m) => m
                    .points
                    .iter()
                    .map(|p| deform(p.as_dvec3(), t, b, up))
                    .collect(),
                Surface::CatmullClark { rest, .. } => {
                    rest.iter().map(|p| deform(*p, t, b, up)).collect()
                }
            }
        });
        self.version += 1;
    }

    /// The buffers to draw, if a run has made any.
    pub fn output(&self) -> Option<&MeshBuffers> {
        match self.drawn {
            Drawn::Nothing => None,
            Drawn::Bezier => self.bezier.as_ref().map(|(_, s)| s.output()),
            Drawn::Cc => self.cc.as_ref().map(|(_, s)| s.output()),
            Drawn::CcUniform => self.cc_uniform.as_ref().map(|(_, s)| s.output()),
            Drawn::Cpu => self.cpu.as_ref().map(|c| &c.buffers),
        }
    }

    /// The drawn output's counts from the newest status that has arrived (never waits).
    pub fn counts(&mut self, device: &wgpu::Device) -> Option<Counts> {
        match self.drawn {
            Drawn::Nothing => None,
            Drawn::Bezier => {
                let (_, s) = self.bezier.as_mut()?;
                let status = s.poll_status(device)?;
                // An overflowed run reports what it needed and draws nothing.
                let drawn = status.overflow == 0;
                Some(Counts {
                    triangles: if drawn { status.indices / 3 } else { 0 },
                    vertices: if drawn { status.vertices } else { 0 },
                    guaranteed_bound: None,
                    culled_patches: None,
                    tolerance_px: None,
                    growths: s.growths(),
                    overflowed: !drawn,
                })
            }
            Drawn::Cc => {
                let (_, s) = self.cc.as_mut()?;
                let status = s.poll_status(device)?;
                let drawn = !status.overflowed();
                Some(Counts {
                    triangles: status.indices / 3,
                    vertices: if drawn { status.vertices() } else { 0 },
                    guaranteed_bound: drawn.then_some(status.max_bound() as f64),
                    culled_patches: drawn.then_some(status.state.culled_patches),
                    tolerance_px: s.tolerance_px(),
                    growths: s.growths(),
                    overflowed: !drawn,
                })
            }
            Drawn::CcUniform => {
                let (_, s) = self.cc_uniform.as_ref()?;
                Some(Counts {
                    triangles: s.index_count() / 3,
                    vertices: s.vertex_count(),
                    ..Counts::default()
                })
            }
            Drawn::Cpu => {
                let c = self.cpu.as_ref()?;
                Some(Counts {
                    triangles: c.triangles,
                    vertices: c.vertices,
                    guaranteed_bound: c.bound,
                    culled_patches: c.culled_patches,
                    tolerance_px: c.tolerance_px,
                    ..Counts::default()
                })
            }
        }
    }

    /// Whether the drawn stage's newest status overflowed and nothing has grown for it:
    /// one more run draws the mesh.
    pub fn grow_pending(&self) -> bool {
        match self.drawn {
            Drawn::Bezier => self.bezier.as_ref().is_some_and(|(_, s)| s.grow_pending()),
            Drawn::Cc => self.cc.as_ref().is_some_and(|(_, s)| s.grow_pending()),
            _ => false,
        }
    }

    /// Records one tessellation with `params` for `view` (the view drawn) into `encoder`
    /// (GPU), or makes it on the CPU and uploads it. A stage is made the first time its method is asked for, and
    /// run to fit on its own submission then (as after loading in the CLI); every later
    /// run is recorded here, timed by `timer` when there is one.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &Params,
        view: &View,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
    ) -> Result<RunTime, String> {
        let kind = self.model.kind();
        if !Method::of(kind).contains(&params.method) {
            return Err(format!(
                "{} is not a method for {} surfaces",
                params.method.name(),
                match kind {
                    Kind::Bezier => "Bézier",
                    Kind::CatmullClark => "Catmull-Clark",
                }
            ));
        }
        let on_gpu = params.backend == Backend::Gpu && params.method.on_gpu(kind);
        let result = if on_gpu {
            self.record_gpu(device, queue, params, view, encoder, timer)
        } else {
            self.run_cpu(device, params, view).map(RunTime::Cpu)
        };
        if result.is_err() {
            // The old output may belong to other parameters: draw nothing rather than
            // something the panel no longer describes.
            self.drawn = Drawn::Nothing;
        }
        result
    }

    fn record_gpu(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &Params,
        view: &View,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
    ) -> Result<RunTime, String> {
        let e = |e: tessera_wgpu::Error| e.to_string();
        let version = self.version;
        let timed = timer.is_some();
        match (&self.model.surface, params.method) {
            (Surface::Bezier(_), m) => {
                let Some(p) = params.bezier() else {
                    return Err(format!("{} runs on the CPU only", m.name()));
                };
                p.validate().map_err(|e| e.to_string())?;
                self.bezier_now();
                let Some((_, _, prepared)) = &self.bezier_at else {
                    return Err("no prepared model".into());
                };
                match &mut self.bezier {
                    Some((v, stage)) => {
                        if *v != version {
                            stage.update_model(queue, prepared).map_err(e)?;
                            *v = version;
                        }
                        if *stage.params() != p {
                            stage.set_params(device, queue, &p).map_err(e)?;
                        }
                    }
                    None => {
                        let mut stage =
                            BezierStage::new(device, queue, &self.kernels, prepared, &p)
                                .map_err(e)?;
                        stage.run_blocking(device, queue).map_err(e)?;
                        self.bezier = Some((version, stage));
                    }
                }
                let Some((_, stage)) = &mut self.bezier else {
                    return Err("no stage".into());
                };
                match timer {
                    Some(t) => {
                        stage
                            .prepare_timed(device, queue, encoder, t.timestamps())
                            .map_err(e)?;
                        t.resolve(device, encoder);
                    }
                    None => stage.prepare(device, queue, encoder).map_err(e)?,
                }
                self.drawn = Drawn::Bezier;
            }
            (Surface::CatmullClark { model, .. }, Method::Adaptive) => {
                let p = params.cc();
                p.validate(model).map_err(|e| e.to_string())?;
                if self.cc.is_none() {
                    let mut stage =
                        CcStage::new(device, queue, &self.kernels, model, &p).map_err(e)?;
                    if let Some(points) = &self.points {
                        stage.update_points(queue, &as_vec3(points)).map_err(e)?;
                    }
                    stage.run_blocking(device, queue).map_err(e)?;
                    self.cc = Some((version, stage));
                }
                let Some((v, stage)) = &mut self.cc else {
                    return Err("no stage".into());
                };
                if *v != version {
                    let points = current_points(&self.points, &self.model.surface);
                    stage.update_points(queue, &points).map_err(e)?;
                    *v = version;
                }
                if *stage.params() != p {
                    stage.set_params(device, queue, &p).map_err(e)?;
                }
                // A few bytes through the queue, every run.
                stage
                    .set_view(queue, params.in_view(view).as_ref())
                    .map_err(e)?;
                match timer {
                    Some(t) => {
                        stage
                            .prepare_timed(device, queue, encoder, t.timestamps())
                            .map_err(e)?;
                        t.resolve(device, encoder);
                    }
                    None => stage.prepare(device, queue, encoder).map_err(e)?,
                }
                self.drawn = Drawn::Cc;
            }
            (Surface::CatmullClark { model, .. }, _) => {
                let p = UniformParams {
                    segments: params.segments,
                };
                if self.cc_uniform.is_none() {
                    let stage =
                        CcUniformStage::new(device, queue, &self.kernels, model, &p).map_err(e)?;
                    // Its sizes follow from the parameters: nothing to fit.
                    self.cc_uniform = Some((u64::MAX, stage));
                }
                let Some((v, stage)) = &mut self.cc_uniform else {
                    return Err("no stage".into());
                };
                if *v != version {
                    let points = current_points(&self.points, &self.model.surface);
                    stage.update_points(queue, &points).map_err(e)?;
                    *v = version;
                }
                if stage.params() != p {
                    stage.set_params(device, queue, &p).map_err(e)?;
                }
                match timer {
                    Some(t) => {
                        stage
                            .prepare_timed(device, queue, encoder, t.timestamps())
                            .map_err(e)?;
                        t.resolve(device, encoder);
                    }
                    None => stage.prepare(device, queue, encoder).map_err(e)?,
                }
                self.drawn = Drawn::CcUniform;
            }
        }
        Ok(if timed {
            RunTime::Timestamps
        } else {
            RunTime::Submission
        })
    }

    /// The CPU reference at the current points, uploaded; its wall time in ms.
    fn run_cpu(
        &mut self,
        device: &wgpu::Device,
        params: &Params,
        view: &View,
    ) -> Result<f64, String> {
        let start = Instant::now();
        let e = |e: tessera_core::Error| e.to_string();
        let (mesh, bound, culled_patches, tolerance_px) = match self.model.kind() {
            Kind::Bezier => {
                self.bezier_now();
                let Some((_, model, prepared)) = &self.bezier_at else {
                    return Err("no prepared model".into());
                };
                let mesh = match params.bezier() {
                    Some(p) => bezier::tessellate_adaptive(prepared, &p).map_err(e)?.mesh,
                    None => {
                        bezier::tessellate_uniform(model, prepared, params.segments)
                            .map_err(e)?
                            .mesh
                    }
                };
                (mesh, None, None, None)
            }
            Kind::CatmullClark => {
                self.cc_now().map_err(e)?;
                let Some((_, model)) = &self.cc_at else {
                    return Err("no model".into());
                };
                match params.method {
                    Method::Adaptive => {
                        let p = params.cc();
                        p.validate(model).map_err(e)?;
                        let out = match params.in_view(view) {
                            Some(v) => catmull_clark::tessellate_adaptive_in_view(model, &p, &v)
                                .map_err(e)?,
                            None => catmull_clark::tessellate_adaptive(model, &p).map_err(e)?,
                        };
                        let culled = params.pixels.map(|_| out.culled_patches as u32);
                        (out.mesh, Some(out.max_bound), culled, out.tolerance_px)
                    }
                    _ => (
                        catmull_clark::tessellate_uniform(model, params.segments)
                            .map_err(e)?
                            .mesh,
                        None,
                        None,
                        None,
                    ),
                }
            }
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        self.cpu = Some(CpuOutput {
            buffers: MeshBuffers::from_mesh(device, &mesh),
            triangles: mesh.triangle_count() as u32,
            vertices: mesh.vertices.len() as u32,
            bound,
            culled_patches,
            tolerance_px,
        });
        self.drawn = Drawn::Cpu;
        Ok(ms)
    }

    /// Brings `bezier_at` to the current points: the model rebuilt from the moved
    /// welded points and the same nets, prepared again on the CPU.
    fn bezier_now(&mut self) {
        if self
            .bezier_at
            .as_ref()
            .is_some_and(|(v, _, _)| *v == self.version)
        {
            return;
        }
        let Surface::Bezier(rest) = &self.model.surface else {
            return;
        };
        let model = match &self.points {
            Some(points) => BezierModel::from_nets(
                points.iter().map(|p| p.as_vec3()).collect(),
                rest.nets.clone(),
            ),
            None => rest.clone(),
        };
        let prepared = PreparedBezier::new(&model);
        self.bezier_at = Some((self.version, model, prepared));
    }

    /// Brings `cc_at` to the current points.
    fn cc_now(&mut self) -> tessera_core::Result<()> {
        if self.cc_at.as_ref().is_some_and(|(v, _)| *v == self.version) {
            return Ok(());
        }
        let Surface::CatmullClark { model, rest } = &self.model.surface else {
            return Ok(());
        };
        let moved = match &self.points {
            Some(points) => SurfaceModel::new(model.mesh.with_control_points(points)?, model.depth),
            None => SurfaceModel::new(model.mesh.with_control_points(rest)?, model.depth),
        };
        self.cc_at = Some((self.version, moved));
        Ok(())
    }
}

fn rest_points(surface: &Surface) -> Vec<DVec3> {
    match surface {
        Surface::Bezier(m) => m.points.iter().map(|p| p.as_dvec3()).collect(),
        Surface::CatmullClark { rest, .. } => rest.clone(),
    }
}

/// The control points the stages draw: the animated ones, or the model's at rest.
fn current_points(points: &Option<Vec<DVec3>>, surface: &Surface) -> Vec<Vec3> {
    match points {
        Some(p) => as_vec3(p),
        None => as_vec3(&rest_points(surface)),
    }
}

fn as_vec3(points: &[DVec3]) -> Vec<Vec3> {
    points.iter().map(|p| p.as_vec3()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asset(name: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../assets")
            .join(name)
    }

    #[test]
    fn loads_both_kinds_with_the_clis_defaults() {
        let teapot = Model::load(&asset("teaset/teapot"), false).expect("teapot");
        assert_eq!(teapot.kind(), Kind::Bezier);
        assert_eq!(teapot.patches, 32);
        let p = Params::defaults(&teapot);
        assert_eq!(p.method, Method::Map4p);
        let (lo, hi) = teapot.bounds;
        assert_eq!(p.threshold, 0.002 * (hi - lo).length());
        assert_eq!(p.bezier_depth, 6);
        let torus = Model::load(&asset("opensubdiv/catmark_torus.obj"), false).expect("torus");
        assert_eq!(torus.kind(), Kind::CatmullClark);
        let q = p.for_model(Kind::Bezier, &torus);
        assert_eq!(
            (q.method, q.tolerance_rel, q.cc_depth),
            (Method::Adaptive, 1e-3, 10)
        );
        assert_eq!(q.first_split, FirstSplit::Search);
    }

    #[test]
    fn a_bad_file_gives_the_clis_line() {
        let dir = std::env::temp_dir().join(format!("tessera-demo-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let bad = dir.join("bad.obj");
        std::fs::write(&bad, "v 0 0 0\nf 1 2 3\n").expect("write");
        let e = Model::load(&bad, false).err().expect("refused").to_string();
        assert!(e.starts_with(&format!("{}:", bad.display())), "{e}");
        assert!(!e.contains('\n'));
        let missing = Model::load(&dir.join("missing"), false)
            .err()
            .expect("refused");
        assert!(missing
            .to_string()
            .starts_with(&dir.join("missing").display().to_string()));
        std::fs::remove_dir_all(&dir).expect("clean");
    }

    #[test]
    fn the_deformation_is_smooth_and_rests_at_its_phase() {
        let b = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let p = DVec3::new(0.5, 0.2, 0.3);
        // Points on the up axis through the centre stay.
        let axis = DVec3::new(0.0, 0.0, 0.7);
        assert!((deform(axis, 1.3, b, Axis::Z) - axis).length() < 1e-12);
        // Small steps in time move a point a little; the motion is periodic.
        let a = deform(p, 0.4, b, Axis::Z);
        let c = deform(p, 0.4 + 1e-3, b, Axis::Z);
        assert!((a - c).length() < 1e-3);
        assert!((deform(p, 0.4 + PERIOD, b, Axis::Z) - a).length() < 1e-9);
        // The height along the up axis is kept.
        assert!((a.z - p.z).abs() < 1e-12);
    }
}
