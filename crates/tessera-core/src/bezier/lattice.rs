//! The dyadic lattice of one coarse triangle, on which its refinement lives.
//! CPU twin of `shaders/shared/lattice.wgsl`.
//!
//! A coarse triangle with corners `C0, C1, C2` (grid points of its patch, see
//! [`coarse_triangle_grid`]) carries the lattice points `(i, j)`, `i, j ≥ 0`,
//! `i + j ≤ N`, `N = 2^depth`, at `C0 + i/N (C1 − C0) + j/N (C2 − C0)`. Every vertex the
//! refinement can create is a lattice point, so a vertex is named by its lattice point
//! and the points a triangle made fit in a bit set (`points_words`).
//!
//! Side `k` of the triangle runs from corner `k` to corner `k + 1`:
//! side 0 is `j = 0`, side 1 is `i + j = N`, side 2 is `i = 0`.

use super::prepare::coarse_triangle_grid;
use crate::gpu_types::{COARSE_SEGMENTS, COARSE_TRIANGLES_PER_PATCH};

/// A lattice point `(i, j)`.
pub type Lp = [u32; 2];

/// Where a lattice point lies in its coarse triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LatticePlace {
    /// Corner `k` (0..3) of the triangle.
    Corner(usize),
    /// On side `k`, `f` lattice steps from corner `k`.
    Side(usize, u32),
    /// Inside; the index of its bit.
    Inside(usize),
}

/// The lattice of coarse triangle `tri` at refinement depth `depth`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lattice {
    /// Patch index of the coarse triangle.
    pub patch: u32,
    /// Grid points (in thirds of the patch) of the corners, counter-clockwise.
    pub grid: [[u32; 2]; 3],
    /// Lattice steps per side, `2^depth`.
    pub n: u32,
    /// Halvings of each side: `n = 2^depth`.
    pub depth: u32,
}

impl Lattice {
    /// The lattice of global coarse triangle `tri` (18 per patch, in patch order).
    pub fn new(tri: u32, depth: u32) -> Self {
        let per_patch = COARSE_TRIANGLES_PER_PATCH as u32;
        Lattice {
            patch: tri / per_patch,
            grid: coarse_triangle_grid(tri % per_patch),
            n: 1 << depth,
            depth,
        }
    }

    /// The three corners as lattice points.
    pub fn corners(&self) -> [Lp; 3] {
        [[0, 0], [self.n, 0], [0, self.n]]
    }

    /// Position in the patch in units of `1 / (3N)`: exact integers, so every stage
    /// (and the GPU) derives the same parameter from the same point.
    pub fn patch_coords(&self, p: Lp) -> [u32; 2] {
        let n = self.n as i64;
        let g = self.grid.map(|g| g.map(|x| x as i64));
        let (i, j) = (p[0] as i64, p[1] as i64);
        std::array::from_fn(|a| {
            (g[0][a] * n + i * (g[1][a] - g[0][a]) + j * (g[2][a] - g[0][a])) as u32
        })
    }

    /// Patch parameter `(u, v)` of a lattice point.
    pub fn uv(&self, p: Lp) -> [f32; 2] {
        let c = self.patch_coords(p);
        let inv = inv_lattice(self.depth);
        [c[0] as f32 * inv, c[1] as f32 * inv]
    }

    /// Whether `p` is a corner, on a side (and where) or inside (and its bit).
    pub fn place(&self, p: Lp) -> LatticePlace {
        let (i, j, n) = (p[0], p[1], self.n);
        match (i, j) {
            (0, 0) => LatticePlace::Corner(0),
            _ if i == n => LatticePlace::Corner(1),
            _ if j == n => LatticePlace::Corner(2),
            (_, 0) => LatticePlace::Side(0, i),
            _ if i + j == n => LatticePlace::Side(1, j),
            (0, _) => LatticePlace::Side(2, n - j),
            _ => LatticePlace::Inside(self.index(p)),
        }
    }

    /// The side both points lie on, if any.
    pub fn common_side(&self, a: Lp, b: Lp) -> Option<usize> {
        if a[1] == 0 && b[1] == 0 {
            Some(0)
        } else if a[0] + a[1] == self.n && b[0] + b[1] == self.n {
            Some(1)
        } else if a[0] == 0 && b[0] == 0 {
            Some(2)
        } else {
            None
        }
    }

    /// Bit index of a lattice point: rows of constant `j`.
    pub fn index(&self, p: Lp) -> usize {
        let (i, j, n) = (p[0] as usize, p[1] as usize, self.n as usize);
        j * (2 * n + 3 - j) / 2 + i
    }

