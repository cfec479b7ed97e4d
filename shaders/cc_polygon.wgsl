// Base-quadrilateral replacement, one invocation per leaf: each side of the leaf is
// replaced by the marked points on it, found by looking them up in the vertex hash in
// the leaf's chart (`cc_leaf_keys` puts a point marked across a seam in both charts).
// `count` writes how many points each side gets (and the polygon's size, scanned by the
// host); `emit` writes the polygon: corner 0, the points of side 0 in order, corner 1, ...
//
// Inside a patch every cell lies on the grid of the patch's first split, so the points
// on a side are dyadic subdivisions of it: if its midpoint is marked, look in both
// halves, else there is none. On the patch boundary the points come from the patch
// across the edge, whose own first split may differ: its root cells divide the edge in
// steps of grid / k, and inside each step the same dyadic search applies.
// A face leaf's sides each run along two patches of its face (`face_side_walk`), and its
// points go out in the face's grid.
// Twin: `tessera_core::catmull_clark::polygon`. The CPU reference builds the same
// polygons from sorted lines of marked points instead (`Lines::between` in
// `tessera_core::catmull_clark::adaptive`, step 2); tests compare all three.

#include "shared/cc_tess.wgsl"
#include "shared/cc_poly.wgsl"
#include "shared/cc_hash_key.wgsl"
#include "shared/lane_order.wgsl"

struct CcHashSlotView {
    key_hi: u32,
    key_lo: u32,
    first: u32,
}

@group(0) @binding(41) var<storage, read> table: array<CcHashSlotView>;
@group(0) @binding(45) var<storage, read> ids: array<u32>;
@group(0) @binding(55) var<storage, read> leaves: array<CcCell>;
@group(0) @binding(59) var<storage, read> topo: array<CcPatchTopo>;
@group(0) @binding(63) var<storage, read_write> poly_verts: array<vec4u>;
// Marking's words (`shared/cc_tess.wgsl`): here the trial each patch chose.
@group(0) @binding(57) var<storage, read> marks: array<u32>;

// The slot of a key, or CC_NO_SLOT if it is not in the table (unmarked).
fn cc_find(key: vec2u) -> u32 {
    let capacity = arrayLength(&table);
    var slot = cc_home_slot(key, capacity);
    let hi = ~key.x;
    let lo = ~key.y;
    for (var probe = 0u; probe < CC_HASH_MAX_PROBES; probe++) {
        let s = table[slot];
        if s.key_hi == 0u {
            return CC_NO_SLOT;
        }
        if s.key_hi == hi && s.key_lo == lo {
            return slot;
        }
        slot = (slot + 1u) & (capacity - 1u);
    }
    return CC_NO_SLOT;
}

// The line a side runs along: a patch-boundary edge (positions are canonical t along
// it) or a row or column inside the patch (positions are i or j).
struct CcLine {
    patch_id: u32,
    edge_side: u32, // 0..4: edge k of the patch; 4: inside
    fixed: u32,     // the other coordinate of a row or column
    is_row: bool,
}

var<private> line: CcLine;
var<private> line_topo: CcPatchTopo;
// Output of the walk: how many points so far, and where to write them (emit only).
var<private> found: u32;
var<private> emitting: bool;
var<private> emit_at: u32;
// In a face leaf's polygon: the patch of the face whose grid the points are in (their
// coordinates go out in the face's grid, `cc_face_grid`); 4 in a leaf's own.
var<private> face_k: u32 = 4u;

// Point q of the patch at corner k of a quad face in the face's grid: units of 1/(2n) of
// its side, (0, 0) at its first vertex (`adaptive::face_grid`).
fn cc_face_grid(k: u32, q: vec2u) -> vec2u {
    let m = 2u * cc_params.grid;
    switch k {
        case 0u: { return q; }
        case 1u: { return vec2u(m - q.y, q.x); }
        case 2u: { return vec2u(m - q.x, m - q.y); }
        default: { return vec2u(q.y, m - q.x); }
    }
}

// Grid point of the leaf's patch at position x of the line.
fn line_point(x: u32) -> vec2u {
    let n = cc_params.grid;
    if line.edge_side < 4u {
        let local = cc_edge_canonical(line_topo, line.edge_side, x);
        switch line.edge_side {
            case 0u: { return vec2u(local, 0u); }
            case 1u: { return vec2u(n, local); }
            case 2u: { return vec2u(n - local, n); }
            default: { return vec2u(0u, n - local); }
        }
    }
    if line.is_row {
        return vec2u(x, line.fixed);
    }
    return vec2u(line.fixed, x);
}

fn line_slot(x: u32) -> u32 {
    let q = line_point(x);
    return cc_find(cc_chart_key(line_topo, line.patch_id, q.x, q.y));
}

fn found_point(x: u32, slot: u32) {
    found_at(line_point(x), slot);
}

