//! Base-quadrilateral replacement as the GPU does it: the CPU twin of the kernel
//! `shaders/cc_polygon.wgsl`, one call per invocation, written to read like it.
//!
//! Each side of a leaf is replaced by the marked points on it, found by looking their
//! keys in the leaf's chart up in the vertex hash (a point marked in the chart across a
//! seam is in the hash in both: [`super::gpu_model::leaf_items`]). Inside a patch every cell lies on the grid of the patch's
//! first split, so the points on a side are dyadic subdivisions of it: if its midpoint is
//! marked, look in both halves, else there is none. On the patch boundary the points
//! come from the patch across the edge, whose first split may differ: its root cells
//! divide the edge in steps of `grid / k`, and inside each step the same search applies.
//!
//! A face leaf's sides each run along two patches of its face, through the level-1 edge
//! point where it is marked, and its points are in the face's grid ([`face_grid`]).
//!
//! The CPU reference ([`super::adaptive`], step 2) builds the same polygons another way,
//! from sorted lines of marked points; a test checks that both agree.

use super::keys::topo_chart_key;
use super::vertex_hash::split_key;
use crate::gpu_types::{
    cc_trial_split, CcCell, CcPatchTopo, CC_CELL_CULLED, CC_CELL_FACE, CC_CELL_PATCH_CULLED,
    CC_NO_NEIGHBOUR,
};

/// What the kernel reads besides the leaf: the grid, the patches' connectivity, their
/// first splits and the vertex hash.
pub struct PolygonKernel<'a> {
    /// `840 · 2^max_depth`: grid units per patch side.
    pub grid: u32,
    /// Connectivity of each patch (binding 59).
    pub topo: &'a [CcPatchTopo],
    /// Per patch, the trial ([`cc_trial_split`]) of its first split: the kernel's `best[p].y`.
    pub first_trial: &'a [u32],
    /// The vertex of a marked point's chart key ([`super::keys::chart_key`]), `None` if
    /// the point is not marked: the kernel's `cc_find` in the hash table, then `ids`.
    pub vertex_of: &'a dyn Fn([u32; 2]) -> Option<u32>,
}

/// A polygon vertex as the kernel writes it: vertex id, grid point `(i, j)`, 0.
pub type PolyVert = [u32; 4];

/// The line a side runs along: a patch-boundary edge (positions are canonical t along
/// it) or a row or column inside the patch (positions are i or j).
#[derive(Clone, Copy, Default)]
struct Line {
    patch_id: u32,
    /// 0..4: edge k of the patch; 4: inside.
    edge_side: u32,
    /// The other coordinate of a row or column.
    fixed: u32,
    is_row: bool,
}

/// One invocation's private state: its line, and the points found so far (the kernel
/// counts them in `found` and writes them only when emitting).
struct Walk<'k, 'a> {
    kernel: &'k PolygonKernel<'a>,
    line: Line,
    line_topo: CcPatchTopo,
    found: Vec<PolyVert>,
    /// In a face leaf's polygon: the patch of the face whose grid the points are in
    /// (they go out in the face's grid, [`face_grid`]); 4 in a leaf's own.
    face_k: u32,
}

/// Point `q` of the patch at corner `k` of a quad face in the face's grid: units of
/// `1/(2n)` of its side, `(0, 0)` at its first vertex (`cc_face_grid`).
pub fn face_grid(grid: u32, k: u32, (i, j): (u32, u32)) -> (u32, u32) {
    let m = 2 * grid;
    match k {
        0 => (i, j),
        1 => (m - j, i),
        2 => (m - i, m - j),
        _ => (j, m - i),
    }
}

/// Width and height of a cell in grid units (`cc_cell_size`).
fn cell_size(grid: u32, cell: &CcCell) -> (u32, u32) {
    let (ku, kv) = cc_trial_split(cell.trial_depth & 0xff);
    let depth = (cell.trial_depth & !(CC_CELL_CULLED | CC_CELL_PATCH_CULLED | CC_CELL_FACE)) >> 8;
    ((grid / ku) >> depth, (grid / kv) >> depth)
}

/// Corner k of a cell, counter-clockwise from its lower-left (`cc_cell_corner`).
pub fn cell_corner(grid: u32, cell: &CcCell, k: u32) -> (u32, u32) {
    let (w, h) = cell_size(grid, cell);
    let (ox, oy) = (u32::from(k == 1 || k == 2), u32::from(k >= 2));
    (cell.i + ox * w, cell.j + oy * h)
}

