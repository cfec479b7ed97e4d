// Adaptive marking to full depth in one dispatch per pass. The count pass takes one
// invocation per patch and first split (trial): it walks the cells of the split row by
// row, each cell's subtree depth first, without a stack (`cc_next_cell`), and keeps
// every decision as a bit in a chain of blocks of 32. A trial that finishes offers
// itself as the patch's best, !(leaves << 5 | trial) kept by atomicMax: the fewest
// leaves, ties to the earlier trial, as the CPU's search. A trial is skipped, or
// stopped, once it cannot beat a finished one; the best trial is never stopped, so the
// choice does not depend on timing. The scan turns each patch's best into its first
// leaf, and the emit pass (one invocation per patch) replays the best trial's bits to
// write its leaves there: nothing is decided twice. A cell is decided alone
// (`cc_decide`), so the leaves do not depend on the order of work.
//
// No workgroup memory beyond the lanes' order, no waiting on other invocations. A CPU
// device (lavapipe) runs eight lanes at a time through every instruction, and through a
// loop until its last lane is done: with midpoint splits alone the lanes are eight
// patches deciding side by side. It also stops every loop of those eight lanes after
// 65 535 iterations in all, which one invocation per trial keeps far off; a walk cut
// short is reported (overflow bit 4) if it could have been the best, never taken for a
// mesh.
//
// The same entry runs for both passes, told apart by `cc_pass` (one pipeline).
// Twin: `tessera_core::catmull_clark::traverse`.

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"
#include "shared/cc_view.wgsl"
#include "shared/cc_facing.wgsl"
#include "shared/lane_order.wgsl"

@group(0) @binding(55) var<storage, read_write> leaves: array<CcCell>;
@group(0) @binding(68) var<uniform> cc_pass: vec4u;
// `shared/cc_tess.wgsl` gives the layout.
@group(0) @binding(57) var<storage, read_write> marks: array<atomic<u32>>;


fn cc_corner(p: u32, i: u32, j: u32) -> vec3f {
    return cc_eval(CcPoint(p, cc_grid_fixed(i), cc_grid_fixed(j))).position;
}

struct CcDecision {
    split: bool,
    bound: f32,
    proven: bool,
    // A leaf wholly outside the view's frustum: it emits nothing.
    culled: bool,
    // Whether the bound meets the cell's tolerance: the world's, and within its share of
    // the view's pixels.
    met: bool,
    // Flatness bounds computed (0 or 1).
    bounds: u32,
}

// Whether a cell with these corners and this bound lies wholly outside the frustum of a
// culling view: its surface is within `bound` of its corners' hull.
fn cc_outside(corners: array<vec3f, 4>, bound: f32) -> bool {
    if (cc_params.view.cull & CC_VIEW_CULL_FRUSTUM) == 0u {
        return false;
    }
    let b = vec3f(bound);
    return cc_view_box_outside(cc_corners_lo(corners) - b, cc_corners_hi(corners) + b);
}

// The bound of patch p's whole square depends on the surface alone, not on the view or
// the tolerance: computed by the first run that needs it and kept in the marks until the
// control points move (`SurfaceModel::root_bound` on the CPU). Only trial 0's invocation
// of the patch reads and writes it. `cc_decide` calls the walk once in each of its two
// decisions: each call is a copy of its loop, which a CPU device runs for every lane.
fn cc_kept_bound(p: u32, whole: bool) -> u32 {
    if !whole {
        return 0u;
    }
    return atomicLoad(&marks[cc_root_bound_at(p)]);
}

fn cc_bound_or_kept(p: u32, whole: bool, walk_box: vec4u, corners: array<vec3f, 4>) -> f32 {
    let kept = cc_kept_bound(p, whole);
    if kept != 0u {
        return bitcast<f32>(kept - 1u);
    }
    let bound = cc_box_bound(p, walk_box, corners);
    if whole {
        atomicStore(&marks[cc_root_bound_at(p)], bitcast<u32>(bound) + 1u);
    }
    return bound;
}

// `CellTolerance::admits`: whether `bound` meets the world's tolerance and, in a view
// in pixels, the cell's share of them.
fn cc_cell_admits(search: ptr<function, CcViewSearch>, bound: f32) -> bool {
    return bound <= cc_params.tolerance && (cc_params.view.pixels <= 0.0 || cc_view_admits(search, bound));
}

