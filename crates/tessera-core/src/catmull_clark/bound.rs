//! The flatness bound: a guaranteed upper bound on the distance between the surface
//! over a box of a patch and ANY triangulation of the box's polygon (its corners plus
//! whatever points finer neighbours put on its sides). The adaptive tessellator splits
//! a cell until this is at most ε. It is the smaller of two bounds.
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
//! sides, from the control points of the Bézier pieces, and for the innermost square the
//! convex-hull radius of its one-ring plus the distance from the limit point to `B` (the
//! paper's `m_ε` argument: that square shrinks to the vertex).
//! That second form holds on any cell (it needs no derivatives); on patches shaped by a
//! crease or corner it is taken wherever it is the smaller, since a semi-sharp crease is
//! a band of curvature as high as the sharpness is large but only as wide as it decays,
//! which bends the surface little in distance.
//!
//! **Slab (geometric).** A parametric bound also counts how unevenly the parameter runs
//! over the surface, which costs nothing in distance: near an extraordinary vertex it can
//! be far above the true distance, and even on regular cells it splits cells that are
//! already flat enough. The slab bound measures distance only. Take the unit normal `n` of
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
//! is `max(sqrt(T² + δ²), h)`. It fails (and the parametric bound is used alone) only
//! where the projection folds or a side doubles back.
//!
//! # How it reads the surface (the same way as the GPU)
//!
//! The box is given in **walk units**, `1 / (105 · 2^21)` of the patch side, in which every
//! node of the stored quadtree down to level 21 and every cell of the adaptive grid has
//! integer corners. The quadtree is walked from the root: a node partly inside the box is
//! clipped (de Casteljau) or, if split, its children visited; a node wholly inside is
//! taken as is, and its descendants (the chain of squares at an extraordinary vertex,
//! [`CORNER_DEPTH`](super::CORNER_DEPTH) levels deep) inherit from it which sides of the
//! box they lie on. Down the chain, a square 64 times smaller than the box whose ball
//! (around the vertex, holding the surface over it) is below 1e-4 of the cell ends the
//! walk there, as that ball. Each piece is fed to a [`PieceSink`]: here [`BoundSum`], which
//! keeps every running maximum the two bounds need (the distance bound to known
//! triangles of [`super::triangle_bound`] walks the same way). Points are taken relative to the box's first corner, so that
//! single precision keeps the shape of small cells.
//!
//! This is the CPU twin of `shaders/shared/cc_bound.wgsl`, in double precision. Both add
//! the same allowance for single-precision rounding (`ROUNDING` below), so the GPU and
//! the CPU reach the same decisions except on bounds within ~1e-6 of the tolerance.

use glam::{DVec2, DVec3};

use super::bicubic::{self, Net};
use super::patch::{Node, PatchSurface};

/// The walk's unit: `WALK_ONE` units span the patch side.
pub const WALK_ONE: u32 = 105 << 21;
/// The walk's stack: the split nodes on the path from the root to the node visited.
/// Stored trees split to level 30 at most (the chains at extraordinary vertices), so
/// the path holds at most 31; running out makes the bound infinite (sound: the cell is
/// split).
pub const WALK_STACK: usize = 32;

/// Side bits of a piece: on the box's bottom (`v = v0`), right, top and left side.
pub const SIDE_BOTTOM: u32 = 1;
/// Side bit: on the box's right side (`u = u1`).
pub const SIDE_RIGHT: u32 = 2;
/// Side bit: on the box's top side (`v = v1`).
pub const SIDE_TOP: u32 = 4;
/// Side bit: on the box's left side (`u = u0`).
pub const SIDE_LEFT: u32 = 8;
/// The sides a quadrant of a node shares with the node, in quadrant order.
const QUADRANT_SIDES: [u32; 4] = [
    SIDE_BOTTOM | SIDE_LEFT,
    SIDE_BOTTOM | SIDE_RIGHT,
    SIDE_RIGHT | SIDE_TOP,
    SIDE_TOP | SIDE_LEFT,
];

/// Allowance for rounding in single precision, per unit of the largest relative and
/// absolute coordinate.
const ROUNDING_RELATIVE: f64 = 64.0 * f32::EPSILON as f64;
const ROUNDING_ABSOLUTE: f64 = 8.0 * f32::EPSILON as f64;

