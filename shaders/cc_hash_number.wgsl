// Vertex numbers from the filled hash, independent of which invocation inserted first:
// `mark_first` flags each key's smallest item; the host scans the flags (exclusive
// prefix sum, in place); `assign` gives every item the number of its key's first item
// and lists the distinct keys in order of first occurrence (`assign_gather` also
// gathers each key's vertex).
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

// Assign's work for one item, but the distinct keys; whether it is its key's first.
fn assign_item(item: u32) -> bool {
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
        return false;
    }
    cc_ids[item] = cc_offsets[first];
    return is_first;
}

fn assign_in_range(item: u32) -> bool {
    return in_range(item) && item < arrayLength(&cc_ids);
}

@compute @workgroup_size(64)
fn assign(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if !assign_in_range(item) || item >= arrayLength(&cc_keys) {
        return;
    }
    if assign_item(item) && cc_offsets[item] < arrayLength(&cc_unique_keys) {
        cc_unique_keys[cc_offsets[item]] = cc_keys[item];
    }
}

// The adaptive stage's numbering (it needs no list of keys): `assign`, and the vertex of
// each distinct key from its first item for the vertex evaluation, in one dispatch (the
// vertex goes where the scan already put it: nothing `assign` writes is read). The hash's
// outcome goes to the stage's counters for `cc_polygon`'s emit to decide the run.
@group(0) @binding(60) var<storage, read> item_points: array<CcVertexPoint>;
@group(0) @binding(30) var<storage, read_write> vertex_points: array<CcVertexPoint>;

// `tessera_core::gpu_types::CcState`, the words this writes (see shared/cc_tess.wgsl).
struct CcRunCounters {
    drawn_vertices: u32,
    leaves: u32,
    overflow: atomic<u32>,
    need_poly: u32,
    need_indices: u32,
    unmet: u32,
    max_bound_bits: u32,
    vertices: u32,
}

@group(0) @binding(51) var<storage, read_write> run_state: CcRunCounters;

@compute @workgroup_size(64)
fn assign_gather(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if item == 0u && atomicLoad(&cc_hash_status.overflow) != 0u {
        atomicOr(&run_state.overflow, 1u);
    }
    if !assign_in_range(item) {
        return;
    }
    let first = assign_item(item);
    if item == cc_hash_status.items - 1u {
        run_state.vertices = cc_hash_status.unique;
    }
    if first && item < arrayLength(&item_points) {
        let id = cc_offsets[item];
        if id < arrayLength(&vertex_points) {
            vertex_points[id] = item_points[item];
        }
    }
}
