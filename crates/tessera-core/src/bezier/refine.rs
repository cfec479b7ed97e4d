//! Refinement of one coarse triangle from its edge decisions and tests inside it.
//! CPU twin of `shaders/bezier_tri_mark.wgsl` (mark, count) and `bezier_tri_emit.wgsl`,
//! with the shared parts in `shaders/shared/need.wgsl` and `refine.wgsl`.
//!
//! The pattern lives on the triangle's dyadic [`Lattice`]. A coarse triangle is a right
//! isosceles triangle in `(u, v)`, and so is each half of one cut from its right angle to
//! the midpoint of its hypotenuse: the refinement is that binary bisection (a right
//! triangulated irregular network), which refines area in steps of 2 rather than the 4
//! of a 1-to-4 split, so each region lands closer to the density it needs.
//! 1. **Mark** (decisions, before any vertex exists): starting from the coarse triangle,
//!    a right triangle is bisected when [`splits`] says so, down to `2 · max_depth`
//!    levels (`max_depth` halvings of every coarse edge). Each bisection marks the
//!    midpoint of its hypotenuse in a bit set of lattice points.
//! 2. **Count / emit**: the same bisection is replayed from the marked points alone (a
//!    triangle is cut when its hypotenuse midpoint is a vertex). Each leaf becomes the
//!    polygon of its corners plus every vertex on its sides, cut into triangles by ear
//!    clipping without new vertices: no T-junction, no zero-area triangle.
//!
//! Why not the paper's rows ("layer strips")? Rows zipped between unequally refined
//! sides produce long edges that no test has looked at, so the error inside a strip is
//! not held to the threshold and the max error stops falling as triangles are added.
//! Here every side of every leaf was tested (or is at the depth limit), which bounds the
//! error inside it.
//!
//! Consistency without communication: inside a coarse triangle, neighbours need not
//! agree (a point one side makes is a vertex on the other side's polygon). Across coarse
//! edges the bit sets are the only shared truth: a triangle whose hypotenuse lies on a
//! coarse edge is cut exactly where the edge has a point, and the coarse-edge stage sets
//! a point wherever the triangle on either side asks for one ([`interior_need`], the same
//! function of the same data in both stages).

use super::coarse_edges::coarse_edge_of;
use super::edge_tests::{
    bit_is_set, bit_rank, map_test_with, segment_test, EdgeBits, EdgeTest, TestInputs, DYADIC_SCALE,
};
use super::lattice::{bit_get, bit_set, lattice_mid, Lattice, LatticePlace, Lp, TreeWalk};
use super::prepare::map_read;
use super::prepare::PreparedBezier;

/// A vertex as the triangle stages see it, before global numbering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRef {
    /// A coarse grid vertex (global id).
    Coarse(u32),
    /// The `rank`-th inserted point of a coarse edge, in canonical order.
    Edge {
        /// Coarse edge id.
        edge: u32,
        /// Rank of the point among the edge's inserted points.
        rank: u32,
    },
    /// The `n`-th inner point of this coarse triangle, in lattice-index order.
    Inner(u32),
}

/// Receives the triangles of a coarse triangle: a counting sink and a writing sink give
/// the count and emit stages.
pub trait TriangleSink {
    /// One output triangle, counter-clockwise seen from the front (flipped patches
    /// already reversed).
    fn triangle(&mut self, tri: [VertexRef; 3]);
}

/// The test of lattice edge `a – b` in the patch, end points in canonical order (by
/// patch coordinates) so that both triangles on the edge compute exactly the same.
/// Returns the decision and the surface evaluations it made.
pub fn lattice_edge_test(inp: &TestInputs, l: &Lattice, a: Lp, b: Lp) -> (bool, u32) {
    let (a, b) = canonical(l, a, b);
    segment_test(inp, l.uv(a), l.uv(b))
}

