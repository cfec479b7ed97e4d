//! The map-based adaptive tessellator as a straight-line script of stages, each the CPU
//! twin of one compute kernel. The wgpu stage records the same stages as dispatches.
//!
//! | stage | kernel | work item |
//! |---|---|---|
//! | [`edge_decide`] | `bezier_edge_decide.wgsl` | coarse edge |
//! | [`root_known_leaf`] and [`euler_count`] | `bezier_tri_roots.wgsl` | coarse triangle |
//! | [`tri_mark`], [`tri_count`] | `bezier_tri_mark.wgsl` | coarse triangle not decided by its root |
//! | [`exclusive_scan`] | `scan.wgsl` (the GPU scans all three counts as one array) | — |
//! | totals, [`emit_order`]'s bucket slots | `bezier_finish.wgsl` | 1 |
//! | [`emit_order`] | `bezier_tri_order.wgsl` | coarse triangle |
//! | [`coarse_vertex_records`](PreparedBezier::coarse_vertex_records) (uploaded), [`edge_emit`], [`tri_emit`], [`tri_emit_plain`] | `bezier_*_emit*.wgsl` | edge / triangle (in the emit order) |
//! | [`vertex_eval`] | `bezier_vertex_eval.wgsl` | output vertex |

use glam::{DVec3, Vec3};

use bytemuck::Zeroable;

use super::coarse_edges::{coarse_edge_sides, edge_collapsed, edge_endpoints};
use super::edge_tests::{
    bit_count, bit_positions, lerp_uv, subdivide_segment_with, EdgeBits, EdgeTest, TestInputs,
    DYADIC_SCALE,
};
use super::lattice::{Lattice, LatticeRows};
use super::patch::{eval_frame_f32, frame_normal_f32};
use super::prepare::PreparedBezier;
use super::refine::{
    inner_rank, interior_need, splits, tri_mark, tri_triangles, TriContext, TriScratch,
    TriangleSink, VertexRef,
};
use crate::catmull_clark::bicubic::Net;
use crate::catmull_clark::facing::net_normals;
use crate::error::{Error, Result};
use crate::gpu_types::{tally, OutVertex, VertexRecord, EDGE_BIT_WORDS, MAX_DEPTH_LIMIT};
use crate::mesh::Mesh;
pub use crate::scan::exclusive_scan;
use crate::view::View;

/// Parameters of the adaptive (map or flat) tessellator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveParams {
    /// Which test decides whether a segment is split.
    pub test: EdgeTest,
    /// `th`: map-distance difference (map tests) or chord deviation (flat), model units.
    pub threshold: f32,
    /// Levels of recursive bisection per coarse edge (at most 2^depth segments).
    pub max_depth: u32,
}

impl AdaptiveParams {
    /// The depth used when none is given: at most 64 segments per coarse edge.
    pub const DEFAULT_MAX_DEPTH: u32 = 6;

    /// Checks that the threshold is positive and finite and the depth at most
    /// [`MAX_DEPTH_LIMIT`].
    pub fn validate(&self) -> Result<()> {
        if !(self.threshold.is_finite() && self.threshold > 0.0) {
            return Err(Error::Param(format!(
                "threshold must be a positive number, got {}",
                self.threshold
            )));
        }
        if self.max_depth > MAX_DEPTH_LIMIT {
            return Err(Error::Param(format!(
                "max depth {} is beyond the supported {MAX_DEPTH_LIMIT}",
                self.max_depth
            )));
        }
        Ok(())
    }
}

/// A tessellated mesh and what it cost.
#[derive(Clone, Debug, Default)]
pub struct Tessellation {
    /// The triangles and their vertices.
    pub mesh: Mesh,
    /// Surface evaluations: one per output vertex that a triangle uses ([`unused`]),
    /// plus the flat test's candidates.
    pub evaluations: u64,
    /// Patches the view culls: no triangles, and no evaluation but of the vertices they
    /// share with patches in view.
    pub culled_patches: usize,
}