/// An orthonormal pair `(e1, e2)` spanning the plane normal to the unit vector `n`, with
/// `e1 × e2 = n` (the formula of Duff et al. 2017; the kernel computes the same).
pub fn orthonormal_pair(n: DVec3) -> (DVec3, DVec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// The running maxima of both bounds over the pieces of a box.
pub struct BoundSum {
    /// Box corners relative to the first, counter-clockwise from `(u0, v0)`.
    corners: [DVec3; 4],
    scale_rel: f64,
    scale_abs: f64,
    // Parametric: second-derivative bounds (cells without a vertex), deviation from
    // the bilinear quad over the box and along its sides (cells with one).
    second: (f64, f64, f64),
    dev: f64,
    dev_side: f64,
    has_vertex: bool,
    /// Whether the box may reach a vertex, so that `dev` is needed (never on a patch
    /// without one, whose cells then skip the 16 deviations per piece).
    track_dev: bool,
    /// Whether the deviation form of the parametric bound is taken wherever it is
    /// smaller, not only at a vertex: on creased patches, whose narrow bands of high
    /// curvature along semi-sharp creases bend little in distance.
    dev_everywhere: bool,
    // Slab.
    slab: bool,
    normal: DVec3,
    plane: (DVec3, DVec3),
    chords: [DVec2; 4],
    lo: f64,
    hi: f64,
    hull: f64,
    band: [(f64, f64); 4],
}

/// Side `s` of the box runs from corner `SIDES[s].0` to corner `SIDES[s].1`.
const SIDES: [(usize, usize); 4] = [(0, 1), (1, 2), (3, 2), (0, 3)];

impl BoundSum {
    /// Starts a box with these corner positions (absolute).
    pub fn new(corners: [DVec3; 4]) -> Self {
        let scale_abs = corners
            .iter()
            .map(|p| p.abs().max_element())
            .fold(0.0, f64::max);
        let c = corners.map(|p| p - corners[0]);
        let scale_rel = c.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        let cross = (c[2] - c[0]).cross(c[3] - c[1]);
        let len = cross.length();
        let mut slab = len > 0.0;
        let normal = if slab { cross / len } else { DVec3::Z };
        let plane = orthonormal_pair(normal);
        let mut chords = [DVec2::ZERO; 4];
        for (s, &(a, b)) in SIDES.iter().enumerate() {
            let d = project(plane, c[b] - c[a]);
            let l = d.length();
            if l > 0.0 {
                chords[s] = d / l;
            } else {
                slab = false;
            }
        }
        BoundSum {
            corners: c,
            scale_rel,
            scale_abs,
            second: (0.0, 0.0, 0.0),
            dev: 0.0,
            dev_side: 0.0,
            has_vertex: false,
            track_dev: true,
            dev_everywhere: false,
            slab,
            normal,
            plane,
            chords,
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            hull: 0.0,
            band: [(0.0, 0.0); 4],
        }
    }

    /// The bilinear quad through the corners at box coordinates `(u, v) ∈ [0, 1]²`.
    fn bilinear(&self, u: f64, v: f64) -> DVec3 {
        bicubic::bilinear(&self.corners, u, v)
    }

    /// A Bézier piece over `rect = [u0, u1, v0, v1]` in box coordinates, lying on the box
    /// sides `sides`: its net is `shape + offset` relative to the first corner. Whatever
    /// depends on differences of control points reads `shape` alone, which keeps the
    /// tiny pieces at a vertex exact in single precision.
    pub fn piece(&mut self, shape: &Net, offset: DVec3, rect: [f64; 4], sides: u32) {
        let net = shape.map(|p| p + offset);
        for p in &net {
            self.scale_rel = self.scale_rel.max(p.abs().max_element());
        }
        let (fu, fv) = (rect[1] - rect[0], rect[3] - rect[2]);
        let (a, b, c) = bicubic::second_derivatives(shape);
        self.second.0 = self.second.0.max(a / (fu * fu));
        self.second.1 = self.second.1.max(b / (fv * fv));
        self.second.2 = self.second.2.max(c / (fu * fv));
        if self.track_dev {
            for j in 0..4 {
                for i in 0..4 {
                    let u = rect[0] + fu * i as f64 / 3.0;
                    let v = rect[2] + fv * j as f64 / 3.0;
                    let e = (net[4 * j + i] - self.bilinear(u, v)).length();
                    self.dev = self.dev.max(e);
                    let on_side = (i == 0 && sides & SIDE_LEFT != 0)
                        || (i == 3 && sides & SIDE_RIGHT != 0)
                        || (j == 0 && sides & SIDE_BOTTOM != 0)
                        || (j == 3 && sides & SIDE_TOP != 0);
                    if on_side {
                        self.dev_side = self.dev_side.max(e);
                    }
                }
            }
        }
        if self.slab {
            self.slab = self.slab_piece(shape, &net, sides);
        }
    }

    /// The slab part of a piece; false where its conditions fail. (The kernel runs every
    /// pass to the end instead of returning early: a failing piece turns the slab bound
    /// off for good, so the sums it still adds are never read.)
    fn slab_piece(&mut self, shape: &Net, net: &Net, sides: u32) -> bool {
        // The heights of the net split at u = v = 1/2: the four halves' control points
        // hold the surface more tightly than the net's. A height is linear in the
        // point, so the heights split as the points would.
        let (lo, hi) = halved_grid_range(std::array::from_fn(|k| self.normal.dot(net[k])));
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        // n · (a × b) > 0 for every u-step a and v-step b: with (e1, e2, n) right-handed
        // that is the perp-dot of their projections, which is cheaper.
        let mut du = [DVec2::ZERO; 12];
        let mut dv = [DVec2::ZERO; 12];
        for j in 0..4 {
            for k in 0..3 {
                du[3 * j + k] = project(self.plane, shape[4 * j + k + 1] - shape[4 * j + k]);
                dv[4 * k + j] = project(self.plane, shape[4 * (k + 1) + j] - shape[4 * k + j]);
            }
        }
        if !orientation_kept(&du, &dv) {
            return false;
        }
        for (s, &(start_corner, _)) in SIDES.iter().enumerate() {
            if sides & (1 << s) == 0 {
                continue;
            }
            let side = |n: &Net| -> [DVec3; 4] {
                std::array::from_fn(|t| match s {
                    0 => n[t],
                    1 => n[4 * t + 3],
                    2 => n[12 + t],
                    _ => n[4 * t],
                })
            };
            let (steps, pts) = (side(shape), side(net));
            let d = self.chords[s];
            for t in 0..3 {
                if project(self.plane, steps[t + 1] - steps[t]).dot(d) <= 0.0 {
                    return false;
                }
            }
            let start = self.corners[start_corner];
            // The side's offsets from its chord, split at its middle likewise.
            let (lo, hi) = halved_range(pts.map(|p| d.perp_dot(project(self.plane, p - start))));
            self.band[s] = (self.band[s].0.min(lo), self.band[s].1.max(hi));
        }
        true
    }

    /// The innermost square at an extraordinary vertex: its limit point (relative to the
    /// first corner) and hull radius, over `rect` on the box sides `sides`.
    pub fn vertex(&mut self, limit: DVec3, radius: f64, rect: [f64; 4], sides: u32) {
        self.has_vertex = true;
        self.scale_rel = self.scale_rel.max(limit.abs().max_element());
        let mut e = 0f64;
        for (u, v) in [
            (rect[0], rect[2]),
            (rect[1], rect[2]),
            (rect[1], rect[3]),
            (rect[0], rect[3]),
        ] {
            e = e.max((limit - self.bilinear(u, v)).length());
        }
        self.dev = self.dev.max(radius + e);
        if sides != 0 {
            self.dev_side = self.dev_side.max(radius + e);
        }
        let at_corner =
            sides & (SIDE_LEFT | SIDE_RIGHT) != 0 && sides & (SIDE_BOTTOM | SIDE_TOP) != 0;
        if !at_corner {
            self.slab = false;
        }
        // The square is within `radius` of its limit point, which is a polygon vertex
        // (the box corner there); `near` keeps the bound sound if it were not.
        let near = self
            .corners
            .iter()
            .map(|q| (*q - limit).length())
            .fold(f64::INFINITY, f64::min);
        self.hull = self.hull.max(radius + near);
        let h = self.normal.dot(limit);
        self.lo = self.lo.min(h - radius);
        self.hi = self.hi.max(h + radius);
    }

    /// The bound: the smaller of the parametric and (where it holds) the slab bound, plus
    /// the rounding allowance.
    pub fn finish(&self) -> f64 {
        let c = &self.corners;
        let deviation = || {
            let twist = c[0] - c[1] + c[2] - c[3];
            self.dev + self.dev_side + 0.25 * twist.length()
        };
        let parametric = if self.has_vertex {
            deviation()
        } else if self.dev_everywhere && self.track_dev {
            deviation().min(0.25 * bicubic::hessian_bound(self.second))
        } else {
            0.25 * bicubic::hessian_bound(self.second)
        };
        let mut bound = parametric;
        if self.slab {
            let width = self.band.iter().map(|(a, b)| b - a).fold(0.0, f64::max);
            // Near the vertex a side is only known to lie within `hull` of it.
            let delta = width + 4.0 * self.hull;
            let thick = self.hi - self.lo;
            bound = bound.min((thick * thick + delta * delta).sqrt().max(self.hull));
        }
        bound + ROUNDING_RELATIVE * self.scale_rel + ROUNDING_ABSOLUTE * self.scale_abs
    }
}

/// A lower bound on the flatness bound of a box ([`box_bound`]) from surface points
/// the box's children need anyway: its corners `c`, its centre and the midpoints of its
/// sides (side `k` from corner `k` to corner `k + 1`). Where it is above ε the box must
/// be split, and the walk is skipped: the same decision for a fraction of the cost.
/// Both parts of the bound are at least their part here:
/// - Parametric. Along a side, `S` at the midpoint is within `M / 8` of the mean of the
///   side's ends (`|g''| / 8` for `g` the side, `M` bounding second directional
///   derivatives in the box's unit coordinates); at the centre within `M / 4` of the
///   corners' mean (the mean of the same along both diagonals, where `|g''| ≤ 2M`). So
///   `M / 4` is at least twice the first and once the second. At a vertex the bound
///   holds `D + D_side`, which bound `|S − B|` over the box and along its sides (`B` the
///   bilinear quad, which is the corners' mean at the centre and the ends' mean at a
///   side's midpoint).
/// - Slab. Every surface point of the box lies between the heights `lo` and `hi` along
///   the same normal, so `sqrt(T² + δ²) ≥ T ≥` the spread of the nine points' heights.
///
/// The allowance for rounding is subtracted, as the bound adds it; the kernel
/// (`cc_split_proof` in `shaders/shared/cc_bound.wgsl`) computes the same in single
/// precision.
pub fn split_proof(corners: [DVec3; 4], centre: DVec3, mids: [DVec3; 4]) -> f64 {
    let c = corners.map(|p| p - corners[0]);
    let s = centre - corners[0];
    let m = mids.map(|p| p - corners[0]);
    let points = || corners.iter().chain([&centre]).chain(&mids);
    let scale_abs = points().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    let scale_rel = points()
        .map(|p| (*p - corners[0]).abs().max_element())
        .fold(0.0, f64::max);
    let mut parametric = (s - 0.25 * (c[0] + c[1] + c[2] + c[3])).length();
    for k in 0..4 {
        let side = m[k] - 0.5 * (c[k] + c[(k + 1) % 4]);
        parametric = parametric.max(2.0 * side.length());
    }
    let cross = (c[2] - c[0]).cross(c[3] - c[1]);
    let len = cross.length();
    // Without a normal the slab bound is off and the parametric bound is the bound.
    let mut proof = parametric;
    if len > 0.0 {
        let n = cross / len;
        let (mut lo, mut hi) = (0f64, 0f64);
        for p in [c[1], c[2], c[3], s, m[0], m[1], m[2], m[3]] {
            lo = lo.min(n.dot(p));
            hi = hi.max(n.dot(p));
        }
        proof = proof.min(hi - lo);
    }
    proof - ROUNDING_RELATIVE * scale_rel - ROUNDING_ABSOLUTE * scale_abs
}

/// The range of the seven control values of a cubic (control values `a`) split at its
/// middle by de Casteljau: it holds the cubic's values, more tightly than `a` does.
pub fn halved_range(a: [f64; 4]) -> (f64, f64) {
    let b01 = 0.5 * (a[0] + a[1]);
    let b12 = 0.5 * (a[1] + a[2]);
    let b23 = 0.5 * (a[2] + a[3]);
    let c0 = 0.5 * (b01 + b12);
    let c1 = 0.5 * (b12 + b23);
    let m = 0.5 * (c0 + c1);
    let all = [a[0], b01, c0, m, c1, b23, a[3]];
    let lo = all.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = all.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (lo, hi)
}

/// The range of the 7 × 7 control values of a bicubic (control values `h`, row-major in
/// v) split at u = 1/2 and v = 1/2: the columns are split along u as vectors, then each
/// of the seven along v ([`halved_range`]).
pub fn halved_grid_range(h: [f64; 16]) -> (f64, f64) {
    let col = |i: usize| [h[i], h[4 + i], h[8 + i], h[12 + i]];
    let (c0, c1, c2, c3) = (col(0), col(1), col(2), col(3));
    let mid =
        |a: [f64; 4], b: [f64; 4]| -> [f64; 4] { std::array::from_fn(|j| 0.5 * (a[j] + b[j])) };
    let (b01, b12, b23) = (mid(c0, c1), mid(c1, c2), mid(c2, c3));
    let (d0, d1) = (mid(b01, b12), mid(b12, b23));
    let m = mid(d0, d1);
    [c0, b01, d0, m, d1, b23, c3]
        .into_iter()
        .map(halved_range)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        })
}

