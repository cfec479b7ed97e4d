// One invocation per cell of the current list: the flatness bound of the cell
// (`shared/cc_bound.wgsl`) unless its centre and side midpoints already prove it must be
// split (`cc_split_proof`), and the decision: a leaf if the bound is within the
// tolerance or the cell is at the deepest level, else split (flag 1, scanned next).
// Splits are counted per (patch, trial) for the first-split search.
// Twin: `tessera_core::catmull_clark::adaptive::mark` (the bound: `bound::box_bound`).

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"
#include "shared/lane_order.wgsl"

@group(0) @binding(53) var<storage, read> cells_in: array<CcCell>;
@group(0) @binding(54) var<storage, read_write> flags: array<u32>;

fn cc_corner(p: u32, i: u32, j: u32) -> vec3f {
    return cc_eval(CcPoint(p, cc_grid_fixed(i), cc_grid_fixed(j))).position;
}

// Whether the cell touches a corner of its patch whose quadrant is not one Bézier piece
// (the patch's quadtree goes on there toward an extraordinary vertex).
fn cc_long_walk(cell: CcCell) -> bool {
    if cell.patch_id == CC_NO_NEIGHBOUR {
        return false;
    }
    let root = cc_nodes[cc_roots[cell.patch_id]];
    if (root.kind & CC_NODE_KIND_MASK) != CC_NODE_SPLIT {
        return false;
    }
    let quadrants = cc_splits[root.index];
    let n = cc_params.grid;
    let size = cc_cell_size(cell);
    let left = cell.i == 0u;
    let right = cell.i + size.x == n;
    let bottom = cell.j == 0u;
    let top = cell.j + size.y == n;
    // Patch corner k lies in quadrant k.
    let at = array<bool, 4>(left && bottom, right && bottom, right && top, left && top);
    var long = false;
    for (var k = 0u; k < 4u; k++) {
        long = long || (at[k] && (cc_nodes[quadrants[k]].kind & CC_NODE_KIND_MASK) != CC_NODE_BEZIER);
    }
    return long;
}

// The cells whose bound walks the chain of pieces at an extraordinary vertex (some 50
// nodes against 1 to 3 elsewhere) run last in their workgroup, together
// (`shared/lane_order.wgsl`): interleaved, one such cell in each group of 8 lanes made
// its 7 neighbours wait for it on a CPU device.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(local_invocation_index) lid: u32,
    @builtin(num_workgroups) groups: vec3u) {
    let mine = cc_invocation(gid, groups);
    let valid = mine < cc_state.count && mine < arrayLength(&cells_in) && mine < arrayLength(&flags);
    let c = lane_order(lid, valid, mine, valid && cc_long_walk(cells_in[mine]));
    if c != LANE_NONE {
        mark_cell(c);
    }
}

// The cell at index c of the list.
fn mark_cell(c: u32) {
    let cell = cells_in[c];
    // A cell of a trial dropped by the search (see cc_split.wgsl): nothing to test.
    if cell.patch_id == CC_NO_NEIGHBOUR {
        flags[c] = 0u;
        return;
    }
    let size = cc_cell_size(cell);
    let i1 = cell.i + size.x;
    let j1 = cell.j + size.y;
    let corners = array<vec3f, 4>(cc_corner(cell.patch_id, cell.i, cell.j),
        cc_corner(cell.patch_id, i1, cell.j), cc_corner(cell.patch_id, i1, j1), cc_corner(cell.patch_id, cell.i, j1));
    let depth = cell.trial_depth >> 8u;
    // A cell whose children's corners already prove it too far from flat is split
    // without its bound. Only at a vertex: a regular patch's bound is one Bézier piece,
    // about as costly as the proof's five evaluations.
    var bound = CC_INFINITY;
    var proven = false;
    let regular = (cc_nodes[cc_roots[cell.patch_id]].kind & CC_NODE_KIND_MASK) == CC_NODE_BEZIER;
    if depth < cc_params.max_depth && !regular {
        let w = size.x / 2u;
        let h = size.y / 2u;
        let centre = cc_corner(cell.patch_id, cell.i + w, cell.j + h);
        let mids = array<vec3f, 4>(cc_corner(cell.patch_id, cell.i + w, cell.j),
            cc_corner(cell.patch_id, i1, cell.j + h), cc_corner(cell.patch_id, cell.i + w, j1),
            cc_corner(cell.patch_id, cell.i, cell.j + h));
        proven = cc_split_proof(corners, centre, mids) > cc_params.tolerance;
    }
    if proven {
        atomicAdd(&cc_state.proven, 1u);
    } else {
        atomicAdd(&cc_state.bounds, 1u);
        // Grid units to walk units: CC_WALK_ONE / grid = 2^(18 - max_depth).
        let scale = CC_WALK_ONE / cc_params.grid;
        bound = cc_box_bound(cell.patch_id, vec4u(cell.i, i1, cell.j, j1) * scale, corners);
    }
    let leaf = bound <= cc_params.tolerance || depth >= cc_params.max_depth;
    flags[c] = select(1u, 0u, leaf);
    let t = cell.trial_depth & 0xffu;
    if !leaf {
        // A trial ends with ku·kv + 3 · (its splits) leaves: each split turns one cell
        // into four.
        atomicAdd(&cc_state.trials[cc_trial_slot(0u, cell.patch_id, t)], 1u);
    } else {
        // What the output will guarantee if this trial is the patch's best.
        atomicMax(&cc_state.trials[cc_trial_slot(1u, cell.patch_id, t)], bitcast<u32>(min(bound, CC_INFINITY)));
        if bound > cc_params.tolerance {
            atomicAdd(&cc_state.trials[cc_trial_slot(2u, cell.patch_id, t)], 1u);
        }
    }
}