/// A view for the Bézier path: each patch's edge-test threshold in `pixels` of it
/// ([`patch_thresholds`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BezierView {
    /// The camera, with the model's placement ([`View::with_model`]).
    pub view: View,
    /// The threshold in pixels.
    pub pixels: f64,
    /// Patches whose control points' box lies wholly outside the frustum (the patch lies
    /// in their hull) emit nothing.
    pub cull: bool,
    /// Patches facing away from the eye everywhere emit nothing too: the normals of a
    /// bicubic piece lie in the cone of its control net's 144 products of u- and
    /// v-differences ([`net_normals`]), tested over the control points' box
    /// ([`View::box_back_facing`]). Outside the threshold's heuristic as well.
    pub cull_backfaces: bool,
}

/// Each patch's edge-test threshold, model units: `world`, or in `view` the smaller of
/// it and the view's pixels over the pixels per model unit of the box of the patch's
/// control points ([`View::gain`]; the patch lies in their hull). Known before any
/// evaluation and one per patch, so both stages and both triangles beside an edge use
/// the same, and the mesh stays crack-free. The paper's heuristic scaled by distance, not
/// a guarantee in pixels. A patch a culling view culls gets its threshold negated
/// ([`culled`]; the tests take [`test_threshold`]), so the kernels read both from one
/// buffer.
pub fn patch_thresholds(
    cps: &[[Vec3; 16]],
    flipped: &[bool],
    world: f32,
    view: Option<&BezierView>,
) -> Result<Vec<f32>> {
    let Some(v) = view else {
        return Ok(vec![world; cps.len()]);
    };
    if !(v.pixels.is_finite() && v.pixels > 0.0) {
        return Err(Error::Param(format!(
            "pixel threshold must be a positive number, got {}",
            v.pixels
        )));
    }
    Ok(cps
        .iter()
        .zip(flipped)
        .map(|(net, &flipped)| {
            let lo = net.iter().fold(DVec3::INFINITY, |a, p| a.min(p.as_dvec3()));
            let hi = net
                .iter()
                .fold(DVec3::NEG_INFINITY, |a, p| a.max(p.as_dvec3()));
            let th = v.pixels / v.view.gain(lo, hi, 0.0);
            // A positive single-precision number at least.
            let th = (th.min(world as f64) as f32).max(f32::MIN_POSITIVE);
            // A flipped patch's normals, and its winding, are the net's reversed.
            let away = v.cull_backfaces && {
                let net: Net = net.map(|p| p.as_dvec3());
                let sign = if flipped { -1.0 } else { 1.0 };
                v.view.box_back_facing(
                    lo,
                    hi,
                    net_normals(&net, (hi - lo).length()).map(|n| sign * n),
                )
            };
            if (v.cull && v.view.box_outside(lo, hi)) || away {
                -th
            } else {
                th
            }
        })
        .collect())
}

/// Whether [`patch_thresholds`] culled the patch whose threshold is `signed`.
pub fn culled(signed: f32) -> bool {
    signed < 0.0
}

/// The threshold the edge tests take from [`patch_thresholds`]'s `signed` one.
pub fn test_threshold(signed: f32) -> f32 {
    signed.abs()
}

/// Inputs of the tests on patch `p`, with its own `threshold` ([`patch_thresholds`]).
pub fn test_inputs_at<'a>(
    prep: &'a PreparedBezier,
    cps: &'a [[Vec3; 16]],
    params: &AdaptiveParams,
    threshold: f32,
    p: u32,
) -> TestInputs<'a> {
    TestInputs {
        threshold: test_threshold(threshold),
        ..test_inputs(prep, cps, params, p)
    }
}

/// Inputs of the tests on patch `p`.
pub fn test_inputs<'a>(
    prep: &'a PreparedBezier,
    cps: &'a [[Vec3; 16]],
    params: &AdaptiveParams,
    p: u32,
) -> TestInputs<'a> {
    TestInputs {
        test: params.test,
        threshold: params.threshold,
        max_depth: params.max_depth,
        map: &prep.maps[p as usize],
        cp: &cps[p as usize],
    }
}

/// Stage 1, one work item per coarse edge: recursive bisection. The whole edge is split
/// by its edge test on the owner patch's map (as the paper states it: the map
/// is the displacement from the coarse mesh, which the edge belongs to). Each piece is
/// then split when the right triangle beside it, on either side, asks to be
/// ([`interior_need`]: the same tests, on the displacement from that triangle, in each
/// patch's own map). The flat test, which measures the chord itself, also tests every
/// piece directly. Collapsed edges are never split.
pub fn edge_decide(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    params: &AdaptiveParams,
    e: u32,
) -> (EdgeBits, u32) {
    edge_decide_by(prep, cps, params, |_| params.threshold, e)
}