fn found_at(grid_point: vec2u, slot: u32) {
    if emitting {
        var q = grid_point;
        if face_k < 4u {
            q = cc_face_grid(face_k, q);
        }
        let at = emit_at + found;
        if at < arrayLength(&poly_verts) && at < cc_params.poly_capacity {
            poly_verts[at] = vec4u(ids[~table[slot].first], q.x, q.y, 0u);
        }
    }
    found += 1u;
}

// The marked points strictly inside (lo, hi) among the dyadic subdivisions of the
// segment [a, b], in order (ascending or not): in-order walk with an explicit stack.
fn dyadic_walk(a: u32, b: u32, lo: u32, hi: u32, ascending: bool) {
    var stack: array<vec3u, 24>;
    var len = 0u;
    var cur = vec2u(a, b);
    for (var guard = 0u; guard < 4096u; guard++) {
        // Go down toward the near end while the midpoint is marked.
        loop {
            let s = cur.y - cur.x;
            if (s & 1u) != 0u || cur.x >= hi || cur.y <= lo {
                break;
            }
            let m = cur.x + s / 2u;
            let slot = line_slot(m);
            if slot == CC_NO_SLOT || len >= 24u {
                break;
            }
            if ascending {
                stack[len] = vec3u(m, cur.y, slot);
                cur = vec2u(cur.x, m);
            } else {
                stack[len] = vec3u(cur.x, m, slot);
                cur = vec2u(m, cur.y);
            }
            len += 1u;
        }
        if len == 0u {
            return;
        }
        len -= 1u;
        let e = stack[len];
        let m = select(e.y, e.x, ascending);
        if m > lo && m < hi {
            found_point(m, e.z);
        }
        cur = e.xy;
    }
}

// Walks side s of the leaf from its corner s to corner s + 1.
fn side_walk(cell: CcCell, s: u32) {
    let n = cc_params.grid;
    let side_from = cc_cell_corner(cell, s);
    let side_to = cc_cell_corner(cell, (s + 1u) % 4u);
    line.patch_id = cell.patch_id;
    var on_edge = 4u;
    if s == 0u && side_from.y == 0u {
        on_edge = 0u;
    } else if s == 1u && side_from.x == n {
        on_edge = 1u;
    } else if s == 2u && side_from.y == n {
        on_edge = 2u;
    } else if s == 3u && side_from.x == 0u {
        on_edge = 3u;
    }
    line.edge_side = on_edge;
    if on_edge == 4u {
        line.is_row = s == 0u || s == 2u;
        line.fixed = select(side_from.x, side_from.y, line.is_row);
        let ta = select(side_from.y, side_from.x, line.is_row);
        let tb = select(side_to.y, side_to.x, line.is_row);
        dyadic_walk(min(ta, tb), max(ta, tb), min(ta, tb), max(ta, tb), ta < tb);
        return;
    }
    // Canonical positions along the level-1 edge, and the patch across it.
    let local = array<u32, 4>(side_from.x, side_from.y, n - side_from.x, n - side_from.y);
    let local_to = array<u32, 4>(side_to.x, side_to.y, n - side_to.x, n - side_to.y);
    let ta = cc_edge_canonical(line_topo, on_edge, local[on_edge]);
    let tb = cc_edge_canonical(line_topo, on_edge, local_to[on_edge]);
    let across = line_topo.across[on_edge];
    if across == CC_NO_NEIGHBOUR {
        return;
    }
    let q = across >> 2u;
    // A patch of a face leaf chose trial 0, its one cell (marked CC_CHOSEN_FACE_LEAF).
    let split = cc_trial_split(marks[cc_chosen_at(q)] & 0xffu);
    // Edges 0 and 2 of the patch across run along its u, 1 and 3 along its v.
    let k = select(split.y, split.x, ((across & 3u) % 2u) == 0u);
    let step = n / k;
    let lo = min(ta, tb);
    let hi = max(ta, tb);
    let ascending = ta < tb;
    let first = lo / step;
    let last = (hi + step - 1u) / step; // exclusive
    for (var g = 0u; g < last - first; g++) {
        let root = select(last - 1u - g, first + g, ascending);
        let a = root * step;
        let b = a + step;
        // Order: the root's near end (a boundary point of the patch across), then inside.
        let near = select(b, a, ascending);
        if near > lo && near < hi {
            let slot = line_slot(near);
            if slot != CC_NO_SLOT {
                found_point(near, slot);
            }
        }
        dyadic_walk(a, b, lo, hi, ascending);
    }
}

