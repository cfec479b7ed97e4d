// Adaptive marking, one workgroup per patch, to full depth in one dispatch: the cells of
// a first split are decided level by level in workgroup memory until a level holds at
// least CC_SLOTS cells; then the cells of that level are shared out by slot (slot k:
// cells k, k + 64, ...) and each slot's cells are walked depth first, without a stack
// (`cc_next_cell`). A cell is decided alone (`cc_decide`), so the leaves do not depend
// on the order of work; the order of the walk only fixes where each leaf is written.
//
// The same entry runs twice, told apart by `cc_pass` (one pipeline, so the two passes
// compile to the same decisions):
// - pass 0, count: tries the first splits of the search in order, skipping those that
//   cannot beat the best so far and stopping a trial as soon as its leaves reach the
//   best (ties go to the earlier trial, as the CPU reference). Writes per patch the
//   best trial, its leaves (scanned next), and the leaves of each slot's walk.
// - pass 1, emit: walks the best trial again and writes its leaves at the patch's
//   offset: first those decided level by level, in order, then slot after slot.
//   Workgroup 0 sets the run's leaf count and the next dispatches' sizes.
//
// No workgroup waits on another, and every loop is bounded by the tree's depth. A CPU
// device (lavapipe) also stops every loop of a group of 8 lanes once they have run
// 65 535 iterations in all: the lanes turn between slots from trial to trial
// (`cc_slot`), surface points are found without loops (`cc_grid_fixed`), and a walk the
// device cut short is reported (overflow bit 4), never taken for a mesh.
// Twin: `tessera_core::catmull_clark::traverse`.

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"

@group(0) @binding(55) var<storage, read_write> leaves: array<CcCell>;
@group(0) @binding(68) var<uniform> cc_pass: vec4u;

const CC_SLOTS: u32 = 64u;
// Cells of one level held in workgroup memory: a level of fewer than CC_SLOTS cells
// splits into at most 4 · (CC_SLOTS - 1).
const CC_LEVEL_CELLS: u32 = 256u;

var<workgroup> level_cells: array<array<vec2u, CC_LEVEL_CELLS>, 2>;
var<workgroup> level_len: u32;
var<workgroup> found: atomic<u32>;
var<workgroup> found_now: u32;
var<workgroup> lane_split: array<u32, CC_SLOTS>;
var<workgroup> lane_leaf: array<u32, CC_SLOTS>;

fn best_at(p: u32) -> u32 {
    return cc_params.patch_count + 1u + 2u * p;
}

fn slot_at(p: u32, lane: u32) -> u32 {
    return 3u * cc_params.patch_count + 1u + CC_SLOTS * p + lane;
}

// A cell as held in workgroup memory and by a walk: `i | depth << 20`, `j`
// (i < 840 · 2^MAX_DEPTH < 2^20).
fn cc_cell_of(p: u32, t: u32, c: vec2u) -> CcCell {
    return CcCell(p, t | ((c.x >> 20u) << 8u), c.x & 0xfffffu, c.y);
}

fn cc_corner(p: u32, i: u32, j: u32) -> vec3f {
    return cc_eval(CcPoint(p, cc_grid_fixed(i), cc_grid_fixed(j))).position;
}

struct CcDecision {
    split: bool,
    bound: f32,
    proven: bool,
}

