//! Patch-level topology of a Bézier model: which patches share a boundary curve or a
//! corner, which boundary curves collapse to a point, and a consistent orientation.
//!
//! This is the "Far" of the Bézier path (after OpenSubdiv's split): pure connectivity,
//! computed once on the CPU from the control nets. Two patches share a boundary curve
//! when the four (welded) control points of one side equal those of the other, in either
//! order; sharing is then exact, since both patches evaluate the very same cubic curve.

use std::collections::HashMap;

/// Side `s` of a patch as a function of its parameter `t ∈ [0, 1]`:
/// 0: `(t, 0)`, 1: `(1, t)`, 2: `(t, 1)`, 3: `(0, t)`.
pub fn side_uv(side: usize, t: f32) -> [f32; 2] {
    match side {
        0 => [t, 0.0],
        1 => [1.0, t],
        2 => [t, 1.0],
        _ => [0.0, t],
    }
}

/// Control-net indices of side `s`, in the order of increasing side parameter.
pub const SIDE_CONTROL: [[usize; 4]; 4] = [
    [0, 1, 2, 3],
    [3, 7, 11, 15],
    [12, 13, 14, 15],
    [0, 4, 8, 12],
];

/// Corner slots (0: (0,0), 1: (1,0), 2: (1,1), 3: (0,1)) at the start and end of each side.
pub const SIDE_CORNERS: [[usize; 2]; 4] = [[0, 1], [1, 2], [3, 2], [0, 3]];

/// Control-net index of each corner slot.
pub const CORNER_CONTROL: [usize; 4] = [0, 3, 15, 12];

/// Where grid point `(i, j)` of an `n × n` grid over a patch lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridPoint {
    /// Corner slot 0..4: (0,0), (1,0), (1,1), (0,1).
    Corner(usize),
    /// Side 0..4 and the position `k ∈ 1..n` along the side's own direction.
    Side(usize, u32),
    /// Strictly inside the patch.
    Interior,
}

/// Classifies grid point `(i, j)`, `i, j ∈ 0..=n`.
pub fn grid_point(i: u32, j: u32, n: u32) -> GridPoint {
    let on_u = i == 0 || i == n;
    let on_v = j == 0 || j == n;
    if on_u && on_v {
        return GridPoint::Corner(match (i == n, j == n) {
            (false, false) => 0,
            (true, false) => 1,
            (true, true) => 2,
            (false, true) => 3,
        });
    }
    if j == 0 {
        GridPoint::Side(0, i)
    } else if i == n {
        GridPoint::Side(1, j)
    } else if j == n {
        GridPoint::Side(2, i)
    } else if i == 0 {
        GridPoint::Side(3, j)
    } else {
        GridPoint::Interior
    }
}

/// A side of a patch, as a reference to a shared boundary curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SideRef {
    /// Index of the curve in [`PatchTopology::curves`].
    pub curve: u32,
    /// The side parameter runs against the curve's canonical direction.
    pub reversed: bool,
}

/// A boundary curve, shared by every patch side with the same four control points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Curve {
    /// The patch that evaluates points on this curve; its side runs along the curve's
    /// canonical direction.
    pub owner: u32,
    /// The side of `owner` (0..4) the curve is on.
    pub owner_side: u8,
    /// All four control points coincide: the curve is a single point.
    pub collapsed: bool,
    /// How many patch sides use the curve (1: an open boundary of the surface).
    pub users: u32,
}

/// A point given by a patch and a parameter: what a vertex record holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamPoint {
    /// Patch index.
    pub patch: u32,
    /// Parameter `(u, v)` in the patch, in `[0, 1]²`.
    pub uv: [f32; 2],
}

/// The connectivity of a set of patches.
#[derive(Clone, Debug, Default)]
pub struct PatchTopology {
    /// Global corner id at corner slots 0..4 of each patch.
    pub patch_corners: Vec<[u32; 4]>,
    /// The curve on each side 0..4 of each patch (see [`side_uv`]).
    pub patch_sides: Vec<[SideRef; 4]>,
    /// The distinct boundary curves, in order of first use.
    pub curves: Vec<Curve>,
    /// Where each corner is evaluated.
    pub corner_owner: Vec<ParamPoint>,
    /// Patches whose winding is reversed so that neighbours agree and closed parts face out.
    pub flip: Vec<bool>,
    /// Shared curves whose two patches could not be oriented consistently.
    pub orientation_conflicts: u32,
}

