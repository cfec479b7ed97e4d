//! Lai–Cheng adaptive tessellation (paper §3–5), the CPU reference:
//!
//! 1. **Adaptive marking**: each patch's parameter square is split into cells until
//!    every cell passes the flatness test; the corners of the leaf cells are marked,
//!    under their canonical [`keys`](super::keys).
//! 2. **Base-quadrilateral replacement**: each side of a leaf is replaced by the
//!    polyline of the marked points on it (the corners of finer neighbours).
//! 3. Each polygon is triangulated without new vertices ([`super::triangulate`]).
//!
//! # Splits
//!
//! The paper splits at midpoints only, so a patch gets `2^L` cells per side and
//! loses up to 4× in triangles against a uniform grid of the right size. Here the first
//! split of a patch is `ku × kv` (each ≤ 8; rectangles too, for patches that bend more
//! one way) for the pair that gives the fewest leaves (tried in turn, skipping pairs
//! that cannot win), and every later split is at midpoints as in the paper. Parameters are
//! integers in units of `1 / (840 · 2^max_depth)` (840 = lcm(1..=8)), so keys stay exact.
//!
//! # Flatness test with a guaranteed bound
//!
//! A cell passes when a guaranteed upper bound on the distance from the surface over it
//! to its triangulated polygon is at most ε. Two bounds are computed and the smaller
//! kept; both hold for ANY triangulation of the polygon, so the extra vertices that
//! finer neighbours put on its sides keep them.
//!
//! **Parametric.** The output over a leaf is the piecewise-linear interpolant `L S` of
//! the surface at the polygon's vertices. Where the surface is C² over the cell,
//! `|S - L S| ≤ M R² / 2` on every triangle, with `M` a bound on the second directional
//! derivative and `R` the radius of a disc holding the triangle (Waldron 1998). In the
//! cell's unit coordinates `R² ≤ ½`, so the bound is `M / 4`, `M` from the Bézier nets of
//! the second derivatives of the pieces that cover the cell
//! ([`bicubic::second_derivatives`]). A cell touching the innermost square around an
//! extraordinary vertex has no bounded second derivative. There, with `B` the bilinear
//! quad through its corners, `|S - L S| ≤ |S - B| + |B - L B| + |L (B - S)| ≤ D +
//! |twist|/4 + D_side`, where `D` bounds `|S - B|` over the cell and `D_side` along its
//! sides, from the control points of the Bézier pieces of every level below, and for the
//! innermost square the convex-hull radius of its one-ring plus the distance from the
//! limit point to `B` (the paper's `m_ε` argument: that square shrinks to the vertex).
//!
//! **Slab (geometric).** A parametric bound also counts how unevenly the parameter runs
//! over the surface, which costs nothing in distance: near an extraordinary vertex it is
//! 2–300× the true distance, and even on regular cells of the cube it doubles the
//! triangle count. The slab bound measures distance only. Take the unit normal `n` of
//! the corners' diagonals and project along it onto the plane `Π ⊥ n`:
//! - `T`: the surface over the cell lies in a slab `lo ≤ n·x ≤ hi` (control points of
//!   the pieces, the innermost square as a ball), `T = hi - lo`; so do the polygon's
//!   triangles, whose vertices are surface points.
//! - The projected surface keeps orientation: `n · (a × b) > 0` for every pair of
//!   u- and v-derivative control vectors of every piece (so the Jacobian of the projection
//!   is positive everywhere: Bernstein weights are non-negative).
//! - Each side is monotone along its projected chord (its derivative control vectors have
//!   positive dot product with the chord) and lies in a band of width `w` around the
//!   chord's line (signed offsets of its control points); near a vertex it is only known
//!   to lie within `h` (hull radius of the innermost square) of the vertex.
//!
//! Let `q` be the projection of a surface point `x` of the cell. By the degree of the
//! projection (positive Jacobian), the image of the cell's boundary winds around `q` at
//! least once. That image minus the projected polygon is a sum of loops, each a piece of
//! a side between two consecutive polygon vertices and its chord; by monotonicity each
//! loop lies within `δ = w + 4h` of its chord (the one at the vertex within `δ` of its
//! two chords: a star-shaped region). So either the projected polygon winds around `q`,
//! and then a point `y` of the triangles projects onto `q` (a piecewise-linear disc
//! covers what its boundary winds around) with `|x - y| ≤ T`; or some loop winds around
//! `q`, so `q` is within `δ` of a chord and `|x - y| ≤ sqrt(T² + δ²)` for a point `y`
//! of that chord. Points of the innermost square are within `h` of the vertex. The bound
//! is `max(sqrt(T² + δ²), h)` plus a few ulps for rounding. It fails (and the parametric
//! bound is used alone) only where the projection folds or a side doubles back.
//! `the_bound_of_a_cell_is_above_its_true_error` (tests/cc_adaptive.rs) checks both
//! against sampled true distances, within 2% of them at the tightest.