// `traverse::decide` (and `adaptive::mark`): split unless the flatness bound is within
// the tolerance or the cell is at the deepest level; a cell at a vertex whose children's
// corners already prove it too far from flat is split without its bound.
fn cc_decide(cell: CcCell) -> CcDecision {
    let size = cc_cell_size(cell);
    let i1 = cell.i + size.x;
    let j1 = cell.j + size.y;
    let p = cell.patch_id;
    let corners = array<vec3f, 4>(cc_corner(p, cell.i, cell.j), cc_corner(p, i1, cell.j),
        cc_corner(p, i1, j1), cc_corner(p, cell.i, j1));
    let depth = cell.trial_depth >> 8u;
    // Only at a vertex: a regular patch's bound is one Bézier piece, about as costly as
    // the proof's five evaluations.
    let regular = (cc_nodes[cc_roots[p]].kind & CC_NODE_KIND_MASK) == CC_NODE_BEZIER;
    if depth < cc_params.max_depth && !regular {
        let w = size.x / 2u;
        let h = size.y / 2u;
        let centre = cc_corner(p, cell.i + w, cell.j + h);
        let mids = array<vec3f, 4>(cc_corner(p, cell.i + w, cell.j), cc_corner(p, i1, cell.j + h),
            cc_corner(p, cell.i + w, j1), cc_corner(p, cell.i, cell.j + h));
        if cc_split_proof(corners, centre, mids) > cc_params.tolerance {
            return CcDecision(true, CC_INFINITY, true);
        }
    }
    // Grid units to walk units: CC_WALK_ONE / grid = 2^(18 - max_depth).
    let scale = CC_WALK_ONE / cc_params.grid;
    let bound = cc_box_bound(p, vec4u(cell.i, i1, cell.j, j1) * scale, corners);
    let leaf = bound <= cc_params.tolerance || depth >= cc_params.max_depth;
    return CcDecision(!leaf, bound, false);
}

// Per lane: what its decisions cost, and (emit) what its leaves guarantee.
var<private> lane_bounds: u32;
var<private> lane_proven: u32;
var<private> lane_unmet: u32;
var<private> lane_max_bound: f32;
// Whether the lane's walk stopped at the best so far.
var<private> lane_stopped: bool;

fn decide_counted(cell: CcCell) -> bool {
    let d = cc_decide(cell);
    if d.proven {
        lane_proven += 1u;
    } else {
        lane_bounds += 1u;
    }
    if !d.split {
        lane_max_bound = max(lane_max_bound, min(d.bound, CC_INFINITY));
        if d.bound > cc_params.tolerance {
            lane_unmet += 1u;
        }
    }
    return d.split;
}

// The quadrant q of a cell held as `i | depth << 20`, `j`, whose size is `size`.
fn cc_child(c: vec2u, size: vec2u, q: u32) -> vec2u {
    let half = size / 2u;
    let o = vec2u(select(0u, 1u, q == 1u || q == 2u), select(0u, 1u, q >= 2u));
    return vec2u(c.x + o.x * half.x + (1u << 20u), c.y + o.y * half.y);
}

// The slot lane `lid` works in trial t: the cells `slot, slot + 64, ...` of a level, the
// slot's leaves in the output. The lanes turn by a group of 8 per trial, so that the
// cells at a patch corner with an extraordinary vertex, slot 0 in every trial and the
// longest walks, do not all fall to the same group of lanes (see the top).
fn cc_slot(lid: u32, t: u32) -> u32 {
    return (lid + CC_SLOTS - (8u * t) % CC_SLOTS) % CC_SLOTS;
}

