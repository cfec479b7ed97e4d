//! Lai–Cheng adaptive tessellation (paper §3–5), the CPU reference:
//!
//! 1. **Adaptive marking**: each patch's parameter square is split into cells until
//!    every cell passes the flatness test; the corners of the leaf cells are marked,
//!    under their canonical [`keys`](super::keys).
//! 2. **Base-quadrilateral replacement**: each side of a leaf is replaced by the
//!    polyline of the marked points on it (the corners of finer neighbours).
//! 3. Each polygon is triangulated without new vertices ([`super::triangulate`]).
//!
//! Output vertices are points in charts ([`super::keys`]): a point on a seam between
//! control faces (or between the sub-faces of a face that is not a quad) is one vertex
//! per chart, evaluated once and copied, each copy with its own face and `(u, v)`. Every
//! triangle lies in one leaf, hence in one chart.
//!
//! # Splits
//!
//! The paper splits at midpoints only, so a patch gets `2^L` cells per side and
//! loses up to 4× in triangles against a uniform grid of the right size. Here the first
//! split of a patch is `ku × kv` (each ≤ 8, and `|ku - kv| ≤ 1`: squares and the
//! rectangles next to them) for the pair that gives the fewest leaves (tried in turn,
//! skipping pairs that cannot win, [`first_splits`]), and every later split is at
//! midpoints as in the paper. Trying all 64 pairs instead gives about the same
//! triangles for several times the bound evaluations, which are the cost of the
//! method. Parameters are integers in units of `1 / (840 · 2^max_depth)`
//! (840 = lcm(1..=8)), so keys stay exact.
//!
//! # Flatness test with a guaranteed bound
//!
//! A cell passes when [`bound::box_bound`](super::bound::box_bound), a guaranteed upper
//! bound on the distance from the surface over it to ANY triangulation of its polygon,
//! is at most ε (the proof is in [`super::bound`]); the extra vertices that finer
//! neighbours put on its sides keep it. In a patch at an extraordinary vertex, where
//! the bound walks many pieces, a cell whose centre and side midpoints (its children's
//! corners) already show it to be too far from flat is split without computing the
//! bound ([`bound::split_proof`](super::bound::split_proof), a lower bound on it): the
//! same decisions, with most of the long walks of the large cells at a vertex left out.
//!
//! # The cell's own triangles ([`LeafBound::Triangles`], CPU only)
//!
//! Holding for any triangulation costs: on a saddle the flatness bound counts both the
//! rise above the corners and the fall below them. With [`LeafBound::Triangles`] a cell
//! the flatness bound would split is kept where
//! [`triangle_bound::triangles_bound`](super::triangle_bound::triangles_bound) shows the
//! surface over it within ε of its own two triangles (the diagonal the zip will cut, on
//! the output's single-precision corners). Once every patch is marked, each such leaf
//! whose polygon got points from finer neighbours is bounded again against the
//! triangles it really gets; one that fails is marked again below, by the flatness
//! bound alone. That only adds points, so the rounds end, and the result does not
//! depend on the order of work; then every leaf is within ε of its own triangles, with
//! fewer triangles than the flatness bound alone makes (`bench/RESULTS.md`).

use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;
use serde::Serialize;

use super::bound::{box_bound, split_proof, WALK_ONE};
use super::facing::patch_back_facing;
use super::keys::{chart_key, key_place, point_key, point_of, vertex_face_uv, KeyPlace};
use super::patch::{SurfaceModel, SurfacePoint};
use super::topology::PatchMesh;
use super::traverse::{self, Cell};
use super::triangle_bound::triangles_bound;
use super::triangulate::{triangulate, zip_start, PolyVertex};
use crate::error::{Error, Result};
use crate::gpu_types::{CcCell, OutVertex};
use crate::measure::closest_point_on_triangle;
use crate::mesh::Mesh;
use crate::tolerance::Tolerance;
use crate::view::{ToleranceSearch, View};

/// The largest first split of a patch along each side (`ku × kv` cells).
pub const MAX_BASE_SPLIT: u32 = 8;
/// lcm(1..=MAX_BASE_SPLIT): every first split divides it.
const BASE_GRID: u32 = 840;

/// The first splits tried, in order (ties go to the earlier): the odd squares `k × k`,
/// then the rectangles `k × (k + 1)` and `(k + 1) × k` by `ku`, then `kv`. The GPU
/// numbers them the same way ([`crate::gpu_types::cc_trial_split`]).
///
/// An even square `2k × 2k` never wins against `k × k`, so it is not tried: its cells
/// are the children of `k × k`'s, the same boxes with the same bounds. If the `k × k`
/// cells all pass, that split has `k²` leaves against at least `4k²`; otherwise
/// `2k × 2k` grows the same trees with one more split allowed at the bottom, which only
/// adds leaves, and a tie goes to `k × k`.
pub fn first_splits() -> impl Iterator<Item = (u32, u32)> {
    let squares = (1..=MAX_BASE_SPLIT).step_by(2).map(|k| (k, k));
    let rectangles = (1..MAX_BASE_SPLIT).flat_map(|k| [(k, k + 1), (k + 1, k)]);
    squares.chain(rectangles)
}

/// The finest tolerance accepted, relative to the surface's size: output positions are
/// single precision (a relative step of 6e-8), and the work grows as 1/ε (the cube at
/// 1e-5 of its diagonal: 211k triangles, 6 s on one core).
pub const MIN_TOLERANCE_REL: f64 = 1e-6;

/// How each patch is first split: the quality/cost choice of the method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum FirstSplit {
    /// The `ku × kv` of [`first_splits`] with the fewest leaves (the default): fewer
    /// triangles than midpoint splits alone at the same tolerance, for more flatness
    /// bounds, more so at fine tolerances (`bench/RESULTS.md`).
    #[default]
    Search,
    /// Midpoint splits from the whole patch, as in the paper: one tree per patch, so
    /// every split costs four bounds and the cost follows the output.
    Midpoint,
}

impl FirstSplit {
    /// The name the CLI and the bench use: `search` or `midpoint`.
    pub fn name(self) -> &'static str {
        match self {
            FirstSplit::Search => "search",
            FirstSplit::Midpoint => "midpoint",
        }
    }

    /// The first splits tried, in order.
    pub fn splits(self) -> Vec<(u32, u32)> {
        match self {
            FirstSplit::Search => first_splits().collect(),
            FirstSplit::Midpoint => vec![(1, 1)],
        }
    }

    /// First splits the GPU tries, in order ([`crate::gpu_types::CcTessParams::trials`]).
    pub fn trials(self) -> u32 {
        match self {
            FirstSplit::Search => crate::gpu_types::CC_TRIALS,
            FirstSplit::Midpoint => 1,
        }
    }
}

/// Which bound accepts a leaf: the quality/portability choice of the method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum LeafBound {
    /// The flatness bound ([`super::bound`]): it holds for ANY triangulation of the
    /// leaf's polygon, so every cell is decided alone, in any order, as the GPU stage
    /// decides them (the default, and the only one the GPU stage runs).
    #[default]
    Flatness,
    /// Also the distance bound to the cell's own two triangles
    /// ([`super::triangle_bound`]): a cell the flatness bound would split is kept where
    /// its triangles are within ε, and checked again with the polygon its neighbours'
    /// points give it, marked again if that fails (module docs). On the CPU only.
    Triangles,
}

impl LeafBound {
    /// The name the CLI and the bench use: `flatness` or `triangles`.
    pub fn name(self) -> &'static str {
        match self {
            LeafBound::Flatness => "flatness",
            LeafBound::Triangles => "triangles",
        }
    }
}