// `adaptive::decide_cell`: split unless the flatness bound is within the cell's
// tolerance, the cell is outside the view, or it is at the deepest level; a cell at a
// vertex whose children's corners already prove it too far from flat is split without
// its bound.
fn cc_decide(cell: CcCell) -> CcDecision {
    let size = cc_cell_size(cell);
    let i1 = cell.i + size.x;
    let j1 = cell.j + size.y;
    let p = cell.patch_id;
    let corners = array<vec3f, 4>(cc_corner(p, cell.i, cell.j), cc_corner(p, i1, cell.j),
        cc_corner(p, i1, j1), cc_corner(p, cell.i, j1));
    let depth = cell.trial_depth >> 8u;
    // The world's tolerance, and the view's search for the cell's share of its pixels.
    var search: CcViewSearch;
    if cc_params.view.pixels > 0.0 {
        search = cc_view_search(cc_corners_lo(corners), cc_corners_hi(corners));
    }
    // Grid units to walk units: CC_WALK_ONE / grid = 2^(18 - max_depth).
    let scale = CC_WALK_ONE / cc_params.grid;
    let walk_box = vec4u(cell.i, i1, cell.j, j1) * scale;
    var bound = CC_INFINITY;
    var bounds = 0u;
    // Trial 0's root (1 × 1): the whole patch.
    let whole = (cell.trial_depth & 0xffu) == 0u && depth == 0u;
    // A whole patch outside a culling view, or facing away from the eye, costs one bound
    // and no search: trial 0's root is culled before the proof, and its bound serves the
    // decision.
    if cc_params.view.cull != 0u && whole {
        bound = cc_bound_or_kept(p, true, walk_box, corners);
        bounds = 1u;
        var culled = cc_outside(corners, bound);
        if !culled && (cc_params.view.cull & CC_VIEW_CULL_BACKFACES) != 0u && bound < CC_INFINITY {
            let b = vec3f(bound);
            culled = cc_patch_back_facing(p, cc_corners_lo(corners) - b, cc_corners_hi(corners) + b);
        }
        if culled {
            // A culled leaf counts apart, whatever its bound.
            return CcDecision(false, bound, false, true, false, bounds);
        }
    }
    // Only at a vertex: a regular patch's bound is one Bézier piece, about as costly as
    // the proof's five evaluations.
    let regular = (cc_nodes[cc_roots[p].node].kind & CC_NODE_KIND_MASK) == CC_NODE_BEZIER;
    if depth < cc_params.max_depth && !regular {
        let w = size.x / 2u;
        let h = size.y / 2u;
        let centre = cc_corner(p, cell.i + w, cell.j + h);
        let mids = array<vec3f, 4>(cc_corner(p, cell.i + w, cell.j), cc_corner(p, i1, cell.j + h),
            cc_corner(p, cell.i + w, j1), cc_corner(p, cell.i, cell.j + h));
        if !cc_cell_admits(&search, cc_split_proof(corners, centre, mids)) {
            return CcDecision(true, CC_INFINITY, true, false, false, bounds);
        }
    }
    if bounds == 0u {
        bound = cc_bound_or_kept(p, whole, walk_box, corners);
        bounds = 1u;
    }
    let culled = cc_outside(corners, bound);
    let met = cc_cell_admits(&search, bound);
    let leaf = met || culled || depth >= cc_params.max_depth;
    return CcDecision(!leaf, bound, false, culled, met, bounds);
}

// A face leaf (`adaptive::mark_faces`): with a view's face leaves, the quad control
// face of patch p is one leaf when its bound taken whole (`cc_face_bound.wgsl`, kept in
// the marks) meets the tolerance at its corners' box. Every patch of the face, in every
// trial, decides it alike. `kind`: 0 none, 1 a face leaf, 2 a face leaf culled (outside
// the frustum, or all four patches facing away).
struct CcFaceDecision {
    kind: u32,
    bound: f32,
    // Its patch's place in the face: patch 0 holds the leaf.
    corner: u32,
    // Bounds taken (0 or 1).
    bounds: u32,
}