/// Whether `a.perp_dot(b) > 0` for every `a` of `du` and `b` of `dv`, in linear time.
/// All `a` must lie left of `dv[0]`: in that open half-plane turning counter-clockwise
/// is a total order, and a scan finds the first and the last `a`. A `b` is left of every
/// `a` exactly when it is left of both: the directions left of `a` are the half-turn
/// after it, and those half-turns meet in the range from the last `a` to the first `a`
/// plus a half-turn.
pub fn orientation_kept(du: &[DVec2], dv: &[DVec2]) -> bool {
    let (mut first, mut last) = (du[0], du[0]);
    for &a in du {
        if a.perp_dot(dv[0]) <= 0.0 {
            return false;
        }
        if a.perp_dot(first) > 0.0 {
            first = a;
        }
        if last.perp_dot(a) > 0.0 {
            last = a;
        }
    }
    dv.iter()
        .all(|b| first.perp_dot(*b) > 0.0 && last.perp_dot(*b) > 0.0)
}

/// The running maxima of the face bound ([`face_bound`]) over the pieces of a quad
/// control face's four patches.
struct FaceDeviation {
    /// The face's corners relative to the first: the limit points of its vertices.
    corners: [DVec3; 4],
    /// Patch `k` of the face: its first corner relative to the face's.
    shift: DVec3,
    k: usize,
    scale_rel: f64,
    dev: f64,
    dev_side: f64,
}