/// Parameters of the adaptive method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CcParams {
    /// ε: the largest distance allowed between the output and the limit surface.
    pub tolerance: Tolerance,
    /// At most this many midpoint splits after the first split (≤ the model's depth).
    pub max_depth: u32,
    /// How each patch is first split.
    pub first_split: FirstSplit,
    /// Which bound accepts a leaf.
    pub leaf_bound: LeafBound,
}

impl CcParams {
    /// Grid units per patch side: `840 · 2^max_depth`, in which every cell corner of
    /// every first split and later midpoint split is an integer (the GPU's `grid`).
    pub fn grid(&self) -> u32 {
        BASE_GRID << self.max_depth
    }

    /// ε in model units for `model` (a relative tolerance is a fraction of the control
    /// points' box, [`PatchMesh::control_diag`](super::PatchMesh::control_diag)).
    pub fn epsilon(&self, model: &SurfaceModel) -> f64 {
        self.tolerance.resolve(model.mesh.control_diag)
    }

    /// Checks the tolerance (positive, and at least [`MIN_TOLERANCE_REL`] of the
    /// bounding-box diagonal of the refined control points) and the depth.
    pub fn validate(&self, model: &SurfaceModel) -> Result<()> {
        self.validate_for(&model.mesh, model.depth)
    }

    /// [`validate`](Self::validate) for patches `mesh` whose quadtrees have `depth`
    /// levels (a stage keeps these, not the quadtrees).
    pub fn validate_for(&self, mesh: &PatchMesh, depth: u32) -> Result<()> {
        self.tolerance.validate()?;
        let eps = self.tolerance.resolve(mesh.control_diag);
        let size = mesh.bbox_diag();
        if eps < MIN_TOLERANCE_REL * size {
            return Err(Error::Param(format!(
                "tolerance {eps:e} is below {MIN_TOLERANCE_REL:e} of the surface's size ({size:e}): finer than single-precision output can hold"
            )));
        }
        if self.max_depth > depth.min(super::MAX_DEPTH) {
            return Err(Error::Param(format!(
                "max depth {} out of range 0..={}",
                self.max_depth,
                depth.min(super::MAX_DEPTH)
            )));
        }
        Ok(())
    }
}

/// What a view changes in a tessellation ([`tessellate_adaptive_in_view`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewTolerance {
    /// The camera, with the model's placement ([`View::with_model`]).
    pub view: View,
    /// Every surface point inside the frustum projects within this many pixels of the
    /// projection of its nearest point on the output (the world tolerance of the
    /// parameters still caps each cell's). `None`: the world tolerance alone.
    pub pixels: Option<f64>,
    /// Cells whose bounds lie wholly outside the frustum emit nothing.
    pub cull: bool,
    /// Patches whose every normal faces away from the eye over their whole box emit
    /// nothing ([`super::facing`]): outside the pixel guarantee, which speaks of every
    /// point in the frustum, back-facing or not.
    pub cull_backfaces: bool,
    /// At most this many triangles: where the pixels would need more, they are coarsened
    /// by √2 at a time until the mesh fits (the achieved pixels are reported in
    /// [`CcTessellation::tolerance_px`]). A run that cannot fit stops marking as soon as
    /// its leaves (two triangles at least each) pass the cap, so no step holds much more
    /// than the cap.
    pub max_triangles: Option<usize>,
    /// A quad control face whose four patches meet their tolerance taken together, as
    /// one cell through its vertices' limit points ([`SurfaceModel::face_bound`]), is one
    /// leaf: a level of detail above the patch, two triangles for four patches where a
    /// view sees a face from far away. Its sides get the points of the faces across, and
    /// the level-1 edge point where the face across is not a leaf itself.
    pub face_leaves: bool,
}

/// A tessellation with what it cost.
#[derive(Clone, Debug, Default)]
pub struct CcTessellation {
    /// The triangles and their vertices.
    pub mesh: Mesh,
    /// Distinct surface points evaluated: the corners of every cell tested, and the
    /// centres and side midpoints of the split proof (see [`super::bound::split_proof`]).
    pub evaluations: u64,
    /// Leaf cells (the polygons before triangulation).
    pub leaves: usize,
    /// Leaves stopped by `max_depth` with a bound above the tolerance: where the
    /// guarantee does not hold. 0 means the whole output is within the tolerance.
    pub unmet: usize,
    /// The largest flatness bound of any leaf: the guaranteed error of the output.
    pub max_bound: f64,
    /// Leaves outside the view's frustum, which emit nothing, in patches partly in view.
    pub culled_leaves: usize,
    /// Patches that emit nothing: all of whose leaves lie outside the view's frustum, or,
    /// culling back faces, that face away from the eye.
    pub culled_patches: usize,
    /// The pixel tolerance the output meets in its view: the one asked for, or coarser
    /// where a triangle cap made it so.
    pub tolerance_px: Option<f64>,
    /// Flatness bounds the decisions took, every trial of the first-split search
    /// included: the method's cost, most of its time. A patch's bound over its whole
    /// square is computed once per model ([`SurfaceModel::root_bound`]; the GPU stage
    /// keeps it too) and counted in each decision that takes it, on both sides alike.
    pub bounds: u64,
    /// Cells split on the split proof alone, without a bound: with
    /// [`bounds`](Self::bounds), every cell tested.
    pub proven: u64,
    /// Distance bounds to a cell's own triangles computed ([`LeafBound::Triangles`]).
    pub triangle_bounds: u64,
}

/// Surface points evaluated once per canonical key.
struct Evaluator<'a> {
    model: &'a SurfaceModel,
    n: u32,
    /// Flatness bounds computed so far.
    bounds: u64,
    /// Cells split on the split proof alone so far.
    proven: u64,
    /// Triangle-distance bounds computed so far.
    triangle_bounds: u64,
    /// Per point key: the point, evaluated from the first patch that asked.
    points: HashMap<u64, SurfacePoint>,
    /// ε in model units.
    eps: f64,
    /// The view that sets each cell's ε and culls, if any.
    view: Option<&'a ViewTolerance>,
    /// The patch whose root bound its culling took: its first trial's root takes the
    /// same bound, counted once.
    root_counted: Option<usize>,
}

impl<'a> Evaluator<'a> {
    /// An evaluator on the grid of `params` (`840 · 2^max_depth` units per patch side).
    fn new(model: &'a SurfaceModel, params: &CcParams) -> Self {
        Evaluator {
            model,
            n: params.grid(),
            eps: params.epsilon(model),
            bounds: 0,
            proven: 0,
            triangle_bounds: 0,
            points: HashMap::default(),
            view: None,
            root_counted: None,
        }
    }

    /// Whether a cell with these corners and this bound lies wholly outside the frustum
    /// of a culling view: its surface is within `bound` of its corners' hull.
    fn outside(&self, corners: &[DVec3; 4], bound: f64) -> bool {
        match self.view {
            Some(ViewTolerance {
                view, cull: true, ..
            }) if bound.is_finite() => {
                let (lo, hi) = corner_box(corners);
                view.box_outside(lo - DVec3::splat(bound), hi + DVec3::splat(bound))
            }
            _ => false,
        }
    }