/// [`edge_decide`] with each patch's threshold from `thresholds`.
pub fn edge_decide_at(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    params: &AdaptiveParams,
    thresholds: &[f32],
    e: u32,
) -> (EdgeBits, u32) {
    edge_decide_by(prep, cps, params, |p| thresholds[p as usize], e)
}

fn edge_decide_by(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    params: &AdaptiveParams,
    threshold_of: impl Fn(u32) -> f32,
    e: u32,
) -> (EdgeBits, u32) {
    if edge_collapsed(prep, e) {
        return ([0; EDGE_BIT_WORDS], 0);
    }
    let (p, uv0, uv1) = edge_endpoints(prep, e);
    let sides = coarse_edge_sides(prep, e);
    // The triangles of culled patches emit nothing: they ask for no points, and an edge
    // between two of them gets none.
    let lattices: Vec<(Lattice, TestInputs, usize, bool)> = sides
        .iter()
        .map(|&(t, k, fwd)| (Lattice::new(t, params.max_depth), k, fwd))
        .filter(|(l, _, _)| !culled(threshold_of(l.patch)))
        .map(|(l, k, fwd)| {
            (
                l,
                test_inputs_at(prep, cps, params, threshold_of(l.patch), l.patch),
                k,
                fwd,
            )
        })
        .collect();
    if lattices.is_empty() && !sides.is_empty() {
        return ([0; EDGE_BIT_WORDS], 0);
    }
    let own_test_levels = if params.test == EdgeTest::Flat {
        u32::MAX
    } else {
        1
    };
    let owner = test_inputs_at(prep, cps, params, threshold_of(p), p);
    subdivide_segment_with(&owner, uv0, uv1, own_test_levels, |lo, hi| {
        let mut evals = 0;
        for (l, inputs, k, fwd) in &lattices {
            // Dividing by DYADIC_SCALE / l.n, a power of two: a shift, as on the GPU.
            let shift = DYADIC_SCALE.trailing_zeros() - l.depth;
            let (f0, f1) = if *fwd {
                (lo >> shift, hi >> shift)
            } else {
                ((DYADIC_SCALE - hi) >> shift, (DYADIC_SCALE - lo) >> shift)
            };
            let tri = l.triangle_on_side(*k, f0, f1);
            let (yes, ev) = interior_need(inputs, l, tri);
            evals += ev;
            if yes {
                return (true, evals);
            }
        }
        (false, evals)
    })
}

/// What the triangle stages of coarse triangle `t` read.
pub fn tri_context<'a>(
    prep: &'a PreparedBezier,
    cps: &'a [[Vec3; 16]],
    bits: &'a [EdgeBits],
    params: &AdaptiveParams,
    t: u32,
) -> TriContext<'a> {
    let p = t / crate::gpu_types::COARSE_TRIANGLES_PER_PATCH as u32;
    TriContext::new(prep, test_inputs(prep, cps, params, p), bits, t)
}

/// [`tri_context`] with each patch's threshold from `thresholds`.
pub fn tri_context_at<'a>(
    prep: &'a PreparedBezier,
    cps: &'a [[Vec3; 16]],
    bits: &'a [EdgeBits],
    params: &AdaptiveParams,
    thresholds: &[f32],
    t: u32,
) -> TriContext<'a> {
    let p = t / crate::gpu_types::COARSE_TRIANGLES_PER_PATCH as u32;
    TriContext::new(
        prep,
        test_inputs_at(prep, cps, params, thresholds[p as usize], p),
        bits,
        t,
    )
}

struct CountSink(u32);

impl TriangleSink for CountSink {
    fn triangle(&mut self, _tri: [VertexRef; 3]) {
        self.0 += 1;
    }
}

/// Stage 3b, one work item per coarse triangle: how many triangles it makes, by
/// Euler's formula where it applies ([`euler_count`]), else by replaying the
/// bisection.
pub fn tri_count(ctx: &TriContext, scratch: &TriScratch) -> u32 {
    euler_count(ctx, scratch).unwrap_or_else(|| replay_count(ctx, scratch))
}

