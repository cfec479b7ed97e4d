// Vertex numbers from the filled hash, independent of which invocation inserted first:
// `mark_first` flags each key's smallest item; the host scans the flags (exclusive
// prefix sum, in place); `assign` gives every item the number of its key's first item
// and lists the distinct keys in order of first occurrence.
// Twin of `tessera_core::catmull_clark::vertex_hash::{mark_first, assign}`.

#include "shared/cc_hash.wgsl"

@group(0) @binding(44) var<storage, read_write> cc_offsets: array<u32>;
@group(0) @binding(45) var<storage, read_write> cc_ids: array<u32>;
@group(0) @binding(46) var<storage, read_write> cc_unique_keys: array<vec2u>;

fn first_of(slot: u32) -> u32 {
    return ~atomicLoad(&cc_table[slot].first);
}

fn in_range(item: u32) -> bool {
    return item < cc_hash_status.items && item < arrayLength(&cc_item_slot)
        && item < arrayLength(&cc_offsets);
}

@compute @workgroup_size(64)
fn mark_first(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if !in_range(item) {
        return;
    }
    let slot = cc_item_slot[item];
    cc_offsets[item] = select(0u, 1u, slot != CC_NO_SLOT && first_of(slot) == item);
}

@compute @workgroup_size(64)
fn assign(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if !in_range(item) || item >= arrayLength(&cc_ids) || item >= arrayLength(&cc_keys) {
        return;
    }
    let slot = cc_item_slot[item];
    var first = CC_NO_SLOT;
    if slot != CC_NO_SLOT {
        first = first_of(slot);
    }
    let is_first = first == item;
    // The last item counts the keys, whether it has one or not.
    if item == cc_hash_status.items - 1u {
        cc_hash_status.unique = cc_offsets[item] + select(0u, 1u, is_first);
    }
    if slot == CC_NO_SLOT {
        cc_ids[item] = CC_NO_SLOT;
        return;
    }
    cc_ids[item] = cc_offsets[first];
    if is_first && cc_offsets[item] < arrayLength(&cc_unique_keys) {
        cc_unique_keys[cc_offsets[item]] = cc_keys[item];
    }
}

// After `assign`: the vertex of each distinct key (from its first item) for the vertex
// evaluation, and how many there are.
@group(0) @binding(60) var<storage, read> item_points: array<CcVertexPoint>;
@group(0) @binding(30) var<storage, read_write> vertex_points: array<CcVertexPoint>;
@group(0) @binding(32) var<storage, read_write> vertex_count: array<u32>;

@compute @workgroup_size(64)
fn gather_points(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if item == 0u {
        vertex_count[0] = cc_hash_status.unique;
    }
    if !in_range(item) || item >= arrayLength(&item_points) {
        return;
    }
    let slot = cc_item_slot[item];
    if slot != CC_NO_SLOT && first_of(slot) == item {
        let id = cc_offsets[item];
        if id < arrayLength(&vertex_points) {
            vertex_points[id] = item_points[item];
        }
    }
}