/// Whether right triangle `t = (r, a, b)` asks to be bisected: the test of its
/// hypotenuse, of either leg (a leg that needs a point is the hypotenuse of a child), or
/// of the segment from the right angle to the hypotenuse midpoint (it sees a bulge whose
/// sides are straight, as on a saddle). A hypotenuse on a coarse side is tested here in
/// this patch's own map too: the coarse-edge stage asks both patches, because a map only
/// sees displacement along its own normals and a boundary curve that bends within one
/// patch's tangent plane bends out of the other's.
///
/// The map tests read the displacement *from this triangle*: the map value minus the
/// plane through the map values at its corners. The map measures distance to the coarse
/// mesh, and once a coarse triangle is being refined the question is how far the surface
/// is from the triangle at hand. On a coarse triangle (corners on coarse vertices, map
/// zero there) this is the map itself, so the paper's tests apply unchanged; deeper it
/// turns `|d1 − d12|` into the chord deviation `|d12 − (d1 + d2)/2|` instead of the
/// slope of the surface against the coarse plane, which grows toward coarse vertices
/// and would over-refine them.
pub fn interior_need(inp: &TestInputs, l: &Lattice, t: [Lp; 3]) -> (bool, u32) {
    let [r, a, b] = t;
    let m = lattice_mid(a, b);
    if inp.test == EdgeTest::Flat {
        let mut evals = 0;
        for (p, q) in [(a, b), (r, a), (b, r), (r, m)] {
            let (yes, e) = lattice_edge_test(inp, l, p, q);
            evals += e;
            if yes {
                return (true, evals);
            }
        }
        return (false, evals);
    }
    // The map is read once per corner and at the hypotenuse midpoint: each is the end of
    // two segments, and the corners also fix the plane.
    let [ur, ua, ub, um] = [r, a, b, m].map(|p| l.uv(p));
    let raw = [ur, ua, ub].map(|p| map_read(inp.map, p[0], p[1]));
    let plane = TrianglePlane::new([ur, ua, ub], raw);
    let [dr, da, db] = [(ur, raw[0]), (ua, raw[1]), (ub, raw[2])].map(|(p, x)| plane.value(p, x));
    let dm = plane.value(um, map_read(inp.map, um[0], um[1]));
    // The hypotenuse and the legs are sides of t; the median r – m is not.
    let segments = [
        ((a, ua, da), (b, ub, db), true),
        ((r, ur, dr), (a, ua, da), true),
        ((b, ub, db), (r, ur, dr), true),
        ((r, ur, dr), (m, um, dm), false),
    ];
    let yes = segments.into_iter().any(|(p, q, one_inside)| {
        let ((_, u1, d1), (_, u2, d2)) = if l.patch_coords(p.0) <= l.patch_coords(q.0) {
            (p, q)
        } else {
            (q, p)
        };
        map_test_with(
            inp.test,
            inp.threshold,
            [u1, u2],
            [d1, d2],
            one_inside,
            |u, v| plane.displacement(inp.map, u, v),
        )
    });
    (yes, 0)
}

/// The affine function of `(u, v)` through the map values at a triangle's corners.
struct TrianglePlane {
    origin: [f32; 2],
    d0: f32,
    /// Gradient of the displacement in `(u, v)`.
    grad: [f32; 2],
    /// Edge vectors and determinant, for the inside test.
    e1: [f32; 2],
    e2: [f32; 2],
    det: f32,
}

impl TrianglePlane {
    /// The plane through the map values `d` at the corners `p`.
    fn new(p: [[f32; 2]; 3], d: [f32; 3]) -> Self {
        let [p0, p1, p2] = p;
        let [d0, d1, d2] = d;
        let (e1, e2) = (
            [p1[0] - p0[0], p1[1] - p0[1]],
            [p2[0] - p0[0], p2[1] - p0[1]],
        );
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        let (g1, g2) = (d1 - d0, d2 - d0);
        // Solve grad · e1 = g1, grad · e2 = g2.
        let grad = [
            (g1 * e2[1] - g2 * e1[1]) / det,
            (e1[0] * g2 - e2[0] * g1) / det,
        ];
        TrianglePlane {
            origin: p0,
            d0,
            grad,
            e1,
            e2,
            det,
        }
    }

