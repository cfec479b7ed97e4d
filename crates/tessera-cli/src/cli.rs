//! Command-line arguments of `tessera` (reference: `docs/cli.md`).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

#[derive(Parser, Debug)]
#[command(
    name = "tessera",
    version,
    about = "GPU tessellation of Bézier and Catmull-Clark surfaces"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Tessellate a surface and write the mesh and/or its statistics.
    Tessellate(TessellateArgs),
    /// Tessellate a surface on the GPU and render it headless to a PNG.
    Render(RenderArgs),
    /// Print what a surface file holds.
    Info { input: PathBuf },
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Map2p,
    Map4p,
    Map8p,
    Flat,
    Uniform,
    Adaptive,
}

/// How the adaptive Catmull-Clark method first splits each patch.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FirstSplit {
    /// Try the near-square k×k and k×(k+1) splits (k ≤ 8) and keep the one with the
    /// fewest leaves: fewest triangles.
    #[default]
    Search,
    /// Midpoint splits only, as in Lai and Cheng's paper: more triangles, fewer flatness
    /// bounds (faster at fine tolerances).
    Midpoint,
}

impl From<FirstSplit> for tessera_core::catmull_clark::FirstSplit {
    fn from(f: FirstSplit) -> Self {
        match f {
            FirstSplit::Search => Self::Search,
            FirstSplit::Midpoint => Self::Midpoint,
        }
    }
}

/// Which bound accepts a leaf of the adaptive Catmull-Clark method.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LeafBound {
    /// The flatness bound, which holds for any triangulation of the leaf's polygon: every
    /// cell decided alone, as the GPU decides them.
    #[default]
    Flatness,
    /// Also the distance to the cell's own triangles, checked again against the points
    /// its neighbours add: fewer triangles, more time, CPU only.
    Triangles,
}

impl From<LeafBound> for tessera_core::catmull_clark::LeafBound {
    fn from(b: LeafBound) -> Self {
        match b {
            LeafBound::Flatness => Self::Flatness,
            LeafBound::Triangles => Self::Triangles,
        }
    }
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// The CPU reference (the kernels' twins).
    Cpu,
    /// The WGSL kernels through wgpu (any Vulkan, Metal, DX12 adapter; lavapipe on CPU).
    Gpu,
}