use std::collections::HashMap;

use glam::DVec3;
use serde::Serialize;

use super::bicubic::{self, Net};
use super::keys::{key_place, point_key, KeyPlace};
use super::patch::{CornerNode, Node, PatchSurface, SurfaceModel, SurfacePoint};
use super::topology::PatchMesh;
use super::triangulate::{triangulate, PolyVertex};
use crate::error::{Error, Result};
use crate::gpu_types::OutVertex;
use crate::mesh::Mesh;

/// The largest first split of a patch along each side (`ku × kv` cells).
pub const MAX_BASE_SPLIT: u32 = 8;
/// lcm(1..=MAX_BASE_SPLIT): every first split divides it.
const BASE_GRID: u32 = 840;

/// Parameters of the adaptive method.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct CcParams {
    /// ε: the largest distance allowed between the output and the limit surface.
    pub tolerance: f64,
    /// At most this many midpoint splits after the first split (≤ the model's depth).
    pub max_depth: u32,
}

impl CcParams {
    pub fn validate(&self, model: &SurfaceModel) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::Param(format!(
                "tolerance must be a positive number, got {}",
                self.tolerance
            )));
        }
        if self.max_depth > model.depth.min(super::MAX_DEPTH) {
            return Err(Error::Param(format!(
                "max depth {} out of range 0..={}",
                self.max_depth,
                model.depth.min(super::MAX_DEPTH)
            )));
        }
        Ok(())
    }
}

/// A tessellation with what it cost.
#[derive(Clone, Debug, Default)]
pub struct CcTessellation {
    pub mesh: Mesh,
    /// Distinct surface points evaluated (output vertices and the cell corners the
    /// test near extraordinary vertices needs).
    pub evaluations: u64,
    /// Leaf cells (the polygons before triangulation).
    pub leaves: usize,
    /// Leaves stopped by `max_depth` with a bound above the tolerance: where the
    /// guarantee does not hold. 0 means the whole output is within the tolerance.
    pub unmet: usize,
    /// The largest flatness bound of any leaf: the guaranteed error of the output.
    pub max_bound: f64,
}

/// A cell of a patch: `[i, i + w] × [j, j + h]` in grid units.
#[derive(Clone, Copy, Debug)]
struct Cell {
    i: u32,
    j: u32,
    w: u32,
    h: u32,
}

impl Cell {
    fn corners(&self) -> [(u32, u32); 4] {
        let Cell { i, j, w, h } = *self;
        [(i, j), (i + w, j), (i + w, j + h), (i, j + h)]
    }
}

/// Surface points evaluated once per canonical key.
struct Evaluator<'a> {
    model: &'a SurfaceModel,
    n: u32,
    points: HashMap<u64, (SurfacePoint, usize, u32, u32)>,
}