    /// Whether `p` is in the triangle (with a little slack for rounding).
    fn inside(&self, p: [f32; 2]) -> bool {
        let (du, dv) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        let s = (du * self.e2[1] - dv * self.e2[0]) / self.det;
        let t = (self.e1[0] * dv - self.e1[1] * du) / self.det;
        const SLACK: f32 = 1e-4;
        !(s < -SLACK || t < -SLACK || s + t > 1.0 + SLACK)
    }

    /// The displacement from the plane at `p`, where the map value is `raw`; `None`
    /// outside the triangle, where the plane is an extrapolation and says nothing about
    /// this triangle (a Map4p/Map8p point across an edge falls there).
    fn value(&self, p: [f32; 2], raw: f32) -> Option<f32> {
        self.inside(p).then(|| raw - self.plane_at(p))
    }

    /// [`value`](Self::value) reading the map, only inside the triangle.
    fn displacement(&self, map: &crate::gpu_types::DisplacementMap, u: f32, v: f32) -> Option<f32> {
        self.inside([u, v])
            .then(|| map_read(map, u, v) - self.plane_at([u, v]))
    }

    /// The plane's value at `p`.
    fn plane_at(&self, p: [f32; 2]) -> f32 {
        let (du, dv) = (p[0] - self.origin[0], p[1] - self.origin[1]);
        self.d0 + self.grad[0] * du + self.grad[1] * dv
    }
}

/// The end points of a lattice edge in canonical order (by patch coordinates).
fn canonical(l: &Lattice, a: Lp, b: Lp) -> (Lp, Lp) {
    if l.patch_coords(a) <= l.patch_coords(b) {
        (a, b)
    } else {
        (b, a)
    }
}

/// What the triangle stages of one coarse triangle read.
pub struct TriContext<'a> {
    /// What the tests on the triangle's patch read.
    pub inputs: TestInputs<'a>,
    /// The triangle's lattice at the tests' `max_depth`.
    pub lattice: Lattice,
    /// Per side: coarse edge id, whether the side runs along its canonical direction,
    /// whether it is collapsed to a point.
    pub sides: [(u32, bool, bool); 3],
    /// Global ids of the corners.
    pub corner_ids: [u32; 3],
    /// Every coarse edge's inserted points, by edge id (the edge stage's output).
    pub edge_bits: &'a [EdgeBits],
    /// Whether the triangle's patch is flipped (its triangles are emitted reversed).
    pub flipped: bool,
}

impl<'a> TriContext<'a> {
    /// The context of global coarse triangle `tri`, with the tests `inputs` of its patch.
    pub fn new(
        prep: &PreparedBezier,
        inputs: TestInputs<'a>,
        edge_bits: &'a [EdgeBits],
        tri: u32,
    ) -> Self {
        let lattice = Lattice::new(tri, inputs.max_depth);
        let p = lattice.patch;
        let g = lattice.grid;
        let sides = std::array::from_fn(|k| {
            let (e, fwd) = coarse_edge_of(prep, p, g[k], g[(k + 1) % 3]);
            (e, fwd, super::coarse_edges::edge_collapsed(prep, e))
        });
        TriContext {
            inputs,
            lattice,
            sides,
            corner_ids: g.map(|c| prep.coarse_vertex(p, c[0], c[1])),
            edge_bits,
            flipped: prep.topo[p as usize].flipped(),
        }
    }

    /// Canonical position (in 1/256ths) of the point `f` lattice steps along `side`.
    fn canonical(&self, side: usize, f: u32) -> u32 {
        let q = f * (DYADIC_SCALE / self.lattice.n);
        if self.sides[side].1 {
            q
        } else {
            DYADIC_SCALE - q
        }
    }

