// One invocation per leaf: the canonical keys of its four corners (items 4·leaf + k,
// in corner order) for the vertex hash, with the point each key stands for; invocation
// 0 tells the hash how many items there are.
// Twin: the corner keys of `tessera_core::catmull_clark::keys::point_key`, as the CPU
// reference adds them per leaf (`adaptive::tessellate_with_splits`, step 2).

#include "shared/cc_tess.wgsl"

struct CcHashStatusOut {
    items: u32,
    overflow: u32,
    unique: u32,
    pad: u32,
}

@group(0) @binding(40) var<storage, read_write> keys_out: array<vec2u>;
@group(0) @binding(43) var<storage, read_write> hash_status: CcHashStatusOut;
@group(0) @binding(55) var<storage, read> leaves: array<CcCell>;
@group(0) @binding(59) var<storage, read> topo: array<CcPatchTopo>;
@group(0) @binding(60) var<storage, read_write> item_points: array<CcPoint>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    if l == 0u {
        hash_status.items = 4u * n;
    }
    if l >= n || l >= arrayLength(&leaves) {
        return;
    }
    let cell = leaves[l];
    let tp = topo[cell.patch_id];
    for (var k = 0u; k < 4u; k++) {
        let at = 4u * l + k;
        let q = cc_cell_corner(cell, k);
        if at < arrayLength(&keys_out) && at < arrayLength(&item_points) {
            keys_out[at] = cc_point_key(tp, cell.patch_id, q.x, q.y);
            item_points[at] = CcPoint(cell.patch_id, cc_grid_fixed(q.x), cc_grid_fixed(q.y));
        }
    }
}
