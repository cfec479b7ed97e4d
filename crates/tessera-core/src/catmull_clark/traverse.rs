//! Adaptive marking as the GPU runs it, one patch at a time: twin of
//! `shaders/cc_traverse.wgsl`, which marks every patch to full depth in one dispatch (an
//! invocation per patch and trial) rather than one dispatch per level.
//!
//! A trial (a first split `ku × kv`) is walked cell by cell of the split, row by row,
//! each cell's subtree depth first, quadrant 0 first. The leaves come out in that order.
//! Each cell is decided alone, so the leaves are the recursion's ([`super::adaptive`]).
//!
//! The first-split search keeps the trial with the fewest leaves, ties to the earlier:
//! here the trials run in order, one that cannot beat the best so far (a split into
//! `ku · kv` cells has at least that many leaves) is skipped, and one is stopped once
//! its leaves reach the best. The kernel runs them side by side and stops a trial once
//! its leaves exceed a finished one's; both keep the same trial.

/// A cell of a patch: `[i, i + w] × [j, j + h]` in grid units, `depth` midpoint splits
/// below its first split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cell {
    /// Lower-left corner along u.
    pub i: u32,
    /// Lower-left corner along v.
    pub j: u32,
    /// Width along u.
    pub w: u32,
    /// Height along v.
    pub h: u32,
    /// Midpoint splits below the first split.
    pub depth: u32,
}

impl Cell {
    /// Corners counter-clockwise from the lower left.
    pub fn corners(&self) -> [(u32, u32); 4] {
        let Cell { i, j, w, h, .. } = *self;
        [(i, j), (i + w, j), (i + w, j + h), (i, j + h)]
    }

    /// Quadrant `q` (`[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`).
    pub fn child(&self, q: u32) -> Cell {
        let (w, h) = (self.w / 2, self.h / 2);
        Cell {
            i: self.i + u32::from(q == 1 || q == 2) * w,
            j: self.j + u32::from(q >= 2) * h,
            w,
            h,
            depth: self.depth + 1,
        }
    }
}

/// The cells of first split `ku × kv` on a grid of `n` units per patch side, in the
/// kernel's order (row by row).
pub fn first_cells(n: u32, (ku, kv): (u32, u32)) -> impl Iterator<Item = Cell> {
    let (w, h) = (n / ku, n / kv);
    (0..ku * kv).map(move |c| Cell {
        i: (c % ku) * w,
        j: (c / ku) * h,
        w,
        h,
        depth: 0,
    })
}

/// Twin of `cc_next_cell`: the cell after `c` in a depth-first walk from a cell at depth
/// `top`, once `c` and everything below it is done: its next sibling, else its parent's,
/// and so on; `None` when the walk is over. A cell's quadrant is the parity of its
/// position in cells of its size, so the walk needs no stack.
pub fn next_cell(c: Cell, top: u32) -> Option<Cell> {
    let mut c = c;
    while c.depth > top {
        match ((c.i / c.w) & 1, (c.j / c.h) & 1) {
            (0, 0) => return Some(Cell { i: c.i + c.w, ..c }),
            (1, 0) => return Some(Cell { j: c.j + c.h, ..c }),
            (1, 1) => return Some(Cell { i: c.i - c.w, ..c }),
            // Quadrant 3, the last: on to the parent's next.
            _ => {
                c = Cell {
                    j: c.j - c.h,
                    w: 2 * c.w,
                    h: 2 * c.h,
                    depth: c.depth - 1,
                    ..c
                }
            }
        }
    }
    None
}

/// One trial's leaves in the kernel's order, each with what the decision gave it.
#[derive(Clone, Debug)]
pub struct Walk<L> {
    /// Every leaf with its payload.
    pub leaves: Vec<(Cell, L)>,
}