    /// Whether patch `p`, whose whole box has these corners and this bound, faces away
    /// from the eye of a view culling back faces.
    fn back_facing(&self, p: usize, corners: &[DVec3; 4], bound: f64) -> bool {
        match self.view {
            Some(ViewTolerance {
                view,
                cull_backfaces: true,
                ..
            }) if bound.is_finite() => {
                let (lo, hi) = corner_box(corners);
                let b = DVec3::splat(bound);
                patch_back_facing(view, &self.model.patches[p], lo - b, hi + b)
            }
            _ => false,
        }
    }

    fn corners(&mut self, p: usize, cell: Cell) -> [DVec3; 4] {
        cell.corners().map(|(a, c)| self.get(p, a, c).position)
    }

    fn get(&mut self, p: usize, i: u32, j: u32) -> SurfacePoint {
        let key = point_key(&self.model.mesh, p, i, j, self.n);
        let (model, n) = (self.model, self.n as f64);
        *self
            .points
            .entry(key)
            .or_insert_with(|| model.eval(p, i as f64 / n, j as f64 / n))
    }
}

/// The box of a cell's corners.
fn corner_box(corners: &[DVec3; 4]) -> (DVec3, DVec3) {
    let lo = corners.iter().fold(DVec3::INFINITY, |a, &c| a.min(c));
    let hi = corners.iter().fold(DVec3::NEG_INFINITY, |a, &c| a.max(c));
    (lo, hi)
}

/// A cell's tolerance: `world`, and within the view's pixels at the box of its corners
/// where the view sets them ([`View::cell_tolerance`]), the view's search run only as far
/// as each question needs: a far cell's bound is most often far from its tolerance, and
/// the answer is the whole search's ([`ToleranceSearch`]).
struct CellTolerance<'v> {
    world: f64,
    search: Option<ToleranceSearch<'v>>,
}

impl<'v> CellTolerance<'v> {
    fn new(view: Option<&'v ViewTolerance>, corners: &[DVec3; 4], world: f64) -> Self {
        let search = view.and_then(|v| {
            let px = v.pixels?;
            let (lo, hi) = corner_box(corners);
            Some(v.view.tolerance_search(lo, hi, px))
        });
        CellTolerance { world, search }
    }

    /// Whether `bound` is within the tolerance.
    fn admits(&mut self, bound: f64) -> bool {
        bound <= self.world && self.search.as_mut().is_none_or(|s| s.admits(bound))
    }

    /// The tolerance itself.
    fn value(&mut self) -> f64 {
        self.search
            .as_mut()
            .map_or(self.world, |s| self.world.min(s.value()))
    }
}

/// The flatness bound of the box `[u0, u1] × [v0, v1]` of patch `p`: a guaranteed upper
/// bound on the distance between the surface and any triangulation of the box's
/// polygon ([`super::bound`]). The box is snapped to the walk grid (`1 / WALK_ONE`).
pub fn flatness_bound(model: &SurfaceModel, p: usize, b: [f64; 4]) -> f64 {
    let (bx, corners) = snapped_box(model, p, b);
    box_bound(&model.patches[p], bx, corners)
}

/// The distance bound from the surface over the box `[u0, u1] × [v0, v1]` of patch `p`
/// to the nearest of `triangles`, refined toward `target`
/// ([`triangle_bound::triangles_bound`](super::triangle_bound::triangles_bound)); the box
/// is snapped as in [`flatness_bound`].
pub fn triangle_distance_bound(
    model: &SurfaceModel,
    p: usize,
    b: [f64; 4],
    triangles: &[[DVec3; 3]],
    target: f64,
) -> f64 {
    let (bx, corners) = snapped_box(model, p, b);
    triangles_bound(&model.patches[p], bx, corners, triangles, target)
}

/// The box in walk units and its corner positions.
fn snapped_box(model: &SurfaceModel, p: usize, b: [f64; 4]) -> ([u32; 4], [DVec3; 4]) {
    let bx = b.map(|t| (t.clamp(0.0, 1.0) * WALK_ONE as f64).round() as u32);
    let t = |x: u32| x as f64 / WALK_ONE as f64;
    let corners = [
        (bx[0], bx[2]),
        (bx[1], bx[2]),
        (bx[1], bx[3]),
        (bx[0], bx[3]),
    ]
    .map(|(u, v)| model.eval(p, t(u), t(v)).position);
    (bx, corners)
}

/// The decision on one cell alone (twin of `cc_decide` in `shaders/cc_traverse.wgsl`):
/// `None` to split it, else the leaf's bound, for a leaf kept by its own triangles
/// (`exact`) the splits it had left, and whether the bound meets the cell's tolerance.
fn decide_cell(
    eval: &mut Evaluator,
    p: usize,
    cell: Cell,
    splits_left: u32,
    tolerance: f64,
    exact: bool,
) -> Option<(f64, Option<u32>, bool)> {
    // Grid units to walk units: WALK_ONE / n = 2^(18 - max_depth).
    let scale = WALK_ONE / eval.n;
    let bx = [cell.i, cell.i + cell.w, cell.j, cell.j + cell.h].map(|t| t * scale);
    let corners = cell.corners().map(|(a, c)| eval.get(p, a, c).position);
    // The world ε, or the cell's share of the view's pixels.
    let mut tolerance = CellTolerance::new(eval.view, &corners, tolerance.min(eval.eps));
    // A cell whose children's corners already prove it too far from flat is split
    // without its bound. Only at a vertex: a regular patch's bound is one Bézier piece,
    // about as costly as the proof's five evaluations.
    let proven = splits_left > 0 && !eval.model.patches[p].is_regular() && {
        let (w, h) = (cell.w / 2, cell.h / 2);
        let centre = eval.get(p, cell.i + w, cell.j + h).position;
        let mids = [(w, 0), (2 * w, h), (w, 2 * h), (0, h)]
            .map(|(a, b)| eval.get(p, cell.i + a, cell.j + b).position);
        !tolerance.admits(split_proof(corners, centre, mids))
    };
    let bound = if proven {
        eval.proven += 1;
        f64::INFINITY
    } else if cell.w == eval.n && cell.h == eval.n {
        // The whole patch: its bound is the model's, computed once.
        if eval.root_counted != Some(p) {
            eval.bounds += 1;
        }
        eval.model.root_bound(p)
    } else {
        eval.bounds += 1;
        box_bound(&eval.model.patches[p], bx, corners)
    };
    let met = tolerance.admits(bound);
    // Nothing of it can be seen: a leaf that emits nothing.
    if met || eval.outside(&corners, bound) {
        return Some((bound, None, met));
    }
    if exact {
        let target = tolerance.value();
        if let Some(b) = own_triangles_bound(eval, p, cell, bx, corners, target) {
            return Some((b, Some(splits_left), true));
        }
    }
    (splits_left == 0).then_some((bound, None, met))
}

/// Recursive marking of one cell (a leaf kept by its own triangles that failed against
/// its polygon is marked again this way); `leaf` receives each leaf and its bound.
fn mark(
    eval: &mut Evaluator,
    p: usize,
    cell: Cell,
    splits_left: u32,
    tolerance: f64,
    leaf: &mut dyn FnMut(Cell, f64, bool),
) {
    match decide_cell(eval, p, cell, splits_left, tolerance, false) {
        Some((bound, _, met)) => leaf(cell, bound, met),
        None => {
            for q in 0..4 {
                mark(eval, p, cell.child(q), splits_left - 1, tolerance, leaf);
            }
        }
    }
}