    /// The lattice point of a bit index (inverse of [`Lattice::index`]).
    pub fn point(&self, index: usize) -> Lp {
        LatticeRows::default().seek(self, index).point(index)
    }

    /// Words of the bit set of lattice points.
    pub fn points_words(depth: u32) -> usize {
        let n = 1usize << depth;
        ((n + 1) * (n + 2) / 2).div_ceil(32)
    }

    /// The words of the point set go in groups of `1 << word_group_shift` words, at most
    /// 32 groups, so that one word ([`TriScratch::groups`]) says which groups hold points
    /// and the emit stage reads only those (a coarse triangle makes a few points at most
    /// thresholds, in a set of 68 words at depth 6).
    ///
    /// [`TriScratch::groups`]: super::refine::TriScratch::groups
    pub fn word_group_shift(points_words: u32) -> u32 {
        points_words
            .div_ceil(32)
            .next_power_of_two()
            .trailing_zeros()
    }

    /// Lattice point of patch coordinates `c` (inverse of [`Lattice::patch_coords`];
    /// the corner steps are unit vectors or the unit diagonal, so it is exact).
    pub fn from_patch_coords(&self, c: [u32; 2]) -> Lp {
        let n = self.n as i64;
        let g = self.grid.map(|g| g.map(|x| x as i64));
        let d = [c[0] as i64 - g[0][0] * n, c[1] as i64 - g[0][1] * n];
        let (e1, e2) = (
            [g[1][0] - g[0][0], g[1][1] - g[0][1]],
            [g[2][0] - g[0][0], g[2][1] - g[0][1]],
        );
        // Solve d = i e1 + j e2. The determinant is ±1 (half a grid cell): dividing by
        // it is multiplying, as the shader does.
        let det = e1[0] * e2[1] - e1[1] * e2[0];
        debug_assert_eq!(det.abs(), 1);
        let i = (d[0] * e2[1] - d[1] * e2[0]) * det;
        let j = (e1[0] * d[1] - e1[1] * d[0]) * det;
        [i as u32, j as u32]
    }

    /// The whole coarse triangle as a right triangle `(r, a, b)`: right angle at `r`
    /// (in the patch's `(u, v)`), hypotenuse `a – b` on the coarse diagonal,
    /// counter-clockwise.
    pub fn root(&self) -> [Lp; 3] {
        let [c0, c1, c2] = self.corners();
        // A cell's first triangle has its right angle at C1, the second at C2.
        if self.grid[1][1] == self.grid[0][1] {
            [c1, c2, c0]
        } else {
            [c2, c0, c1]
        }
    }

    /// The right triangle inside this coarse triangle whose hypotenuse is the piece
    /// `[f0, f1]` (lattice steps from corner `side`) of side `side`.
    pub fn triangle_on_side(&self, side: usize, f0: u32, f1: u32) -> [Lp; 3] {
        let n = self.n;
        let on_side = |f: u32| match side {
            0 => [f, 0],
            1 => [n - f, f],
            _ => [0, n - f],
        };
        let (a, b) = (on_side(f0), on_side(f1));
        let (pa, pb) = (self.patch_coords(a), self.patch_coords(b));
        // The apex is to the left of a → b (inside), at half the hypotenuse.
        let h = [
            (pb[0] as i64 - pa[0] as i64) / 2,
            (pb[1] as i64 - pa[1] as i64) / 2,
        ];
        let r = [
            (pa[0] as i64 + h[0] - h[1]) as u32,
            (pa[1] as i64 + h[1] + h[0]) as u32,
        ];
        [self.from_patch_coords(r), a, b]
    }
}

/// A cursor over the lattice's rows (`j`), for bit indices taken in increasing order:
/// each row is passed once, where [`Lattice::point`] searches from row 0 every time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LatticeRows {
    /// The current row.
    pub j: u32,
    /// The bit index of its first point, (0, j).
    pub start: usize,
}

impl LatticeRows {
    /// The row holding bit `index`, searching forward from this one.
    pub fn seek(self, l: &Lattice, index: usize) -> LatticeRows {
        let mut r = self;
        let n = l.n as usize;
        while r.start + (n + 1 - r.j as usize) <= index {
            r.start += n + 1 - r.j as usize;
            r.j += 1;
        }
        r
    }

    /// The point of bit `index`, which lies in this row.
    pub fn point(self, index: usize) -> Lp {
        [(index - self.start) as u32, self.j]
    }
}