impl Evaluator<'_> {
    fn get(&mut self, p: usize, i: u32, j: u32) -> SurfacePoint {
        let key = point_key(&self.model.mesh, p, i, j, self.n);
        let (model, n) = (self.model, self.n as f64);
        self.points
            .entry(key)
            .or_insert_with(|| (model.eval(p, i as f64 / n, j as f64 / n), p, i, j))
            .0
    }
}

/// Lower-left offsets of the quadrants, in units of half the parent.
const QUADRANT: [(f64, f64); 4] = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];

/// What of a patch's quadtree covers a parameter box.
struct Cover {
    /// Bézier pieces clipped to the box, with the part of the box they cover.
    pieces: Vec<(Net, [f64; 4])>,
    /// Squares around an extraordinary vertex: limit point, hull radius, overlap.
    corners: Vec<(DVec3, f64, [f64; 4])>,
}

/// Intersection of two boxes `[u0, u1, v0, v1]`, if of positive area.
fn overlap(b: [f64; 4], ou: f64, ov: f64, s: f64) -> Option<[f64; 4]> {
    let i = [
        b[0].max(ou),
        b[1].min(ou + s),
        b[2].max(ov),
        b[3].min(ov + s),
    ];
    (i[0] < i[1] && i[2] < i[3]).then_some(i)
}

/// Adds a Bézier piece over `[ou, ou+s] × [ov, ov+s]`, clipped to `b`.
fn push_piece(out: &mut Cover, net: &Net, b: [f64; 4], (ou, ov, s): (f64, f64, f64)) {
    let Some(i) = overlap(b, ou, ov, s) else {
        return;
    };
    let local = |a: f64, o: f64| (a - o) / s;
    let clipped = bicubic::clip(
        net,
        (local(i[0], ou), local(i[1], ou)),
        (local(i[2], ov), local(i[3], ov)),
    );
    out.pieces.push((clipped, i));
}

/// The stored quadtree ends at `TREE_DEPTH`; here the corner's one-ring is subdivided
/// further until the innermost square is below 1/64 of the box and its hull radius
/// below `max_hull` (40 levels at most), so that it does not dominate the bound.
fn expand_corner(
    out: &mut Cover,
    cn: &CornerNode,
    rule: super::BoundaryRule,
    (b, max_hull): ([f64; 4], f64),
    square: (f64, f64, f64),
) {
    let (mut ou, mut ov, mut s) = square;
    let mut ring = std::borrow::Cow::Borrowed(&cn.ring);
    let mut hull = cn.hull_radius;
    let target = (b[1] - b[0]).min(b[3] - b[2]) / 64.0;
    for _ in 0..40 {
        if s <= target && hull <= max_hull {
            break;
        }
        let children = ring.children(rule);
        let h = 0.5 * s;
        let mut next = None;
        for (c, child) in children.into_iter().enumerate() {
            let (cu, cv) = (ou + QUADRANT[c].0 * h, ov + QUADRANT[c].1 * h);
            if c == cn.corner {
                next = Some((child, cu, cv));
            } else if let Some(net) = child.regular_net(rule) {
                push_piece(out, &super::local::bspline_to_bezier(&net), b, (cu, cv, h));
            } else if let Some(i) = overlap(b, cu, cv, h) {
                // Not expected (one extraordinary corner per child); stay sound anyway:
                // the convex-hull bound holds around any centre.
                let c = child.points[0];
                out.corners.push((c, child.hull_radius(c), i));
            }
        }
        let (child, cu, cv) = next.expect("the vertex is in one child");
        hull = child.hull_radius(cn.limit);
        ring = std::borrow::Cow::Owned(child);
        (ou, ov, s) = (cu, cv, h);
    }
    if let Some(i) = overlap(b, ou, ov, s) {
        out.corners.push((cn.limit, hull, i));
    }
}

