//! Layer-strip subdivision of one coarse triangle. CPU twin of
//! `shaders/bezier_tri_count.wgsl` and `shaders/bezier_tri_emit.wgsl`.
//!
//! The pattern, decided entirely from edge bits and map tests before any vertex is
//! evaluated:
//! 1. The apex `A` is the corner opposite the edge with the fewest segments; `B`, `C`
//!    follow counter-clockwise. The sides `A→B` and `A→C` carry their edges' points.
//! 2. Rows ("rungs") join a point of `A→B` to a point of `A→C`, walking down both sides
//!    in step (the side whose next point is nearer to `A` moves; both move on a tie).
//!    The last row is the base `B→C` with its own edge points.
//! 3. Each inner row is split by the same edge test as the coarse edges (the tests
//!    inside the triangle); its new points are the triangle's own vertices.
//! 4. Consecutive rows are stitched into a strip by a zipper that walks both rows
//!    left to right. Rows only meet at shared end points, handled explicitly.
//!
//! Every vertex on a coarse edge is the edge's, shared by index with the triangle on the
//! other side (and the other patch on a shared boundary); each row is built once and
//! used by the strips above and below it.

use super::coarse_edges::coarse_edge_of;
use super::edge_tests::{
    bit_count, bit_is_set, lerp_uv, subdivide_interval, EdgeBits, TestInputs, DYADIC_SCALE,
};
use super::prepare::{coarse_triangle_grid, PreparedBezier};
use crate::gpu_types::{VertexRecord, COARSE_SEGMENTS, COARSE_TRIANGLES_PER_PATCH};

/// A vertex as the triangle stage sees it, before global numbering.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRef {
    /// A coarse grid vertex (global id).
    Coarse(u32),
    /// The `rank`-th inserted point of a coarse edge, in canonical order.
    Edge { edge: u32, rank: u32 },
    /// The `n`-th vertex created inside this coarse triangle.
    Inner(u32),
}

/// Receives what the triangle stage produces; a counting sink and a writing sink give
/// the count and emit passes.
pub trait StripSink {
    fn inner_vertex(&mut self, local: u32, record: VertexRecord);
    fn triangle(&mut self, tri: [VertexRef; 3]);
    fn evaluations(&mut self, n: u32);
}

#[derive(Clone, Copy, Debug)]
struct RowPoint {
    vertex: VertexRef,
    /// Position along its row, in 1/256ths.
    f: u32,
    uv: [f32; 2],
}

/// The points of coarse edge `edge` from `from` to `to` (triangle corners), in that
/// order, with `forward` telling whether that is the edge's canonical direction.
fn side_points(
    edge: u32,
    forward: bool,
    bits: &EdgeBits,
    from: (VertexRef, [f32; 2]),
    to: (VertexRef, [f32; 2]),
) -> Vec<RowPoint> {
    let count = bit_count(bits);
    let mut pts = Vec::with_capacity(count as usize + 2);
    pts.push(RowPoint {
        vertex: from.0,
        f: 0,
        uv: from.1,
    });
    let mut rank = 0;
    for k in 1..DYADIC_SCALE {
        let kc = if forward { k } else { DYADIC_SCALE - k };
        if bit_is_set(bits, kc) {
            let r = if forward { rank } else { count - 1 - rank };
            pts.push(RowPoint {
                vertex: VertexRef::Edge { edge, rank: r },
                f: k,
                uv: lerp_uv(from.1, to.1, k),
            });
            rank += 1;
        }
    }
    pts.push(RowPoint {
        vertex: to.0,
        f: DYADIC_SCALE,
        uv: to.1,
    });
    pts
}

struct Emitter<'a, S: StripSink> {
    sink: &'a mut S,
    flipped: bool,
}

impl<S: StripSink> Emitter<'_, S> {
    /// Emits `(a, b, c)`, counter-clockwise in `(u, v)`, unless two of its corners are
    /// one vertex (a coarse edge collapsed to a point): that triangle has no area.
    fn tri(&mut self, a: &RowPoint, b: &RowPoint, c: &RowPoint) {
        let (a, b, c) = (a.vertex, b.vertex, c.vertex);
        if a == b || b == c || a == c {
            return;
        }
        self.sink
            .triangle(if self.flipped { [a, c, b] } else { [a, b, c] });
    }

    /// Stitches the upper row `p` (nearer the apex) to the lower row `q`, both running
    /// from the `A→B` side to the `A→C` side. `shared_start`/`shared_end`: the rows
    /// share their first/last point.
    fn zip(&mut self, p: &[RowPoint], q: &[RowPoint], shared_start: bool, shared_end: bool) {
        let (a, b) = (p.len() - 1, q.len() - 1);
        let (mut i, mut j) = (0, 0);
        let (end_i, end_j) = if shared_end { (a - 1, b - 1) } else { (a, b) };
        if shared_start {
            // Of the three points p0 = q0, q1, p1, no two lie on one row's line twice.
            self.tri(&p[0], &q[1], &p[1]);
            (i, j) = (1, 1);
        }
        while i < end_i || j < end_j {
            let advance_p = if i == end_i {
                false
            } else if j == end_j {
                true
            } else {
                p[i + 1].f < q[j + 1].f
            };
            if advance_p {
                self.tri(&p[i], &q[j], &p[i + 1]);
                i += 1;
            } else {
                self.tri(&p[i], &q[j], &q[j + 1]);
                j += 1;
            }
        }
        if shared_end {
            self.tri(&p[end_i], &q[end_j], &q[b]);
        }
    }
}

