//! Triangulation of a leaf's polygon (its corners plus the marked vertices on its
//! sides) without new vertices, T-junctions or zero-area triangles. CPU twin of
//! `shaders/cc_triangulate.wgsl`.
//!
//! The polygon is the cell's rectangle in the parameter plane with extra vertices on its
//! sides. It is zipped from one corner `s` to the opposite corner `e`: the chain `L`
//! runs forward from `s` to `e` (through corner `s + 1`), the chain `R` backward
//! (through `s - 1`); the first triangle is `(R₀, s, L₀)`, then each step advances the
//! chain whose next vertex is nearer `s` along the diagonal, and the last triangle is
//! `(L_last, e, R_last)`. No triangle is degenerate: the vertices of `L` other than `s`
//! and `e` lie on the two sides at `s + 1`, those of `R` on the two sides at `s - 1`, and
//! a side line of one chain meets the other chain's sides only at `s` or `e` (or is
//! parallel to them). A plain quad gets the diagonal `(s + 1, s - 1)`: the zip starts at a
//! corner of the longer diagonal in space, so a quad is cut along its shorter one.

use glam::DVec3;

/// A polygon vertex: integer parameter coordinates and the output vertex id.
#[derive(Clone, Copy, Debug)]
pub struct PolyVertex {
    /// Parameter coordinate along u, in grid units.
    pub i: i64,
    /// Parameter coordinate along v, in grid units.
    pub j: i64,
    /// The id the output triangles are written with.
    pub id: u32,
}

/// Relative margin by which the diagonals must differ before the second is chosen:
/// diagonals equal in exact arithmetic (symmetric models) then pick the same corner in
/// single and double precision.
pub const DIAGONAL_MARGIN: f64 = 1e-4;

/// The corner the zip starts from: 1 (diagonal 0–2 kept) unless 1–3 is shorter by more
/// than the margin.
pub fn zip_start(d02: f64, d13: f64) -> usize {
    if d02 <= d13 * (1.0 + DIAGONAL_MARGIN) {
        1
    } else {
        0
    }
}

/// Appends the counter-clockwise triangles of `poly` (counter-clockwise in the parameter
/// plane; `corners` are the indices of the cell's corners, the first at its smallest
/// `(i, j)`) to `out`; `position` gives the space position of an output vertex.
pub fn triangulate(
    poly: &[PolyVertex],
    corners: [usize; 4],
    position: impl Fn(u32) -> DVec3,
    out: &mut Vec<u32>,
) {
    let m = poly.len();
    let at = |k: usize| poly[corners[k]];
    let d02 = (position(at(0).id) - position(at(2).id)).length_squared();
    let d13 = (position(at(1).id) - position(at(3).id)).length_squared();
    let s = zip_start(d02, d13);
    let (start, end) = (corners[s], corners[s + 2]);
    // Progress toward the end corner along the diagonal, in integers: in the cell's unit
    // coordinates (x, y) it is x + y from corner 0 and (1 - x) + y from corner 1.
    let (c0, c2) = (at(0), at(2));
    let (w, h) = (c2.i - c0.i, c2.j - c0.j);
    let progress = |v: PolyVertex| {
        let x = if s == 0 { v.i - c0.i } else { c2.i - v.i };
        x * h + (v.j - c0.j) * w
    };
    let forward = |k: usize| poly[(start + 1 + k) % m];
    let backward = |k: usize| poly[(start + m - 1 - k) % m];
    let len_l = (end + m - start) % m - 1;
    let len_r = (start + m - end) % m - 1;
    out.extend([backward(0).id, poly[start].id, forward(0).id]);
    let (mut l, mut r) = (0, 0);
    while l + 1 < len_l || r + 1 < len_r {
        let advance_l = r + 1 == len_r
            || (l + 1 < len_l && progress(forward(l + 1)) <= progress(backward(r + 1)));
        if advance_l {
            out.extend([backward(r).id, forward(l).id, forward(l + 1).id]);
            l += 1;
        } else {
            out.extend([backward(r + 1).id, backward(r).id, forward(l).id]);
            r += 1;
        }
    }
    out.extend([forward(l).id, poly[end].id, backward(r).id]);
}