/// The quadtree nodes over `[u0, u1] × [v0, v1]` (overlaps of positive area), the
/// squares at extraordinary vertices no wider than `max_hull`.
fn cover(surface: &PatchSurface, b: [f64; 4], max_hull: f64) -> Cover {
    let mut out = Cover {
        pieces: Vec::new(),
        corners: Vec::new(),
    };
    let mut stack = vec![(0u32, 0.0, 0.0, 1.0)];
    while let Some((node, ou, ov, s)) = stack.pop() {
        if overlap(b, ou, ov, s).is_none() {
            continue;
        }
        match &surface.nodes[node as usize] {
            Node::Bezier(net) => push_piece(&mut out, net, b, (ou, ov, s)),
            Node::Split(children) => {
                for (c, &child) in children.iter().enumerate() {
                    let h = 0.5 * s;
                    stack.push((child, ou + QUADRANT[c].0 * h, ov + QUADRANT[c].1 * h, h));
                }
            }
            Node::Corner(cn) => {
                expand_corner(&mut out, cn, surface.rule, (b, max_hull), (ou, ov, s))
            }
        }
    }
    out
}

/// Guaranteed bound on the distance from the surface over the box `b = [u0, u1, v0,
/// v1]` of a patch to any triangulation of its polygon (module docs): the smaller of the
/// parametric and the slab bound. `corners` evaluates the box corners.
fn cell_bound(surface: &PatchSurface, b: [f64; 4], corners: impl FnOnce() -> [DVec3; 4]) -> f64 {
    let corners = corners();
    // The innermost square's radius enters the bound as is: keep it well below the
    // cell's size.
    let size = (corners[2] - corners[0])
        .length()
        .max((corners[3] - corners[1]).length());
    let cover = cover(surface, b, 1e-4 * size);
    let parametric = if cover.corners.is_empty() {
        waldron_bound(&cover, b)
    } else {
        bilinear_bound(&cover, b, &corners)
    };
    match slab_bound(&cover, b, &corners) {
        Some(slab) => slab.min(parametric),
        None => parametric,
    }
}

/// `M / 4` with `M` bounding the second directional derivative over the box (cells
/// without an extraordinary vertex).
fn waldron_bound(cover: &Cover, b: [f64; 4]) -> f64 {
    let (cu, cv) = (b[1] - b[0], b[3] - b[2]);
    let (mut a, mut bb, mut c) = (0f64, 0f64, 0f64);
    for (net, i) in &cover.pieces {
        let (fu, fv) = ((i[1] - i[0]) / cu, (i[3] - i[2]) / cv);
        let (pa, pb, pc) = bicubic::second_derivatives(net);
        a = a.max(pa / (fu * fu));
        bb = bb.max(pb / (fv * fv));
        c = c.max(pc / (fu * fv));
    }
    0.25 * bicubic::hessian_bound((a, bb, c))
}

/// `D + D_side + |twist| / 4` against the bilinear quad through the corners (cells at
/// an extraordinary vertex).
fn bilinear_bound(cover: &Cover, b: [f64; 4], corners: &[DVec3; 4]) -> f64 {
    let (cu, cv) = (b[1] - b[0], b[3] - b[2]);
    // B in the box's unit coordinates.
    let bil = |u: f64, v: f64| bicubic::bilinear(corners, (u - b[0]) / cu, (v - b[2]) / cv);
    let (mut d, mut d_side) = (0f64, 0f64);
    for (net, i) in &cover.pieces {
        for jj in 0..4 {
            for ii in 0..4 {
                let u = i[0] + (i[1] - i[0]) * ii as f64 / 3.0;
                let v = i[2] + (i[3] - i[2]) * jj as f64 / 3.0;
                let e = (net[4 * jj + ii] - bil(u, v)).length();
                d = d.max(e);
                let on_side = (ii == 0 && i[0] == b[0])
                    || (ii == 3 && i[1] == b[1])
                    || (jj == 0 && i[2] == b[2])
                    || (jj == 3 && i[3] == b[3]);
                if on_side {
                    d_side = d_side.max(e);
                }
            }
        }
    }
    for (limit, hull, i) in &cover.corners {
        let e = hull
            + [(i[0], i[2]), (i[1], i[2]), (i[1], i[3]), (i[0], i[3])]
                .iter()
                .map(|&(u, v)| (*limit - bil(u, v)).length())
                .fold(0.0, f64::max);
        d = d.max(e);
        if i[0] == b[0] || i[1] == b[1] || i[2] == b[2] || i[3] == b[3] {
            d_side = d_side.max(e);
        }
    }
    let twist = corners[0] - corners[1] + corners[2] - corners[3];
    d + d_side + 0.25 * twist.length()
}