/// Builds the inner row from side point `l` to side point `r`. First evenly spaced
/// points: as many segments as the base has, scaled by how far down the sides the row
/// lies (an evenly refined triangle thus becomes the regular lattice). Then the edge
/// test, run on each of those segments, refines where the inside of the triangle needs
/// it (a twisted patch can curve along a row while its base is straight). Its points
/// are new vertices of this triangle.
fn inner_row<S: StripSink>(
    emit: &mut Emitter<'_, S>,
    inputs: &TestInputs,
    patch: u32,
    l: RowPoint,
    r: RowPoint,
    base_segments: u32,
    next_inner: &mut u32,
) -> Vec<RowPoint> {
    // Row position down the sides, in 1/512ths: (fl + fr) / 2 of 256.
    let along = l.f + r.f;
    let segments =
        ((base_segments * along + DYADIC_SCALE) / (2 * DYADIC_SCALE)).clamp(1, DYADIC_SCALE / 2);
    let mut bits = [0u32; crate::gpu_types::EDGE_BIT_WORDS];
    let depth = inputs.max_depth.saturating_sub(ceil_log2(segments));
    let mut lo = 0;
    for k in 1..=segments {
        let hi = k * DYADIC_SCALE / segments;
        let evals = subdivide_interval(inputs, l.uv, r.uv, lo, hi, depth, &mut bits);
        emit.sink.evaluations(evals);
        if k < segments {
            bits[(hi / 32) as usize] |= 1 << (hi % 32);
        }
        lo = hi;
    }
    let mut row = Vec::with_capacity(segments as usize + 1);
    row.push(RowPoint { f: 0, ..l });
    for k in 1..DYADIC_SCALE {
        if bit_is_set(&bits, k) {
            let uv = lerp_uv(l.uv, r.uv, k);
            emit.sink.inner_vertex(
                *next_inner,
                VertexRecord {
                    patch,
                    u: uv[0],
                    v: uv[1],
                },
            );
            row.push(RowPoint {
                vertex: VertexRef::Inner(*next_inner),
                f: k,
                uv,
            });
            *next_inner += 1;
        }
    }
    row.push(RowPoint {
        f: DYADIC_SCALE,
        ..r
    });
    row
}

fn ceil_log2(n: u32) -> u32 {
    32 - (n.max(1) - 1).leading_zeros()
}

/// Runs the layer-strip pattern of coarse triangle `tri` into `sink`.
/// `inputs` are the tests of the triangle's patch.
pub fn layer_strip<S: StripSink>(
    prep: &PreparedBezier,
    edge_bits: &[EdgeBits],
    inputs: &TestInputs,
    tri: u32,
    sink: &mut S,
) {
    let per_patch = COARSE_TRIANGLES_PER_PATCH as u32;
    let (p, local) = (tri / per_patch, tri % per_patch);
    let grid = coarse_triangle_grid(local);
    let n = COARSE_SEGMENTS as f32;
    let corner = |k: usize| {
        let g = grid[k];
        (
            VertexRef::Coarse(prep.coarse_vertex(p, g[0], g[1])),
            [g[0] as f32 / n, g[1] as f32 / n],
        )
    };
    // Edge k runs from corner k to corner k+1.
    let edges: [(u32, bool); 3] =
        std::array::from_fn(|k| coarse_edge_of(prep, p, grid[k], grid[(k + 1) % 3]));
    let segments: [u32; 3] =
        std::array::from_fn(|k| bit_count(&edge_bits[edges[k].0 as usize]) + 1);
    // Apex: the corner opposite the edge with the fewest segments (first one on ties),
    // so that the rows run along the direction that needs the least refinement and the
    // two sides, which carry the row ends, are the most refined and best balanced.
    let mut apex = 0;
    for k in 1..3 {
        if segments[(k + 1) % 3] < segments[(apex + 1) % 3] {
            apex = k;
        }
    }
    let (ka, kb, kc) = (apex, (apex + 1) % 3, (apex + 2) % 3);
    let (a, b, c) = (corner(ka), corner(kb), corner(kc));
    let side = |k: usize, reverse: bool, from, to| {
        let (e, fwd) = edges[k];
        side_points(e, fwd != reverse, &edge_bits[e as usize], from, to)
    };
    let left = side(ka, false, a, b); // A → B along edge ka
    let right = side(kc, true, a, c); // A → C against edge kc (C → A)
    let base = side(kb, false, b, c); // B → C along edge kb

    let mut emit = Emitter {
        sink,
        flipped: prep.topo[p as usize].flipped(),
    };
    let mut next_inner = 0u32;
    let (m, nr) = (left.len() - 1, right.len() - 1);
    let mut prev: Vec<RowPoint> = vec![left[0]];
    let (mut i, mut j) = (1, 1);
    let (mut shared_start, mut shared_end) = (false, false);
    loop {
        let row = if i == m && j == nr {
            base.clone()
        } else {
            inner_row(
                &mut emit,
                inputs,
                p,
                left[i],
                right[j],
                segments[kb],
                &mut next_inner,
            )
        };
        emit.zip(&prev, &row, shared_start, shared_end);
        if i == m && j == nr {
            break;
        }
        // Walk down the sides: the side whose next point is nearer A moves.
        let (move_l, move_r) = if i == m {
            (false, true)
        } else if j == nr {
            (true, false)
        } else {
            let (fl, fr) = (left[i + 1].f, right[j + 1].f);
            (fl <= fr, fr <= fl)
        };
        i += move_l as usize;
        j += move_r as usize;
        shared_start = !move_l;
        shared_end = !move_r;
        prev = row;
    }
}