/// The patch sides on the face's boundary: a patch of a quad face runs from the face's
/// vertex (its corner 0) along `v = 0` and `u = 0`; its other two sides are inside.
const FACE_SIDES: u32 = SIDE_BOTTOM | SIDE_LEFT;

impl FaceDeviation {
    /// The bilinear quad through the face's corners at the point `(u, v)` of its patch
    /// `k` ([`super::topology::PatchMesh::face_point_at`]: patch `k` covers the quarter at
    /// vertex `k`, rotated).
    fn bilinear(&self, u: f64, v: f64) -> DVec3 {
        let (s, t) = match self.k {
            0 => (u, v),
            1 => (2.0 - v, u),
            2 => (2.0 - u, 2.0 - v),
            _ => (v, 2.0 - u),
        };
        bicubic::bilinear(&self.corners, 0.5 * s, 0.5 * t)
    }
}

impl PieceSink for FaceDeviation {
    fn piece(&mut self, shape: &Net, offset: DVec3, rect: [f64; 4], sides: u32) {
        let (fu, fv) = (rect[1] - rect[0], rect[3] - rect[2]);
        // B restricted to the piece is bilinear, so degree-raised to bicubic its control
        // points are its values on the piece's 4 × 4 grid: `S − B` is the Bézier patch
        // of these differences, within their hull; split at u = v = ½, within the
        // tighter hulls of its four quarters.
        let diff: [DVec3; 16] = std::array::from_fn(|k| {
            let (i, j) = (k % 4, k / 4);
            let p = shape[k] + offset + self.shift;
            self.scale_rel = self.scale_rel.max(p.abs().max_element());
            let u = rect[0] + fu * i as f64 / 3.0;
            let v = rect[2] + fv * j as f64 / 3.0;
            p - self.bilinear(u, v)
        });
        let halves = halved_grid(diff);
        for j in 0..7 {
            for i in 0..7 {
                let e = halves[7 * j + i].length();
                self.dev = self.dev.max(e);
                let on_side =
                    (i == 0 && sides & SIDE_LEFT != 0) || (j == 0 && sides & SIDE_BOTTOM != 0);
                if on_side {
                    self.dev_side = self.dev_side.max(e);
                }
            }
        }
    }

