// After the search: the output's leaves are the search's leaves of each patch's best
// trial, in the order the search found them. `count` flags them (one invocation per
// search leaf), the host scans the flags, `emit` copies them to the leaves, `finish`
// sets the leaf count and the dispatches of the leaf and hash kernels.
// Twin: `tessera_core::catmull_clark::adaptive::tessellate_with_splits`, which keeps the
// leaves of the best trial it marked.

#include "shared/cc_tess.wgsl"

@group(0) @binding(54) var<storage, read_write> flags: array<u32>;
@group(0) @binding(55) var<storage, read_write> leaves: array<CcCell>;
@group(0) @binding(61) var<storage, read> search_leaves: array<CcCell>;

fn search_leaf_count() -> u32 {
    return min(cc_state.search_leaves, cc_params.search_leaf_capacity);
}

// Whether search leaf l belongs to its patch's best trial (dead cells of dropped
// trials belong to no patch).
fn kept(l: u32) -> bool {
    let cell = search_leaves[l];
    return cell.patch_id != CC_NO_NEIGHBOUR && (cell.trial_depth & 0xffu) == best[cell.patch_id].y;
}

@compute @workgroup_size(64)
fn count(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    if l >= search_leaf_count() || l >= arrayLength(&search_leaves) || l >= arrayLength(&flags) {
        return;
    }
    flags[l] = select(0u, 1u, kept(l));
}

@compute @workgroup_size(64)
fn emit(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    if l >= search_leaf_count() || l + 1u >= arrayLength(&flags) || l >= arrayLength(&search_leaves) {
        return;
    }
    let at = flags[l];
    if flags[l + 1u] > at && at < arrayLength(&leaves) && at < cc_params.leaf_capacity {
        leaves[at] = search_leaves[l];
    }
}

@compute @workgroup_size(1)
fn finish() {
    cc_state.leaves = flags[search_leaf_count()];
    if cc_state.leaves > cc_params.leaf_capacity {
        atomicOr(&cc_state.overflow, 1u);
    }
    // The leaf kernels run over min(leaves, capacity); the hash over their eight items
    // each, at least one invocation, which writes the counts even when there are none.
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    cc_write_args(3u, n);
    cc_write_args(6u, max(8u * n, 1u));
}