/// The distance bound from the surface over `cell` to its own two triangles (the zip's
/// diagonal, on the output's single-precision corners), where it is at most the
/// tolerance.
fn own_triangles_bound(
    eval: &mut Evaluator,
    p: usize,
    cell: Cell,
    bx: [u32; 4],
    corners: [DVec3; 4],
    tolerance: f64,
) -> Option<f64> {
    let quad = corners.map(|c| c.as_vec3().as_dvec3());
    let s = zip_start(
        (quad[0] - quad[2]).length_squared(),
        (quad[1] - quad[3]).length_squared(),
    );
    let triangles = [
        [quad[(s + 3) % 4], quad[s], quad[s + 1]],
        [quad[s + 1], quad[s + 2], quad[(s + 3) % 4]],
    ];
    // The centre and side midpoints (the children's corners, needed if it splits) are
    // surface points: one farther than ε from both triangles fails the cell at once.
    let (w, h) = (cell.w / 2, cell.h / 2);
    let far = [(w, h), (w, 0), (2 * w, h), (w, 2 * h), (0, h)]
        .iter()
        .any(|&(a, b)| {
            let x = eval.get(p, cell.i + a, cell.j + b).position;
            triangles
                .iter()
                .all(|t| (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length() > tolerance)
        });
    if far {
        return None;
    }
    eval.triangle_bounds += 1;
    let b = triangles_bound(&eval.model.patches[p], bx, corners, &triangles, tolerance);
    (b <= tolerance).then_some(b)
}

/// Adaptive tessellation of every (non-hole) patch to within `params.tolerance`.
pub fn tessellate_adaptive(model: &SurfaceModel, params: &CcParams) -> Result<CcTessellation> {
    tessellate_with_splits(model, params, &params.first_split.splits(), None)
}

/// [`tessellate_adaptive`] for a view: each cell's ε the smaller of the world tolerance
/// and the one that keeps its points inside the frustum within `view.pixels` pixels of
/// the mesh ([`View::cell_tolerance`], where the bound is proven); with `view.cull`,
/// cells wholly outside the frustum emit nothing. Leaves whose bound the depth limit
/// leaves above their ε (next to the near plane, where ε shrinks) count as `unmet`.
pub fn tessellate_adaptive_in_view(
    model: &SurfaceModel,
    params: &CcParams,
    view: &ViewTolerance,
) -> Result<CcTessellation> {
    if let Some(px) = view.pixels {
        if !(px.is_finite() && px > 0.0) {
            return Err(Error::Param(format!(
                "pixel tolerance must be a positive number, got {px}"
            )));
        }
    }
    let splits = params.first_split.splits();
    let Some(cap) = view.max_triangles else {
        return tessellate_with_splits(model, params, &splits, Some(*view));
    };
    let Some(asked) = view.pixels else {
        return Err(Error::Param(
            "a triangle cap needs a pixel tolerance to coarsen".into(),
        ));
    };
    // Past the viewport's diagonal, coarser pixels change little: the coarsest mesh.
    let coarsest = view.view.viewport().length();
    let mut px = asked;
    loop {
        let step = ViewTolerance {
            pixels: Some(px),
            ..*view
        };
        if let Some(out) = tessellate_within(model, params, &splits, Some(step), Some(cap))? {
            return Ok(out);
        }
        if px > coarsest {
            return Err(Error::Param(format!(
                "at most {cap} triangles: not met even at {px:.0} pixels ({asked} asked): the patches in view need more"
            )));
        }
        px *= std::f64::consts::SQRT_2;
    }
}

/// What `cc_traverse` writes for `params` (flatness bound): every leaf in the GPU's
/// order. The twin's output for the tests.
#[doc(hidden)]
pub fn marking_leaves(model: &SurfaceModel, params: &CcParams) -> Result<Vec<CcCell>> {
    params.validate(model)?;
    let mut eval = Evaluator::new(model, params);
    let flatness = CcParams {
        leaf_bound: LeafBound::Flatness,
        ..*params
    };
    let marking = mark_patches(&mut eval, &flatness, &params.first_split.splits(), None);
    let cells = marking
        .leaves
        .iter()
        .map(|&(p, c)| CcCell {
            patch_id: p as u32,
            trial_depth: marking.first_split[p] | c.depth << 8,
            i: c.i,
            j: c.j,
        })
        .collect();
    Ok(cells)
}

/// [`tessellate_adaptive`] trying these first splits in this order.
fn tessellate_with_splits(
    model: &SurfaceModel,
    params: &CcParams,
    splits: &[(u32, u32)],
    view: Option<ViewTolerance>,
) -> Result<CcTessellation> {
    let out = tessellate_within(model, params, splits, view, None)?;
    Ok(out.expect("no triangle cap"))
}

/// [`tessellate_with_splits`], `None` where the mesh would have more than `cap` triangles.
fn tessellate_within(
    model: &SurfaceModel,
    params: &CcParams,
    splits: &[(u32, u32)],
    view: Option<ViewTolerance>,
    cap: Option<usize>,
) -> Result<Option<CcTessellation>> {
    params.validate(model)?;
    let mut eval = Evaluator::new(model, params);
    eval.view = view.as_ref();
    let n = eval.n;
    let mesh = &model.mesh;
    let mut out = CcTessellation {
        tolerance_px: view.and_then(|v| v.pixels),
        ..Default::default()
    };
    // 1. Adaptive marking. 2. Base-quadrilateral replacement.
    let mut marking = mark_patches(&mut eval, params, splits, cap.map(|c| c / 2));
    if marking.over_cap {
        return Ok(None);
    }
    let (polygons, lines) = settle_exact_leaves(&mut eval, &mut marking);
    out.unmet = marking.unmet;
    out.bounds = eval.bounds;
    out.proven = eval.proven;
    out.triangle_bounds = eval.triangle_bounds;
    out.max_bound = marking.max_bound;
    out.culled_leaves = marking.culled_leaves;
    out.culled_patches = marking.culled_patches;
    let faces = face_polygons(mesh, &marking, &lines, n);
    let leaves = marking.leaves;
    out.leaves = leaves.len() + faces.len();

    // Every polygon vertex evaluated once per point; one output vertex per point and
    // chart, its position and normal copied from the point's. Ids in the order of the
    // chart keys, so the numbering does not depend on the order of work.
    // About one new point per leaf, the rest shared with neighbours.
    let mut used: HashMap<u64, (usize, u32, u32)> =
        HashMap::with_capacity_and_hasher(2 * (leaves.len() + faces.len()), Default::default());
    for (&(p, _), (poly, _)) in leaves.iter().zip(polygons.iter()) {
        for &(a, b) in poly {
            eval.get(p, a, b);
            used.entry(chart_key(mesh, p, a, b, n)).or_insert((p, a, b));
        }
    }
    for (poly, _) in faces.iter() {
        for &(p, a, b) in poly {
            eval.get(p, a, b);
            used.entry(chart_key(mesh, p, a, b, n)).or_insert((p, a, b));
        }
    }
    out.evaluations = eval.points.len() as u64;
    let mut keys: Vec<u64> = used.keys().copied().collect();
    keys.sort_unstable();
    let id_of: HashMap<u64, u32> = keys
        .iter()
        .enumerate()
        .map(|(k, &key)| (key, k as u32))
        .collect();
    out.mesh.vertices = keys
        .iter()
        .map(|key| {
            // Any patch of the chart gives the same face coordinates (exact integers).
            let (p, i, j) = used[key];
            let (face, uv) = vertex_face_uv(mesh, p, i, j, n);
            out_vertex(eval.points[&point_of(*key)], face, uv)
        })
        .collect();

    // 3. Triangulation.
    let vertices = &out.mesh.vertices;
    let position = |id: u32| DVec3::from(vertices[id as usize].position.map(f64::from));
    let mut indices = Vec::with_capacity(3 * (2 * leaves.len() + 4 * faces.len()));
    // One polygon buffer for all: a leaf's allocation would cost more than its zip.
    let mut zip_poly: Vec<PolyVertex> = Vec::new();
    for (&(p, _), (poly, corners)) in leaves.iter().zip(polygons.iter()) {
        zip_poly.clear();
        zip_poly.extend(poly.iter().map(|&(a, b)| PolyVertex {
            i: a as i64,
            j: b as i64,
            id: id_of[&chart_key(mesh, p, a, b, n)],
        }));
        triangulate(&zip_poly, *corners, position, &mut indices);
    }
    for (poly, corners) in faces.iter() {
        zip_poly.clear();
        zip_poly.extend(poly.iter().map(|&(p, a, b)| {
            let (s, t) = face_grid(mesh.face_of[p].1, a, b, n);
            PolyVertex {
                i: s,
                j: t,
                id: id_of[&chart_key(mesh, p, a, b, n)],
            }
        }));
        triangulate(&zip_poly, *corners, position, &mut indices);
    }
    out.mesh.indices = indices;
    if cap.is_some_and(|c| out.mesh.triangle_count() > c) {
        return Ok(None);
    }
    Ok(Some(out))
}

/// What step 1 found: every leaf, and the first split each patch chose.
struct Marking {
    leaves: Vec<(usize, Cell)>,
    /// Per leaf: its bound, and for a leaf accepted by the triangle-distance bound of
    /// its plain quad, the splits it had left (it is checked again with its polygon).
    bounds: Vec<(f64, Option<u32>)>,
    /// Per patch, the index in the splits tried of its first split (`u32::MAX` for a
    /// hole): with [`first_splits`] in order, the GPU's trial number.
    first_split: Vec<u32>,
    unmet: usize,
    max_bound: f64,
    culled_leaves: usize,
    culled_patches: usize,
    /// The culled leaves of patches partly in view: they emit nothing, but their corners
    /// still mark points on their neighbours' sides, as on the GPU (whose side walk finds
    /// a side's points by halving it, and needs every corner of the quadtree marked).
    culled: Vec<(usize, Cell)>,
    /// Marking stopped: more leaves than the cap allowed.
    over_cap: bool,
    /// Face leaves in view ([`ViewTolerance::face_leaves`]): control faces emitted whole.
    faces: Vec<usize>,
    /// Per control face, whether it is a face leaf, in view or culled: its patches then
    /// have no leaves of their own.
    face_leaf: Vec<bool>,
}

/// Step 1, adaptive marking: the first split ku×kv of each patch is the one with the
/// fewest leaves.
fn mark_patches(
    eval: &mut Evaluator,
    params: &CcParams,
    splits: &[(u32, u32)],
    leaf_cap: Option<usize>,
) -> Marking {
    let eps = eval.eps;
    let (n, model) = (eval.n, eval.model);
    let mesh = &model.mesh;
    let exact = params.leaf_bound == LeafBound::Triangles;
    let mut out = Marking {
        leaves: Vec::new(),
        bounds: Vec::new(),
        first_split: vec![u32::MAX; mesh.patch_count()],
        unmet: 0,
        max_bound: 0.0,
        culled_leaves: 0,
        culled_patches: 0,
        culled: Vec::new(),
        over_cap: false,
        faces: Vec::new(),
        face_leaf: vec![false; mesh.control_faces.len()],
    };
    if eval.view.is_some_and(|v| v.face_leaves) {
        mark_faces(eval, &mut out);
    }
    for p in mesh.surface_patches() {
        if out.face_leaf[mesh.face_of[p].0 as usize] {
            continue;
        }
        // A patch wholly outside a culling view, or facing away, costs one bound and no
        // search.
        if eval.view.is_some_and(|v| v.cull || v.cull_backfaces) {
            let root = Cell {
                i: 0,
                j: 0,
                w: n,
                h: n,
                depth: 0,
            };
            let corners = eval.corners(p, root);
            eval.bounds += 1;
            eval.root_counted = Some(p);
            let bound = model.root_bound(p);
            if eval.outside(&corners, bound) || eval.back_facing(p, &corners, bound) {
                out.culled_patches += 1;
                continue;
            }
        }
        // In the GPU's order (`traverse`): the same leaves as marking each cell
        // recursively, in the order the kernel writes them.
        let max_depth = params.max_depth;
        let mut decide = |c: Cell| decide_cell(eval, p, c, max_depth - c.depth, eps, exact);
        let (trial, walk) = traverse::search(n, splits, &mut decide);
        out.first_split[p] = trial;
        let culled_before = out.culled_leaves;
        let mut seen = false;
        let mut culled = Vec::new();
        for (c, (bound, e, met)) in walk.leaves {
            if !out.keep_leaf(eval, p, c, bound, met) {
                culled.push((p, c));
                continue;
            }
            seen = true;
            out.leaves.push((p, c));
            out.bounds.push((bound, e));
        }
        // A patch wholly out of view counts as a patch, not as leaves.
        if seen {
            out.culled.extend(culled);
        } else {
            out.culled_patches += 1;
            out.culled_leaves = culled_before;
        }
        if leaf_cap.is_some_and(|cap| out.leaves.len() + out.faces.len() > cap) {
            out.over_cap = true;
            return out;
        }
    }
    out
}

/// The face leaves: every quad control face whose bound taken whole
/// ([`SurfaceModel::face_bound`]) meets the tolerance at its corners' box. Such a face
/// outside the frustum, or with its four patches facing away, counts as four culled
/// patches. The GPU decides the same in `cc_traverse.wgsl` (`cc_face_decision`).
fn mark_faces(eval: &mut Evaluator, out: &mut Marking) {
    let model = eval.model;
    let mesh = &model.mesh;
    for f in 0..mesh.control_faces.len() {
        let bound = model.face_bound(f);
        if !bound.is_finite() {
            continue;
        }
        let first = mesh.first_patch[f] as usize;
        let corners: [DVec3; 4] = std::array::from_fn(|k| eval.get(first + k, 0, 0).position);
        eval.bounds += 1;
        if !CellTolerance::new(eval.view, &corners, eval.eps).admits(bound) {
            continue;
        }
        out.face_leaf[f] = true;
        // The face's surface lies within its bound of the corners' hull, each patch's too.
        let back_facing = eval.view.is_some_and(|v| v.cull_backfaces)
            && (first..first + 4).all(|p| eval.back_facing(p, &corners, bound));
        if eval.outside(&corners, bound) || back_facing {
            out.culled_patches += 4;
            continue;
        }
        out.max_bound = out.max_bound.max(bound);
        out.faces.push(f);
    }
}

impl Marking {
    /// Counts a leaf of patch `p` with its bound: false for one outside the view (it
    /// emits nothing), else whether the bound `met` the cell's ε (as its decision took
    /// it), and the largest bound.
    fn keep_leaf(
        &mut self,
        eval: &mut Evaluator,
        p: usize,
        c: Cell,
        bound: f64,
        met: bool,
    ) -> bool {
        let corners = eval.corners(p, c);
        if eval.outside(&corners, bound) {
            self.culled_leaves += 1;
            return false;
        }
        if !met {
            self.unmet += 1;
        }
        self.max_bound = self.max_bound.max(bound);
        true
    }
}

/// Checks every leaf accepted by the triangle-distance bound of its plain quad against
/// the polygon it got (the points finer neighbours put on its sides change its
/// triangles), and marks again, with the flatness bound alone, each that fails; until
/// none does. Marking again only adds points, so this ends, and the order of work does
/// not matter. Returns the leaves' polygons.
fn settle_exact_leaves(
    eval: &mut Evaluator,
    marking: &mut Marking,
) -> (Polygons<(u32, u32)>, Lines) {
    let eps = eval.eps;
    let (n, mesh) = (eval.n, &eval.model.mesh);
    loop {
        let lines = marked_lines(mesh, &marking.leaves, &marking.culled, n);
        let polygons = leaf_polygons(mesh, &marking.leaves, &lines, n);
        let mut failed = Vec::new();
        for (k, (poly, corners)) in polygons.iter().enumerate() {
            let Some(_) = marking.bounds[k].1 else {
                continue;
            };
            if poly.len() == 4 {
                continue;
            }
            let (p, cell) = marking.leaves[k];
            let positions: Vec<DVec3> = poly
                .iter()
                .map(|&(a, b)| eval.get(p, a, b).position.as_vec3().as_dvec3())
                .collect();
            let pv: Vec<PolyVertex> = poly
                .iter()
                .enumerate()
                .map(|(id, &(a, b))| PolyVertex {
                    i: a as i64,
                    j: b as i64,
                    id: id as u32,
                })
                .collect();
            let mut tris = Vec::new();
            triangulate(&pv, *corners, |id| positions[id as usize], &mut tris);
            let triangles: Vec<[DVec3; 3]> = tris
                .chunks(3)
                .map(|t| [0, 1, 2].map(|q| positions[t[q] as usize]))
                .collect();
            let scale = WALK_ONE / n;
            let bx = [cell.i, cell.i + cell.w, cell.j, cell.j + cell.h].map(|t| t * scale);
            let quad = cell.corners().map(|(a, c)| eval.get(p, a, c).position);
            let eps = CellTolerance::new(eval.view, &quad, eval.eps).value();
            eval.triangle_bounds += 1;
            let b = triangles_bound(&eval.model.patches[p], bx, quad, &triangles, eps);
            if b <= eps {
                marking.bounds[k].0 = b;
            } else {
                failed.push(k);
            }
        }
        if failed.is_empty() {
            marking.max_bound = marking.bounds.iter().map(|b| b.0).fold(0.0, f64::max);
            return (polygons, lines);
        }
        let mut leaves = Vec::new();
        let mut bounds = Vec::new();
        let mut next = failed.iter().peekable();
        for k in 0..marking.leaves.len() {
            if next.peek() == Some(&&k) {
                next.next();
                let (p, cell) = marking.leaves[k];
                let splits_left = marking.bounds[k].1.expect("an exact leaf");
                let mut marked = Vec::new();
                mark(eval, p, cell, splits_left, eps, &mut |c, b, e| {
                    marked.push((c, b, e))
                });
                for (c, b, e) in marked {
                    if marking.keep_leaf(eval, p, c, b, e) {
                        leaves.push((p, c));
                        bounds.push((b, None));
                    } else {
                        marking.culled.push((p, c));
                    }
                }
            } else {
                leaves.push(marking.leaves[k]);
                bounds.push(marking.bounds[k]);
            }
        }
        marking.leaves = leaves;
        marking.bounds = bounds;
    }
}

/// Polygons in one list (a list per polygon would cost an allocation per leaf): polygon
/// `k` is `points[start[k]..start[k + 1]]`, with the positions of its four corners in it.
struct Polygons<T> {
    points: Vec<T>,
    start: Vec<usize>,
    corners: Vec<[usize; 4]>,
}

impl<T> Polygons<T> {
    fn with_capacity(polygons: usize) -> Self {
        let mut start = Vec::with_capacity(polygons + 1);
        start.push(0);
        Polygons {
            points: Vec::with_capacity(4 * polygons),
            start,
            corners: Vec::with_capacity(polygons),
        }
    }

    /// Ends the polygon whose points were pushed since the last one ended.
    fn end(&mut self, corners: [usize; 4]) {
        self.start.push(self.points.len());
        self.corners.push(corners);
    }

    fn len(&self) -> usize {
        self.corners.len()
    }

    /// Where the next point pushed lies in its polygon.
    fn next_at(&self) -> usize {
        self.points.len() - self.start[self.start.len() - 1]
    }

    fn iter(&self) -> impl Iterator<Item = (&[T], &[usize; 4])> {
        self.start
            .windows(2)
            .zip(&self.corners)
            .map(|(w, c)| (&self.points[w[0]..w[1]], c))
    }
}

/// Step 2, base-quadrilateral replacement: each leaf's sides through the marked points
/// on them (`lines`: the corners of the leaves and of the culled leaves).
fn leaf_polygons(
    mesh: &PatchMesh,
    leaves: &[(usize, Cell)],
    lines: &Lines,
    n: u32,
) -> Polygons<(u32, u32)> {
    let mut polygons = Polygons::with_capacity(leaves.len());
    for &(p, cell) in leaves {
        let c = cell.corners();
        let mut at = [0; 4];
        for k in 0..4 {
            at[k] = polygons.next_at();
            polygons.points.push(c[k]);
            lines.between(mesh, p, c[k], c[(k + 1) % 4], n, &mut polygons.points);
        }
        polygons.end(at);
    }
    polygons
}

/// The marked points of every line: the corners of the leaves and of the culled leaves.
fn marked_lines(
    mesh: &PatchMesh,
    leaves: &[(usize, Cell)],
    culled: &[(usize, Cell)],
    n: u32,
) -> Lines {
    let mut lines = Lines::default();
    for &(p, cell) in leaves.iter().chain(culled) {
        for (a, b) in cell.corners() {
            lines.add(point_key(mesh, p, a, b, n));
        }
    }
    lines.sort();
    lines
}

/// The polygons of the face leaves. Side `k` runs from vertex `k` along patch `k`'s
/// side `v = 0` to the level-1 edge point, then along patch `k + 1`'s side `u = 0` to
/// vertex `k + 1`, through the marked points of both halves; the edge point itself is
/// on it when the face across is not a face leaf (its leaves have it as a corner).
/// Their vertices are `(patch, i, j)`, each in the patch of the face it lies in.
fn face_polygons(
    mesh: &PatchMesh,
    marking: &Marking,
    lines: &Lines,
    n: u32,
) -> Polygons<(usize, u32, u32)> {
    let mut polygons = Polygons::with_capacity(marking.faces.len());
    if marking.faces.is_empty() {
        return polygons;
    }
    let mut uses: Vec<Vec<usize>> = vec![Vec::new(); mesh.edge_uses.len()];
    for (p, edges) in mesh.quad_edges.iter().enumerate() {
        if !mesh.hole[p] {
            uses[edges[0] as usize].push(p);
            uses[edges[3] as usize].push(p);
        }
    }
    let mut half = Vec::new();
    for &f in &marking.faces {
        let first = mesh.first_patch[f] as usize;
        let mut at = [0; 4];
        for (k, corner) in at.iter_mut().enumerate() {
            let (p, q) = (first + k, first + (k + 1) % 4);
            *corner = polygons.next_at();
            polygons.points.push((p, 0, 0));
            lines.between(mesh, p, (0, 0), (n, 0), n, &mut half);
            polygons
                .points
                .extend(half.drain(..).map(|(a, b)| (p, a, b)));
            // Any face across that is not a face leaf (more than one on an edge that is
            // not manifold) has the edge point as a corner.
            let edge = mesh.quad_edges[p][0] as usize;
            let needed = uses[edge]
                .iter()
                .map(|&r| mesh.face_of[r].0 as usize)
                .any(|g| g != f && !marking.face_leaf[g]);
            if needed {
                polygons.points.push((p, n, 0));
            }
            lines.between(mesh, q, (0, n), (0, 0), n, &mut half);
            polygons
                .points
                .extend(half.drain(..).map(|(a, b)| (q, a, b)));
        }
        polygons.end(at);
    }
    polygons
}

/// Point `(i, j)` of the patch at corner `k` of a quad face in the face's grid: units
/// of `1/(2n)` of its side, `(0, 0)` at its first vertex
/// ([`PatchMesh::face_point_at`]).
fn face_grid(k: u8, i: u32, j: u32, n: u32) -> (i64, i64) {
    let (i, j, m) = (i as i64, j as i64, 2 * n as i64);
    match k {
        0 => (i, j),
        1 => (m - j, i),
        2 => (m - i, m - j),
        _ => (j, m - i),
    }
}

/// Which line a side runs along: a level-1 edge, or a grid line inside a patch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Line {
    Edge(u32),
    /// `u = i` inside patch `p`: positions are `j`.
    Column(u32, u32),
    /// `v = j` inside patch `p`: positions are `i`.
    Row(u32, u32),
}