impl PatchTopology {
    /// Builds the topology from welded control nets (indices into one point array).
    pub fn build(nets: &[[u32; 16]]) -> Self {
        let mut corner_of_point: HashMap<u32, u32> = HashMap::new();
        let mut corner_owner = Vec::new();
        let mut patch_corners = Vec::with_capacity(nets.len());
        for (p, net) in nets.iter().enumerate() {
            let mut ids = [0u32; 4];
            for (slot, &ci) in CORNER_CONTROL.iter().enumerate() {
                let point = net[ci];
                ids[slot] = *corner_of_point.entry(point).or_insert_with(|| {
                    corner_owner.push(ParamPoint {
                        patch: p as u32,
                        uv: [
                            (slot == 1 || slot == 2) as u32 as f32,
                            (slot >= 2) as u32 as f32,
                        ],
                    });
                    (corner_owner.len() - 1) as u32
                });
            }
            patch_corners.push(ids);
        }

        let mut curve_of_key: HashMap<[u32; 4], u32> = HashMap::new();
        let mut curves: Vec<Curve> = Vec::new();
        let mut patch_sides = Vec::with_capacity(nets.len());
        for (p, net) in nets.iter().enumerate() {
            let mut sides = [SideRef {
                curve: 0,
                reversed: false,
            }; 4];
            for (s, ctrl) in SIDE_CONTROL.iter().enumerate() {
                let fwd = ctrl.map(|c| net[c]);
                let mut rev = fwd;
                rev.reverse();
                let reversed = rev < fwd;
                let key = if reversed { rev } else { fwd };
                let id = *curve_of_key.entry(key).or_insert_with(|| {
                    curves.push(Curve {
                        owner: p as u32,
                        owner_side: s as u8,
                        collapsed: fwd.iter().all(|&i| i == fwd[0]),
                        users: 0,
                    });
                    (curves.len() - 1) as u32
                });
                // The owner's own direction is the canonical one.
                let owner = curves[id as usize];
                let owner_reversed = {
                    let on = nets[owner.owner as usize];
                    let ofwd = SIDE_CONTROL[owner.owner_side as usize].map(|c| on[c]);
                    ofwd != fwd
                };
                curves[id as usize].users += 1;
                sides[s] = SideRef {
                    curve: id,
                    reversed: owner_reversed,
                };
            }
            patch_sides.push(sides);
        }

        let mut topo = PatchTopology {
            patch_corners,
            patch_sides,
            curves,
            corner_owner,
            flip: vec![false; nets.len()],
            orientation_conflicts: 0,
        };
        topo.orient_consistently();
        topo
    }

    /// Direction in which the counter-clockwise boundary loop of `patch` runs along the
    /// canonical direction of the curve on `side`: +1 or -1.
    fn loop_direction(&self, patch: usize, side: usize) -> i32 {
        let along = if side < 2 { 1 } else { -1 };
        if self.patch_sides[patch][side].reversed {
            -along
        } else {
            along
        }
    }