/// The slab bound (module docs): `sqrt(T² + δ²)`, `T` the thickness of the surface over
/// the box along the normal `n` of the corners' diagonals and `δ` the width of the band
/// around each side's chord, in the plane normal to `n`, that holds the side. `None`
/// where its conditions fail: a projected derivative pair of any piece not positively
/// oriented (the projection must keep orientation), or a side not monotone along its
/// chord.
fn slab_bound(cover: &Cover, b: [f64; 4], c: &[DVec3; 4]) -> Option<f64> {
    let n = (c[2] - c[0]).cross(c[3] - c[1]).try_normalize()?;
    let (e1, e2) = n.any_orthonormal_pair();
    let proj = |p: DVec3| glam::DVec2::new(p.dot(e1), p.dot(e2));
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut hull = 0f64;
    for (limit, r, i) in &cover.corners {
        let at_corner = (i[0] == b[0] || i[1] == b[1]) && (i[2] == b[2] || i[3] == b[3]);
        if !at_corner {
            return None;
        }
        // The square is within `r` of its limit point, which is a polygon vertex (the
        // box corner there); `near` keeps the bound sound if it were not.
        let near = c
            .iter()
            .map(|q| (*q - *limit).length())
            .fold(f64::INFINITY, f64::min);
        hull = hull.max(r + near);
        lo = lo.min(n.dot(*limit) - r);
        hi = hi.max(n.dot(*limit) + r);
    }
    let sides = [(0usize, 1usize), (1, 2), (3, 2), (0, 3)];
    let mut dirs = [glam::DVec2::ZERO; 4];
    for (s, &(ca, cb)) in sides.iter().enumerate() {
        dirs[s] = proj(c[cb] - c[ca]).try_normalize()?;
    }
    let mut band = [(0f64, 0f64); 4];
    let mut scale = c.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    for (net, i) in &cover.pieces {
        for p in net {
            let h = n.dot(*p);
            lo = lo.min(h);
            hi = hi.max(h);
            scale = scale.max(p.abs().max_element());
        }
        for j in 0..4 {
            for k in 0..3 {
                let a = net[4 * j + k + 1] - net[4 * j + k];
                for jj in 0..3 {
                    for kk in 0..4 {
                        let bv = net[4 * (jj + 1) + kk] - net[4 * jj + kk];
                        if n.dot(a.cross(bv)) <= 0.0 {
                            return None;
                        }
                    }
                }
            }
        }
        for (s, &(ca, _)) in sides.iter().enumerate() {
            let on = match s {
                0 => i[2] == b[2],
                1 => i[1] == b[1],
                2 => i[3] == b[3],
                _ => i[0] == b[0],
            };
            if !on {
                continue;
            }
            let pts: [DVec3; 4] = std::array::from_fn(|t| match s {
                0 => net[t],
                1 => net[4 * t + 3],
                2 => net[12 + t],
                _ => net[4 * t],
            });
            let d = dirs[s];
            for t in 0..3 {
                if proj(pts[t + 1] - pts[t]).dot(d) <= 0.0 {
                    return None;
                }
            }
            for p in pts {
                let off = d.perp_dot(proj(p - c[ca]));
                band[s] = (band[s].0.min(off), band[s].1.max(off));
            }
        }
    }
    // Near the vertex a side is only known to lie within `hull` of it, unordered.
    let delta = band.iter().map(|(a, b)| b - a).fold(0.0, f64::max) + 4.0 * hull;
    let thick = hi - lo;
    // Rounding: the products above and the distances measured later, a few ulps each.
    let rounding = 64.0 * f64::EPSILON * scale;
    Some((thick * thick + delta * delta).sqrt().max(hull) + rounding)
}