/// Trial `split` of a patch, stopped (`None`) once its leaves reach `stop`. `decide`
/// gives `None` for a cell to split, the leaf's payload for a leaf.
pub fn walk_trial<L>(
    n: u32,
    split: (u32, u32),
    stop: usize,
    decide: &mut dyn FnMut(Cell) -> Option<L>,
) -> Option<Walk<L>> {
    let mut leaves = Vec::new();
    for start in first_cells(n, split) {
        let mut at = Some(start);
        while let Some(cell) = at {
            if leaves.len() >= stop {
                return None;
            }
            at = match decide(cell) {
                None => Some(cell.child(0)),
                Some(leaf) => {
                    leaves.push((cell, leaf));
                    next_cell(cell, start.depth)
                }
            };
        }
    }
    Some(Walk { leaves })
}

/// The first-split search of one patch over `splits` in order: the index of the split
/// with the fewest leaves (ties to the earlier) and its walk.
pub fn search<L>(
    n: u32,
    splits: &[(u32, u32)],
    decide: &mut dyn FnMut(Cell) -> Option<L>,
) -> (u32, Walk<L>) {
    let mut best: Option<(u32, Walk<L>)> = None;
    for (t, &split) in splits.iter().enumerate() {
        let stop = best.as_ref().map_or(usize::MAX, |(_, w)| w.leaves.len());
        if (split.0 * split.1) as usize >= stop {
            continue;
        }
        // A walk can end on its `stop`-th leaf: a tie, which goes to the earlier trial.
        if let Some(walk) = walk_trial(n, split, stop, decide).filter(|w| w.leaves.len() < stop) {
            best = Some((t as u32, walk));
        }
    }
    best.expect("the first trial is never skipped or stopped")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_walk_finds_the_recursions_leaves_in_its_order() {
        // Split where a cell overlaps a disc near one corner, down to depth 5.
        let n = 840 << 5;
        let mut decide = |c: Cell| {
            let near = c.i < n / 3 && c.j < n / 5;
            (c.depth == 5 || !near).then_some(())
        };
        let walk = walk_trial(n, (3, 3), usize::MAX, &mut decide).expect("not stopped");
        fn recurse(c: Cell, d: &mut dyn FnMut(Cell) -> Option<()>, out: &mut Vec<Cell>) {
            match d(c) {
                None => (0..4).for_each(|q| recurse(c.child(q), d, out)),
                Some(()) => out.push(c),
            }
        }
        let mut reference = Vec::new();
        for c in first_cells(n, (3, 3)) {
            recurse(c, &mut decide, &mut reference);
        }
        let key = |c: &Cell| (c.i, c.j, c.w, c.depth);
        let got: Vec<_> = walk.leaves.iter().map(|(c, _)| key(c)).collect();
        let want: Vec<_> = reference.iter().map(key).collect();
        assert_eq!(got, want);
        assert!(want.iter().any(|k| k.3 == 5) && want.iter().any(|k| k.3 == 0));
    }

    #[test]
    fn the_search_keeps_the_fewest_leaves_with_ties_to_the_earlier_trial() {
        let n = 840 << 3;
        // Every cell is a leaf: a split of ku·kv cells has ku·kv leaves; 1×1 wins.
        let (t, walk) = search(n, &[(1, 1), (3, 3)], &mut |_| Some(()));
        assert_eq!((t, walk.leaves.len()), (0, 1));
        // Split cells wider than a third of the patch: 1×1 gives 16 leaves, 3×3 gives 9.
        let mut decide = |c: Cell| (c.w <= n / 3).then_some(());
        let (t, walk) = search(n, &[(1, 1), (3, 3), (2, 3)], &mut decide);
        assert_eq!((t, walk.leaves.len()), (1, 9));
        // A trial stopped at the best is not the best.
        assert!(walk_trial(n, (1, 1), 9, &mut decide).is_none());
        // A tie goes to the earlier trial, also when the later one ends on its last leaf.
        let (t, walk) = search(n, &[(3, 3), (1, 1), (3, 3)], &mut decide);
        assert_eq!((t, walk.leaves.len()), (0, 9));
    }
}
