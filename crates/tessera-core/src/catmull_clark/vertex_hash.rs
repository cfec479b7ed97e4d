//! The global vertex hash of the GPU path (the paper's "globalization"), as the kernels
//! `shaders/cc_hash_insert.wgsl` and `shaders/cc_hash_number.wgsl` run it; these are
//! their CPU twins, one loop iteration per invocation.
//!
//! Items are canonical point keys in their charts ([`super::keys::chart_key`]), many
//! equal (a point marked by every cell around it), some absent ([`CC_NO_KEY`]: the
//! table passes them over). Insertion is lock-free with 32-bit atomics only: a slot's high word
//! is claimed by compare-exchange, then its low word; whoever sets the low word owns the
//! slot for that key, and an insertion that finds another key's word moves on. Nobody
//! waits on anybody. Each slot keeps the smallest item that inserted its key, so the
//! numbering (distinct keys in order of first occurrence, by a prefix sum) does not
//! depend on which invocation ran first, though slots may.

use crate::gpu_types::{CcHashSlot, CcHashStatus, CC_HASH_MAX_PROBES, CC_NO_KEY, CC_NO_SLOT};

/// A key as the kernels see it: `[hi, lo]`. No canonical key has a word equal to
/// `u32::MAX` (tag 3 is unused; charts are below 2^22, `j` and `t` at most
/// `840 · 2^10`), so the inverted words are never 0, and [`CC_NO_KEY`] is no key.
pub fn split_key(key: u64) -> [u32; 2] {
    [(key >> 32) as u32, key as u32]
}

/// The first slot probed for a key in a table of `capacity` (a power of two) slots.
pub fn home_slot(key: [u32; 2], capacity: u32) -> u32 {
    let mut h = key[1].wrapping_mul(0x9E37_79B1) ^ key[0].wrapping_mul(0x85EB_CA77);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    h & (capacity - 1)
}

/// Twin of `cc_hash_insert`: every item's slot ([`CC_NO_SLOT`] where the probes ran out,
/// which sets `status.overflow`, and for [`CC_NO_KEY`]).
///
/// `table.len()` must be a power of two.
pub fn hash_insert(
    table: &mut [CcHashSlot],
    keys: &[[u32; 2]],
    item_slot: &mut [u32],
    status: &mut CcHashStatus,
) {
    let capacity = table.len() as u32;
    for item in 0..status.items.min(keys.len() as u32) {
        let key = keys[item as usize];
        if key == CC_NO_KEY {
            item_slot[item as usize] = CC_NO_SLOT;
            continue;
        }
        let (hi, lo) = (!key[0], !key[1]);
        let mut slot = home_slot(key, capacity);
        let mut found = CC_NO_SLOT;
        for _ in 0..CC_HASH_MAX_PROBES {
            let s = &mut table[slot as usize];
            // atomicCompareExchangeWeak(&key_hi, 0, hi), then the same on key_lo.
            if s.key_hi == 0 {
                s.key_hi = hi;
            }
            if s.key_hi == hi {
                if s.key_lo == 0 {
                    s.key_lo = lo;
                }
                if s.key_lo == lo {
                    s.first = s.first.max(!item);
                    found = slot;
                    break;
                }
            }
            slot = (slot + 1) & (capacity - 1);
        }
        if found == CC_NO_SLOT {
            status.overflow = 1;
        }
        item_slot[item as usize] = found;
    }
}

/// Twin of `cc_hash_number`'s `mark_first`: 1 where an item is its key's first.
pub fn mark_first(table: &[CcHashSlot], item_slot: &[u32], status: &CcHashStatus) -> Vec<u32> {
    (0..status.items as usize)
        .map(|i| {
            let s = item_slot[i];
            u32::from(s != CC_NO_SLOT && !table[s as usize].first == i as u32)
        })
        .collect()
}

/// Twin of `cc_hash_number`'s `assign`, after the exclusive prefix sum of the flags:
/// each item's vertex number, the distinct keys in order, and their count.
pub fn assign(
    table: &[CcHashSlot],
    item_slot: &[u32],
    keys: &[[u32; 2]],
    offsets: &[u32],
    status: &mut CcHashStatus,
) -> (Vec<u32>, Vec<[u32; 2]>) {
    let n = status.items as usize;
    let mut ids = vec![CC_NO_SLOT; n];
    let mut unique = vec![[0u32; 2]; n];
    for i in 0..n {
        let s = item_slot[i];
        let is_first = s != CC_NO_SLOT && !table[s as usize].first == i as u32;
        if i == n - 1 {
            status.unique = offsets[i] + u32::from(is_first);
        }
        if s == CC_NO_SLOT {
            continue;
        }
        let first = !table[s as usize].first;
        ids[i] = offsets[first as usize];
        if is_first {
            unique[offsets[i] as usize] = keys[i];
        }
    }
    unique.truncate(status.unique as usize);
    (ids, unique)
}

/// The whole hash on the CPU: vertex number per item and the distinct keys in order of
/// first occurrence, or `None` if `capacity` slots (rounded up to a power of two, as the
/// GPU table is) overflowed.
pub fn number_keys(keys: &[[u32; 2]], capacity: u32) -> Option<(Vec<u32>, Vec<[u32; 2]>)> {
    let mut table = vec![CcHashSlot::default(); capacity.max(1).next_power_of_two() as usize];
    let mut status = CcHashStatus {
        items: keys.len() as u32,
        ..Default::default()
    };
    let mut item_slot = vec![CC_NO_SLOT; keys.len()];
    hash_insert(&mut table, keys, &mut item_slot, &mut status);
    if status.overflow != 0 {
        return None;
    }
    let mut offsets = mark_first(&table, &item_slot, &status);
    crate::scan::exclusive_scan(&mut offsets);
    Some(assign(&table, &item_slot, keys, &offsets, &mut status))
}