/// The triangle count of a coarse triangle from its vertex counts alone.
///
/// The leaves' triangulation covers the coarse triangle's lattice triangle with
/// triangles of non-zero area whose corners are exactly the existing points, so it is a
/// triangulated disk: `T = 2·I + B − 2` for `I` inner and `B` boundary points (Euler,
/// with each inner edge in two triangles and each boundary edge in one). The boundary
/// holds the 3 corners, the points of each side's coarse edge, and the pole points `P`
/// of a side collapsed to a point. The triangles on a collapsed side, one per boundary
/// segment (`P + 1`), have two corners on its one vertex and are dropped. So
/// `T = 2·I + 1 + Σ (edge points of the open sides) − (collapsed sides)`.
///
/// That holds while the only shared vertex is one collapsed side's (the corners'
/// ids otherwise distinct): a patch degenerate enough to break it returns `None`.
pub fn euler_count(ctx: &TriContext, scratch: &TriScratch) -> Option<u32> {
    let mut count = 2 * scratch.inner_count() + 1;
    for (k, &(e, _, is_collapsed)) in ctx.sides.iter().enumerate() {
        let [a, b, c] = [k, (k + 1) % 3, (k + 2) % 3].map(|i| ctx.corner_ids[i]);
        if is_collapsed {
            // Checked first: a second collapsed side always fails it (all three corners
            // are then one vertex), so `count` (at least 1) is lowered at most once.
            if a != b || c == a {
                return None;
            }
            count -= 1;
        } else {
            count += bit_count(&ctx.edge_bits[e as usize]);
            if a == b {
                return None;
            }
        }
    }
    Some(count)
}

/// The triangle count by replaying the bisection and triangulating every leaf.
pub fn replay_count(ctx: &TriContext, scratch: &TriScratch) -> u32 {
    let mut sink = CountSink(0);
    // Any injective numbering of inner points will do for counting.
    tri_triangles(ctx, scratch, &|i| i as u32, &mut sink);
    sink.0
}

/// Where the indices of one coarse triangle go.
struct EmitSink<'a> {
    indices: &'a mut [u32],
    edge_vertex_base: u32,
    edge_offsets: &'a [u32],
    inner_base: u32,
    next_index: usize,
}

impl TriangleSink for EmitSink<'_> {
    fn triangle(&mut self, tri: [VertexRef; 3]) {
        for v in tri {
            self.indices[self.next_index] = match v {
                VertexRef::Coarse(id) => id,
                VertexRef::Edge { edge, rank } => {
                    self.edge_vertex_base + self.edge_offsets[edge as usize] + rank
                }
                VertexRef::Inner(n) => self.inner_base + n,
            };
            self.next_index += 1;
        }
    }
}

/// Stage 5b, one work item per coarse edge: records of its inserted points.
pub fn edge_emit(
    prep: &PreparedBezier,
    bits: &EdgeBits,
    e: u32,
    first: u32,
    records: &mut [VertexRecord],
) {
    let (p, uv0, uv1) = edge_endpoints(prep, e);
    for (rank, k) in bit_positions(bits).enumerate() {
        let [u, v] = lerp_uv(uv0, uv1, k);
        records[first as usize + rank] = VertexRecord { patch: p, u, v };
    }
}

/// Whether the root of a coarse triangle's bisection is known to be a leaf without the
/// interior test: its hypotenuse is a coarse side (the cell's diagonal), whose own
/// decision says whether its midpoint is a point. `false` where that does not decide (a
/// collapsed side, which a cell's diagonal never is: a guard). Twin of `root_known_leaf`
/// in `shaders/shared/refine.wgsl`, which the root kernel (`bezier_tri_roots.wgsl`) asks
/// so that the mark kernel walks only the triangles that split.
pub fn root_known_leaf(ctx: &TriContext) -> bool {
    let root = ctx.lattice.root();
    match ctx.lattice.common_side(root[1], root[2]) {
        Some(side) if !ctx.sides[side].2 => !splits(ctx, root, 0).0,
        _ => false,
    }
}

/// Whether a coarse triangle is plain: no point inside, none on its sides, no side
/// collapsed, one triangle made. Its mesh is then its corners, which
/// [`tri_emit_plain`] writes without the bisection walk.
pub fn is_plain(ctx: &TriContext, inner: u32, made: u32) -> bool {
    inner == 0
        && made == 1
        && ctx
            .sides
            .iter()
            .all(|&(e, _, collapsed)| !collapsed && bit_count(&ctx.edge_bits[e as usize]) == 0)
}