    fn vertex(&mut self, limit: DVec3, radius: f64, rect: [f64; 4], sides: u32) {
        let limit = limit + self.shift;
        self.scale_rel = self.scale_rel.max(limit.abs().max_element());
        // The square lies within `radius` of its limit point, and `B` over it within the
        // largest distance of its corners' values (B is bilinear) from that point.
        let e = [(0, 2), (1, 2), (1, 3), (0, 3)]
            .map(|(a, b)| (limit - self.bilinear(rect[a], rect[b])).length())
            .into_iter()
            .fold(0.0, f64::max);
        self.dev = self.dev.max(radius + e);
        if sides & FACE_SIDES != 0 {
            self.dev_side = self.dev_side.max(radius + e);
        }
    }
}

/// The control points of a bicubic's four quarters split at `u = v = ½`, on one 7 × 7
/// grid (row-major, the quarters sharing their middle row and column).
fn halved_grid(d: [DVec3; 16]) -> [DVec3; 49] {
    let split = |a: [DVec3; 4]| -> [DVec3; 7] {
        let b = [
            0.5 * (a[0] + a[1]),
            0.5 * (a[1] + a[2]),
            0.5 * (a[2] + a[3]),
        ];
        let c = [0.5 * (b[0] + b[1]), 0.5 * (b[1] + b[2])];
        let m = 0.5 * (c[0] + c[1]);
        [a[0], b[0], c[0], m, c[1], b[2], a[3]]
    };
    let rows: [[DVec3; 7]; 4] =
        std::array::from_fn(|j| split(std::array::from_fn(|i| d[4 * j + i])));
    let mut out = [DVec3::ZERO; 49];
    for i in 0..7 {
        let column = split(std::array::from_fn(|j| rows[j][i]));
        for (j, p) in column.into_iter().enumerate() {
            out[7 * j + i] = p;
        }
    }
    out
}