    /// Whether the coarse edge of `side` has a point `f` steps along it.
    fn side_point(&self, side: usize, f: u32) -> bool {
        let e = self.sides[side].0;
        bit_is_set(&self.edge_bits[e as usize], self.canonical(side, f))
    }

    /// Whether lattice point `p` is a vertex, given the points marked so far.
    pub fn exists(&self, scratch: &TriScratch, p: Lp) -> bool {
        match self.lattice.place(p) {
            LatticePlace::Corner(_) => true,
            LatticePlace::Side(k, f) if self.sides[k].2 => {
                bit_get(&scratch.pole, pole_index(&self.lattice, k, f))
            }
            LatticePlace::Side(k, f) => self.side_point(k, f),
            LatticePlace::Inside(i) => bit_get(&scratch.points, i),
        }
    }

    /// The vertex at lattice point `p`; `inner_rank` numbers the inner points.
    pub fn vertex(&self, p: Lp, inner_rank: &dyn Fn(usize) -> u32) -> VertexRef {
        match self.lattice.place(p) {
            LatticePlace::Corner(k) => VertexRef::Coarse(self.corner_ids[k]),
            LatticePlace::Side(k, f) => {
                let (e, _, collapsed) = self.sides[k];
                if collapsed {
                    // Every point of a collapsed side is its corner.
                    return VertexRef::Coarse(self.corner_ids[k]);
                }
                let rank = bit_rank(&self.edge_bits[e as usize], self.canonical(k, f));
                VertexRef::Edge { edge: e, rank }
            }
            LatticePlace::Inside(i) => VertexRef::Inner(inner_rank(i)),
        }
    }
}

/// The bisection decision of right triangle `t = (r, a, b)` at `level` (0: the coarse
/// triangle). A hypotenuse on a coarse side can be cut only where the coarse edge has a
/// point, and then is; otherwise the inside decides. (On a side collapsed to a point,
/// the inside decides too: its points are all the one corner vertex.)
pub fn splits(ctx: &TriContext, t: [Lp; 3], level: u32) -> (bool, u32) {
    if level >= 2 * ctx.lattice.depth {
        return (false, 0);
    }
    if let Some(side) = ctx.lattice.common_side(t[1], t[2]) {
        if !ctx.sides[side].2 {
            let LatticePlace::Side(_, f) = ctx.lattice.place(lattice_mid(t[1], t[2])) else {
                unreachable!("the midpoint of a side piece lies on the side")
            };
            return (ctx.side_point(side, f), 0);
        }
    }
    interior_need(&ctx.inputs, &ctx.lattice, t)
}

/// Bit of point `f` of collapsed side `k` in [`TriScratch::pole`].
fn pole_index(l: &Lattice, k: usize, f: u32) -> usize {
    k * (l.n as usize + 1) + f as usize
}

/// Per-triangle scratch the mark stage writes and the count and emit stages read.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TriScratch {
    /// Inner lattice points that are vertices.
    pub points: Vec<u32>,
    /// Points marked on sides collapsed to a point (all one vertex, but they steer the
    /// replay of the bisection).
    pub pole: Vec<u32>,
    /// Bit g: group g of `points` (words `g << group_shift ..`, see
    /// [`Lattice::word_group_shift`]) holds a point.
    pub groups: u32,
    /// [`Lattice::word_group_shift`] of the points' words.
    pub group_shift: u32,
}

impl TriScratch {
    /// Empty scratch for a lattice of depth `depth`.
    pub fn new(depth: u32) -> Self {
        let points_words = Lattice::points_words(depth);
        TriScratch {
            points: vec![0; points_words],
            pole: vec![0; (3 * ((1usize << depth) + 1)).div_ceil(32)],
            groups: 0,
            group_shift: Lattice::word_group_shift(points_words as u32),
        }
    }
    /// The words as the GPU stores them: points, pole points, groups.
    pub fn words(&self) -> Vec<u32> {
        [&self.points[..], &self.pole[..], &[self.groups]].concat()
    }
    /// Inner lattice points that are vertices.
    pub fn inner_count(&self) -> u32 {
        self.points.iter().map(|w| w.count_ones()).sum()
    }
}