/// The emit-order bucket of a coarse triangle that makes `made` triangles: plain ones
/// ([`is_plain`]) last, in a bucket of their own; the others those that make the most
/// first, every count from `ORDER_BUCKETS - 2` up sharing bucket 0.
pub fn order_bucket(made: u32, plain: bool) -> u32 {
    let plain_bucket = tally::ORDER_BUCKETS - 1;
    if plain {
        return plain_bucket;
    }
    let last = plain_bucket - 1;
    last - made.min(last)
}

/// Stage 4b: the order stage 5c takes the coarse triangles in, from each one's bucket
/// ([`order_bucket`]), by bucket and by index within one. Twin of the bucket slots in
/// `bezier_finish.wgsl` and of `bezier_tri_order.wgsl`, whose slots within a bucket are
/// taken by atomics in any order. The mesh does not depend on it: each triangle writes
/// where the scan says. A SIMD device runs lanes side by side in lockstep, each loop as
/// long as its longest lane, so lanes with alike work waste less; and the plain
/// triangles, last, go to a kernel of their own.
pub fn emit_order(buckets: &[u32]) -> Vec<u32> {
    // The finish kernel's half: each bucket's first slot.
    let mut first = vec![0u32; tally::ORDER_BUCKETS as usize];
    for &b in buckets {
        first[b as usize] += 1;
    }
    exclusive_scan(&mut first);
    // The order kernel's half: one slot per triangle.
    let mut order = vec![0u32; buckets.len()];
    for (t, &b) in buckets.iter().enumerate() {
        let slot = &mut first[b as usize];
        order[*slot as usize] = t as u32;
        *slot += 1;
    }
    order
}

/// Stage 5d, one work item per plain coarse triangle ([`is_plain`]): its one triangle,
/// the corners of its root as the walk would emit them. Twin of
/// `bezier_tri_emit_plain.wgsl`.
pub fn tri_emit_plain(ctx: &TriContext, first_index: u32, indices: &mut [u32]) {
    let corners = ctx.lattice.root().map(|p| ctx.vertex(p, &|_| 0));
    let mut sink = EmitSink {
        indices,
        edge_vertex_base: 0,
        edge_offsets: &[],
        inner_base: 0,
        next_index: first_index as usize,
    };
    let [a, b, c] = corners;
    sink.triangle(if ctx.flipped { [a, c, b] } else { [a, b, c] });
}

/// Stage 5c, one work item per coarse triangle that is not plain (the plain ones are
/// [`tri_emit_plain`]'s): records of its inner points (in lattice order) and its indices.
#[allow(clippy::too_many_arguments)]
pub fn tri_emit(
    ctx: &TriContext,
    scratch: &TriScratch,
    edge_vertex_base: u32,
    edge_offsets: &[u32],
    inner_base: u32,
    first_index: u32,
    records: &mut [VertexRecord],
    indices: &mut [u32],
) {
    let points = &scratch.points;
    let mut next = inner_base as usize;
    // Inner points before each word, set for the words of groups that hold points (the
    // only ones a rank is asked of).
    let mut prefix = vec![0; points.len()];
    let mut rows = LatticeRows::default();
    let mut groups = scratch.groups;
    while groups != 0 {
        let g = groups.trailing_zeros();
        groups &= groups - 1;
        let first = (g << scratch.group_shift) as usize;
        let end = (((g + 1) << scratch.group_shift) as usize).min(points.len());
        for w in first..end {
            prefix[w] = next as u32 - inner_base;
            let mut bits = points[w];
            while bits != 0 {
                let i = 32 * w + bits.trailing_zeros() as usize;
                bits &= bits - 1;
                rows = rows.seek(&ctx.lattice, i);
                let [u, v] = ctx.lattice.uv(rows.point(i));
                records[next] = VertexRecord {
                    patch: ctx.lattice.patch,
                    u,
                    v,
                };
                next += 1;
            }
        }
    }
    let mut sink = EmitSink {
        indices,
        edge_vertex_base,
        edge_offsets,
        inner_base,
        next_index: first_index as usize,
    };
    tri_triangles(ctx, scratch, &|i| inner_rank(points, &prefix, i), &mut sink);
}

