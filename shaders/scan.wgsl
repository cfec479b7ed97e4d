// Exclusive prefix sum of u32, in place, one level of a multi-level scan (the host
// records the levels). `scan_blocks`: each workgroup scans its block of
// BLOCK values and writes the block's total to `sums`; `add_offsets` adds the
// scanned block totals back. Twin of `tessera_core::scan::{scan_blocks, add_offsets}`.

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
    // Levels of the whole scan (read by `dispatch_args` on the first level).
    levels: u32,
}

@group(0) @binding(0) var<uniform> scan: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;
@group(0) @binding(3) var<storage, read> live: array<u32>;
// Indirect dispatch arguments, three words per level.
@group(0) @binding(4) var<storage, read_write> level_args: array<u32>;

fn scan_len() -> u32 {
    if scan.live_slot == 0xffffffffu {
        return scan.n;
    }
    return min(scan.n, live[scan.live_slot] + 1u);
}

var<workgroup> lane_totals: array<u32, WORKGROUP>;

fn block_index(wg: vec3u, groups: vec3u) -> u32 {
    return wg.x + wg.y * groups.x;
}

@compute @workgroup_size(64)
fn scan_blocks(
    @builtin(workgroup_id) wg: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = block_index(wg, groups);
    let n = scan_len();
    // Uniform per workgroup: a block wholly past the live values does nothing.
    if block * BLOCK >= n && block > 0u {
        return;
    }
    let i0 = block * BLOCK + PER_LANE * lid;
    var values: array<u32, PER_LANE>;
    var total = 0u;
    for (var k = 0u; k < PER_LANE; k++) {
        if i0 + k < n {
            values[k] = data[i0 + k];
        }
        total += values[k];
    }
    lane_totals[lid] = total;
    workgroupBarrier();
    // One lane scans the lane totals (64 additions), where a tree took a barrier a round.
    if lid == 0u {
        var run = 0u;
        for (var l = 0u; l < WORKGROUP; l++) {
            let x = lane_totals[l];
            lane_totals[l] = run;
            run += x;
        }
        // Dispatches folded into two dimensions may carry whole groups past the last block.
        if block < arrayLength(&sums) {
            sums[block] = run;
        }
    }
    workgroupBarrier();
    var before = lane_totals[lid];
    for (var k = 0u; k < PER_LANE; k++) {
        if i0 + k < n {
            data[i0 + k] = before;
        }
        before += values[k];
    }
}

@compute @workgroup_size(64)
fn add_offsets(
    @builtin(workgroup_id) wg: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = block_index(wg, groups);
    if block >= arrayLength(&sums) {
        return;
    }
    let i0 = block * BLOCK + PER_LANE * lid;
    let n = scan_len();
    let add = sums[block];
    for (var k = 0u; k < PER_LANE; k++) {
        if i0 + k < n {
            data[i0 + k] += add;
        }
    }
}

// One invocation, before a scan bounded by a live count: the workgroups each level needs
// for that count, so that a list sized for its capacity costs what it holds (as
// `kernel::groups_2d`).
@compute @workgroup_size(1)
fn dispatch_args() {
    var count = scan_len();
    for (var l = 0u; l < scan.levels; l++) {
        let g = max((count + BLOCK - 1u) / BLOCK, 1u);
        level_args[3u * l] = min(g, 32768u);
        level_args[3u * l + 1u] = (g + 32767u) / 32768u;
        level_args[3u * l + 2u] = 1u;
        count = g;
    }
}
