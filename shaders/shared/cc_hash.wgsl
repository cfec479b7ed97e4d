// The vertex hash's table and status (bindings 40-46 of the cc_hash kernels). Slot words
// are stored bit-inverted: an all-zero table is empty.
// Twin: `tessera_core::catmull_clark::vertex_hash`.

#include "shared/types.wgsl"
#include "shared/cc_hash_key.wgsl"

struct CcHashSlot {
    key_hi: atomic<u32>,
    key_lo: atomic<u32>,
    first: atomic<u32>,
}

struct CcHashStatus {
    items: u32,
    overflow: atomic<u32>,
    unique: u32,
    pad: u32,
}

@group(0) @binding(40) var<storage, read> cc_keys: array<vec2u>;
@group(0) @binding(41) var<storage, read_write> cc_table: array<CcHashSlot>;
@group(0) @binding(42) var<storage, read_write> cc_item_slot: array<u32>;
@group(0) @binding(43) var<storage, read_write> cc_hash_status: CcHashStatus;


fn cc_item_index(gid: vec3u, groups: vec3u) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