/// The marked points of every line, sorted by position.
#[derive(Default)]
struct Lines {
    points: HashMap<Line, Vec<u32>>,
}

impl Lines {
    fn add(&mut self, key: u64) {
        match key_place(key) {
            KeyPlace::Vertex(_) => {}
            KeyPlace::Edge { edge, t } => self.points.entry(Line::Edge(edge)).or_default().push(t),
            KeyPlace::Interior { patch, i, j } => {
                self.points
                    .entry(Line::Column(patch, i))
                    .or_default()
                    .push(j);
                self.points.entry(Line::Row(patch, j)).or_default().push(i);
            }
        }
    }

    fn sort(&mut self) {
        for v in self.points.values_mut() {
            v.sort_unstable();
            v.dedup();
        }
    }

    /// Appends the marked points strictly between `a` and `b` (a side of a cell of
    /// patch `p`), in order from `a`.
    fn between(
        &self,
        mesh: &PatchMesh,
        p: usize,
        a: (u32, u32),
        b: (u32, u32),
        n: u32,
        out: &mut Vec<(u32, u32)>,
    ) {
        // A side on the patch boundary lies on a level-1 edge: compare canonical t.
        let edge = if a.1 == 0 && b.1 == 0 {
            Some(0)
        } else if a.0 == n && b.0 == n {
            Some(1)
        } else if a.1 == n && b.1 == n {
            Some(2)
        } else if a.0 == 0 && b.0 == 0 {
            Some(3)
        } else {
            None
        };
        let (line, ta, tb) = match edge {
            Some(k) => {
                let quad = mesh.quads[p];
                let forward = quad[k] < quad[(k + 1) % 4];
                // Distance from corner k along edge k, then canonical.
                let local = |q: (u32, u32)| match k {
                    0 => q.0,
                    1 => q.1,
                    2 => n - q.0,
                    _ => n - q.1,
                };
                let canon = |t: u32| if forward { t } else { n - t };
                (
                    Line::Edge(mesh.quad_edges[p][k]),
                    canon(local(a)),
                    canon(local(b)),
                )
            }
            None if a.0 == b.0 => (Line::Column(p as u32, a.0), a.1, b.1),
            None => (Line::Row(p as u32, a.1), a.0, b.0),
        };
        let Some(ts) = self.points.get(&line) else {
            return;
        };
        let (lo, hi) = (ta.min(tb), ta.max(tb));
        let first = ts.partition_point(|&t| t <= lo);
        let last = ts.partition_point(|&t| t < hi);
        let inside = ts[first..last].iter().copied();
        let to_point = |t: u32| -> (u32, u32) {
            // Linear between a and b.
            let f = |x: u32, y: u32| -> u32 {
                let (x, y, t, ta, tb) = (x as i64, y as i64, t as i64, ta as i64, tb as i64);
                (x + (y - x) * (t - ta) / (tb - ta)) as u32
            };
            (f(a.0, b.0), f(a.1, b.1))
        };
        if ta < tb {
            out.extend(inside.map(to_point));
        } else {
            out.extend(inside.rev().map(to_point));
        }
    }
}

