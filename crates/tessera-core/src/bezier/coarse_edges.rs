//! Numbering of coarse edges (see [`CoarseLayout`](super::prepare::CoarseLayout)):
//! three per boundary curve in its canonical direction, then 21 per patch.
//! CPU twin of `shaders/shared/coarse.wgsl`.

use super::prepare::coarse_triangle_grid;
use super::prepare::PreparedBezier;
use super::topology::side_uv;
use crate::gpu_types::{COARSE_SEGMENTS, COARSE_TRIANGLES_PER_PATCH, INTERIOR_EDGES_PER_PATCH};

/// The coarse edge joining neighbouring grid points `a → b` of patch `p`, and whether
/// `a → b` runs along the edge's canonical direction.
pub fn coarse_edge_of(prep: &PreparedBezier, p: u32, a: [u32; 2], b: [u32; 2]) -> (u32, bool) {
    let n = COARSE_SEGMENTS as u32;
    let topo = &prep.topo[p as usize];
    let interior = 3 * prep.layout.curves + INTERIOR_EDGES_PER_PATCH as u32 * p;
    let lo = [a[0].min(b[0]), a[1].min(b[1])];
    if a[1] == b[1] {
        // Along u.
        let j = a[1];
        if j == 0 || j == n {
            let side = if j == 0 { 0 } else { 2 };
            return side_edge(
                topo.side_curve(side),
                topo.side_reversed(side),
                lo[0],
                b[0] > a[0],
            );
        }
        return (interior + (j - 1) * 3 + lo[0], b[0] > a[0]);
    }
    if a[0] == b[0] {
        // Along v.
        let i = a[0];
        if i == 0 || i == n {
            let side = if i == 0 { 3 } else { 1 };
            return side_edge(
                topo.side_curve(side),
                topo.side_reversed(side),
                lo[1],
                b[1] > a[1],
            );
        }
        return (interior + 6 + (i - 1) * 3 + lo[1], b[1] > a[1]);
    }
    // The diagonal of cell lo, from (i, j) to (i+1, j+1).
    (interior + 12 + lo[1] * 3 + lo[0], b[0] > a[0])
}

/// Segment `seg` (in the side's own direction) of a side on `curve`.
fn side_edge(curve: u32, reversed: bool, seg: u32, along_side: bool) -> (u32, bool) {
    let n = COARSE_SEGMENTS as u32;
    let canonical_seg = if reversed { n - 1 - seg } else { seg };
    (3 * curve + canonical_seg, along_side != reversed)
}

/// The patch that evaluates points on edge `e`, and the edge's end points in its
/// parameter space, in canonical direction.
pub fn edge_endpoints(prep: &PreparedBezier, e: u32) -> (u32, [f32; 2], [f32; 2]) {
    let n = COARSE_SEGMENTS as f32;
    let curve_edges = 3 * prep.layout.curves;
    if e < curve_edges {
        let c = &prep.curves[(e / 3) as usize];
        let s = (e % 3) as f32;
        return (
            c.owner,
            side_uv(c.owner_side(), s / n),
            side_uv(c.owner_side(), (s + 1.0) / n),
        );
    }
    let (p, a, b) = interior_edge_grid(prep, e);
    let uv = |g: [u32; 2]| [g[0] as f32 / n, g[1] as f32 / n];
    (p, uv(a), uv(b))
}

/// Patch and grid end points (canonical order) of an edge inside a patch
/// (`e >= 3 * curves`).
fn interior_edge_grid(prep: &PreparedBezier, e: u32) -> (u32, [u32; 2], [u32; 2]) {
    let k = e - 3 * prep.layout.curves;
    let p = k / INTERIOR_EDGES_PER_PATCH as u32;
    let local = k % INTERIOR_EDGES_PER_PATCH as u32;
    let (a, b) = if local < 6 {
        let (i, j) = (local % 3, local / 3 + 1);
        ([i, j], [i + 1, j])
    } else if local < 12 {
        let (i, j) = ((local - 6) / 3 + 1, (local - 6) % 3);
        ([i, j], [i, j + 1])
    } else {
        let (i, j) = ((local - 12) % 3, (local - 12) / 3);
        ([i, j], [i + 1, j + 1])
    };
    (p, a, b)
}

/// Whether edge `e` lies on a curve collapsed to a point (it is never split).
pub fn edge_collapsed(prep: &PreparedBezier, e: u32) -> bool {
    e < 3 * prep.layout.curves && prep.curves[(e / 3) as usize].collapsed()
}

/// The coarse triangles on either side of edge `e`: `(triangle, side k of it, whether
/// the side runs along the edge's canonical direction)`. One on an open boundary; on a
/// curve shared by more than two patch sides, the owner's and one other (see
/// [`GpuCurve::other`](crate::gpu_types::GpuCurve::other)).
pub fn coarse_edge_sides(prep: &PreparedBezier, e: u32) -> Vec<(u32, usize, bool)> {
    let n = COARSE_SEGMENTS as u32;
    let curve_edges = 3 * prep.layout.curves;
    // (patch, grid end points of the edge in it).
    let mut users: Vec<(u32, [u32; 2], [u32; 2])> = Vec::with_capacity(2);
    if e < curve_edges {
        let c = &prep.curves[(e / 3) as usize];
        let seg = e % 3;
        let mut sides = vec![(c.owner, c.owner_side())];
        if c.other != crate::gpu_types::GpuCurve::NO_SIDE {
            sides.push((c.other >> 2, (c.other & 3) as usize));
        }
        for (q, side) in sides {
            let s = if prep.topo[q as usize].side_reversed(side) {
                n - 1 - seg
            } else {
                seg
            };
            let at = |t: u32| match side {
                0 => [t, 0],
                1 => [n, t],
                2 => [t, n],
                _ => [0, t],
            };
            users.push((q, at(s), at(s + 1)));
        }
    } else {
        users.push(interior_edge_grid(prep, e));
    }
    let mut out = Vec::with_capacity(2);
    for (q, a, b) in users {
        for local in 0..COARSE_TRIANGLES_PER_PATCH as u32 {
            let grid = coarse_triangle_grid(local);
            for k in 0..3 {
                let (x, y) = (grid[k], grid[(k + 1) % 3]);
                if (x, y) == (a, b) || (x, y) == (b, a) {
                    let (_, forward) = coarse_edge_of(prep, q, x, y);
                    out.push((q * COARSE_TRIANGLES_PER_PATCH as u32 + local, k, forward));
                }
            }
        }
    }
    out
}
