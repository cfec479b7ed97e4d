// After the scan of the split flags (`flags[c]` = split cells before c, `flags[count]`
// = all of them): a split cell writes its four quadrants to the next list at
// 4 · flags[c]; in the final round a leaf is appended to the leaves at c - flags[c].
// `finish` sets the next list's size and dispatch. Nothing is written past a capacity;
// the sizes needed are recorded for the host to grow the buffers.
// Twin: `gpu_pipeline::split`.

#include "shared/cc_tess.wgsl"

@group(0) @binding(53) var<storage, read> cells_in: array<CcCell>;
@group(0) @binding(52) var<storage, read_write> cells_out: array<CcCell>;
@group(0) @binding(54) var<storage, read> flags: array<u32>;
@group(0) @binding(55) var<storage, read_write> leaves: array<CcCell>;

// Whether the cell's trial can no longer beat its patch's best split so far: it will
// have at least ku·kv + 3 · (splits so far) leaves. Its cells are then dropped (the
// quadrants are written as dead cells), as the CPU reference stops counting a trial
// once it reaches the best.
fn cannot_win(cell: CcCell) -> bool {
    let t = cell.trial_depth & 0xffu;
    let s = cc_trial_split(t);
    let at_least = s.x * s.y + 3u * atomicLoad(&cc_state.trials[cell.patch_id * CC_TRIALS + t]);
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
        let dead = cc_state.round < CC_SEARCH_ROUNDS && cannot_win(cell);
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
    } else if cc_state.round >= CC_SEARCH_ROUNDS {
        let at = cc_state.leaves + c - before;
        if at < arrayLength(&leaves) && at < cc_params.leaf_capacity {
            leaves[at] = cell;
        }
    }
}

@compute @workgroup_size(1)
fn finish() {
    let n = cc_state.count;
    let split = flags[n];
    if cc_state.round >= CC_SEARCH_ROUNDS {
        cc_state.leaves += n - split;
        if cc_state.leaves > cc_params.leaf_capacity {
            atomicOr(&cc_state.overflow, 1u);
        }
        // The leaf kernels run over min(leaves, capacity).
        cc_write_args(3u, min(cc_state.leaves, cc_params.leaf_capacity));
        // The hash runs over their four corner keys each; at least one invocation, which
        // writes the counts even when there are none.
        cc_write_args(6u, max(4u * min(cc_state.leaves, cc_params.leaf_capacity), 1u));
    }
    let next = 4u * split;
    atomicMax(&cc_state.need_cells, next);
    if next > cc_params.cell_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    cc_state.count = min(next, cc_params.cell_capacity);
    cc_write_args(0u, cc_state.count);
}
