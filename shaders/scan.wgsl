// Exclusive prefix sum of u32, in place, one level of a multi-level scan (the host
// records the levels). `scan_blocks`: each workgroup scans its block of
// 2 × WORKGROUP values and writes the block's total to `sums`; `add_offsets` adds the
// scanned block totals back. Twin of `tessera_core::scan::{scan_blocks, add_offsets}`.

const WORKGROUP: u32 = 256u;
const BLOCK: u32 = 2u * WORKGROUP;

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

var<workgroup> partial: array<u32, WORKGROUP>;

fn block_index(wg: vec3u, groups: vec3u) -> u32 {
    return wg.x + wg.y * groups.x;
}

@compute @workgroup_size(256)
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
    let i0 = block * BLOCK + 2u * lid;
    var a = 0u;
    var b = 0u;
    if i0 < n {
        a = data[i0];
    }
    if i0 + 1u < n {
        b = data[i0 + 1u];
    }
    // Inclusive Hillis–Steele scan of the pair sums across the workgroup.
    partial[lid] = a + b;
    workgroupBarrier();
    for (var offset = 1u; offset < WORKGROUP; offset *= 2u) {
        var x = 0u;
        if lid >= offset {
            x = partial[lid - offset];
        }
        workgroupBarrier();
        partial[lid] += x;
        workgroupBarrier();
    }
    let before = partial[lid] - (a + b);
    if i0 < n {
        data[i0] = before;
    }
    if i0 + 1u < n {
        data[i0 + 1u] = before + a;
    }
    // Dispatches folded into two dimensions may carry whole groups past the last block.
    if lid == WORKGROUP - 1u && block < arrayLength(&sums) {
        sums[block] = partial[lid];
    }
}

@compute @workgroup_size(256)
fn add_offsets(
    @builtin(workgroup_id) wg: vec3u,
    @builtin(num_workgroups) groups: vec3u,
    @builtin(local_invocation_index) lid: u32,
) {
    let block = block_index(wg, groups);
    if block >= arrayLength(&sums) {
        return;
    }
    let i0 = block * BLOCK + 2u * lid;
    let n = scan_len();
    let add = sums[block];
    if i0 < n {
        data[i0] += add;
    }
    if i0 + 1u < n {
        data[i0 + 1u] += add;
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
