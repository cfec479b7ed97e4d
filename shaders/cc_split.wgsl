// After the scan of the split flags (`flags[c]` = split cells before c, `flags[count]`
// = all of them): a split cell writes its four quadrants to the next list at
// 4 · flags[c]; any other cell (a leaf, or a dead cell of a dropped trial) is appended
// to the search's leaves at c - flags[c], where `cc_collect` finds the leaves of each
// patch's best trial once the search is over. `finish` sets the next list's size and
// dispatch. Nothing is written past a capacity; the sizes needed are recorded for the
// host to grow the buffers.
// Twin: the recursion of `tessera_core::catmull_clark::adaptive::mark`.

#include "shared/cc_tess.wgsl"

@group(0) @binding(53) var<storage, read> cells_in: array<CcCell>;
@group(0) @binding(52) var<storage, read_write> cells_out: array<CcCell>;
@group(0) @binding(54) var<storage, read> flags: array<u32>;
@group(0) @binding(61) var<storage, read_write> search_leaves: array<CcCell>;

// Whether the cell's trial can no longer beat its patch's best split so far: it will
// have at least ku·kv + 3 · (splits so far) leaves. Its cells are then dropped (the
// quadrants are written as dead cells), as the CPU reference stops counting a trial
// once it reaches the best.
fn cannot_win(cell: CcCell) -> bool {
    let t = cell.trial_depth & 0xffu;
    let s = cc_trial_split(t);
    let at_least = s.x * s.y + 3u * atomicLoad(&cc_state.trials[cc_trial_slot(0u, cell.patch_id, t)]);
    let b = best_before(cell.patch_id);
    return at_least > b.x || (at_least == b.x && t > b.y);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let c = cc_invocation(gid, groups);
    if c >= cc_state.count || c + 1u >= arrayLength(&flags) || c >= arrayLength(&cells_in) {
        return;
    }
    let before = flags[c];
    let cell = cells_in[c];
    if flags[c + 1u] > before {
        let half = cc_cell_size(cell) / 2u;
        let deeper = cell.trial_depth + (1u << 8u);
        let dead = cannot_win(cell);
        for (var q = 0u; q < 4u; q++) {
            let at = 4u * before + q;
            let o = vec2u(select(0u, 1u, q == 1u || q == 2u), select(0u, 1u, q >= 2u));
            var child = CcCell(cell.patch_id, deeper, cell.i + o.x * half.x, cell.j + o.y * half.y);
            if dead {
                child.patch_id = CC_NO_NEIGHBOUR;
            }
            if at < arrayLength(&cells_out) && at < cc_params.cell_capacity {
                cells_out[at] = child;
            }
        }
    } else {
        let at = cc_state.search_leaves + c - before;
        if at < arrayLength(&search_leaves) && at < cc_params.search_leaf_capacity {
            search_leaves[at] = cell;
        }
    }
}

@compute @workgroup_size(1)
fn finish() {
    let n = cc_state.count;
    let split = flags[n];
    cc_state.search_leaves += n - split;
    if cc_state.search_leaves > cc_params.search_leaf_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    cc_write_args(9u, min(cc_state.search_leaves, cc_params.search_leaf_capacity));
    let next = 4u * split;
    atomicMax(&cc_state.need_cells, next);
    if next > cc_params.cell_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    cc_state.count = min(next, cc_params.cell_capacity);
    cc_write_args(0u, cc_state.count);
}