fn cc_face_decision(p: u32) -> CcFaceDecision {
    let flags = cc_roots[p].flags;
    let corner = flags >> CC_ROOT_CORNER_SHIFT;
    var none = CcFaceDecision(0u, 0.0, corner, 0u);
    if cc_params.view.face_leaves == 0u || (flags & CC_ROOT_QUAD_FACE) == 0u {
        return none;
    }
    let first = p - corner;
    let kept = atomicLoad(&marks[cc_face_bound_at(first)]);
    let bound = bitcast<f32>(kept - 1u);
    if kept == 0u || bound >= CC_INFINITY {
        return none;
    }
    none.bounds = 1u;
    let corners = array<vec3f, 4>(cc_corner(first, 0u, 0u), cc_corner(first + 1u, 0u, 0u),
        cc_corner(first + 2u, 0u, 0u), cc_corner(first + 3u, 0u, 0u));
    let lo = cc_corners_lo(corners);
    let hi = cc_corners_hi(corners);
    var search: CcViewSearch;
    if cc_params.view.pixels > 0.0 {
        search = cc_view_search(lo, hi);
    }
    if !cc_cell_admits(&search, bound) {
        return none;
    }
    // The face's surface lies within its bound of the corners' hull.
    var culled = cc_outside(corners, bound);
    if !culled && (cc_params.view.cull & CC_VIEW_CULL_BACKFACES) != 0u {
        let b = vec3f(bound);
        culled = true;
        for (var k = 0u; k < 4u; k++) {
            culled = culled && cc_patch_back_facing(first + k, lo - b, hi + b);
        }
    }
    return CcFaceDecision(select(1u, 2u, culled), bound, corner, 1u);
}

// Per invocation: what its decisions cost, and (emit) what its leaves guarantee.
var<private> lane_bounds: u32;
var<private> lane_proven: u32;
var<private> lane_unmet: u32;
var<private> lane_max_bound: f32;
var<private> lane_culled: u32;

// `adaptive::Marking::keep_leaf`: a culled leaf counts apart, the others by their bound.
fn decide_counted(cell: CcCell) -> CcDecision {
    let d = cc_decide(cell);
    lane_bounds += d.bounds;
    if d.proven {
        lane_proven += 1u;
    }
    if !d.split {
        if d.culled {
            lane_culled += 1u;
        } else {
            lane_max_bound = max(lane_max_bound, min(d.bound, CC_INFINITY));
            if !d.met {
                lane_unmet += 1u;
            }
        }
    }
    return d;
}

// A cell during a walk: `i | depth << 20`, `j` (i < 840 · 2^MAX_DEPTH < 2^20).
fn cc_cell_of(p: u32, t: u32, c: vec2u) -> CcCell {
    return CcCell(p, t | ((c.x >> 20u) << 8u), c.x & 0xfffffu, c.y);
}

// Quadrant 0 of a cell held as `i | depth << 20`, `j`: the same corner, one level down.
fn cc_first_child(c: vec2u) -> vec2u {
    return vec2u(c.x + (1u << 20u), c.y);
}

// The cell after `c` (held as `i | depth << 20`, `j`) in a depth-first walk of trial t
// from a cell at depth 0, once c and everything below it is done: its next sibling,
// else its parent's, and so on; `j` = 0xffffffff when the walk is over. A cell's
// quadrant is the parity of its position in cells of its size, so the walk needs no
// stack.
fn cc_next_cell(t: u32, c: vec2u) -> vec2u {
    let s = cc_trial_split(t);
    var i = c.x & 0xfffffu;
    var j = c.y;
    var depth = c.x >> 20u;
    var done = false;
    var next = vec2u(0u, 0xffffffffu);
    for (var guard = 0u; guard <= 10u && !done; guard++) {
        if depth == 0u {
            done = true;
        } else {
            let w = (cc_params.grid / s.x) >> depth;
            let h = (cc_params.grid / s.y) >> depth;
            let o = vec2u((i / w) & 1u, (j / h) & 1u);
            // Quadrants 0 (0,0), 1 (1,0), 2 (1,1), 3 (0,1).
            if o.x == 0u && o.y == 0u {
                next = vec2u((i + w) | (depth << 20u), j);
                done = true;
            } else if o.x == 1u && o.y == 0u {
                next = vec2u(i | (depth << 20u), j + h);
                done = true;
            } else if o.x == 1u && o.y == 1u {
                next = vec2u((i - w) | (depth << 20u), j);
                done = true;
            } else {
                // Quadrant 3, the last: on to the parent's next.
                j -= h;
                depth -= 1u;
            }
        }
    }
    return next;
}