// Side s of a face leaf (the quad face whose first patch is `first`), from vertex s to
// vertex s + 1: along patch s's side v = 0 to the level-1 edge point, the point itself
// where it is marked (`cc_leaf_keys` puts it in the hash where the face across is not
// a face leaf), then along patch s + 1's side u = 0 (`adaptive::face_polygons`).
fn face_side_walk(first: u32, s: u32) {
    let n = cc_params.grid;
    let p = first + s;
    let q = first + (s + 1u) % 4u;
    line_topo = topo[p];
    face_k = s;
    side_walk(CcCell(p, 0u, 0u, 0u), 0u);
    let slot = cc_find(cc_chart_key(line_topo, p, n, 0u));
    if slot != CC_NO_SLOT {
        found_at(vec2u(n, 0u), slot);
    }
    line_topo = topo[q];
    face_k = (s + 1u) % 4u;
    side_walk(CcCell(q, 0u, 0u, 0u), 3u);
}

// The points on side s of leaf `cell`.
fn leaf_side_walk(cell: CcCell, s: u32) {
    if (cell.trial_depth & CC_CELL_FACE) != 0u {
        face_side_walk(cell.patch_id, s);
    } else {
        side_walk(cell, s);
    }
}

// Whether invocation l has a leaf (and room for its side counts).
fn leaf_in_range(l: u32) -> bool {
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    return l < n && l < arrayLength(&leaves) && cc_side_base(l) + 4u <= arrayLength(&poly_offsets);
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    if !leaf_in_range(l) {
        return;
    }
    let cell = leaves[l];
    // A culled leaf's polygon has two vertices that are never written: no triangles.
    if (cell.trial_depth & CC_CELL_CULLED) != 0u {
        for (var s = 0u; s < 4u; s++) {
            poly_offsets[cc_side_base(l) + s] = 0u;
        }
        poly_offsets[l] = 2u;
        return;
    }
    line_topo = topo[cell.patch_id];
    emitting = false;
    var counts = vec4u(0u);
    for (var s = 0u; s < 4u; s++) {
        found = 0u;
        leaf_side_walk(cell, s);
        counts[s] = found;
    }
    for (var s = 0u; s < 4u; s++) {
        poly_offsets[cc_side_base(l) + s] = counts[s];
    }
    poly_offsets[l] = 4u + counts.x + counts.y + counts.z + counts.w;
}

// Leaves with points on their sides run last in their workgroup
// (`shared/lane_order.wgsl`): about nine leaves in ten have none and walk no side, so
// grouped they need not wait, lane by lane, for the walks of the others.
@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) gid: vec3u, @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) groups: vec3u) {
    let mine = cc_invocation(gid, groups);
    // The polygons go to the stage's own buffers; the output comes after this dispatch.
    if mine == 0u {
        finish_run();
    }
    let valid = leaf_in_range(mine);
    let l = lane_order(lid, valid, mine, valid && any(cc_side_counts(mine) != vec4u(0u)));
    if l != LANE_NONE {
        emit_leaf(l);
    }
}

fn emit_leaf(l: u32) {
    let cell = leaves[l];
    if (cell.trial_depth & CC_CELL_CULLED) != 0u {
        return;
    }
    let counts = cc_side_counts(l);
    if any(counts != vec4u(0u)) {
        line_topo = topo[cell.patch_id];
    }
    var at = poly_offsets[l];
    emitting = true;
    let face = (cell.trial_depth & CC_CELL_FACE) != 0u;
    for (var s = 0u; s < 4u; s++) {
        // The corner's vertex is its item's number (items 8·leaf + corner); a face
        // leaf's corner s is vertex s of the face, in the face's grid.
        if at < arrayLength(&poly_verts) && at < cc_params.poly_capacity {
            var c = cc_cell_corner(cell, s);
            if face {
                c = cc_face_grid(s, vec2u(0u));
            }
            poly_verts[at] = vec4u(ids[8u * l + s], c.x, c.y, 0u);
        }
        // `count` found the side's points: a side without any is not walked again.
        if counts[s] > 0u {
            emit_at = at + 1u;
            found = 0u;
            leaf_side_walk(cell, s);
        }
        at += 1u + counts[s];
    }
}

// Once the polygons are counted and the vertices numbered, and before any output is
// written (invocation 0 of `emit`, which the leaf dispatch always has): what the run
// needed, and whether the mesh fits (the hash's overflow and its vertex count came from
// `cc_hash_number`'s assign_gather). Only then are the vertices evaluated (`drawn_vertices`
// is their count) and the triangles and draw arguments written (`cc_triangulate`), so
// that a run that overflows leaves the last complete mesh drawn.
fn finish_run() {
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    let polys = poly_offsets[n];
    cc_state.need_poly = polys;
    cc_state.need_indices = 3u * (polys - 2u * n);
    if polys > cc_params.poly_capacity || cc_state.need_indices > cc_params.index_capacity
        || cc_state.vertices > cc_params.vertex_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    let ok = atomicLoad(&cc_state.overflow) == 0u;
    cc_state.drawn_vertices = select(0u, cc_state.vertices, ok);
}
