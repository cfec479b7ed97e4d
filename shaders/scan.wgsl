// Exclusive prefix sum of u32, in place, in two dispatches whatever the length (a
// fixed script: the number of dispatches never depends on the data). The values are cut
// into as many chunks of whole blocks as there are workgroups (at most 256, fewer for a
// short list: `tessera_core::scan::scan_groups`); `reduce` sums each chunk, `scan_chunks` adds up the
// sums of the chunks before its own and scans its chunk block by block. Two lists can be
// scanned by the same two dispatches, each in half the chunks. No workgroup
// waits on another: WGSL promises no forward progress between workgroups, which rules
// out single-pass look-back scans. Twin: `tessera_core::scan::exclusive_scan`.

// A workgroup scans a block of WORKGROUP × PER_LANE values, each lane PER_LANE
// consecutive ones serially. Few lanes and few barriers: a CPU device runs a workgroup
// as fibers of a few lanes and switches every fiber at every barrier, so a wide
// Hillis–Steele scan with a barrier per step spends its time switching.
const WORKGROUP: u32 = 64u;
const PER_LANE: u32 = 8u;
const BLOCK: u32 = WORKGROUP * PER_LANE;

struct ScanParams {
    n: u32,
    // Where the number of live values is, minus one (`live[slot] + 1` values), or
    // 0xffffffff: all n. Lists sized for their capacity are then scanned only as far as
    // they are filled; values beyond are left as they are.
    live_slot: u32,
    // The second list, in `data_b` (its live count in `live_b`), when `lists` is 2.
    n_b: u32,
    live_slot_b: u32,
    lists: u32,
    // The first list's values are read as (x ^ xor) >> shift: keys that pack a count
    // with other bits are scanned in place as their counts.
    xor: u32,
    shift: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> scan: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;
@group(0) @binding(3) var<storage, read> live: array<u32>;
@group(0) @binding(4) var<storage, read_write> data_b: array<u32>;
@group(0) @binding(5) var<storage, read> live_b: array<u32>;


// The workgroups of the dispatch, a multiple of the lists (set in `reduce` and
// `scan_chunks` from their `num_workgroups`).
var<private> groups: u32;

// The chunks of each list, and the list of workgroup g.
fn list_groups() -> u32 {
    return groups / scan.lists;
}

fn list_of(g: u32) -> u32 {
    return g / list_groups();
}

fn scan_len(list: u32) -> u32 {
    if list == 0u {
        if scan.live_slot == 0xffffffffu {
            return scan.n;
        }
        return min(scan.n, live[scan.live_slot] + 1u);
    }
    if scan.live_slot_b == 0xffffffffu {
        return scan.n_b;
    }
    return min(scan.n_b, live_b[scan.live_slot_b] + 1u);
}

fn load(list: u32, i: u32) -> u32 {
    if list == 0u {
        return (data[i] ^ scan.xor) >> scan.shift;
    }
    return data_b[i];
}

fn store(list: u32, i: u32, v: u32) {
    if list == 0u {
        data[i] = v;
    } else {
        data_b[i] = v;
    }
}

// Blocks per chunk: the fewest that cover n in the list's chunks.
fn chunk_blocks(n: u32) -> u32 {
    let per_chunk = BLOCK * list_groups();
    return max((n + per_chunk - 1u) / per_chunk, 1u);
}

var<workgroup> lane_totals: array<u32, WORKGROUP>;
var<workgroup> carry: u32;

@compute @workgroup_size(64)
fn reduce(
    @builtin(workgroup_id) wg: vec3u,
    @builtin(num_workgroups) count: vec3u,
    @builtin(local_invocation_index) lid: u32,
) {
    groups = count.x;
    let list = list_of(wg.x);
    let g = wg.x % list_groups();
    let n = scan_len(list);
    let chunk = chunk_blocks(n) * BLOCK;
    let start = g * chunk;
    let end = min(start + chunk, n);
    var total = 0u;
    for (var i = start + lid; i < end; i += WORKGROUP) {
        total += load(list, i);
    }
    lane_totals[lid] = total;
    workgroupBarrier();
    if lid == 0u {
        var run = 0u;
        for (var l = 0u; l < WORKGROUP; l++) {
            run += lane_totals[l];
        }
        sums[wg.x] = run;
    }
}

@compute @workgroup_size(64)
fn scan_chunks(
    @builtin(workgroup_id) wg: vec3u,
    @builtin(num_workgroups) count: vec3u,
    @builtin(local_invocation_index) lid: u32,
) {
    groups = count.x;
    let list = list_of(wg.x);
    let g = wg.x % list_groups();
    let n = scan_len(list);
    let per = chunk_blocks(n);
    // The chunks of the same list before this one.
    var before = 0u;
    for (var h = wg.x - g + lid; h < wg.x; h += WORKGROUP) {
        before += sums[h];
    }
    lane_totals[lid] = before;
    workgroupBarrier();
    if lid == 0u {
        var run = 0u;
        for (var l = 0u; l < WORKGROUP; l++) {
            run += lane_totals[l];
        }
        carry = run;
    }
    for (var b = 0u; b < per; b++) {
        let i0 = (g * per + b) * BLOCK + PER_LANE * lid;
        var values: array<u32, PER_LANE>;
        var total = 0u;
        for (var k = 0u; k < PER_LANE; k++) {
            if i0 + k < n {
                values[k] = load(list, i0 + k);
            }
            total += values[k];
        }
        workgroupBarrier();
        lane_totals[lid] = total;
        workgroupBarrier();
        // One lane scans the lane totals (64 additions), where a tree took a barrier a
        // round.
        if lid == 0u {
            var run = carry;
            for (var l = 0u; l < WORKGROUP; l++) {
                let x = lane_totals[l];
                lane_totals[l] = run;
                run += x;
            }
            carry = run;
        }
        workgroupBarrier();
        var at = lane_totals[lid];
        for (var k = 0u; k < PER_LANE; k++) {
            if i0 + k < n {
                store(list, i0 + k, at);
            }
            at += values[k];
        }
    }
}