/// `1 / (3 · 2^depth)`, rounded once: lattice coordinates are scaled by it, on the GPU
/// too (where a multiplication is correctly rounded and a division need not be).
pub fn inv_lattice(depth: u32) -> f32 {
    1.0 / (COARSE_SEGMENTS as u32 * (1u32 << depth)) as f32
}

/// Midpoint of two lattice points an even number of steps apart.
pub fn lattice_mid(a: Lp, b: Lp) -> Lp {
    [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2]
}

/// The two children of right triangle `(r, a, b)` split at the midpoint `m` of its
/// hypotenuse: `(m, b, r)` and `(m, r, a)`, right-angled at `m`, counter-clockwise like
/// their parent.
pub fn bisect(t: [Lp; 3]) -> [[Lp; 3]; 2] {
    let [r, a, b] = t;
    let m = lattice_mid(a, b);
    [[m, b, r], [m, r, a]]
}

/// A depth-first walk of a bisection tree without a stack, as the shaders walk it (a
/// stack is an array indexed per lane there, a memory access per lane): a parent is
/// recomputed from its child, and bit `i` of `path` says whether the node at level
/// `i + 1` is a second child of [`bisect`].
#[derive(Clone, Copy, Debug)]
pub struct TreeWalk {
    /// The current node and its level (the root is at 0).
    pub t: [Lp; 3],
    /// Level of `t` in the tree (the root is at 0).
    pub level: u32,
    path: u32,
}

impl TreeWalk {
    /// A walk that starts at `root`, level 0.
    pub fn new(root: [Lp; 3]) -> Self {
        TreeWalk {
            t: root,
            level: 0,
            path: 0,
        }
    }

    /// To the first child of the current node.
    pub fn down(&mut self) {
        self.t = bisect(self.t)[0];
        self.path &= !(1 << self.level);
        self.level += 1;
    }

    /// Past the current node's subtree, to the next node in depth-first order; false
    /// when there is none.
    pub fn advance(&mut self) -> bool {
        let twice = |m: Lp, p: Lp| [2 * m[0] - p[0], 2 * m[1] - p[1]];
        while self.level > 0 && self.path >> (self.level - 1) & 1 != 0 {
            // The second child (m, r, a) of (r, a, b), where b = 2m − a.
            let [m, r, a] = self.t;
            self.t = [r, a, twice(m, a)];
            self.level -= 1;
        }
        if self.level == 0 {
            return false;
        }
        // From the first child (m, b, r) to the second (m, r, a), where a = 2m − b.
        let [m, b, r] = self.t;
        self.t = [m, r, twice(m, b)];
        self.path |= 1 << (self.level - 1);
        true
    }
}

/// Whether bit `k` of the bit set `words` is set.
pub fn bit_get(words: &[u32], k: usize) -> bool {
    words[k / 32] >> (k % 32) & 1 != 0
}