/// Stage 6, one work item per output vertex: position, normal (facing the patch's
/// front after orientation), parameter and patch.
pub fn vertex_eval(prep: &PreparedBezier, cps: &[[Vec3; 16]], r: &VertexRecord) -> OutVertex {
    let f = eval_frame_f32(&cps[r.patch as usize], r.u, r.v);
    let mut n = frame_normal_f32(&f, r.u, r.v);
    if prep.topo[r.patch as usize].flipped() {
        n = -n;
    }
    OutVertex {
        position: f.pos.to_array(),
        normal: n.to_array(),
        uv: [r.u, r.v],
        face: r.patch,
    }
}

/// Stage 3's marks (the root kernel's, per coarse triangle in view): the triangle's
/// corners are used coarse vertices. `used` holds one flag per coarse vertex.
pub fn mark_used(used: &mut [bool], corner_ids: [u32; 3]) {
    for v in corner_ids {
        used[v as usize] = true;
    }
}

/// Whether output vertex `v` is left unevaluated: a coarse vertex that no coarse
/// triangle in view has as a corner ([`mark_used`]), so that no triangle uses it. Every
/// other vertex is made for a triangle in view.
pub fn unused(used: &[bool], v: usize) -> bool {
    v < used.len() && !used[v]
}

/// [`vertex_eval`] of output vertex `v`, with the coarse vertices in use: an
/// [`unused`] one keeps its parameter and patch, at the origin with no normal.
pub fn vertex_eval_at(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    used: &[bool],
    v: usize,
    r: &VertexRecord,
) -> OutVertex {
    if unused(used, v) {
        return OutVertex {
            position: [0.0; 3],
            normal: [0.0; 3],
            uv: [r.u, r.v],
            face: r.patch,
        };
    }
    vertex_eval(prep, cps, r)
}

/// Runs the whole pipeline on the CPU.
pub fn tessellate_adaptive(prep: &PreparedBezier, params: &AdaptiveParams) -> Result<Tessellation> {
    tessellate_adaptive_timed(prep, params).map(|(t, _)| t)
}

/// [`tessellate_adaptive`] in a view: each patch's threshold scaled to the view's pixels
/// ([`patch_thresholds`]), capped by `params.threshold`.
pub fn tessellate_adaptive_in_view(
    prep: &PreparedBezier,
    params: &AdaptiveParams,
    view: &BezierView,
) -> Result<Tessellation> {
    run_adaptive(prep, params, Some(view)).map(|(t, _)| t)
}

/// Wall time of each stage of a CPU run (ms), to set beside the kernels' own times.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Stages 1 and 2: the coarse edges' decisions and their offsets.
    pub edge_decide: f64,
    /// Stages 3 and 4: marking and counting per coarse triangle, and the offsets.
    pub tri_mark: f64,
    /// Stage 5: vertex records of the edges and the triangles' records and indices.
    pub emit: f64,
    /// Stage 6: one evaluation per vertex.
    pub vertex_eval: f64,
}

/// [`tessellate_adaptive`], timing each stage.
pub fn tessellate_adaptive_timed(
    prep: &PreparedBezier,
    params: &AdaptiveParams,
) -> Result<(Tessellation, StageTimes)> {
    run_adaptive(prep, params, None)
}