/// The output vertex of a surface point on control face `face` at `uv` there.
pub fn out_vertex(sp: SurfacePoint, face: u32, uv: [f32; 2]) -> OutVertex {
    OutVertex {
        position: sp.position.as_vec3().to_array(),
        normal: sp.normal.as_vec3().to_array(),
        uv,
        face,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catmull_clark::TREE_DEPTH;
    use crate::io::obj::parse_obj;
    use std::path::Path;

    #[test]
    fn even_square_first_splits_never_win() {
        // A cube (valence-3 vertices) and a 3×3 grid bent into a saddle (regular
        // patches and a boundary).
        let cube = parse_obj(
            Path::new("cube.obj"),
            b"v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
             f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
        )
        .expect("cube");
        let mut saddle = String::new();
        for j in 0..4 {
            for i in 0..4 {
                let (x, y) = (i as f64 - 1.5, j as f64 - 1.5);
                saddle += &format!("v {x} {y} {}\n", 0.4 * x * y);
            }
        }
        for j in 0..3 {
            for i in 0..3 {
                let v = 4 * j + i + 1;
                saddle += &format!("f {} {} {} {}\n", v, v + 1, v + 5, v + 4);
            }
        }
        let saddle = parse_obj(Path::new("saddle.obj"), saddle.as_bytes()).expect("saddle");
        let with_even: Vec<(u32, u32)> = (1..=MAX_BASE_SPLIT)
            .map(|k| (k, k))
            .chain(first_splits().filter(|(ku, kv)| ku != kv))
            .collect();
        // Leaves per patch at the finest: past 4, 2 × 2 is in contention.
        let mut most = 0;
        let mut searched = false;
        for control in [cube, saddle] {
            let model = SurfaceModel::new(PatchMesh::new(&control).expect("valid"), TREE_DEPTH);
            for rel in [1e-2, 2e-3, 5e-4, 2e-4] {
                let params = CcParams {
                    tolerance: Tolerance::Absolute(rel * control.bbox_diag()),
                    max_depth: 4,
                    first_split: Default::default(),
                    leaf_bound: Default::default(),
                };
                let ours = tessellate_adaptive(&model, &params).expect("ours");
                let all = tessellate_with_splits(&model, &params, &with_even, None).expect("all");
                most = most.max(ours.leaves / model.mesh.patch_count());
                // The search matters here: midpoint splits alone give another mesh.
                let midpoints =
                    tessellate_with_splits(&model, &params, &[(1, 1)], None).expect("1x1");
                searched |= midpoints.leaves != ours.leaves;
                assert_eq!(ours.leaves, all.leaves, "{rel}");
                assert_eq!(ours.mesh.indices, all.mesh.indices, "{rel}");
            }
        }
        assert!(
            most > 4,
            "the test must split patches finely ({most} leaves per patch)"
        );
        assert!(searched, "the first split must matter somewhere");
    }

    #[test]
    fn the_bound_count_is_one_per_patch_when_every_root_passes() {
        let cube = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../assets/opensubdiv/catmark_cube.obj"
        );
        let model = crate::catmull_clark::load_surface(Path::new(cube)).expect("cube");
        let patches = model.mesh.patch_count() as u64;
        let coarse = CcParams {
            tolerance: Tolerance::Absolute(10.0),
            max_depth: 4,
            first_split: Default::default(),
            leaf_bound: Default::default(),
        };
        let out = tessellate_adaptive(&model, &coarse).expect("coarse");
        // The 1×1 root passes, and no other split can have fewer than one leaf.
        assert_eq!((out.bounds, out.leaves as u64), (patches, patches));
        let fine = tessellate_adaptive(
            &model,
            &CcParams {
                tolerance: Tolerance::Absolute(1e-3),
                ..coarse
            },
        )
        .expect("fine");
        // Per patch, the 1×1 split is always tried in full: a tree of L1 ≥ L leaves and
        // (L1 - 1) / 3 inner cells (L the leaves kept, whichever split won), each tested
        // by a bound or by the split proof.
        let (bounds, leaves) = (fine.bounds + fine.proven, fine.leaves as u64);
        assert!(leaves > patches, "the fine run must split");
        assert!(
            bounds >= leaves + (leaves - patches) / 3,
            "{bounds} bounds, {leaves} leaves"
        );
    }

    #[test]
    fn midpoint_splits_grow_one_tree_per_patch() {
        // Without the search every cell tested belongs to the one quadtree of its patch:
        // a tree with L leaves over P roots has (L - P) / 3 inner cells, so exactly
        // L + (L - P) / 3 cells, each with a bound or split on the split proof (some
        // are: both meshes have vertices), and the 1×1 split everywhere. The search may
        // only do better, and on Spot it must (it is why the search exists).
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        for (name, rel) in [
            ("opensubdiv/catmark_cube.obj", 1e-3),
            ("catmull_clark/spot_control_mesh.obj", 3e-3),
        ] {
            let model = crate::catmull_clark::load_surface(&assets.join(name)).expect(name);
            let search = CcParams {
                tolerance: Tolerance::Relative(rel),
                max_depth: 6,
                first_split: FirstSplit::Search,
                leaf_bound: Default::default(),
            };
            let midpoint = CcParams {
                first_split: FirstSplit::Midpoint,
                leaf_bound: Default::default(),
                ..search
            };
            let paper = tessellate_adaptive(&model, &midpoint).expect("midpoint");
            let ours = tessellate_adaptive(&model, &search).expect("search");
            let patches = model.mesh.surface_patches().count() as u64;
            let leaves = paper.leaves as u64;
            let tested = paper.bounds + paper.proven;
            assert_eq!(tested, leaves + (leaves - patches) / 3, "{name}");
            assert!(paper.proven > 0, "{name}: no cell split on the proof");
            assert_eq!((paper.unmet, ours.unmet), (0, 0), "{name}");
            assert!(paper.max_bound <= midpoint.epsilon(&model), "{name}");
            assert!(ours.leaves < paper.leaves, "{name}: {} leaves", ours.leaves);
            assert!(ours.bounds > paper.bounds, "{name}");
            let mut eval = Evaluator::new(&model, &midpoint);
            let marking = mark_patches(&mut eval, &midpoint, &FirstSplit::Midpoint.splits(), None);
            assert!(model
                .mesh
                .surface_patches()
                .all(|p| marking.first_split[p] == 0));
        }
    }

    #[test]
    fn the_polygon_kernel_twin_builds_the_reference_polygons() {
        // The GPU's walk (dyadic halving, the patch across's first split on boundaries)
        // against the reference's sorted lines, leaf for leaf, on the same leaves.
        use crate::catmull_clark::gpu_model::{leaf_items, patch_topology, point_homes};
        use crate::catmull_clark::polygon::PolygonKernel;
        use crate::catmull_clark::vertex_hash::split_key;
        use crate::gpu_types::CC_NO_KEY;
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
        let splits: Vec<(u32, u32)> = first_splits().collect();
        // Side points found inside a patch and on a patch's edge.
        let mut found = [0; 2];
        for (name, rel) in [
            ("opensubdiv/catmark_xord_boundary.obj", 3e-3),
            ("opensubdiv/catmark_edgecorner.obj", 1e-3),
            ("opensubdiv/catmark_hole_test1.obj", 2e-3),
            ("catmull_clark/spot_control_mesh.obj", 3e-3),
            ("opensubdiv/catmark_xord_interior.obj", 3e-4),
        ] {
            let model = crate::catmull_clark::load_surface(&assets.join(name)).expect(name);
            let mesh = &model.mesh;
            let size = mesh.bbox_diag();
            let params = CcParams {
                tolerance: Tolerance::Absolute(rel * size),
                max_depth: 6,
                first_split: Default::default(),
                leaf_bound: Default::default(),
            };
            let mut eval = Evaluator::new(&model, &params);
            let n = eval.n;
            let marking = mark_patches(&mut eval, &params, &splits, None);
            let lines = marked_lines(mesh, &marking.leaves, &marking.culled, n);
            let polygons = leaf_polygons(mesh, &marking.leaves, &lines, n);
            let topo = patch_topology(mesh);
            let cells: Vec<CcCell> = marking
                .leaves
                .iter()
                .map(|&(p, cell)| {
                    let trial = marking.first_split[p];
                    CcCell {
                        patch_id: p as u32,
                        trial_depth: trial | cell.depth << 8,
                        i: cell.i,
                        j: cell.j,
                    }
                })
                .collect();
            // The hash holds the leaves' items (corners in their charts and across
            // seams); any numbering will do.
            let homes = point_homes(mesh);
            let points = mesh.points.len() as u32;
            let key = |p: usize, (a, b): (u32, u32)| split_key(chart_key(mesh, p, a, b, n));
            let mut marked: Vec<[u32; 2]> = cells
                .iter()
                .flat_map(|c| leaf_items(&topo, &homes, points, n, &marking.first_split, c).0)
                .filter(|&k| k != CC_NO_KEY)
                .collect();
            marked.sort_unstable();
            marked.dedup();
            let id_of: HashMap<[u32; 2], u32> = marked
                .iter()
                .enumerate()
                .map(|(k, &m)| (m, k as u32))
                .collect();
            let vertex_of = |k: [u32; 2]| id_of.get(&k).copied();
            let kernel = PolygonKernel {
                grid: n,
                topo: &topo,
                first_trial: &marking.first_split,
                vertex_of: &vertex_of,
            };
            for ((&(p, cell), (poly, _)), leaf) in
                marking.leaves.iter().zip(polygons.iter()).zip(&cells)
            {
                let counts = kernel.count(leaf);
                let mut twin = Vec::new();
                kernel.emit(
                    leaf,
                    cell.corners().map(|c| id_of[&key(p, c)]),
                    counts,
                    &mut twin,
                );
                let reference: Vec<[u32; 4]> = poly
                    .iter()
                    .map(|&(a, b)| [id_of[&key(p, (a, b))], a, b, 0])
                    .collect();
                assert_eq!(twin, reference, "{name}: leaf {cell:?} of patch {p}");
                assert_eq!(twin.len() as u32, 4 + counts.iter().sum::<u32>());
                // The points found on the sides (the corners are given).
                let corners = cell.corners();
                for v in twin.iter().filter(|v| !corners.contains(&(v[1], v[2]))) {
                    let on_patch_edge = v[1] == 0 || v[2] == 0 || v[1] == n || v[2] == n;
                    found[usize::from(on_patch_edge)] += 1;
                }
            }
        }
        // Both walks must have had points to find: inside patches and across their edges.
        assert!(found[0] > 0 && found[1] > 0, "points found: {found:?}");
    }
}