/// The flatness bound of a quad control face taken whole, as one cell: a guaranteed
/// upper bound on the distance from the surface over the face (its four patches) to any
/// triangulation of the polygon through the limit points of its four vertices and
/// whatever surface points neighbours put on its sides. `None` where the walk ran out of
/// stack.
///
/// With `B` the bilinear quad through the four corners over the face's `(s, t)`, `L` the
/// piecewise-linear interpolant on the polygon's triangles laid out over the face's
/// square (its side points at their own parameters) and `x = S(s, t)`:
/// `|S − L S| ≤ |S − B| + |B − L B| + |L (B − S)| ≤ D + |twist|/4 + D_side`, the
/// deviation form of a cell's bound ([`BoundSum`]), now over pieces of four patches:
/// `D` bounds `|S − B|` over the face and `D_side` along its boundary (control points of
/// every piece of each patch against `B` degree-raised there, split at its middle; the
/// innermost square at a vertex as its ball), `|twist|/4` bounds a bilinear function's distance from its
/// interpolant on any triangle of the unit square (Waldron's `M R²/2`, `M = |twist|`,
/// `R² ≤ ½`), and `L (B − S)` is at most its largest value at a vertex, `0` at the corners
/// and at most `D_side` on the sides. The surface is within `D` of the corners' hull, and
/// so are the triangles, as the view's tolerance needs ([`crate::view`]).
pub fn face_bound(surfaces: [&PatchSurface; 4], corners: [DVec3; 4]) -> Option<f64> {
    let c = corners.map(|p| p - corners[0]);
    let scale_abs = corners
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f64::max);
    let mut sum = FaceDeviation {
        corners: c,
        shift: DVec3::ZERO,
        k: 0,
        scale_rel: c.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max),
        dev: 0.0,
        dev_side: 0.0,
    };
    for (k, surface) in surfaces.into_iter().enumerate() {
        let own = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .map(|(u, v)| surface.eval(u, v).position);
        sum.k = k;
        sum.shift = own[0] - corners[0];
        if !walk_pieces(surface, [0, WALK_ONE, 0, WALK_ONE], own, &mut sum) {
            return None;
        }
    }
    let twist = c[0] - c[1] + c[2] - c[3];
    Some(
        sum.dev
            + sum.dev_side
            + 0.25 * twist.length()
            + ROUNDING_RELATIVE * sum.scale_rel
            + ROUNDING_ABSOLUTE * scale_abs,
    )
}

fn project(plane: (DVec3, DVec3), p: DVec3) -> DVec2 {
    DVec2::new(p.dot(plane.0), p.dot(plane.1))
}

/// A node to visit: either at integer walk coordinates `(x, y, size)` and not yet known
/// to be inside the box, or inside it with its box rectangle and sides.
#[derive(Clone, Copy)]
struct WalkEntry {
    node: u32,
    level: u32,
    x: u32,
    y: u32,
    size: u32,
    inside: bool,
    rect: [f64; 4],
    sides: u32,
}

/// A split node on the path: itself (placed), whether the box cuts it (its children are
/// then placed by walk coordinates), and its children still to visit (bit `c`).
struct WalkFrame {
    entry: WalkEntry,
    cut: bool,
    children: [u32; 4],
    todo: u32,
}

/// What a walk over the pieces of a box feeds: every Bézier piece inside it, and the
/// innermost square at a vertex as a ball.
pub trait PieceSink {
    /// A Bézier piece over `rect` (box coordinates) on the box sides `sides`, its net
    /// `shape + offset` relative to the box's first corner.
    fn piece(&mut self, shape: &Net, offset: DVec3, rect: [f64; 4], sides: u32);
    /// The innermost square at a vertex: within `radius` of `limit` (relative to the
    /// box's first corner).
    fn vertex(&mut self, limit: DVec3, radius: f64, rect: [f64; 4], sides: u32);
}

impl PieceSink for BoundSum {
    fn piece(&mut self, shape: &Net, offset: DVec3, rect: [f64; 4], sides: u32) {
        BoundSum::piece(self, shape, offset, rect, sides)
    }
    fn vertex(&mut self, limit: DVec3, radius: f64, rect: [f64; 4], sides: u32) {
        BoundSum::vertex(self, limit, radius, rect, sides)
    }
}

/// The flatness bound of the box `bx = [u0, u1, v0, v1]` (walk units) of a patch whose
/// corner positions are `corners`.
///
/// The walk visits one node per step of one loop, and the kernel reads the same: on a
/// SIMD device that masks rather than branches, each place the loop body sums a piece
/// costs a piece on every step, whatever the node.
pub fn box_bound(surface: &PatchSurface, bx: [u32; 4], corners: [DVec3; 4]) -> f64 {
    let mut sum = BoundSum {
        // A patch without a vertex is one Bézier piece.
        track_dev: !matches!(surface.nodes[0], Node::Bezier(_)),
        dev_everywhere: surface.creased,
        ..BoundSum::new(corners)
    };
    if walk_pieces(surface, bx, corners, &mut sum) {
        sum.finish()
    } else {
        f64::INFINITY
    }
}