// The cell after `c` (held as `i | depth << 20`, `j`) in a depth-first walk of trial t
// from a cell at depth `top`, once c and everything below it is done: its next sibling,
// else its parent's, and so on; `j` = 0xffffffff when the walk is over. A cell's
// quadrant is the parity of its position in cells of its size, so the walk needs no
// stack.
fn cc_next_cell(t: u32, c: vec2u, top: u32) -> vec2u {
    let s = cc_trial_split(t);
    var i = c.x & 0xfffffu;
    var j = c.y;
    var depth = c.x >> 20u;
    var done = false;
    var next = vec2u(0u, 0xffffffffu);
    for (var guard = 0u; guard <= 10u && !done; guard++) {
        if depth <= top {
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

// Trial t of patch p: level by level while a level holds fewer than CC_SLOTS cells, then
// each lane's walk. Counting, stops once the leaves reach `stop`; emitting, writes the
// leaves from `first`. Returns the lane's walk's leaves; `found` holds the trial's.
fn run_trial(p: u32, t: u32, lid: u32, emitting: bool, stop: u32, first: u32) -> u32 {
    let slot = cc_slot(lid, t);
    let s = cc_trial_split(t);
    let w = cc_params.grid / s.x;
    let h = cc_params.grid / s.y;
    // Every lane has read what the last trial (or the caller) left in workgroup memory.
    workgroupBarrier();
    if lid < s.x * s.y {
        level_cells[0][lid] = vec2u((lid % s.x) * w, (lid / s.x) * h);
    }
    if lid == 0u {
        level_len = s.x * s.y;
        atomicStore(&found, 0u);
        found_now = 0u;
    }
    var cur = 0u;
    // At most max_depth + 1 levels.
    for (var level = 0u; level <= 10u; level++) {
        let n = workgroupUniformLoad(&level_len);
        let so_far = workgroupUniformLoad(&found_now);
        if n == 0u || n >= CC_SLOTS || (!emitting && so_far >= stop) {
            break;
        }
        var split = false;
        var cell: CcCell;
        if slot < n {
            cell = cc_cell_of(p, t, level_cells[cur][slot]);
            split = decide_counted(cell);
        }
        lane_split[slot] = select(0u, 1u, split);
        lane_leaf[slot] = select(0u, 1u, slot < n && !split);
        workgroupBarrier();
        if lid == 0u {
            var splits = 0u;
            var leaves_before = found_now;
            for (var l = 0u; l < CC_SLOTS; l++) {
                let a = lane_split[l];
                lane_split[l] = splits;
                splits += a;
                let b = lane_leaf[l];
                lane_leaf[l] = leaves_before;
                leaves_before += b;
            }
            level_len = 4u * splits;
            found_now = leaves_before;
            atomicStore(&found, leaves_before);
        }
        workgroupBarrier();
        if slot < n {
            let c = level_cells[cur][slot];
            if split {
                let size = cc_cell_size(cell);
                for (var q = 0u; q < 4u; q++) {
                    level_cells[1u - cur][4u * lane_split[slot] + q] = cc_child(c, size, q);
                }
            } else if emitting {
                let at = first + lane_leaf[slot];
                if at < cc_params.leaf_capacity && at < arrayLength(&leaves) {
                    leaves[at] = cell;
                }
            }
        }
        cur = 1u - cur;
    }
    // A trial stopped here walks nothing more.
    var n = workgroupUniformLoad(&level_len);
    let so_far = workgroupUniformLoad(&found_now);
    if !emitting && so_far >= stop {
        n = 0u;
    }
    // Emitting: this lane's leaves go after those of the levels and of the lanes before.
    var at = 0u;
    if emitting {
        if lid == 0u {
            var run = first + so_far;
            for (var l = 0u; l < CC_SLOTS; l++) {
                let x = marks[slot_at(p, l)];
                lane_leaf[l] = run;
                run += x;
            }
        }
        workgroupBarrier();
        at = lane_leaf[slot];
    }
    // Emitting: at most what the count pass found for this lane, so that a walk that
    // found more cannot write over the next lane's leaves.
    var limit = 0xffffffffu;
    if emitting {
        limit = marks[slot_at(p, slot)];
    }
    var mine = 0u;
    var stopped = false;
    lane_stopped = false;
    for (var c = slot; c < n && !stopped; c += CC_SLOTS) {
        let start = level_cells[cur][c];
        let start_depth = start.x >> 20u;
        var at_cell = start;
        var walking = true;
        while walking && !stopped {
            if !emitting && atomicLoad(&found) >= stop {
                stopped = true;
            } else {
                let cell = cc_cell_of(p, t, at_cell);
                let dsplit = decide_counted(cell);
                if dsplit {
                    at_cell = cc_child(at_cell, cc_cell_size(cell), 0u);
                } else {
                    if emitting {
                        let k = at + mine;
                        if mine < limit && k < cc_params.leaf_capacity && k < arrayLength(&leaves) {
                            leaves[k] = cell;
                        }
                    } else {
                        atomicAdd(&found, 1u);
                    }
                    mine += 1u;
                    let next = cc_next_cell(t, at_cell, start_depth);
                    walking = next.y != 0xffffffffu;
                    at_cell = next;
                }
            }
        }
        // The loop ends only when the walk is over or stopped: otherwise the device cut
        // it short (see the top), and this run's leaves are not the surface's.
        if walking && !stopped {
            atomicOr(&cc_state.overflow, 4u);
        }
    }
    lane_stopped = stopped;
    return mine;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3u, @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32) {
    let p = wg.x + wg.y * groups.x;
    let emitting = cc_pass.x == 1u;
    if emitting && p == 0u && lid == 0u {
        // The scan left the total after the patches' offsets.
        let total = marks[cc_params.patch_count];
        cc_state.leaves = total;
        if total > cc_params.leaf_capacity {
            atomicOr(&cc_state.overflow, 1u);
        }
        let n = min(total, cc_params.leaf_capacity);
        cc_write_args(3u, n);
        cc_write_args(6u, 8u * n);
    }
    if p >= cc_params.patch_count {
        return;
    }
    // A hole has no surface (and no tree).
    let hole = cc_roots[p] == CC_NO_ROOT;
    if !emitting {
        var best = vec2u(0xffffffffu, CC_TRIALS);
        var best_mine = 0u;
        if hole {
            best = vec2u(0u, CC_TRIALS);
        } else {
            for (var t = 0u; t < cc_params.trials; t++) {
                let s = cc_trial_split(t);
                // A split into ku·kv cells has at least ku·kv leaves.
                if s.x * s.y < best.x {
                    let mine = run_trial(p, t, lid, false, best.x, 0u);
                    // The trial's leaves: the levels' and every lane's own count (the
                    // shared counter only tells the lanes when to stop), or none if a
                    // lane stopped.
                    lane_leaf[cc_slot(lid, t)] = select(mine, 0xffffffffu, lane_stopped);
                    workgroupBarrier();
                    if lid == 0u {
                        var total = found_now;
                        for (var l = 0u; l < CC_SLOTS; l++) {
                            total = select(total + lane_leaf[l], 0xffffffffu, lane_leaf[l] == 0xffffffffu || total == 0xffffffffu);
                        }
                        found_now = total;
                    }
                    let total = workgroupUniformLoad(&found_now);
                    if total < best.x {
                        best = vec2u(total, t);
                        best_mine = mine;
                    }
                }
            }
        }
        marks[slot_at(p, cc_slot(lid, best.y))] = best_mine;
        if lid == 0u {
            marks[p] = best.x;
            marks[best_at(p)] = best.x;
            marks[best_at(p) + 1u] = best.y;
        }
    } else if !hole {
        if lid == 0u {
            found_now = marks[best_at(p) + 1u];
        }
        let t = workgroupUniformLoad(&found_now);
        if t < CC_TRIALS {
            let mine = run_trial(p, t, lid, true, 0xffffffffu, marks[p]);
            // Both passes run the same code on the same data; a walk that found another
            // count would write over its neighbours' leaves.
            if mine != marks[slot_at(p, cc_slot(lid, t))] {
                atomicOr(&cc_state.overflow, 2u);
            }
            atomicMax(&cc_state.max_bound_bits, bitcast<u32>(lane_max_bound));
            atomicAdd(&cc_state.unmet, lane_unmet);
        }
    }
    // The search's cost (the emit pass decides the best trial's cells once more).
    if !emitting {
        atomicAdd(&cc_state.bounds, lane_bounds);
        atomicAdd(&cc_state.proven, lane_proven);
    }
}