/// The flatness bound of the box `[u0, u1] × [v0, v1]` of patch `p`: a guaranteed upper
/// bound on the distance between the surface and any triangulation of the box's
/// polygon (module docs).
pub fn flatness_bound(model: &SurfaceModel, p: usize, b: [f64; 4]) -> f64 {
    cell_bound(&model.patches[p], b, || {
        [(b[0], b[2]), (b[1], b[2]), (b[1], b[3]), (b[0], b[3])]
            .map(|(u, v)| model.eval(p, u, v).position)
    })
}

/// Recursive marking of one cell; `leaf` receives each leaf and its bound.
fn mark(
    eval: &mut Evaluator,
    p: usize,
    cell: Cell,
    splits_left: u32,
    tolerance: f64,
    leaf: &mut dyn FnMut(Cell, f64),
) {
    let n = eval.n as f64;
    let surface = &eval.model.patches[p];
    let b = [
        cell.i as f64 / n,
        (cell.i + cell.w) as f64 / n,
        cell.j as f64 / n,
        (cell.j + cell.h) as f64 / n,
    ];
    let bound = cell_bound(surface, b, || {
        cell.corners().map(|(a, c)| eval.get(p, a, c).position)
    });
    if bound <= tolerance || splits_left == 0 {
        leaf(cell, bound);
        return;
    }
    let (w, h) = (cell.w / 2, cell.h / 2);
    for (di, dj) in QUADRANT {
        let child = Cell {
            i: cell.i + di as u32 * w,
            j: cell.j + dj as u32 * h,
            w,
            h,
        };
        mark(eval, p, child, splits_left - 1, tolerance, leaf);
    }
}

