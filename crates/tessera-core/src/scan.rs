//! Exclusive prefix sum of `u32`, written as the GPU runs it (`shaders/scan.wgsl`): the
//! values cut into [`scan_groups`] chunks of whole blocks of [`SCAN_BLOCK`]; each chunk
//! summed (`reduce`), then each chunk scanned after the sum of the chunks before it
//! (`scan_chunks`). Two dispatches whatever the length.

/// Values one workgroup scans at a time: 64 invocations, eight values each.
pub const SCAN_BLOCK: usize = 512;
/// The most workgroups of each of the two dispatches, whatever the length.
pub const SCAN_GROUPS: usize = 256;

/// Workgroups of each dispatch for `lists` lists of at most `n` values: a block's chunk
/// each, up to [`SCAN_GROUPS`] (a multiple of `lists`). A short list is scanned by few:
/// a device that runs workgroups one after another (a CPU's) pays for each one.
pub fn scan_groups(n: usize, lists: usize) -> usize {
    (lists * n.div_ceil(SCAN_BLOCK).max(1)).min(SCAN_GROUPS)
}

/// Blocks per chunk: the fewest that cover `n` values in `groups` chunks.
pub fn chunk_blocks(n: usize, groups: usize) -> usize {
    n.div_ceil(SCAN_BLOCK * groups).max(1)
}

/// Twin of `reduce`: the sum of each chunk.
pub fn reduce(data: &[u32]) -> Vec<u32> {
    let groups = scan_groups(data.len(), 1);
    let chunk = chunk_blocks(data.len(), groups) * SCAN_BLOCK;
    (0..groups)
        .map(|g| {
            let start = (g * chunk).min(data.len());
            let end = (start + chunk).min(data.len());
            data[start..end]
                .iter()
                .fold(0u32, |a, &x| a.wrapping_add(x))
        })
        .collect()
}

/// Twin of `scan_chunks`: each chunk scanned after the chunks before it.
pub fn scan_chunks(data: &mut [u32], sums: &[u32]) {
    let chunk = chunk_blocks(data.len(), sums.len()) * SCAN_BLOCK;
    for (g, values) in data.chunks_mut(chunk).enumerate() {
        // The sums of the chunks before this one, as each workgroup adds them up.
        let mut carry = sums[..g].iter().fold(0u32, |a, &x| a.wrapping_add(x));
        for v in values {
            let x = *v;
            *v = carry;
            carry = carry.wrapping_add(x);
        }
    }
}

/// Exclusive prefix sum in place, as the GPU records it; returns the total.
pub fn exclusive_scan(values: &mut [u32]) -> u32 {
    let sums = reduce(values);
    scan_chunks(values, &sums);
    sums.iter().fold(0u32, |a, &x| a.wrapping_add(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_a_running_sum_across_chunk_sizes() {
        // One block, one block per chunk, several blocks per chunk.
        for n in [0, 1, 511, 512, 513, 4000, 131_072, 131_073, 600_000] {
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
