// Adaptive marking to full depth in one dispatch per pass, one invocation per patch.
// The count pass runs the CPU's first-split search: trials in order, each walking the
// cells of its split row by row and each cell's subtree depth first, without a stack
// (`cc_next_cell`); a trial that cannot beat the best so far is skipped, one that
// reaches it is stopped (ties go to the earlier trial). A cell is decided alone
// (`cc_decide`), so the leaves do not depend on the order of work. Every decision is
// kept as a bit, in a chain of blocks of 32, so the emit pass replays the best trial's
// walk without deciding anything again, writing its leaves from the patch's first
// leaf (scanned in between).
//
// No workgroup memory, no barriers and no waiting on other invocations. A CPU device
// (lavapipe) runs eight lanes at a time through every instruction of a loop until the
// last lane is done, and stops every loop of those eight lanes after 65 535 iterations
// in all: the emit pass has no decision code, and a walk cut short is reported
// (overflow bit 4), never taken for a mesh.
//
// The same entry runs for both passes, told apart by `cc_pass` (one pipeline).
// Twin: `tessera_core::catmull_clark::traverse`.

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"
#include "shared/lane_order.wgsl"

@group(0) @binding(55) var<storage, read_write> leaves: array<CcCell>;
@group(0) @binding(68) var<uniform> cc_pass: vec4u;


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

// Per invocation: what its decisions cost, and (emit) what its leaves guarantee.
var<private> lane_bounds: u32;
var<private> lane_proven: u32;
var<private> lane_unmet: u32;
var<private> lane_max_bound: f32;

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

// The decision blocks of one walk: where the next bit goes (or comes from).
struct CcChain {
    block: u32,
    bit: u32,
    bits: u32,
}

// The walks' decisions, 32 to a block `[bits, next block]` in the marks after the
// patches' words: blocks 2p and 2p + 1 are patch p's own, further blocks are taken in
// turn (`cc_state.decision_blocks`).
fn cc_bits_at(b: u32) -> u32 {
    return 3u * cc_params.patch_count + 1u + 2u * b;
}

fn cc_blocks() -> u32 {
    return (arrayLength(&marks) - cc_bits_at(0u)) / 2u;
}

// A free block for a chain that needs more than its patch's own; CC_NO_BLOCK once there
// are no more (overflow bit 8: the run needs more).
const CC_NO_BLOCK: u32 = 0xffffffffu;

fn cc_take_block() -> u32 {
    let own = 2u * cc_params.patch_count;
    let b = own + atomicAdd(&cc_state.decision_blocks, 1u);
    if b >= cc_blocks() {
        atomicOr(&cc_state.overflow, 8u);
        return CC_NO_BLOCK;
    }
    marks[cc_bits_at(b) + 1u] = CC_NO_BLOCK;
    return b;
}

// Records one decision; a full block is written out and the chain moves on to its next
// block, taking one if it has none.
fn cc_record(c: ptr<function, CcChain>, split: bool) {
    if split {
        (*c).bits |= 1u << (*c).bit;
    }
    (*c).bit += 1u;
    if (*c).bit == 32u && (*c).block != CC_NO_BLOCK {
        marks[cc_bits_at((*c).block)] = (*c).bits;
        var next = marks[cc_bits_at((*c).block) + 1u];
        if next == CC_NO_BLOCK {
            next = cc_take_block();
            marks[cc_bits_at((*c).block) + 1u] = next;
        }
        (*c).block = next;
        (*c).bit = 0u;
        (*c).bits = 0u;
    }
}

// Writes out the last, partly filled block.
fn cc_flush(c: CcChain) {
    if c.block != CC_NO_BLOCK && c.bit > 0u {
        marks[cc_bits_at(c.block)] = c.bits;
    }
}

// The next decision of a chain being replayed.
fn cc_replay(c: ptr<function, CcChain>) -> bool {
    if (*c).bit == 32u {
        if (*c).block != CC_NO_BLOCK {
            (*c).block = marks[cc_bits_at((*c).block) + 1u];
        }
        (*c).bit = 0u;
        (*c).bits = 0u;
        if (*c).block != CC_NO_BLOCK {
            (*c).bits = marks[cc_bits_at((*c).block)];
        }
    }
    let split = ((*c).bits >> (*c).bit & 1u) != 0u;
    (*c).bit += 1u;
    return split;
}

fn cc_chain_at(block: u32) -> CcChain {
    return CcChain(block, 0u, 0u);
}