/// Distance from corner k along edge k, counted from the edge's smaller end point
/// (`cc_edge_canonical`).
fn edge_canonical(grid: u32, topo: &CcPatchTopo, k: u32, t: u32) -> u32 {
    if topo.quad[k as usize] < topo.quad[(k as usize + 1) % 4] {
        t
    } else {
        grid - t
    }
}

impl Walk<'_, '_> {
    /// Grid point of the leaf's patch at position x of the line.
    fn line_point(&self, x: u32) -> (u32, u32) {
        let n = self.kernel.grid;
        let line = self.line;
        if line.edge_side < 4 {
            let local = edge_canonical(n, &self.line_topo, line.edge_side, x);
            return match line.edge_side {
                0 => (local, 0),
                1 => (n, local),
                2 => (n - local, n),
                _ => (0, n - local),
            };
        }
        if line.is_row {
            (x, line.fixed)
        } else {
            (line.fixed, x)
        }
    }

    /// The vertex at position x of the line in the leaf's chart, `None` if the point is
    /// not marked (`line_slot`).
    fn line_vertex(&self, x: u32) -> Option<u32> {
        let (i, j) = self.line_point(x);
        let patch = self.line.patch_id as usize;
        let key = topo_chart_key(&self.line_topo, patch, i, j, self.kernel.grid);
        (self.kernel.vertex_of)(split_key(key))
    }

    fn found_point(&mut self, x: u32, id: u32) {
        self.found_at(self.line_point(x), id);
    }

    fn found_at(&mut self, q: (u32, u32), id: u32) {
        let (i, j) = if self.face_k < 4 {
            face_grid(self.kernel.grid, self.face_k, q)
        } else {
            q
        };
        self.found.push([id, i, j, 0]);
    }

    /// Side s of a face leaf (the quad face whose first patch is `first`), from vertex s
    /// to vertex s + 1: along patch s's side v = 0 to the level-1 edge point, the point
    /// itself where it is marked, then along patch s + 1's side u = 0
    /// (`face_side_walk`).
    fn face_side_walk(&mut self, first: u32, s: u32) {
        let n = self.kernel.grid;
        let (p, q) = (first + s, first + (s + 1) % 4);
        let whole = |patch_id| CcCell {
            patch_id,
            trial_depth: 0,
            i: 0,
            j: 0,
        };
        self.line_topo = self.kernel.topo[p as usize];
        self.face_k = s;
        self.side_walk(&whole(p), 0);
        let key = topo_chart_key(&self.line_topo, p as usize, n, 0, n);
        if let Some(id) = (self.kernel.vertex_of)(split_key(key)) {
            self.found_at((n, 0), id);
        }
        self.line_topo = self.kernel.topo[q as usize];
        self.face_k = (s + 1) % 4;
        self.side_walk(&whole(q), 3);
    }

    /// The points on side s of leaf `cell` (`leaf_side_walk`).
    fn leaf_side_walk(&mut self, cell: &CcCell, s: u32) {
        if cell.trial_depth & CC_CELL_FACE != 0 {
            self.face_side_walk(cell.patch_id, s);
        } else {
            self.side_walk(cell, s);
        }
    }

    /// The marked points strictly inside (lo, hi) among the dyadic subdivisions of the
    /// segment [a, b], in order (ascending or not): in-order walk with an explicit stack.
    fn dyadic_walk(&mut self, a: u32, b: u32, lo: u32, hi: u32, ascending: bool) {
        let mut stack = [(0u32, 0u32, 0u32); 24];
        let mut len = 0;
        let mut cur = (a, b);
        for _guard in 0..4096 {
            // Go down toward the near end while the midpoint is marked.
            loop {
                let s = cur.1 - cur.0;
                if s & 1 != 0 || cur.0 >= hi || cur.1 <= lo {
                    break;
                }
                let m = cur.0 + s / 2;
                let Some(id) = self.line_vertex(m) else {
                    break;
                };
                if len >= 24 {
                    break;
                }
                if ascending {
                    stack[len] = (m, cur.1, id);
                    cur = (cur.0, m);
                } else {
                    stack[len] = (cur.0, m, id);
                    cur = (m, cur.1);
                }
                len += 1;
            }
            if len == 0 {
                return;
            }
            len -= 1;
            let e = stack[len];
            let m = if ascending { e.0 } else { e.1 };
            if m > lo && m < hi {
                self.found_point(m, e.2);
            }
            cur = (e.0, e.1);
        }
    }