// Cell r of trial t (row by row), as held during a walk.
fn cc_root_cell(t: u32, r: u32) -> vec2u {
    let s = cc_trial_split(t);
    return vec2u((r % s.x) * (cc_params.grid / s.x), (r / s.x) * (cc_params.grid / s.y));
}

// A trial's key: the fewest leaves, then the earliest trial, is the least.
fn cc_key(leaves: u32, t: u32) -> u32 {
    return (leaves << 5u) | t;
}

// The key of the best trial of patch p finished so far (0xffffffff: none).
fn cc_best_so_far(p: u32) -> u32 {
    return ~atomicLoad(&marks[cc_best_at(p)]);
}

// The decision blocks of one walk: where the next bit goes (or comes from). With a
// culling view, each leaf's bit is followed by one saying whether it is culled. Block
// p·T + t is trial t of patch p's own; further blocks are taken from the pool in turn
// (`cc_state.decision_blocks`).
struct CcChain {
    block: u32,
    bit: u32,
    bits: u32,
}

const CC_NO_BLOCK: u32 = 0xffffffffu;

fn cc_blocks() -> u32 {
    return (arrayLength(&marks) - cc_bits_at(0u)) / 2u;
}

// A block from the pool; CC_NO_BLOCK once there are none (overflow bit 8: the run needs
// more).
fn cc_take_block() -> u32 {
    let own = cc_params.patch_count * cc_params.trials;
    let b = own + atomicAdd(&cc_state.decision_blocks, 1u);
    if b >= cc_blocks() {
        atomicOr(&cc_state.overflow, 8u);
        return CC_NO_BLOCK;
    }
    atomicStore(&marks[cc_bits_at(b) + 1u], CC_NO_BLOCK);
    return b;
}

// Records one decision; a full block is written out and the chain moves on to a block
// from the pool.
fn cc_record(c: ptr<function, CcChain>, split: bool) {
    if split {
        (*c).bits |= 1u << ((*c).bit & 31u);
    }
    (*c).bit += 1u;
    if (*c).bit == 32u && (*c).block != CC_NO_BLOCK {
        atomicStore(&marks[cc_bits_at((*c).block)], (*c).bits);
        let next = cc_take_block();
        atomicStore(&marks[cc_bits_at((*c).block) + 1u], next);
        (*c).block = next;
        (*c).bit = 0u;
        (*c).bits = 0u;
    }
}

// The next decision of a chain being replayed.
fn cc_replay(c: ptr<function, CcChain>) -> bool {
    if (*c).bit == 32u {
        if (*c).block != CC_NO_BLOCK {
            (*c).block = atomicLoad(&marks[cc_bits_at((*c).block) + 1u]);
        }
        (*c).bit = 0u;
        (*c).bits = 0u;
        if (*c).block != CC_NO_BLOCK {
            (*c).bits = atomicLoad(&marks[cc_bits_at((*c).block)]);
        }
    }
    let split = (((*c).bits >> (*c).bit) & 1u) != 0u;
    (*c).bit += 1u;
    return split;
}