/// Adaptive tessellation of every (non-hole) patch to within `params.tolerance`.
pub fn tessellate_adaptive(model: &SurfaceModel, params: &CcParams) -> Result<CcTessellation> {
    params.validate(model)?;
    let n = BASE_GRID << params.max_depth;
    let mut eval = Evaluator {
        model,
        n,
        points: HashMap::new(),
    };
    let mesh = &model.mesh;
    let mut out = CcTessellation::default();
    let mut leaves: Vec<(usize, Cell)> = Vec::new();

    // 1. Adaptive marking. The first split ku×kv is the one with the fewest leaves.
    for p in mesh.surface_patches() {
        let base_cells = |(ku, kv): (u32, u32)| {
            let (w, h) = (n / ku, n / kv);
            (0..ku * kv).map(move |c| Cell {
                i: (c % ku) * w,
                j: (c / ku) * h,
                w,
                h,
            })
        };
        // Square splits first, then rectangles that could still beat the best so far
        // (a split into ku·kv cells has at least that many leaves).
        let mut best = (usize::MAX, (1, 1));
        let squares = (1..=MAX_BASE_SPLIT).map(|k| (k, k));
        let rectangles = (1..=MAX_BASE_SPLIT)
            .flat_map(|ku| (1..=MAX_BASE_SPLIT).map(move |kv| (ku, kv)))
            .filter(|(ku, kv)| ku != kv);
        for split in squares.chain(rectangles) {
            if (split.0 * split.1) as usize >= best.0 {
                continue;
            }
            let mut count = 0usize;
            for cell in base_cells(split) {
                mark(
                    &mut eval,
                    p,
                    cell,
                    params.max_depth,
                    params.tolerance,
                    &mut |_, _| count += 1,
                );
                if count >= best.0 {
                    break;
                }
            }
            if count < best.0 {
                best = (count, split);
            }
        }
        for cell in base_cells(best.1) {
            mark(
                &mut eval,
                p,
                cell,
                params.max_depth,
                params.tolerance,
                &mut |c, bound| {
                    if bound > params.tolerance {
                        out.unmet += 1;
                    }
                    out.max_bound = out.max_bound.max(bound);
                    leaves.push((p, c));
                },
            );
        }
    }
    out.leaves = leaves.len();

    // 2. Base-quadrilateral replacement: the marked points on every line, in order.
    let mut lines = Lines::default();
    for &(p, cell) in &leaves {
        for (a, b) in cell.corners() {
            lines.add(point_key(mesh, p, a, b, n));
        }
    }
    lines.sort();
    let polygons: Vec<Vec<(u32, u32)>> = leaves
        .iter()
        .map(|&(p, cell)| {
            let c = cell.corners();
            let mut poly = Vec::with_capacity(4);
            for k in 0..4 {
                poly.push(c[k]);
                lines.between(mesh, p, c[k], c[(k + 1) % 4], n, &mut poly);
            }
            poly
        })
        .collect();

    // Every polygon vertex evaluated once; ids in the order of the canonical keys, so
    // the numbering does not depend on the order of work.
    let mut used: Vec<u64> = Vec::new();
    for (&(p, _), poly) in leaves.iter().zip(&polygons) {
        for &(a, b) in poly {
            eval.get(p, a, b);
            used.push(point_key(mesh, p, a, b, n));
        }
    }
    out.evaluations = eval.points.len() as u64;
    used.sort_unstable();
    used.dedup();
    let id_of: HashMap<u64, u32> = used
        .iter()
        .enumerate()
        .map(|(k, &key)| (key, k as u32))
        .collect();
    out.mesh.vertices = used
        .iter()
        .map(|key| {
            let (sp, p, i, j) = eval.points[key];
            out_vertex(sp, p, i as f64 / n as f64, j as f64 / n as f64)
        })
        .collect();

    // 3. Triangulation.
    let vertices = &out.mesh.vertices;
    let position = |id: u32| DVec3::from(vertices[id as usize].position.map(f64::from));
    let mut indices = Vec::new();
    for (&(p, _), poly) in leaves.iter().zip(&polygons) {
        let poly = poly
            .iter()
            .map(|&(a, b)| PolyVertex {
                i: a as i64,
                j: b as i64,
                id: id_of[&point_key(mesh, p, a, b, n)],
            })
            .collect();
        triangulate(poly, position, &mut indices);
    }
    out.mesh.indices = indices;
    Ok(out)
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
        let start = ts.partition_point(|&t| t <= lo);
        let end = ts.partition_point(|&t| t < hi);
        let inside = &ts[start..end];
        let to_point = |t: u32| -> (u32, u32) {
            // Linear between a and b.
            let f = |x: u32, y: u32| -> u32 {
                let (x, y, t, ta, tb) = (x as i64, y as i64, t as i64, ta as i64, tb as i64);
                (x + (y - x) * (t - ta) / (tb - ta)) as u32
            };
            (f(a.0, b.0), f(a.1, b.1))
        };
        if ta < tb {
            out.extend(inside.iter().map(|&t| to_point(t)));
        } else {
            out.extend(inside.iter().rev().map(|&t| to_point(t)));
        }
    }
}

/// The output vertex of a surface point.
pub fn out_vertex(sp: SurfacePoint, patch: usize, u: f64, v: f64) -> OutVertex {
    OutVertex {
        position: sp.position.as_vec3().to_array(),
        normal: sp.normal.as_vec3().to_array(),
        uv: [u as f32, v as f32],
        patch: patch as u32,
    }
}