/// Stage "mark", one work item per coarse triangle: the bisection tree, as the points
/// it makes. Returns the surface evaluations made (flat test only).
pub fn tri_mark(ctx: &TriContext, scratch: &mut TriScratch) -> u32 {
    let mut evals = 0;
    let mut w = TreeWalk::new(ctx.lattice.root());
    loop {
        let (yes, e) = splits(ctx, w.t, w.level);
        evals += e;
        if !yes {
            if !w.advance() {
                return evals;
            }
            continue;
        }
        match ctx.lattice.place(lattice_mid(w.t[1], w.t[2])) {
            LatticePlace::Inside(i) => {
                bit_set(&mut scratch.points, i);
                scratch.groups |= 1 << ((i / 32) >> scratch.group_shift);
            }
            LatticePlace::Side(k, f) if ctx.sides[k].2 => {
                bit_set(&mut scratch.pole, pole_index(&ctx.lattice, k, f))
            }
            _ => {}
        }
        w.down();
    }
}

/// Calls `leaf` on every leaf of the bisection replayed from the marked points, in
/// depth-first order.
fn for_each_leaf(ctx: &TriContext, scratch: &TriScratch, mut leaf: impl FnMut([Lp; 3])) {
    let max_level = 2 * ctx.lattice.depth;
    let mut w = TreeWalk::new(ctx.lattice.root());
    loop {
        while w.level < max_level && ctx.exists(scratch, lattice_mid(w.t[1], w.t[2])) {
            w.down();
        }
        leaf(w.t);
        if !w.advance() {
            return;
        }
    }
}

/// The corners of leaf `t = [r, a, b]` and every existing point on its sides,
/// counter-clockwise. Only the legs r → a and b → r are walked: the hypotenuse a → b
/// holds no point. Its midpoint does not exist (which is why `t` is a leaf), or `t` is
/// at the deepest level, where the hypotenuse is one lattice step; and the points on a
/// side exist only where their dyadic parent does (see [`side_points`]). A SIMD device
/// runs every walk written, so walking the third side would cost the GPU twin as much as
/// either leg.
fn leaf_polygon(ctx: &TriContext, scratch: &TriScratch, t: [Lp; 3], out: &mut Vec<Lp>) {
    let [r, a, b] = t;
    out.clear();
    out.push(r);
    side_points(ctx, scratch, r, a, out);
    out.push(a);
    debug_assert!(
        {
            let mut hypotenuse = Vec::new();
            side_points(ctx, scratch, a, b, &mut hypotenuse);
            hypotenuse.is_empty()
        },
        "a leaf's hypotenuse holds a point"
    );
    out.push(b);
    side_points(ctx, scratch, b, r, out);
}

/// The lattice points strictly inside segment a → b: `a + s · unit` for `0 < s < steps`.
/// Lattice points on a side: a (1, 0), (0, 1), (1, −1) or (2, −1) direction (axes and
/// diagonals of (u, v) under the lattice's shear) times the gcd. A bisection side is
/// a power of two times such a unit, which has an odd component, so the gcd is the
/// largest power of two dividing both components: found by their trailing zeros, where
/// Euclid's modulo was a scalar loop over the lanes on a CPU device.
fn side_steps(a: Lp, b: Lp) -> (u32, [i64; 2]) {
    let d = [b[0] as i64 - a[0] as i64, b[1] as i64 - a[1] as i64];
    // A degenerate side (a = b) has no inner points, not a panic.
    if d == [0, 0] {
        return (1, d);
    }
    let z = (d[0] | d[1]).trailing_zeros();
    debug_assert_eq!(
        1u64 << z,
        gcd(d[0].unsigned_abs(), d[1].unsigned_abs()),
        "{a:?} → {b:?}: not a bisection side"
    );
    (1 << z, [d[0] >> z, d[1] >> z])
}

