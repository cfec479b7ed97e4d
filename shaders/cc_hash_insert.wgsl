// One invocation per item: insert its key, lock-free, with bounded probing. The high
// word is claimed by compare-exchange, then the low word; whoever sets the low word owns
// the slot for that key, and a slot holding another key's word is passed over. Nobody
// waits on anybody (a weak compare-exchange is retried only when it failed spuriously).
// Out of probes: the overflow flag is set and the host grows the table and reruns. An
// item without a key (CC_NO_KEY) gets no slot and is no overflow.
// Twin of `tessera_core::catmull_clark::vertex_hash::hash_insert`.

#include "shared/cc_hash.wgsl"

// The word now in `key_hi` of `slot` after trying to set it from empty to `v`.
fn claim_hi(slot: u32, v: u32) -> u32 {
    loop {
        let r = atomicCompareExchangeWeak(&cc_table[slot].key_hi, 0u, v);
        if r.exchanged {
            return v;
        }
        if r.old_value != 0u {
            return r.old_value;
        }
    }
    return 0u;
}

fn claim_lo(slot: u32, v: u32) -> u32 {
    loop {
        let r = atomicCompareExchangeWeak(&cc_table[slot].key_lo, 0u, v);
        if r.exchanged {
            return v;
        }
        if r.old_value != 0u {
            return r.old_value;
        }
    }
    return 0u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = cc_item_index(gid, groups);
    if item >= cc_hash_status.items || item >= arrayLength(&cc_keys) || item >= arrayLength(&cc_item_slot) {
        return;
    }
    let key = cc_keys[item];
    if all(key == CC_NO_KEY) {
        cc_item_slot[item] = CC_NO_SLOT;
        return;
    }
    let hi = ~key.x;
    let lo = ~key.y;
    let capacity = arrayLength(&cc_table);
    var slot = cc_home_slot(key, capacity);
    var found = CC_NO_SLOT;
    for (var probe = 0u; probe < CC_HASH_MAX_PROBES; probe++) {
        if claim_hi(slot, hi) == hi && claim_lo(slot, lo) == lo {
            atomicMax(&cc_table[slot].first, ~item);
            found = slot;
            break;
        }
        slot = (slot + 1u) & (capacity - 1u);
    }
    if found == CC_NO_SLOT {
        atomicOr(&cc_hash_status.overflow, 1u);
    }
    cc_item_slot[item] = found;
}
