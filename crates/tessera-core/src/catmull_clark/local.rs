//! The one-ring mesh of a (sub)patch: its quad and every quad touching one of its
//! corners. That is exactly what determines the limit surface over the quad, and one
//! Catmull-Clark step of it yields the one-rings of its four children. Repeating that
//! step is the exact evaluation near extraordinary vertices (the same subdivision that
//! Stam's method diagonalises), and a regular one-ring is a bicubic B-spline patch.

use std::collections::HashMap;

use glam::DVec3;

use super::control_mesh::BoundaryRule;
use super::refine::refine;

/// A quad (always `quads[0]`, the target) with its one-ring. The target's corners
/// `quads[0][0..4]` sit at parameters `(0,0), (1,0), (1,1), (0,1)`.
#[derive(Clone, Debug)]
pub struct LocalMesh {
    /// Positions of the one-ring's points.
    pub points: Vec<DVec3>,
    /// The target quad, then the other quads touching its corners, as indices into
    /// `points` (each counter-clockwise).
    pub quads: Vec<[u32; 4]>,
}

/// What a corner of the target is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CornerInfo {
    /// Number of edges at the vertex.
    pub valence: usize,
    /// Number of faces around it.
    pub faces: usize,
    /// Whether the vertex is on an open boundary.
    pub boundary: bool,
}

impl CornerInfo {
    /// Regular corners make the quad a B-spline patch: valence 4 inside, 3 on a
    /// boundary, 2 (a corner) with the edge-and-corner rule.
    pub fn is_regular(&self, rule: BoundaryRule) -> bool {
        match (self.boundary, self.valence) {
            (false, 4) | (true, 3) => true,
            (true, 2) => rule == BoundaryRule::EdgeAndCorner,
            _ => false,
        }
    }
}

/// Bézier form of the uniform cubic B-spline on one span: row `i` gives Bézier point `i`.
const BSPLINE_TO_BEZIER: [[f64; 4]; 4] = [
    [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0],
    [0.0, 4.0 / 6.0, 2.0 / 6.0, 0.0],
    [0.0, 2.0 / 6.0, 4.0 / 6.0, 0.0],
    [0.0, 1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0],
];

/// Converts a 4×4 B-spline net (row-major, `net[4*j + i]`, `i` along u) to Bézier.
pub fn bspline_to_bezier(net: &[DVec3; 16]) -> [DVec3; 16] {
    let mut rows = [DVec3::ZERO; 16];
    for j in 0..4 {
        for i in 0..4 {
            rows[4 * j + i] = (0..4)
                .map(|k| BSPLINE_TO_BEZIER[i][k] * net[4 * j + k])
                .sum();
        }
    }
    let mut out = [DVec3::ZERO; 16];
    for j in 0..4 {
        for i in 0..4 {
            out[4 * j + i] = (0..4)
                .map(|k| BSPLINE_TO_BEZIER[j][k] * rows[4 * k + i])
                .sum();
        }
    }
    out
}

impl LocalMesh {
    /// The one-ring of `target` in a quad mesh with per-point incident quads.
    pub fn gather(
        points: &[DVec3],
        quads: &[[u32; 4]],
        point_quads: &[Vec<u32>],
        target: usize,
    ) -> Self {
        let mut faces = vec![target as u32];
        for &c in &quads[target] {
            for &q in &point_quads[c as usize] {
                if !faces.contains(&q) {
                    faces.push(q);
                }
            }
        }
        Self::compact(points, faces.iter().map(|&q| quads[q as usize]))
    }

    /// Renumbers the points the given quads use; the first quad becomes the target.
    fn compact(points: &[DVec3], quads: impl Iterator<Item = [u32; 4]>) -> Self {
        let mut map: HashMap<u32, u32> = HashMap::new();
        let mut out = LocalMesh {
            points: Vec::new(),
            quads: Vec::new(),
        };
        for quad in quads {
            out.quads.push(quad.map(|v| {
                *map.entry(v).or_insert_with(|| {
                    out.points.push(points[v as usize]);
                    out.points.len() as u32 - 1
                })
            }));
        }
        out
    }