/// Feeds every piece of the box `bx` (walk units) to `sink`, relative to `corners[0]`;
/// false where the walk ran out of stack (then nothing can be concluded).
pub fn walk_pieces<S: PieceSink>(
    surface: &PatchSurface,
    bx: [u32; 4],
    corners: [DVec3; 4],
    sink: &mut S,
) -> bool {
    // The ball at a vertex enters as is: stop at a node 64 times smaller than the box
    // whose ball is below 1e-4 of the cell.
    let size = (corners[2] - corners[0])
        .length()
        .max((corners[3] - corners[1]).length());
    let mut walk = Walk {
        surface,
        bx,
        max_ball: 1e-4 * size,
        origin: corners[0],
        sum: sink,
        stack: Vec::with_capacity(WALK_STACK),
        overflow: false,
    };
    let mut e = WalkEntry {
        node: 0,
        level: 0,
        x: 0,
        y: 0,
        size: WALK_ONE,
        inside: false,
        rect: [0.0; 4],
        sides: 0,
    };
    loop {
        walk.visit(e);
        // The next node: the next child of the innermost split node with one left.
        while walk.stack.last().is_some_and(|f| f.todo == 0) {
            walk.stack.pop();
        }
        if walk.overflow {
            return false;
        }
        let Some(top) = walk.stack.last_mut() else {
            break;
        };
        let c = top.todo.trailing_zeros() as usize;
        top.todo &= top.todo - 1;
        e = walk.child(c);
    }
    true
}

struct Walk<'a, S> {
    surface: &'a PatchSurface,
    bx: [u32; 4],
    max_ball: f64,
    origin: DVec3,
    sum: &'a mut S,
    stack: Vec<WalkFrame>,
    overflow: bool,
}

impl<S: PieceSink> Walk<'_, S> {
    /// Visits a node: a piece is summed, a split node whose ball is small enough enters
    /// as its vertex, any other split node goes on the path.
    fn visit(&mut self, e: WalkEntry) {
        let Some((e, clip)) = self.place(e) else {
            return;
        };
        match &self.surface.nodes[e.node as usize] {
            Node::Split(children) => {
                if clip.is_none() && self.small(e.level) {
                    if let Some(ball) = self.surface.balls[e.node as usize] {
                        if ball.radius <= self.max_ball {
                            self.sum
                                .vertex(ball.limit - self.origin, ball.radius, e.rect, e.sides);
                            return;
                        }
                    }
                }
                self.push(e, clip.is_some(), *children);
            }
            Node::Bezier(net) => {
                // As the GPU stores it: the first point, and the others relative to it.
                let mut shape = net.map(|p| p - net[0]);
                if let Some((cu, cv)) = clip {
                    shape = bicubic::clip(&shape, cu, cv);
                }
                self.sum
                    .piece(&shape, net[0] - self.origin, e.rect, e.sides);
            }
            Node::Corner(c) => {
                self.sum
                    .vertex(c.limit - self.origin, c.hull_radius, e.rect, e.sides)
            }
        }
    }

    /// Where a node not yet known to be inside lies in the box: its rectangle and sides,
    /// and for a node the box cuts, the part inside in the node's own coordinates.
    /// `None` if it does not overlap the box.
    #[allow(clippy::type_complexity)]
    fn place(&self, mut e: WalkEntry) -> Option<(WalkEntry, Option<((f64, f64), (f64, f64))>)> {
        if e.inside {
            return Some((e, None));
        }
        if !self.overlaps(e.x, e.y, e.size) {
            return None;
        }
        let bx = self.bx;
        let ov = [
            bx[0].max(e.x),
            bx[1].min(e.x + e.size),
            bx[2].max(e.y),
            bx[3].min(e.y + e.size),
        ];
        let whole = ov == [e.x, e.x + e.size, e.y, e.y + e.size];
        let local = |a: u32, o: u32| (a - o) as f64 / e.size as f64;
        let clip = (!whole).then(|| {
            (
                (local(ov[0], e.x), local(ov[1], e.x)),
                (local(ov[2], e.y), local(ov[3], e.y)),
            )
        });
        let (bw, bh) = ((bx[1] - bx[0]) as f64, (bx[3] - bx[2]) as f64);
        e.rect = [
            (ov[0] - bx[0]) as f64 / bw,
            (ov[1] - bx[0]) as f64 / bw,
            (ov[2] - bx[2]) as f64 / bh,
            (ov[3] - bx[2]) as f64 / bh,
        ];
        let bit = |on: bool, side: u32| if on { side } else { 0 };
        e.sides = bit(ov[2] == bx[2], SIDE_BOTTOM)
            | bit(ov[1] == bx[1], SIDE_RIGHT)
            | bit(ov[3] == bx[3], SIDE_TOP)
            | bit(ov[0] == bx[0], SIDE_LEFT);
        e.inside = true;
        Some((e, clip))
    }

    /// Whether the square `(x, y, size)` in walk units overlaps the box.
    fn overlaps(&self, x: u32, y: u32, size: u32) -> bool {
        let bx = self.bx;
        bx[0].max(x) < bx[1].min(x + size) && bx[2].max(y) < bx[3].min(y + size)
    }

    /// Whether a node of `level` is at most 1/64 of the box's shorter side: its side is
    /// `105 · 2^(21 - level)` walk units.
    fn small(&self, level: u32) -> bool {
        let bmin = (self.bx[1] - self.bx[0]).min(self.bx[3] - self.bx[2]);
        level >= 27 || (bmin >> (27 - level)) >= 105
    }

    /// A split node (placed) onto the path, with the children to visit: those the box
    /// overlaps while it cuts the node, all four once the node is inside.
    fn push(&mut self, e: WalkEntry, cut: bool, children: [u32; 4]) {
        let mut todo = 15;
        if cut {
            // Below level 21 nodes are never cut by a box of the grid.
            if !e.size.is_multiple_of(2) {
                self.overflow = true;
                return;
            }
            let h = e.size / 2;
            todo = (0..4)
                .filter(|&c| {
                    let (qx, qy) = quadrant_offset(c);
                    self.overlaps(e.x + qx * h, e.y + qy * h, h)
                })
                .fold(0, |m, c| m | 1 << c);
        }
        if self.stack.len() < WALK_STACK {
            self.stack.push(WalkFrame {
                entry: e,
                cut,
                children,
                todo,
            });
        } else {
            self.overflow = true;
        }
    }

    /// Child `c` of the split node on top of the path.
    fn child(&self, c: usize) -> WalkEntry {
        let f = self.stack.last().expect("a split node on the path");
        let e = f.entry;
        let (qx, qy) = quadrant_offset(c);
        if f.cut {
            let h = e.size / 2;
            return WalkEntry {
                node: f.children[c],
                level: e.level + 1,
                x: e.x + qx * h,
                y: e.y + qy * h,
                size: h,
                inside: false,
                ..e
            };
        }
        let r = e.rect;
        let (hu, hv) = (0.5 * (r[1] - r[0]), 0.5 * (r[3] - r[2]));
        let u0 = r[0] + qx as f64 * hu;
        let v0 = r[2] + qy as f64 * hv;
        WalkEntry {
            node: f.children[c],
            level: e.level + 1,
            rect: [u0, u0 + hu, v0, v0 + hv],
            sides: e.sides & QUADRANT_SIDES[c],
            ..e
        }
    }
}

