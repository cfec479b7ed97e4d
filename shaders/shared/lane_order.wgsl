// The order in which a workgroup's invocations take its items: those flagged `last` run
// after the others, together. A CPU device (lavapipe) runs each group of 8 lanes for as
// long as its slowest lane, so grouping the slow items spares the fast ones the wait.
// Only the schedule changes: callers write each result at its item's own index. Each
// part keeps the order in which the lanes placed their items (on a CPU device, lane
// order), so items that depend on the ones before them (a first-split search's trials)
// still run after them.

var<workgroup> lane_items: array<u32, 64>;
var<workgroup> lane_front: atomic<u32>;
var<workgroup> lane_back: atomic<u32>;

const LANE_NONE: u32 = 0xffffffffu;

// Called by every invocation of a workgroup of 64, in uniform control flow: places item
// `mine` (if `valid`) first or last; returns the item invocation `lid` takes, or
// LANE_NONE.
fn lane_order(lid: u32, valid: bool, mine: u32, last: bool) -> u32 {
    if lid == 0u {
        atomicStore(&lane_front, 0u);
        atomicStore(&lane_back, 0u);
    }
    workgroupBarrier();
    if valid {
        var slot = 0u;
        if last {
            slot = 63u - atomicAdd(&lane_back, 1u);
        } else {
            slot = atomicAdd(&lane_front, 1u);
        }
        lane_items[slot] = mine;
    }
    workgroupBarrier();
    let front = atomicLoad(&lane_front);
    let back = atomicLoad(&lane_back);
    if lid >= front && lid < 64u - back {
        return LANE_NONE;
    }
    // The last items were placed from the end: read back in the order they came.
    if lid >= 64u - back {
        return lane_items[127u - back - lid];
    }
    return lane_items[lid];
}