    /// Quads around point `v`, and for each the position of `v` in it.
    fn around(&self, v: u32) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.quads
            .iter()
            .enumerate()
            .filter_map(move |(q, quad)| quad.iter().position(|&w| w == v).map(|k| (q, k)))
    }

    /// Edge neighbours of `v` with the number of quads using each edge.
    fn edges_at(&self, v: u32) -> Vec<(u32, u32)> {
        let mut edges: Vec<(u32, u32)> = Vec::new();
        for (q, k) in self.around(v) {
            let quad = self.quads[q];
            for w in [quad[(k + 1) % 4], quad[(k + 3) % 4]] {
                match edges.iter_mut().find(|(x, _)| *x == w) {
                    Some(e) => e.1 += 1,
                    None => edges.push((w, 1)),
                }
            }
        }
        edges
    }

    /// What corner `c` of the target is. Exact: the one-ring holds all quads around it.
    pub fn corner(&self, c: usize) -> CornerInfo {
        let v = self.quads[0][c];
        let edges = self.edges_at(v);
        CornerInfo {
            valence: edges.len(),
            faces: self.around(v).count(),
            boundary: edges.iter().any(|&(_, n)| n == 1),
        }
    }

    /// The first irregular corner of the target, if any.
    pub fn irregular_corner(&self, rule: BoundaryRule) -> Option<usize> {
        (0..4).find(|&c| !self.corner(c).is_regular(rule))
    }

    /// The limit position of target corner `c` (limit masks). Interior, valence n:
    /// `(n² P + 4 Σ eᵢ + Σ fᵢ) / (n (n + 5))` over edge neighbours eᵢ and diagonal
    /// points fᵢ; smooth boundary: `(a + 4P + b)/6`; corner: `P`.
    pub fn limit_point(&self, c: usize, rule: BoundaryRule) -> DVec3 {
        let v = self.quads[0][c];
        let p = self.points[v as usize];
        let info = self.corner(c);
        if info.boundary {
            if info.faces == 1 && rule == BoundaryRule::EdgeAndCorner {
                return p;
            }
            let b: Vec<u32> = self
                .edges_at(v)
                .into_iter()
                .filter(|&(_, n)| n == 1)
                .map(|(w, _)| w)
                .collect();
            return (self.points[b[0] as usize] + 4.0 * p + self.points[b[1] as usize]) / 6.0;
        }
        let n = info.valence as f64;
        let mut sum = n * n * p;
        for (q, k) in self.around(v) {
            let quad = self.quads[q];
            sum += 4.0 * self.points[quad[(k + 1) % 4] as usize]
                + self.points[quad[(k + 2) % 4] as usize];
        }
        sum / (n * (n + 5.0))
    }

    /// The largest distance from `center` to a point of the mesh. The limit surface over
    /// the target lies in the convex hull of these points (every Catmull-Clark weight is
    /// non-negative for the valences accepted), so this bounds `|S(u,v) - center|`.
    pub fn hull_radius(&self, center: DVec3) -> f64 {
        self.points
            .iter()
            .map(|p| (*p - center).length())
            .fold(0.0, f64::max)
    }

    /// One Catmull-Clark step; returns the one-rings of the four children, child `c`
    /// covering the quadrant at target corner `c` (`[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`),
    /// each with its corners in the same order as the target's.
    pub fn children(&self, rule: BoundaryRule) -> [LocalMesh; 4] {
        let faces: Vec<Vec<u32>> = self.quads.iter().map(|q| q.to_vec()).collect();
        let r = refine(&self.points, &faces, rule);
        std::array::from_fn(|c| {
            // Sub-quad of the target at corner c, rotated so that the child's corner 0
            // (its lower-left) comes first.
            let sub = r.quads[c];
            let start = (4 - c) % 4;
            let child: [u32; 4] = std::array::from_fn(|k| sub[(start + k) % 4]);
            let mut faces = vec![child];
            for (q, quad) in r.quads.iter().enumerate() {
                if q != c && quad.iter().any(|v| child.contains(v)) {
                    faces.push(*quad);
                }
            }
            LocalMesh::compact(&r.points, faces.into_iter())
        })
    }

    /// The face containing the directed edge `a → b`, and the position of `a` in it.
    fn face_with(&self, a: u32, b: u32) -> Option<(usize, usize)> {
        self.quads.iter().enumerate().find_map(|(q, quad)| {
            (0..4)
                .find(|&k| quad[k] == a && quad[(k + 1) % 4] == b)
                .map(|k| (q, k))
        })
    }

    /// The 4×4 B-spline net (row-major, `i` along u) when every target corner is
    /// regular. Missing points beyond a boundary are phantoms `2P - Q` (reflections),
    /// which make the tensor-product spline follow the boundary rules exactly.
    pub fn regular_net(&self, rule: BoundaryRule) -> Option<[DVec3; 16]> {
        if self.irregular_corner(rule).is_some() {
            return None;
        }
        let t = self.quads[0];
        let mut net: [Option<DVec3>; 16] = [None; 16];
        let at = |i: i32, j: i32| (4 * j + i) as usize;
        // Grid positions of the target corners and the outward step of each edge k.
        const CORNER: [(i32, i32); 4] = [(1, 1), (2, 1), (2, 2), (1, 2)];
        const OUT: [(i32, i32); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];
        for k in 0..4 {
            net[at(CORNER[k].0, CORNER[k].1)] = Some(self.points[t[k] as usize]);
        }
        for k in 0..4 {
            let (a, b) = (t[k], t[(k + 1) % 4]);
            // The neighbour across edge k runs b → a: [b, a, x, y], x next to a.
            let Some((n, pos)) = self.face_with(b, a) else {
                continue;
            };
            let quad = self.quads[n];
            let (x, y) = (quad[(pos + 2) % 4], quad[(pos + 3) % 4]);
            let (ca, cb) = (CORNER[k], CORNER[(k + 1) % 4]);
            net[at(ca.0 + OUT[k].0, ca.1 + OUT[k].1)] = Some(self.points[x as usize]);
            net[at(cb.0 + OUT[k].0, cb.1 + OUT[k].1)] = Some(self.points[y as usize]);
            // Diagonal at a (interior corners only): across the edge a–x, [x, a, z, w].
            if !self.corner(k).boundary {
                let (d, dpos) = self.face_with(x, a)?;
                let w = self.quads[d][(dpos + 3) % 4];
                let prev = OUT[(k + 3) % 4];
                net[at(ca.0 + OUT[k].0 + prev.0, ca.1 + OUT[k].1 + prev.1)] =
                    Some(self.points[w as usize]);
            }
        }
        // Phantom rows and columns next to boundary edges, then the grid corners,
        // reflected across the side that is missing.
        let get = |net: &[Option<DVec3>; 16], i: i32, j: i32| net[at(i, j)];
        let mut phantom = [false; 16];
        for s in 1..3 {
            for (i, j, i1, j1, i2, j2) in [
                (s, 0, s, 1, s, 2),
                (s, 3, s, 2, s, 1),
                (0, s, 1, s, 2, s),
                (3, s, 2, s, 1, s),
            ] {
                if net[at(i, j)].is_none() {
                    net[at(i, j)] = Some(2.0 * get(&net, i1, j1)? - get(&net, i2, j2)?);
                    phantom[at(i, j)] = true;
                }
            }
        }
        for (i, j, di, dj) in [(0, 0, 1, 1), (3, 0, -1, 1), (3, 3, -1, -1), (0, 3, 1, -1)] {
            if net[at(i, j)].is_none() {
                // Missing row beyond (i+di, j): reflect in v along column i; else in u.
                net[at(i, j)] = Some(if phantom[at(i + di, j)] {
                    2.0 * get(&net, i, j + dj)? - get(&net, i, j + 2 * dj)?
                } else {
                    2.0 * get(&net, i + di, j)? - get(&net, i + 2 * di, j)?
                });
            }
        }
        let mut out = [DVec3::ZERO; 16];
        for (o, n) in out.iter_mut().zip(net) {
            *o = n?;
        }
        Some(out)
    }

    /// The unit normal of the limit surface at target corner `c` (an extraordinary
    /// vertex). The one-ring is subdivided towards the vertex with the limit point
    /// subtracted and the scale renormalised each step, so it converges (in f64, without
    /// underflow) to an affine image of the subdominant eigenvectors, which span the
    /// tangent plane; the normal is the sum of the fan's cross products.
    pub fn corner_normal(&self, c: usize, rule: BoundaryRule) -> DVec3 {
        let mut ring = self.clone();
        let mut normal = DVec3::ZERO;
        for _ in 0..48 {
            let s = ring.limit_point(c, rule);
            let scale = ring.hull_radius(s).max(f64::MIN_POSITIVE);
            for p in &mut ring.points {
                *p = (*p - s) / scale;
            }
            let v = ring.quads[0][c];
            let next: DVec3 = ring
                .around(v)
                .map(|(q, k)| {
                    let quad = ring.quads[q];
                    let a = ring.points[quad[(k + 1) % 4] as usize];
                    let b = ring.points[quad[(k + 3) % 4] as usize];
                    a.cross(b)
                })
                .sum::<DVec3>()
                .normalize_or_zero();
            if next.dot(normal) > 1.0 - 1e-15 {
                return next;
            }
            normal = next;
            ring = ring.children(rule)[c].clone();
        }
        normal
    }
}