/// Lower-left corner of quadrant `c` in units of half the parent.
pub fn quadrant_offset(c: usize) -> (u32, u32) {
    [(0, 0), (1, 0), (1, 1), (0, 1)][c]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_linear_orientation_check_agrees_with_all_pairs() {
        // Steps spread over narrow and wide angle ranges, so that both answers occur.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut kept, mut lost) = (0, 0);
        for round in 0..20_000 {
            let spread = [0.3, 1.0, 2.0, 3.5][round % 4];
            let (ca, cb) = (next() * 6.3, next() * 6.3);
            let mut steps = |c: f64| -> [DVec2; 12] {
                std::array::from_fn(|_| {
                    let t = c + spread * (next() - 0.5);
                    DVec2::new(t.cos(), t.sin()) * (0.1 + next())
                })
            };
            let (du, dv) = (steps(ca), steps(cb));
            let all_pairs = du.iter().all(|a| dv.iter().all(|b| a.perp_dot(*b) > 0.0));
            assert_eq!(orientation_kept(&du, &dv), all_pairs, "round {round}");
            if all_pairs {
                kept += 1;
            } else {
                lost += 1;
            }
        }
        assert!(kept > 1000 && lost > 1000, "{kept} kept, {lost} lost");
    }

    #[test]
    fn the_orthonormal_pair_is_right_handed() {
        // Both branches of the formula, and near its seam at n = -z.
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::new(0.3, -0.5, 0.8),
            DVec3::new(-0.2, 0.1, -0.97),
            DVec3::new(1e-9, 0.0, -1.0),
            DVec3::X,
        ] {
            let n = n.normalize();
            let (e1, e2) = orthonormal_pair(n);
            assert!((e1.cross(e2) - n).length() < 1e-12, "{n}");
            assert!(e1.dot(n).abs() < 1e-12 && e2.dot(n).abs() < 1e-12);
            // The slab test's orientation check reads n · (a × b) off the projections.
            let (a, b) = (DVec3::new(0.4, 1.0, -2.0), DVec3::new(-0.7, 0.2, 0.5));
            let (pa, pb) = (project((e1, e2), a), project((e1, e2), b));
            assert!((pa.perp_dot(pb) - n.dot(a.cross(b))).abs() < 1e-12);
        }
    }
}