fn run_adaptive(
    prep: &PreparedBezier,
    params: &AdaptiveParams,
    view: Option<&BezierView>,
) -> Result<(Tessellation, StageTimes)> {
    params.validate()?;
    let mut times = StageTimes::default();
    let ms = |t: std::time::Instant| t.elapsed().as_secs_f64() * 1e3;
    let start = std::time::Instant::now();
    let l = prep.layout;
    let cps: Vec<[Vec3; 16]> = (0..l.patches).map(|p| prep.control_points(p)).collect();
    let flipped: Vec<bool> = prep.topo.iter().map(|t| t.flipped()).collect();
    let thresholds = patch_thresholds(&cps, &flipped, params.threshold, view)?;
    let mut evaluations = 0u64;

    // 1. Edge decisions.
    let mut bits = Vec::with_capacity(l.coarse_edges as usize);
    for e in 0..l.coarse_edges {
        let (b, ev) = edge_decide_at(prep, &cps, params, &thresholds, e);
        evaluations += ev as u64;
        bits.push(b);
    }
    // 2. Edge vertex offsets.
    let mut edge_offsets: Vec<u32> = bits.iter().map(bit_count).collect();
    let edge_vertices = exclusive_scan(&mut edge_offsets);
    times.edge_decide = ms(start);
    let start = std::time::Instant::now();
    // 3. Per-triangle split trees and counts, 4. their offsets.
    let mut scratch = Vec::with_capacity(l.coarse_triangles as usize);
    let mut inner_offsets = Vec::with_capacity(l.coarse_triangles as usize);
    let mut tri_offsets = Vec::with_capacity(l.coarse_triangles as usize);
    let mut buckets = Vec::with_capacity(l.coarse_triangles as usize);
    let mut plain = Vec::with_capacity(l.coarse_triangles as usize);
    let patch_of = |t: u32| t / crate::gpu_types::COARSE_TRIANGLES_PER_PATCH as u32;
    let mut used = vec![false; l.coarse_vertices as usize];
    for t in 0..l.coarse_triangles {
        let mut s = TriScratch::new(params.max_depth);
        // A culled patch's triangles make nothing and use no vertex (the root kernel's).
        if culled(thresholds[patch_of(t) as usize]) {
            plain.push(false);
            buckets.push(order_bucket(0, false));
            inner_offsets.push(0);
            tri_offsets.push(0);
            scratch.push(s);
            continue;
        }
        let ctx = tri_context_at(prep, &cps, &bits, params, &thresholds, t);
        mark_used(&mut used, ctx.corner_ids);
        // The root kernel's triangles, then the mark kernel's.
        let known = root_known_leaf(&ctx)
            .then(|| euler_count(&ctx, &s))
            .flatten();
        let (inner, made) = match known {
            Some(made) => (0, made),
            None => {
                evaluations += tri_mark(&ctx, &mut s) as u64;
                (s.inner_count(), tri_count(&ctx, &s))
            }
        };
        plain.push(is_plain(&ctx, inner, made));
        buckets.push(order_bucket(made, plain[t as usize]));
        inner_offsets.push(inner);
        tri_offsets.push(made);
        scratch.push(s);
    }
    let inner_vertices = exclusive_scan(&mut inner_offsets);
    let order = emit_order(&buckets);
    let triangles = exclusive_scan(&mut tri_offsets);
    let edge_vertex_base = l.coarse_vertices;
    let inner_vertex_base = edge_vertex_base + edge_vertices;
    let vertex_count = inner_vertex_base + inner_vertices;
    times.tri_mark = ms(start);
    let start = std::time::Instant::now();

    // 5. Emit vertex records and indices.
    let mut records = prep.coarse_vertex_records();
    records.resize(vertex_count as usize, VertexRecord::zeroed());
    for e in 0..l.coarse_edges {
        edge_emit(
            prep,
            &bits[e as usize],
            e,
            edge_vertex_base + edge_offsets[e as usize],
            &mut records,
        );
    }
    let mut indices = vec![0u32; 3 * triangles as usize];
    for t in order {
        if culled(thresholds[patch_of(t) as usize]) {
            continue;
        }
        let ctx = tri_context_at(prep, &cps, &bits, params, &thresholds, t);
        if plain[t as usize] {
            tri_emit_plain(&ctx, 3 * tri_offsets[t as usize], &mut indices);
            continue;
        }
        tri_emit(
            &ctx,
            &scratch[t as usize],
            edge_vertex_base,
            &edge_offsets,
            inner_vertex_base + inner_offsets[t as usize],
            3 * tri_offsets[t as usize],
            &mut records,
            &mut indices,
        );
    }
    times.emit = ms(start);
    let start = std::time::Instant::now();
    // 6. Evaluate each vertex once.
    let vertices: Vec<OutVertex> = records
        .iter()
        .enumerate()
        .map(|(v, r)| vertex_eval_at(prep, &cps, &used, v, r))
        .collect();
    let skipped = (0..records.len()).filter(|&v| unused(&used, v)).count();
    evaluations += (vertices.len() - skipped) as u64;
    times.vertex_eval = ms(start);
    let out = Tessellation {
        mesh: Mesh { vertices, indices },
        evaluations,
        culled_patches: thresholds.iter().filter(|&&th| culled(th)).count(),
    };
    Ok((out, times))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_patchs_threshold_grows_with_its_distance_and_the_world_one_caps_it() {
        // Two unit patches in a plane facing the eye, one twice as far as the other.
        let net = |depth: f32| -> [Vec3; 16] {
            std::array::from_fn(|k| Vec3::new((k % 4) as f32 / 3.0, (k / 4) as f32 / 3.0, -depth))
        };
        let cps = [net(5.0), net(10.0)];
        let view = BezierView {
            view: View::look_at(
                DVec3::ZERO,
                DVec3::new(0.0, 0.0, -1.0),
                DVec3::Y,
                40f64.to_radians(),
                (800, 600),
                0.1,
            )
            .expect("view"),
            pixels: 1.0,
            cull: false,
            cull_backfaces: false,
        };
        let flipped = [false; 2];
        let th = patch_thresholds(&cps, &flipped, 1.0, Some(&view)).expect("thresholds");
        assert!(
            th[0] > 0.0 && th[1] > 1.8 * th[0] && th[1] < 2.5 * th[0],
            "{th:?}"
        );
        // At most a pixel's width at the near patch's depth (the gain counts the
        // off-axis stretch too), and not much less.
        let pixel = 5.0 / (300.0 / (20f64.to_radians()).tan());
        assert!(
            th[0] as f64 <= pixel && th[0] as f64 > 0.7 * pixel,
            "{th:?} {pixel}"
        );
        let capped =
            patch_thresholds(&cps, &flipped, 0.5 * th[1], Some(&view)).expect("thresholds");
        assert_eq!(capped, vec![th[0], 0.5 * th[1]]);
        assert_eq!(
            patch_thresholds(&cps, &flipped, 0.3, None).expect("world"),
            vec![0.3, 0.3]
        );
        let bad = BezierView {
            pixels: 0.0,
            ..view
        };
        assert!(patch_thresholds(&cps, &flipped, 1.0, Some(&bad)).is_err());
    }

    #[test]
    fn emit_order_puts_the_heaviest_first_the_plain_last_and_keeps_index_order_within_a_bucket() {
        let made = [3, 0, 7, 1, 3, 900, 254, 7, 1];
        let plain = [false, false, false, true, false, false, false, false, false];
        let buckets: Vec<u32> = made
            .iter()
            .zip(plain)
            .map(|(&m, p)| order_bucket(m, p))
            .collect();
        let order = emit_order(&buckets);
        // 254 and 900 share the first bucket; ties keep index order; the plain one last.
        assert_eq!(order, vec![5, 6, 2, 7, 0, 4, 8, 1, 3]);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..made.len() as u32).collect::<Vec<_>>());
        assert!(emit_order(&[]).is_empty());
    }

    /// Every coarse triangle of the teaset, marked, at two Map4p thresholds.
    fn for_each_marked_triangle(visit: impl FnMut(&str, &TriContext, &TriScratch)) {
        crate::bezier::test_support::for_each_marked_triangle(
            &["teapot", "teacup", "teaspoon"],
            &[(EdgeTest::Map4p, 0.05), (EdgeTest::Map4p, 0.01)],
            visit,
        );
    }

    /// A root known to be a leaf marks nothing (and many are).
    #[test]
    fn a_root_known_to_be_a_leaf_marks_nothing() {
        let (mut known, mut walked) = (0, 0);
        for_each_marked_triangle(|what, ctx, s| {
            if root_known_leaf(ctx) {
                known += 1;
                let empty = TriScratch::new(ctx.lattice.depth);
                assert_eq!(s.words(), empty.words(), "{what}");
            } else {
                walked += 1;
            }
        });
        assert!(
            known > 500 && walked > 500,
            "{known} known leaves, {walked} walked"
        );
    }

    /// The plain path writes what the bisection walk writes, on every plain coarse
    /// triangle (and there are many).
    #[test]
    fn plain_triangles_emit_what_the_walk_emits() {
        let mut plain_seen = 0;
        for_each_marked_triangle(|what, ctx, s| {
            if !is_plain(ctx, s.inner_count(), tri_count(ctx, s)) {
                return;
            }
            plain_seen += 1;
            let (mut walked, mut plain) = ([0u32; 3], [0u32; 3]);
            let mut records = [];
            tri_emit(ctx, s, 0, &[], 0, 0, &mut records, &mut walked);
            tri_emit_plain(ctx, 0, &mut plain);
            assert_eq!(plain, walked, "{what}");
        });
        assert!(plain_seen > 500, "only {plain_seen} plain coarse triangles");
    }
}