// Counting: trial t of patch p, as `traverse::walk_trial` stopped at the best. One
// trial per invocation: even three in one ran past the device's loop limit at a deep
// extraordinary vertex (see the top).
fn count_trial(p: u32, t: u32) {
    let face = cc_face_decision(p);
    // The face's bound counts once, at its first patch's trial 0.
    if t == 0u && face.corner == 0u {
        lane_bounds += face.bounds;
    }
    if face.kind != 0u {
        // Trial 0 alone offers: one leaf at the face's first patch, none at the others.
        if t == 0u {
            let mine = select(0u, 1u, face.corner == 0u);
            atomicMax(&marks[cc_best_at(p)], ~cc_key(mine, 0u));
            atomicMax(&marks[p], ~cc_key(mine, 0u));
        }
        return;
    }
    let s = cc_trial_split(t);
    let area = s.x * s.y;
    // A split into ku·kv cells has at least ku·kv leaves: skipped if a finished trial
    // already beats that.
    if cc_key(area, t) > cc_best_so_far(p) {
        return;
    }
    var chain = CcChain(p * cc_params.trials + t, 0u, 0u);
    var r = 0u;
    var mine = 0u;
    var at_cell = cc_root_cell(t, 0u);
    var walking = true;
    var stopped = false;
    while walking && !stopped {
        if cc_key(mine, t) > cc_best_so_far(p) {
            // Above a finished trial, or level with one from an earlier trial.
            stopped = true;
        } else {
            let cell = cc_cell_of(p, t, at_cell);
            let d = decide_counted(cell);
            cc_record(&chain, d.split);
            if !d.split && cc_params.view.cull != 0u {
                cc_record(&chain, d.culled);
            }
            if d.split {
                at_cell = cc_first_child(at_cell);
            } else {
                mine += 1u;
                let next = cc_next_cell(t, at_cell);
                if next.y != 0xffffffffu {
                    at_cell = next;
                } else if r + 1u < area {
                    r += 1u;
                    at_cell = cc_root_cell(t, r);
                } else {
                    // Written out and offered at once, not after the loop: the lanes
                    // run the loop until the last is done, and the others can stop as
                    // soon as this one beats them.
                    walking = false;
                    if chain.block != CC_NO_BLOCK && chain.bit > 0u {
                        atomicStore(&marks[cc_bits_at(chain.block)], chain.bits);
                    }
                    atomicStore(&marks[cc_stats_at(p, t)], bitcast<u32>(lane_max_bound));
                    atomicStore(&marks[cc_stats_at(p, t) + 1u], lane_unmet);
                    atomicStore(&marks[cc_stats_at(p, t) + 2u], lane_culled);
                    atomicMax(&marks[cc_best_at(p)], ~cc_key(mine, t));
                    atomicMax(&marks[p], ~cc_key(mine, t));
                }
            }
        }
    }
    // The loop ends only when the walk is over or stopped: otherwise the device cut it
    // short. What it had found so far is kept in case it could have been the best.
    if walking && !stopped {
        atomicMax(&marks[cc_cut_at(p)], ~cc_key(mine, t));
    }
}

// Emitting: the best trial's walk replayed, its leaves written from the patch's first.
fn emit_patch(p: u32) {
    let face = cc_face_decision(p);
    if face.kind != 0u {
        atomicStore(&marks[cc_chosen_at(p)], CC_CHOSEN_FACE_LEAF);
        if face.corner != 0u {
            return;
        }
        let k = atomicLoad(&marks[p]);
        let culled = face.kind == 2u;
        if k < cc_params.leaf_capacity && k < arrayLength(&leaves) {
            leaves[k] = CcCell(p, CC_CELL_FACE | select(0u, CC_CELL_CULLED | CC_CELL_PATCH_CULLED, culled), 0u, 0u);
        }
        // A face culled counts as its four patches.
        if culled {
            atomicAdd(&cc_state.culled_patches, 4u);
        } else {
            atomicMax(&cc_state.max_bound_bits, bitcast<u32>(face.bound));
        }
        return;
    }
    let key = cc_best_so_far(p);
    atomicStore(&marks[cc_chosen_at(p)], select(key & 31u, CC_TRIALS, key == 0xffffffffu));
    // A trial cut short that might have beaten the one chosen: no mesh.
    if key == 0xffffffffu || ~atomicLoad(&marks[cc_cut_at(p)]) < key {
        atomicOr(&cc_state.overflow, 4u);
    }
    if key == 0xffffffffu {
        return;
    }
    let t = key & 31u;
    let count = key >> 5u;
    let first = atomicLoad(&marks[p]);
    let own = p * cc_params.trials + t;
    var chain = CcChain(own, 0u, atomicLoad(&marks[cc_bits_at(own)]));
    let culled_leaves = atomicLoad(&marks[cc_stats_at(p, t) + 2u]);
    let patch_flag = select(0u, CC_CELL_PATCH_CULLED, culled_leaves == count);
    let s = cc_trial_split(t);
    let area = s.x * s.y;
    var r = 0u;
    var mine = 0u;
    var at_cell = cc_root_cell(t, 0u);
    var walking = true;
    while walking {
        let cell = cc_cell_of(p, t, at_cell);
        if cc_replay(&chain) {
            at_cell = cc_first_child(at_cell);
        } else {
            var culled = false;
            if cc_params.view.cull != 0u {
                culled = cc_replay(&chain);
            }
            // At most what the count pass found.
            let k = first + mine;
            if mine < count && k < cc_params.leaf_capacity && k < arrayLength(&leaves) {
                leaves[k] = cell;
                if culled {
                    leaves[k].trial_depth |= CC_CELL_CULLED | patch_flag;
                }
            }
            mine += 1u;
            let next = cc_next_cell(t, at_cell);
            if next.y != 0xffffffffu {
                at_cell = next;
            } else {
                r += 1u;
                walking = r < area;
                at_cell = cc_root_cell(t, r);
            }
        }
    }
    if walking {
        atomicOr(&cc_state.overflow, 4u);
    }
    // The replay must find what the count pass counted.
    if mine != count {
        atomicOr(&cc_state.overflow, 2u);
    }
    atomicMax(&cc_state.max_bound_bits, atomicLoad(&marks[cc_stats_at(p, t)]));
    atomicAdd(&cc_state.unmet, atomicLoad(&marks[cc_stats_at(p, t) + 1u]));
    if culled_leaves == count {
        atomicAdd(&cc_state.culled_patches, 1u);
    } else {
        atomicAdd(&cc_state.culled_leaves, culled_leaves);
    }
}