fn step_point(a: Lp, unit: [i64; 2], s: u32) -> Lp {
    [
        (a[0] as i64 + unit[0] * s as i64) as u32,
        (a[1] as i64 + unit[1] * s as i64) as u32,
    ]
}

/// The vertices strictly inside side a → b of a leaf, in order from a.
///
/// Points on a side appear as a dyadic hierarchy: a point is the midpoint of a
/// bisected hypotenuse (or of a coarse-edge piece) whose ends are vertices, so the
/// quarter points exist only where the half point does. The walk therefore goes from
/// vertex to vertex, halving the step while the midpoint ahead exists: O(points ·
/// depth) lookups instead of one per lattice step (up to 2^depth per side, most of them
/// empty, which made building polygons the triangle stages' largest cost on the GPU).
/// At vertex `s` the point `s + lowbit(s)` is known to exist: it closed the interval
/// that `s` is the midpoint of.
fn side_points(ctx: &TriContext, scratch: &TriScratch, a: Lp, b: Lp, out: &mut Vec<Lp>) {
    // `side_steps` checks (in debug builds) that this is a bisection side.
    let (steps, unit) = side_steps(a, b);
    let mut s = 0;
    while s < steps {
        let mut h = if s == 0 { steps } else { s & s.wrapping_neg() };
        while h > 1 && ctx.exists(scratch, step_point(a, unit, s + h / 2)) {
            h /= 2;
        }
        s += h;
        if s < steps {
            out.push(step_point(a, unit, s));
        }
    }
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

fn collinear(a: Lp, b: Lp, c: Lp) -> bool {
    let (ax, ay) = (b[0] as i64 - a[0] as i64, b[1] as i64 - a[1] as i64);
    let (bx, by) = (c[0] as i64 - a[0] as i64, c[1] as i64 - a[1] as i64);
    ax * by - ay * bx == 0
}

/// Cuts a convex polygon whose sides may carry extra collinear points into triangles
/// without new vertices and without zero-area triangles, one triangle per step: the
/// [`best_ear`] while more than three vertices are left, then the last three.
fn clip_ears(l: &Lattice, poly: &mut Vec<Lp>, mut tri: impl FnMut(Lp, Lp, Lp)) {
    while poly.len() >= 3 {
        let n = poly.len();
        // k = 1 of a triangle is the triangle itself, in order.
        let k = if n > 3 { best_ear(l, poly) } else { 1 };
        tri(poly[(k + n - 1) % n], poly[k], poly[(k + 1) % n]);
        if n == 3 {
            break;
        }
        poly.remove(k);
    }
}

/// The ear to clip: a true corner whose removal leaves a polygon with at least three
/// true corners, with the shortest new diagonal (first in polygon order on ties).
fn best_ear(l: &Lattice, poly: &[Lp]) -> usize {
    let n = poly.len();
    let at = |k: usize| poly[k % n];
    let corner = |k: usize| !collinear(at(k + n - 1), at(k), at(k + 1));
    let corners = (0..n).filter(|&k| corner(k)).count();
    let mut best: Option<(u64, usize)> = None;
    for k in 0..n {
        if !corner(k) {
            continue;
        }
        let (u, w) = (k + n - 1, k + 1);
        let u_after = !collinear(at(u + n - 1), at(u), at(w));
        let w_after = !collinear(at(u), at(w), at(w + 1));
        let after = corners - 1 - corner(u) as usize - corner(w) as usize
            + u_after as usize
            + w_after as usize;
        if after < 3 {
            continue;
        }
        let (pu, pw) = (l.patch_coords(at(u)), l.patch_coords(at(w)));
        let dx = pu[0] as i64 - pw[0] as i64;
        let dy = pu[1] as i64 - pw[1] as i64;
        let d2 = (dx * dx + dy * dy) as u64;
        if best.is_none_or(|(b, _)| d2 < b) {
            best = Some((d2, k));
        }
    }
    // A convex polygon with three true corners always has such an ear.
    best.map_or(0, |(_, k)| k)
}

/// Stage "count" / "emit", one work item per coarse triangle: the triangles of every
/// leaf, in depth-first leaf order, counter-clockwise unless the patch is flipped.
/// Triangles with two corners on one vertex (a side collapsed to a point) are dropped.
pub fn tri_triangles(
    ctx: &TriContext,
    scratch: &TriScratch,
    inner_rank: &dyn Fn(usize) -> u32,
    sink: &mut dyn TriangleSink,
) {
    let mut poly = Vec::new();
    for_each_leaf(ctx, scratch, |t| {
        leaf_polygon(ctx, scratch, t, &mut poly);
        clip_ears(&ctx.lattice, &mut poly, |a, b, c| {
            let [a, b, c] = [a, b, c].map(|p| ctx.vertex(p, inner_rank));
            if a == b || b == c || a == c {
                return;
            }
            sink.triangle(if ctx.flipped { [a, c, b] } else { [a, b, c] });
        });
    });
}

/// Rank of inner point `i` given the inner points before each word (`prefix`).
pub fn inner_rank(points: &[u32], prefix: &[u32], i: usize) -> u32 {
    let below = points[i / 32] & ((1u32 << (i % 32)) - 1);
    prefix[i / 32] + below.count_ones()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every existing point on a side, one lookup per lattice step.
    fn side_points_scanned(ctx: &TriContext, scratch: &TriScratch, a: Lp, b: Lp) -> Vec<Lp> {
        let (steps, unit) = side_steps(a, b);
        (1..steps)
            .map(|s| step_point(a, unit, s))
            .filter(|&p| ctx.exists(scratch, p))
            .collect()
    }

    /// The dyadic walk finds exactly the points a scan of every lattice step finds, on
    /// every side of every leaf of the teapot, for each edge test at several thresholds
    /// (collapsed sides at the poles, coarse edges and inner sides included); and no
    /// leaf's hypotenuse holds a point (`leaf_polygon` walks only the legs).
    #[test]
    fn dyadic_side_walk_finds_every_point_a_scan_finds() {
        let (mut sides, mut points, mut several) = (0, 0, 0);
        let settings = [
            (EdgeTest::Map4p, 0.02),
            (EdgeTest::Map4p, 0.002),
            (EdgeTest::Map2p, 0.005),
            (EdgeTest::Map8p, 0.005),
            (EdgeTest::Flat, 0.005),
            (EdgeTest::Flat, 0.0005),
            (EdgeTest::Map4p, 0.0002),
        ];
        crate::bezier::test_support::for_each_marked_triangle(
            &["teapot"],
            &settings,
            |what, ctx, scratch| {
                for_each_leaf(ctx, scratch, |leaf| {
                    for k in 0..3 {
                        let (a, b) = (leaf[k], leaf[(k + 1) % 3]);
                        let mut walked = Vec::new();
                        side_points(ctx, scratch, a, b, &mut walked);
                        let scanned = side_points_scanned(ctx, scratch, a, b);
                        assert_eq!(walked, scanned, "{what}, side {a:?} → {b:?}");
                        // `leaf_polygon` walks only the legs.
                        assert!(
                            k != 1 || scanned.is_empty(),
                            "{what}: the hypotenuse holds a point"
                        );
                        sides += 1;
                        points += scanned.len();
                        several += (scanned.len() >= 2) as usize;
                    }
                });
            },
        );
        // Not a vacuous pass: many sides carry points.
        assert!(
            sides > 100_000 && points > 10_000 && several > 1000,
            "{sides} sides, {points} points, {several} sides with two or more"
        );
    }
}