/// Sets bit `k` of the bit set `words`.
pub fn bit_set(words: &mut [u32], k: usize) {
    words[k / 32] |= 1 << (k % 32);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pre-order of the bisection tree below `t` down to `max_level`, recursively,
    /// entering a node when `enter` says so.
    fn recursive(
        t: [Lp; 3],
        level: u32,
        enter: &dyn Fn([Lp; 3], u32) -> bool,
        out: &mut Vec<([Lp; 3], u32)>,
    ) {
        out.push((t, level));
        if enter(t, level) {
            for child in bisect(t) {
                recursive(child, level + 1, enter, out);
            }
        }
    }

    #[test]
    fn the_stackless_walk_visits_the_tree_in_depth_first_order() {
        let l = Lattice::new(7, 4);
        // Two trees: full to level 8, and an uneven one.
        let full = |_: [Lp; 3], level: u32| level < 8;
        let uneven = |t: [Lp; 3], level: u32| {
            level < 8 && (level < 2 || !(t[0][0] + 2 * t[0][1] + level).is_multiple_of(3))
        };
        for enter in [&full as &dyn Fn([Lp; 3], u32) -> bool, &uneven] {
            let mut expected = Vec::new();
            recursive(l.root(), 0, enter, &mut expected);
            let mut walked = Vec::new();
            let mut w = TreeWalk::new(l.root());
            loop {
                walked.push((w.t, w.level));
                if enter(w.t, w.level) {
                    w.down();
                } else if !w.advance() {
                    break;
                }
            }
            assert!(expected.len() > 20);
            assert_eq!(walked, expected);
        }
        // The full tree has 2^9 − 1 nodes.
        let mut expected = Vec::new();
        recursive(l.root(), 0, &full, &mut expected);
        assert_eq!(expected.len(), 511);
    }

    #[test]
    fn index_and_point_are_inverse() {
        let l = Lattice::new(5, 3);
        let mut seen = 0;
        // A cursor carried forward, skipping rows (every third index) as the emit stage does.
        let mut rows = LatticeRows::default();
        for j in 0..=l.n {
            for i in 0..=l.n - j {
                let k = l.index([i, j]);
                assert_eq!(k, seen);
                assert_eq!(l.point(k), [i, j]);
                if k.is_multiple_of(3) {
                    rows = rows.seek(&l, k);
                    assert_eq!(rows.point(k), [i, j]);
                }
                seen += 1;
            }
        }
        assert!(seen <= 32 * Lattice::points_words(3));
    }

    #[test]
    fn word_groups_cover_the_point_set_in_at_most_32_groups() {
        for depth in 1..=crate::gpu_types::MAX_DEPTH_LIMIT {
            let words = Lattice::points_words(depth) as u32;
            let shift = Lattice::word_group_shift(words);
            assert!(
                words <= 32 << shift,
                "depth {depth}: {words} words, shift {shift}"
            );
            // The smallest such groups: half as large would not cover the set.
            assert!(
                shift == 0 || words > 16 << shift,
                "depth {depth}: groups too large"
            );
        }
        assert_eq!(Lattice::word_group_shift(68), 2);
    }

    #[test]
    fn places_and_coordinates() {
        // Triangle 1 of patch 0: grid (0,0) (1,1) (0,1).
        let l = Lattice::new(1, 2);
        assert_eq!(l.patch_coords([4, 0]), [4, 4]);
        assert_eq!(l.patch_coords([0, 4]), [0, 4]);
        assert_eq!(l.uv([2, 1]), [2.0 / 12.0, 3.0 / 12.0]);
        assert_eq!(l.place([0, 0]), LatticePlace::Corner(0));
        assert_eq!(l.place([4, 0]), LatticePlace::Corner(1));
        assert_eq!(l.place([0, 4]), LatticePlace::Corner(2));
        assert_eq!(l.place([1, 0]), LatticePlace::Side(0, 1));
        assert_eq!(l.place([1, 3]), LatticePlace::Side(1, 3));
        assert_eq!(l.place([0, 3]), LatticePlace::Side(2, 1));
        assert!(matches!(l.place([1, 1]), LatticePlace::Inside(_)));
        for p in [[0, 0], [3, 1], [1, 2]] {
            assert_eq!(l.from_patch_coords(l.patch_coords(p)), p);
        }
        // Right angle at C2 = (0, 4): grid (0, 1).
        assert_eq!(l.root(), [[0, 4], [0, 0], [4, 0]]);
        // Hypotenuse on side 0 (the diagonal), first half: apex at grid (0, 1/2).
        assert_eq!(l.triangle_on_side(0, 0, 2), [[0, 2], [0, 0], [2, 0]]);
        // On side 1 (v = 1 from u = 1 to 0), second half.
        let t = l.triangle_on_side(1, 2, 4);
        assert_eq!(t.map(|p| l.patch_coords(p)), [[1, 3], [2, 4], [0, 4]]);
        let even = Lattice::new(0, 2);
        assert_eq!(even.root(), [[4, 0], [0, 4], [0, 0]]);
        let [c1, c2] = bisect(even.root());
        assert_eq!(c1, [[0, 2], [0, 0], [4, 0]]);
        assert_eq!(c2, [[0, 2], [4, 0], [0, 4]]);
    }
}

#[cfg(test)]
mod bisection_tests {
    use super::*;

    fn area2(l: &Lattice, t: [Lp; 3]) -> i64 {
        let p = t.map(|p| l.patch_coords(p).map(|x| x as i64));
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0])
    }

    #[test]
    fn full_bisection_tiles_the_coarse_triangle() {
        for tri in [0, 1, 6, 7] {
            let l = Lattice::new(tri, 3);
            let whole = area2(&l, l.corners());
            assert!(whole > 0);
            let mut stack = vec![(l.root(), 0)];
            let (mut sum, mut leaves) = (0, 0);
            while let Some((t, level)) = stack.pop() {
                assert!(area2(&l, t) > 0, "tri {tri}: {t:?} not counter-clockwise");
                if level < 2 * l.depth {
                    stack.extend(bisect(t).map(|c| (c, level + 1)));
                } else {
                    sum += area2(&l, t);
                    leaves += 1;
                }
            }
            assert_eq!(sum, whole);
            assert_eq!(leaves, 1 << (2 * l.depth));
        }
    }
}