    /// Walks side s of the leaf from its corner s to corner s + 1.
    fn side_walk(&mut self, cell: &CcCell, s: u32) {
        let n = self.kernel.grid;
        let side_from = cell_corner(n, cell, s);
        let side_to = cell_corner(n, cell, (s + 1) % 4);
        self.line.patch_id = cell.patch_id;
        let on_edge = match s {
            0 if side_from.1 == 0 => 0,
            1 if side_from.0 == n => 1,
            2 if side_from.1 == n => 2,
            3 if side_from.0 == 0 => 3,
            _ => 4,
        };
        self.line.edge_side = on_edge;
        if on_edge == 4 {
            self.line.is_row = s == 0 || s == 2;
            let (fixed, ta, tb) = if self.line.is_row {
                (side_from.1, side_from.0, side_to.0)
            } else {
                (side_from.0, side_from.1, side_to.1)
            };
            self.line.fixed = fixed;
            self.dyadic_walk(ta.min(tb), ta.max(tb), ta.min(tb), ta.max(tb), ta < tb);
            return;
        }
        // Canonical positions along the level-1 edge, and the patch across it.
        let local = [side_from.0, side_from.1, n - side_from.0, n - side_from.1];
        let local_to = [side_to.0, side_to.1, n - side_to.0, n - side_to.1];
        let e = on_edge as usize;
        let ta = edge_canonical(n, &self.line_topo, on_edge, local[e]);
        let tb = edge_canonical(n, &self.line_topo, on_edge, local_to[e]);
        let across = self.line_topo.across[e];
        if across == CC_NO_NEIGHBOUR {
            return;
        }
        let q = (across >> 2) as usize;
        // A patch of a face leaf chose trial 0, its one cell (marked CC_CHOSEN_FACE_LEAF).
        let (ku, kv) = cc_trial_split(self.kernel.first_trial[q] & 0xff);
        // Edges 0 and 2 of the patch across run along its u, 1 and 3 along its v.
        let k = if across & 1 == 0 { ku } else { kv };
        let step = n / k;
        let (lo, hi) = (ta.min(tb), ta.max(tb));
        let ascending = ta < tb;
        let first = lo / step;
        let last = hi.div_ceil(step); // exclusive
        for g in 0..last - first {
            let root = if ascending { first + g } else { last - 1 - g };
            let a = root * step;
            let b = a + step;
            // Order: the root's near end (a boundary point of the patch across), then inside.
            let near = if ascending { a } else { b };
            if near > lo && near < hi {
                if let Some(id) = self.line_vertex(near) {
                    self.found_point(near, id);
                }
            }
            self.dyadic_walk(a, b, lo, hi, ascending);
        }
    }
}

impl<'a> PolygonKernel<'a> {
    fn walk(&self, cell: &CcCell) -> Walk<'_, 'a> {
        Walk {
            kernel: self,
            line: Line::default(),
            line_topo: self.topo[cell.patch_id as usize],
            found: Vec::new(),
            face_k: 4,
        }
    }

    /// Entry point `count`: how many points each side of the leaf gets (the kernel also
    /// writes the polygon's size, `4 +` their sum, for the scan).
    pub fn count(&self, cell: &CcCell) -> [u32; 4] {
        let mut walk = self.walk(cell);
        let mut counts = [0; 4];
        for s in 0..4 {
            walk.found.clear();
            walk.leaf_side_walk(cell, s);
            counts[s as usize] = walk.found.len() as u32;
        }
        counts
    }

    /// Entry point `emit`: the leaf's polygon, corner 0, the points of side 0 in order,
    /// corner 1, ...; `corner_ids` are the corners' vertices (the kernel reads them in
    /// `ids`, items `8 · leaf + corner`), `counts` what [`count`](Self::count) found on
    /// each side (a side without points is not walked again).
    pub fn emit(
        &self,
        cell: &CcCell,
        corner_ids: [u32; 4],
        counts: [u32; 4],
        out: &mut Vec<PolyVert>,
    ) {
        let mut walk = self.walk(cell);
        let face = cell.trial_depth & CC_CELL_FACE != 0;
        for s in 0..4 {
            // A face leaf's corner s is vertex s of the face, in the face's grid.
            let (i, j) = if face {
                face_grid(self.grid, s, (0, 0))
            } else {
                cell_corner(self.grid, cell, s)
            };
            out.push([corner_ids[s as usize], i, j, 0]);
            if counts[s as usize] > 0 {
                walk.found.clear();
                walk.leaf_side_walk(cell, s);
                out.extend_from_slice(&walk.found);
            }
        }
    }
}
