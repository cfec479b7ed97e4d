//! Exclusive prefix sum of `u32`, written as the GPU runs it: blocks of [`SCAN_BLOCK`]
//! values scanned on their own, their totals scanned the same way (recursively), and
//! added back. CPU twin of `shaders/scan.wgsl` (`scan_blocks`, `add_offsets`).

/// Values one workgroup scans: 256 invocations, two values each.
pub const SCAN_BLOCK: usize = 512;

/// Twin of `scan_blocks`: each block of `data` becomes its own exclusive scan, and its
/// total goes to `sums[block]`.
pub fn scan_blocks(data: &mut [u32], sums: &mut [u32]) {
    for (block, chunk) in data.chunks_mut(SCAN_BLOCK).enumerate() {
        let mut running = 0u32;
        for v in chunk {
            let x = *v;
            *v = running;
            running = running.wrapping_add(x);
        }
        sums[block] = running;
    }
}

/// Twin of `add_offsets`: adds each block's scanned total back to its values.
pub fn add_offsets(data: &mut [u32], sums: &[u32]) {
    for (block, chunk) in data.chunks_mut(SCAN_BLOCK).enumerate() {
        for v in chunk {
            *v = v.wrapping_add(sums[block]);
        }
    }
}

/// Exclusive prefix sum in place, level by level as the GPU records it; returns the
/// total.
pub fn exclusive_scan(values: &mut [u32]) -> u32 {
    let blocks = values.len().div_ceil(SCAN_BLOCK).max(1);
    let mut sums = vec![0u32; blocks];
    scan_blocks(values, &mut sums);
    if blocks == 1 {
        return sums[0];
    }
    let total = exclusive_scan(&mut sums);
    add_offsets(values, &sums);
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_running_sum_across_levels() {
        for n in [0, 1, 511, 512, 513, 4000, 262_145] {
            let values: Vec<u32> = (0..n as u32)
                .map(|i| i.wrapping_mul(2_654_435_761) % 7)
                .collect();
            let mut scanned = values.clone();
            let total = exclusive_scan(&mut scanned);
            let mut running = 0u32;
            for (i, v) in values.iter().enumerate() {
                assert_eq!(scanned[i], running, "n {n}, index {i}");
                running += v;
            }
            assert_eq!(total, running, "n {n}");
        }
    }
}