// Counting: patch p's search, as `traverse::search`. One loop over every decision of
// every trial, so that lanes of different patches keep deciding side by side.
fn count_patch(p: u32) {
    // Chain 0 holds the best trial's decisions, chain 1 the current one's (swapped when
    // the current trial becomes the best). Blocks of a losing trial are reused.
    var heads = vec2u(2u * p, 2u * p + 1u);
    marks[cc_bits_at(heads.x) + 1u] = CC_NO_BLOCK;
    marks[cc_bits_at(heads.y) + 1u] = CC_NO_BLOCK;
    var chain = cc_chain_at(heads.y);
    var best = 0xffffffffu;
    var best_trial = CC_TRIALS;
    var best_max = 0.0;
    var best_unmet = 0u;
    var t = 0u;
    var r = 0u;
    var mine = 0u;
    var at_cell = cc_root_cell(0u, 0u);
    var searching = true;
    while searching {
        let cell = cc_cell_of(p, t, at_cell);
        let split = decide_counted(cell);
        cc_record(&chain, split);
        var trial_over = false;
        if split {
            at_cell = cc_first_child(at_cell);
        } else {
            mine += 1u;
            let next = cc_next_cell(t, at_cell);
            if next.y != 0xffffffffu {
                at_cell = next;
            } else {
                r += 1u;
                let s = cc_trial_split(t);
                if r < s.x * s.y {
                    at_cell = cc_root_cell(t, r);
                } else if mine < best {
                    // Finished with fewer leaves than the best so far: the new best.
                    cc_flush(chain);
                    best = mine;
                    best_trial = t;
                    best_max = lane_max_bound;
                    best_unmet = lane_unmet;
                    heads = heads.yx;
                    trial_over = true;
                }
            }
            // Reaching the best (a tie goes to the earlier trial): stopped.
            trial_over = trial_over || mine >= best;
        }
        if trial_over {
            // On to the next trial that could beat the best: ku·kv cells give at least
            // ku·kv leaves.
            t += 1u;
            for (; t < cc_params.trials; t++) {
                let s = cc_trial_split(t);
                if s.x * s.y < best {
                    break;
                }
            }
            searching = t < cc_params.trials;
            r = 0u;
            mine = 0u;
            lane_max_bound = 0.0;
            lane_unmet = 0u;
            at_cell = cc_root_cell(min(t, CC_TRIALS - 1u), 0u);
            chain = cc_chain_at(heads.y);
        }
    }
    // The loop ends only when the search is over: otherwise the device cut it short.
    if searching {
        atomicOr(&cc_state.overflow, 4u);
    }
    marks[p] = best;
    marks[cc_chosen_at(p)] = best_trial;
    marks[cc_head_at(p)] = heads.x;
    atomicMax(&cc_state.max_bound_bits, bitcast<u32>(best_max));
    atomicAdd(&cc_state.unmet, best_unmet);
}

// Emitting: the best trial's walk replayed, its leaves written from the patch's first.
fn emit_patch(p: u32) {
    let t = marks[cc_chosen_at(p)];
    let first = marks[p];
    // The count pass's leaves: at most that many are written here.
    let count = marks[p + 1u] - first;
    let head = marks[cc_head_at(p)];
    var chain = CcChain(head, 0u, marks[cc_bits_at(head)]);
    var r = 0u;
    var mine = 0u;
    var at_cell = cc_root_cell(t, 0u);
    var walking = true;
    let area = cc_trial_split(t).x * cc_trial_split(t).y;
    while walking {
        let cell = cc_cell_of(p, t, at_cell);
        if cc_replay(&chain) {
            at_cell = cc_first_child(at_cell);
        } else {
            let k = first + mine;
            if mine < count && k < cc_params.leaf_capacity && k < arrayLength(&leaves) {
                leaves[k] = cell;
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
    // The replay must find what the search counted.
    if mine != count {
        atomicOr(&cc_state.overflow, 2u);
    }
}

// Whether patch p has an extraordinary vertex (its tree splits at the root): its bounds
// walk chains of pieces and its walks go deeper.
fn cc_irregular(p: u32) -> bool {
    return cc_roots[p] != CC_NO_ROOT && (cc_nodes[cc_roots[p]].kind & CC_NODE_KIND_MASK) != CC_NODE_BEZIER;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32) {
    let x = cc_invocation(gid, groups);
    let emitting = cc_pass.x == 1u;
    let patches = cc_params.patch_count;
    // Counting, the patches at a vertex of each workgroup search side by side, after the
    // others (`shared/lane_order.wgsl`).
    let valid = x < patches;
    let ordered = lane_order(lid, valid, x, valid && cc_irregular(x));
    if x == 0u {
        if emitting {
            // The scan left the total after the patches' offsets.
            let total = marks[patches];
            cc_state.leaves = total;
            if total > cc_params.leaf_capacity {
                atomicOr(&cc_state.overflow, 1u);
            }
            let n = min(total, cc_params.leaf_capacity);
            cc_write_args(3u, n);
            cc_write_args(6u, 8u * n);
        } else {
            // Scanned as no leaves: the total lands here.
            marks[patches] = 0u;
        }
    }
    let p = select(x, ordered, !emitting);
    if p >= patches {
        return;
    }
    // A hole has no surface (and no tree): no leaves, no trial.
    if cc_roots[p] == CC_NO_ROOT {
        if !emitting {
            marks[p] = 0u;
            marks[cc_chosen_at(p)] = CC_TRIALS;
        }
        return;
    }
    if emitting {
        emit_patch(p);
    } else {
        count_patch(p);
        atomicAdd(&cc_state.bounds, lane_bounds);
        atomicAdd(&cc_state.proven, lane_proven);
    }
}