#[derive(Args, Debug)]
pub struct TessellateArgs {
    /// Input surface: a Newell teaset file (Bézier patches) or a Catmull-Clark control
    /// mesh (.obj, .gltf, .glb).
    pub input: PathBuf,
    /// Tessellation method (Bézier inputs default to map4p, Catmull-Clark meshes to
    /// adaptive).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Catmull-Clark adaptive: the largest distance allowed between the output and the
    /// limit surface, in model units (guaranteed, not sampled).
    #[arg(long, conflicts_with = "tolerance_rel")]
    pub tolerance: Option<f64>,
    /// Catmull-Clark adaptive: the tolerance as a fraction of the diagonal of the control
    /// points' bounding box (default 0.001). The stats' `bbox_diag` is that diagonal, and
    /// `max_error_rel` the measured error over it; `surface_bbox_diag` is the measured
    /// surface's box.
    #[arg(long)]
    pub tolerance_rel: Option<f64>,
    /// Catmull-Clark uniform: 2^LEVEL segments per patch side (same as --segments 2^LEVEL).
    #[arg(long, conflicts_with = "segments")]
    pub level: Option<u32>,
    /// Edge-test threshold in model units (map tests: displacement difference; flat: chord
    /// deviation). Default: 0.002 of the control points' bounding-box diagonal.
    #[arg(long)]
    pub threshold: Option<f32>,
    /// Bézier: levels of recursive edge bisection (at most 2^D segments per coarse edge;
    /// default 6). Catmull-Clark: midpoint splits after a patch's first split (default
    /// and most 10).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Segments per patch side for `--method uniform` (default 8).
    #[arg(long)]
    pub segments: Option<u32>,
    /// Catmull-Clark adaptive: how each patch is first split (default search).
    #[arg(long, value_enum)]
    pub first_split: Option<FirstSplit>,
    /// Catmull-Clark adaptive: which bound accepts a leaf (default flatness; triangles
    /// is CPU only).
    #[arg(long, value_enum)]
    pub leaf_bound: Option<LeafBound>,
    /// Catmull-Clark: cut the mesh along its non-manifold edges (three faces or more) and
    /// tessellate each sheet of faces with its own boundary there, as OpenSubdiv does;
    /// without it such edges are an error.
    #[arg(long)]
    pub split_non_manifold: bool,
    /// Catmull-Clark: ignore the mesh's creases and corners (`t crease`, `t corner`) and
    /// tessellate the smooth surface, with a warning.
    #[arg(long)]
    pub no_creases: bool,
    /// Search the threshold (or the uniform segment count) for this many triangles (±2%).
    #[arg(long, conflicts_with = "threshold")]
    pub target_triangles: Option<usize>,
    /// Where the tessellation runs. Default: gpu when an adapter exists, else cpu, for
    /// Bézier surfaces; cpu (the reference) for Catmull-Clark meshes, creased or not.
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// Output mesh (.obj, .ply or .glb). Every vertex carries `face` and `u v`: for a
    /// Catmull-Clark mesh the control face (its 0-based index in the input) and the
    /// point's (u, v) on it in OpenSubdiv Bfr's parameterisation (for quads Ptex's: (0, 0)
    /// at the face's first vertex, u toward its second, v toward its last), a point on an
    /// edge between faces being one vertex per face; for Bézier patches the patch and its
    /// (u, v). PLY: `u v face`; GLB: TEXCOORD_0 and `_FACE`; OBJ: `vt` only (OBJ has no
    /// face id).
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Write statistics as JSON to this file (`vertex_face` and `vertex_uv` say what the
    /// vertices' `face` and `u v` are; for Catmull-Clark meshes `positions` counts the
    /// surface points, `vertices` also the copies of a point on an edge between faces).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Measure the error against the exact surface (max, mean, p99).
    #[arg(long)]
    pub measure: bool,
    /// Surface samples per patch side for --measure (default 64 for Bézier patches, 32
    /// for Catmull-Clark patches; at least 32).
    #[arg(long)]
    pub measure_samples: Option<usize>,
    /// With a view: the viewport in pixels, WIDTHxHEIGHT (default 800x600).
    #[arg(long, value_parser = tessera_wgpu::image_out::parse_size)]
    pub size: Option<(u32, u32)>,
    /// With a view: the model's up axis, which is up on the screen (default z).
    #[arg(long, value_enum)]
    pub up: Option<Axis>,
    #[command(flatten)]
    pub view: ViewArgs,
}

/// A camera for the Catmull-Clark adaptive tessellation: a tolerance in pixels, and
/// culling (with `--size` and `--up`). Without `--eye` and `--target`, the view is
/// `render`'s default framing.
#[derive(Args, Debug, Default)]
pub struct ViewArgs {
    /// Where the eye is, X,Y,Z (with --target).
    #[arg(long, value_parser = parse_point, requires = "target", allow_hyphen_values = true)]
    pub eye: Option<[f64; 3]>,
    /// The point looked at, X,Y,Z (with --eye).
    #[arg(long, value_parser = parse_point, requires = "eye", allow_hyphen_values = true)]
    pub target: Option<[f64; 3]>,
    /// Vertical field of view in degrees (default: the framing's, 30).
    #[arg(long)]
    pub fov: Option<f64>,
    /// Distance of the near plane (default: the framing's, in front of the model; with
    /// --eye, 0.01 of the diagonal of the control points' box).
    #[arg(long)]
    pub near: Option<f64>,
    /// Every point of the limit surface inside the view frustum projects within this many
    /// pixels of the projection of its nearest point on the output (guaranteed). With
    /// --tolerance or --tolerance-rel as well, each cell keeps the smaller of the two.
    #[arg(long)]
    pub tolerance_px: Option<f64>,
    /// Keep the patches outside the view frustum (culled by default with a view).
    #[arg(long)]
    pub no_cull: bool,
    /// Drop the patches that face away from the eye everywhere (a closed surface looks the
    /// same, an open one loses its inside).
    #[arg(long)]
    pub cull_backfaces: bool,
    /// At most this many triangles (with --tolerance-px): the pixel tolerance is coarsened
    /// by √2 at a time until the mesh fits, and the stats report the one achieved
    /// (`achieved_tolerance_px`).
    #[arg(long, requires = "tolerance_px")]
    pub max_triangles: Option<usize>,
    /// Catmull-Clark, both backends: a quad control face whose bound taken whole meets its
    /// tolerance is one leaf, two triangles for its four patches (a level of detail above
    /// the patch, for models seen from far away).
    #[arg(long)]
    pub face_leaves: bool,
}

impl ViewArgs {
    /// Whether any option asks for a view.
    pub fn given(&self) -> bool {
        self.eye.is_some()
            || self.tolerance_px.is_some()
            || self.fov.is_some()
            || self.near.is_some()
            || self.no_cull
            || self.cull_backfaces
            || self.max_triangles.is_some()
            || self.face_leaves
    }
}

/// `X,Y,Z`: three finite numbers.
fn parse_point(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<Vec<f64>>>()
        .ok_or_else(|| format!("{s:?} is not X,Y,Z (three numbers)"))?;
    <[f64; 3]>::try_from(v).map_err(|_| format!("{s:?} is not X,Y,Z (three numbers)"))
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Input surface: a Newell teaset file (Bézier patches) or a Catmull-Clark control
    /// mesh (.obj, .gltf, .glb).
    pub input: PathBuf,
    /// Output PNG.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, default_value = "800x600", value_parser = tessera_wgpu::image_out::parse_size)]
    pub size: (u32, u32),
    /// Bézier: edge test (map2p, map4p, map8p or flat; default map4p). Catmull-Clark:
    /// adaptive (the default) or uniform.
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Bézier: edge-test threshold in model units. Default: 0.002 of the bounding-box
    /// diagonal.
    #[arg(long)]
    pub threshold: Option<f32>,
    /// Catmull-Clark `--method uniform`: segments per patch side (default 8).
    #[arg(long)]
    pub segments: Option<u32>,
    /// Catmull-Clark: largest distance to the limit surface, as a fraction of the
    /// control points' bounding-box diagonal (default 1e-3).
    #[arg(long)]
    pub tolerance_rel: Option<f64>,
    /// Levels of recursive subdivision (Bézier default 6, Catmull-Clark 10).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Catmull-Clark adaptive: how each patch is first split (default search).
    #[arg(long, value_enum)]
    pub first_split: Option<FirstSplit>,
    /// Catmull-Clark: cut the mesh along its non-manifold edges (see `tessellate`).
    #[arg(long)]
    pub split_non_manifold: bool,
    /// Catmull-Clark: ignore creases and corners and draw the smooth surface (see
    /// `tessellate`).
    #[arg(long)]
    pub no_creases: bool,
    /// Where a Catmull-Clark mesh is tessellated before it is drawn. Default: gpu. Bézier
    /// surfaces are tessellated on the GPU.
    #[arg(long, value_enum)]
    pub backend: Option<Backend>,
    /// Draw the triangle edges over the shading.
    #[arg(long)]
    pub wireframe: bool,
    /// Tint each face slightly differently: each Bézier patch, each Catmull-Clark control
    /// face.
    #[arg(long)]
    pub patch_tint: bool,
    /// The model's up axis (the Newell teapot is z-up; the teacup and teaspoon y-up).
    #[arg(long, value_enum, default_value = "z")]
    pub up: Axis,
    /// Catmull-Clark adaptive with `--backend cpu`: the camera drawn and tessellated for
    /// (see `tessellate`).
    #[command(flatten)]
    pub view: ViewArgs,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}