    /// Flips patches so that every shared curve is run in opposite directions by its two
    /// patches (a consistent orientation), by a breadth-first walk over shared curves.
    fn orient_consistently(&mut self) {
        let n = self.patch_sides.len();
        let mut users: Vec<Vec<(usize, usize)>> = vec![Vec::new(); self.curves.len()];
        for p in 0..n {
            for s in 0..4 {
                let c = self.patch_sides[p][s].curve as usize;
                if !self.curves[c].collapsed {
                    users[c].push((p, s));
                }
            }
        }
        let mut seen = vec![false; n];
        for start in 0..n {
            if seen[start] {
                continue;
            }
            seen[start] = true;
            let mut queue = std::collections::VecDeque::from([start]);
            while let Some(p) = queue.pop_front() {
                for s in 0..4 {
                    let c = self.patch_sides[p][s].curve as usize;
                    if users[c].len() != 2 {
                        continue;
                    }
                    let dp = self.loop_direction(p, s) * if self.flip[p] { -1 } else { 1 };
                    for &(q, t) in &users[c] {
                        if q == p && t == s {
                            continue;
                        }
                        // Consistent when q's loop runs against p's along the curve.
                        let want_flip = self.loop_direction(q, t) == dp;
                        if !seen[q] {
                            seen[q] = true;
                            self.flip[q] = want_flip;
                            queue.push_back(q);
                        } else if self.flip[q] != want_flip {
                            self.orientation_conflicts += 1;
                        }
                    }
                }
            }
        }
        // Each curve with a conflict was seen from both sides.
        self.orientation_conflicts /= 2;
    }

    /// Connected components over shared curves (collapsed curves do not connect).
    pub fn components(&self) -> Vec<u32> {
        let n = self.patch_sides.len();
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut x: u32) -> u32 {
            while parent[x as usize] != x {
                parent[x as usize] = parent[parent[x as usize] as usize];
                x = parent[x as usize];
            }
            x
        }
        let mut first_user: Vec<Option<u32>> = vec![None; self.curves.len()];
        for p in 0..n {
            for s in 0..4 {
                let c = self.patch_sides[p][s].curve as usize;
                if self.curves[c].collapsed {
                    continue;
                }
                match first_user[c] {
                    None => first_user[c] = Some(p as u32),
                    Some(q) => {
                        let (a, b) = (find(&mut parent, p as u32), find(&mut parent, q));
                        parent[a as usize] = b;
                    }
                }
            }
        }
        (0..n as u32).map(|p| find(&mut parent, p)).collect()
    }

    /// The parameter of the point at canonical fraction `t` along `curve`, in its owner.
    pub fn curve_point(&self, curve: u32, t: f32) -> ParamPoint {
        let c = self.curves[curve as usize];
        ParamPoint {
            patch: c.owner,
            uv: side_uv(c.owner_side as usize, t),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two patches side by side sharing the column of control points 3,7,11,15 / 16...
    fn two_patches(second_reversed_u: bool) -> Vec<[u32; 16]> {
        let a: [u32; 16] = std::array::from_fn(|i| i as u32);
        // Patch b's column 0 is a's column 3; its other columns are new points.
        let mut b = [0u32; 16];
        for row in 0..4 {
            for col in 0..4 {
                b[4 * row + col] = if col == 0 {
                    a[4 * row + 3]
                } else {
                    16 + 3 * row as u32 + col as u32 - 1
                };
            }
        }
        if second_reversed_u {
            // Mirror b in u: the shared column becomes column 3 of b.
            for row in 0..4 {
                b[4 * row..4 * row + 4].reverse();
            }
        }
        vec![a, b]
    }

    #[test]
    fn shared_curve_found_and_orientation_made_consistent() {
        for mirrored in [false, true] {
            let t = PatchTopology::build(&two_patches(mirrored));
            assert_eq!(t.curves.len(), 7);
            let shared = t.patch_sides[0][1].curve;
            assert_eq!(t.curves[shared as usize].users, 2);
            // Consistent patches keep their winding; a mirrored one is flipped.
            assert_eq!(t.flip, vec![false, mirrored], "mirrored={mirrored}");
            assert_eq!(t.orientation_conflicts, 0);
            assert_eq!(t.components(), vec![t.components()[0]; 2]);
        }
    }

    #[test]
    fn collapsed_row_is_a_collapsed_curve_with_one_corner() {
        let mut net: [u32; 16] = std::array::from_fn(|i| i as u32);
        net[1] = 0;
        net[2] = 0;
        net[3] = 0;
        let t = PatchTopology::build(&[net]);
        let c = t.patch_sides[0][0].curve as usize;
        assert!(t.curves[c].collapsed);
        assert_eq!(t.patch_corners[0][0], t.patch_corners[0][1]);
        assert_eq!(t.corner_owner.len(), 3);
    }
}