// Whether patch p has an extraordinary vertex (its tree splits at the root): its bounds
// walk chains of pieces and its walks go deeper.
fn cc_irregular(p: u32) -> bool {
    return p < cc_params.patch_count && cc_roots[p].node != CC_NO_ROOT
        && (cc_nodes[cc_roots[p].node].kind & CC_NODE_KIND_MASK) != CC_NODE_BEZIER;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32) {
    let x = cc_invocation(gid, groups);
    let emitting = cc_pass.x == 1u;
    let patches = cc_params.patch_count;
    // Counting, invocation x takes trial t of patch p, in blocks of 8 patches: a group
    // of 8 lanes decides the same trial of 8 patches, the first trial first.
    let per_patch = select(cc_params.trials, 1u, emitting);
    let block = x / (8u * per_patch);
    let within = x % (8u * per_patch);
    let mine = (block * 8u + within % 8u) * per_patch + within / 8u;
    // The patches at a vertex of each workgroup run side by side, after the others
    // (`shared/lane_order.wgsl`).
    let valid = mine < patches * per_patch;
    let ordered = lane_order(lid, valid, mine, valid && cc_irregular(mine / per_patch));
    if x == 0u {
        if emitting {
            // The scan left the total after the patches' offsets.
            let total = atomicLoad(&marks[patches]);
            cc_state.leaves = total;
            if total > cc_params.leaf_capacity {
                atomicOr(&cc_state.overflow, 1u);
            }
            let n = min(total, cc_params.leaf_capacity);
            // At least one leaf invocation: `cc_polygon`'s emit finishes the run.
            cc_write_args(3u, max(n, 1u));
            cc_write_args(6u, 8u * n);
        } else {
            // Scanned as no leaves: the total lands here.
            atomicStore(&marks[patches], 0xffffffffu);
        }
    }
    let item = select(x, ordered, !emitting);
    let p = item / per_patch;
    let t = item % per_patch;
    if item == LANE_NONE || p >= patches {
        return;
    }
    // A hole has no surface (and no tree): no leaves, no trial.
    if cc_roots[p].node == CC_NO_ROOT {
        if emitting {
            atomicStore(&marks[cc_chosen_at(p)], CC_TRIALS);
        } else if t == 0u {
            atomicStore(&marks[p], 0xffffffffu);
        }
        return;
    }
    if emitting {
        emit_patch(p);
    } else {
        count_trial(p, t);
        atomicAdd(&cc_state.bounds, lane_bounds);
        atomicAdd(&cc_state.proven, lane_proven);
    }
}
