//! The one-ring mesh of a (sub)patch: its quad and every quad touching one of its
//! corners. That is exactly what determines the limit surface over the quad, and one
//! Catmull-Clark step of it yields the one-rings of its four children. Repeating that
//! step is the exact evaluation near extraordinary vertices (the same subdivision that
//! Stam's method diagonalises), and a regular one-ring is a bicubic B-spline patch.
//!
//! Sharpness rides along: the one-ring holds every edge at its target's corners, which
//! is all the rules read ([`super::refine`]). Where an infinitely sharp edge cuts the
//! fan at a corner, the target's side of it subdivides on its own, as at an open
//! boundary, so a corner on a crease between two faces on each side, or a corner whose
//! two target edges are sharp, is as regular as a boundary vertex: the patch is a
//! B-spline with phantom points beyond the crease. A semi-sharp feature is subdivided
//! until its sharpness has decayed.

use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;

use super::control_mesh::{BoundaryRule, SHARPNESS_INFINITE};
use super::refine::{
    edge_key, is_semi_sharp, refine_sharp, vertex_rule, Scheme, Sharpness, VertexRule,
};

/// A quad (always `quads[0]`, the target) with its one-ring. The target's corners
/// `quads[0][0..4]` sit at parameters `(0,0), (1,0), (1,1), (0,1)`.
#[derive(Clone, Debug)]
pub struct LocalMesh {
    /// Positions of the one-ring's points.
    pub points: Vec<DVec3>,
    /// The target quad, then the other quads touching its corners, as indices into
    /// `points` (each counter-clockwise).
    pub quads: Vec<[u32; 4]>,
    /// Sharpness of its edges and points (exact for those at the target's corners).
    pub sharp: Sharpness,
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
    /// The one-ring of `target` in a quad mesh with per-point incident quads and the
    /// mesh's sharpness.
    pub fn gather(
        points: &[DVec3],
        quads: &[[u32; 4]],
        point_quads: &[Vec<u32>],
        sharp: &Sharpness,
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
        let sharp = ring_sharpness(sharp, quads, point_quads, &faces);
        Self::compact(points, faces.iter().map(|&q| quads[q as usize]), &sharp)
    }

    /// The same one-ring in an order that depends on the local topology alone, with the
    /// level-1 point of each local point: the target, then the quads around each of its
    /// corners in turn, walked across shared edges (one way, then the other from the
    /// target where a boundary stops the walk), each rotated to start at that corner;
    /// points numbered as they first appear. Patches whose one-rings are alike get the
    /// same local mesh, so that the stencil tables can share one table between them.
    pub fn gather_canonical(
        points: &[DVec3],
        quads: &[[u32; 4]],
        point_quads: &[Vec<u32>],
        sharp: &Sharpness,
        target: usize,
    ) -> (Self, Vec<u32>) {
        let mut order: Vec<(u32, usize)> = vec![(target as u32, 0)];
        let seen = |order: &[(u32, usize)], q: u32| order.iter().any(|&(o, _)| o == q);
        for &v in &quads[target] {
            let at = |q: u32| quads[q as usize].iter().position(|&w| w == v);
            // The quad across the edge from `v` to its neighbour `w`, other than `q`.
            let across = |q: u32, w: u32| {
                point_quads[v as usize]
                    .iter()
                    .copied()
                    .find(|&o| o != q && quads[o as usize].contains(&w))
            };
            let mut fan = Vec::new();
            for forward in [true, false] {
                let mut q = target as u32;
                for _ in 0..point_quads[v as usize].len() {
                    let k = at(q).unwrap_or(0);
                    let w = quads[q as usize][if forward { (k + 3) % 4 } else { (k + 1) % 4 }];
                    match across(q, w) {
                        Some(o) if o != target as u32 && !fan.contains(&o) => {
                            fan.push(o);
                            q = o;
                        }
                        _ => break,
                    }
                }
            }
            // Quads the walks missed (a fan that is not a disc) keep the mesh's order.
            fan.extend(
                point_quads[v as usize]
                    .iter()
                    .filter(|&&o| o != target as u32),
            );
            for q in fan {
                if !seen(&order, q) {
                    order.push((q, at(q).unwrap_or(0)));
                }
            }
        }
        let rotated: Vec<[u32; 4]> = order
            .iter()
            .map(|&(q, k)| std::array::from_fn(|i| quads[q as usize][(k + i) % 4]))
            .collect();
        let mut ids: Vec<u32> = Vec::new();
        for quad in &rotated {
            for &v in quad {
                if !ids.contains(&v) {
                    ids.push(v);
                }
            }
        }
        let faces: Vec<u32> = order.iter().map(|&(q, _)| q).collect();
        let sharp = ring_sharpness(sharp, quads, point_quads, &faces);
        (Self::compact(points, rotated.into_iter(), &sharp), ids)
    }

    /// Renumbers the points the given quads use; the first quad becomes the target.
    fn compact(points: &[DVec3], quads: impl Iterator<Item = [u32; 4]>, sharp: &Sharpness) -> Self {
        let mut map: HashMap<u32, u32> = HashMap::default();
        let mut out = LocalMesh {
            points: Vec::new(),
            quads: Vec::new(),
            sharp: Sharpness::default(),
        };
        for quad in quads {
            out.quads.push(quad.map(|v| {
                *map.entry(v).or_insert_with(|| {
                    out.points.push(points[v as usize]);
                    out.points.len() as u32 - 1
                })
            }));
        }
        if !sharp.is_empty() {
            let local = |v: &u32| map.get(v).copied();
            for (&(a, b), &s) in &sharp.edges {
                if let (Some(a), Some(b)) = (local(&a), local(&b)) {
                    out.sharp.edges.insert(edge_key(a, b), s);
                }
            }
            for (&(a, b), &s) in &sharp.next {
                if let (Some(a), Some(b)) = (local(&a), local(&b)) {
                    out.sharp.next.insert((a, b), s);
                }
            }
            for (&v, &s) in &sharp.vertices {
                if let Some(v) = local(&v) {
                    out.sharp.vertices.insert(v, s);
                }
            }
        }
        out
    }

    /// Quads around point `v`, and for each the position of `v` in it.
    pub(crate) fn around(&self, v: u32) -> impl Iterator<Item = (usize, usize)> + '_ {
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

    /// Sharpness of edge `(v, w)` whose use count is `uses`: infinite on an open
    /// boundary (exact for edges at the target's corners).
    fn edge_sharpness(&self, v: u32, w: u32, uses: u32) -> f32 {
        if uses == 1 {
            SHARPNESS_INFINITE
        } else {
            self.sharp.edge(v, w)
        }
    }

    /// What the rules see at target corner `c`: its vertex sharpness (infinite at an
    /// edge-and-corner corner) and its edges with their sharpness.
    fn corner_sharpness(&self, c: usize, rule: BoundaryRule) -> (f32, Vec<(u32, f32)>) {
        let v = self.quads[0][c];
        let edges = self.edges_at(v);
        let faces = self.around(v).count();
        let corner = rule == BoundaryRule::EdgeAndCorner && faces == 1 && edges.len() == 2;
        let vs = if corner {
            SHARPNESS_INFINITE
        } else {
            self.sharp.vertex(v)
        };
        let es = edges
            .iter()
            .map(|&(w, n)| (w, self.edge_sharpness(v, w, n)))
            .collect();
        (vs, es)
    }

    /// Whether target corner `c` still has semi-sharp sharpness (its vertex or an edge
    /// at it), which decays with subdivision.
    pub fn corner_is_semi_sharp(&self, c: usize, rule: BoundaryRule) -> bool {
        if self.sharp.is_empty() {
            return false;
        }
        let (vs, es) = self.corner_sharpness(c, rule);
        is_semi_sharp(vs) || es.iter().any(|&(_, s)| is_semi_sharp(s))
    }

    /// Whether any target corner has semi-sharp sharpness.
    pub fn has_semi_sharp(&self, rule: BoundaryRule) -> bool {
        (0..4).any(|c| self.corner_is_semi_sharp(c, rule))
    }

    /// The faces on the target's side of the infinitely sharp edges at corner `c`
    /// (all of them where none is sharp): walking around the vertex from the target,
    /// each way, until a sharp or open edge.
    fn sheet_size(&self, c: usize, sharp_edge: &dyn Fn(u32) -> bool) -> usize {
        let v = self.quads[0][c];
        let mut count = 1;
        for forward in [true, false] {
            let mut q = 0usize;
            loop {
                let quad = self.quads[q];
                let k = quad.iter().position(|&w| w == v).expect("quad at v");
                let w = if forward {
                    quad[(k + 1) % 4]
                } else {
                    quad[(k + 3) % 4]
                };
                if sharp_edge(w) {
                    break;
                }
                // The quad across edge v–w runs it the other way.
                let next = if forward {
                    self.face_with(w, v)
                } else {
                    self.face_with(v, w)
                };
                let Some((n, _)) = next else { break };
                if n == 0 {
                    return self.around(v).count();
                }
                count += 1;
                q = n;
            }
        }
        count
    }

    /// Whether target corner `c` lets the target be a B-spline patch: no semi-sharp
    /// sharpness, and a smooth vertex of valence 4, a crease vertex with two faces on
    /// the target's side of the crease, or a corner whose two target edges are sharp.
    pub fn corner_is_regular(&self, c: usize, rule: BoundaryRule) -> bool {
        let (vs, es) = self.corner_sharpness(c, rule);
        if is_semi_sharp(vs) || es.iter().any(|&(_, s)| is_semi_sharp(s)) {
            return false;
        }
        let sharp: Vec<f32> = es.iter().map(|e| e.1).collect();
        let is_sharp = |w: u32| es.iter().any(|&(x, s)| x == w && s > 0.0);
        match vertex_rule(vs, &sharp) {
            VertexRule::Smooth => es.len() == 4 && self.around(self.quads[0][c]).count() == 4,
            VertexRule::Dart => false,
            VertexRule::Crease => self.sheet_size(c, &is_sharp) == 2,
            VertexRule::Corner => self.sheet_size(c, &is_sharp) == 1,
        }
    }

    /// The first irregular corner of the target, if any.
    pub fn irregular_corner(&self, rule: BoundaryRule) -> Option<usize> {
        (0..4).find(|&c| !self.corner_is_regular(c, rule))
    }

    /// The limit position of target corner `c`. With semi-sharp sharpness left, that of
    /// the corner one step down (the same point); otherwise the limit mask of its rule:
    /// smooth, valence n: `(n² P + 4 Σ eᵢ + Σ fᵢ) / (n (n + 5))` over edge neighbours eᵢ
    /// and diagonal points fᵢ; crease: `(a + 4P + b)/6` along it; corner: `P`. A dart's
    /// limit is found by subdividing towards it (its sharp edge changes the eigenvector
    /// the smooth mask is).
    pub fn limit_point(&self, c: usize, scheme: &Scheme) -> DVec3 {
        let rule = scheme.boundary;
        if self.corner_is_semi_sharp(c, rule) {
            return self.children(scheme)[c].limit_point(c, scheme);
        }
        let v = self.quads[0][c];
        let p = self.points[v as usize];
        let (vs, es) = self.corner_sharpness(c, rule);
        let sharp: Vec<f32> = es.iter().map(|e| e.1).collect();
        match vertex_rule(vs, &sharp) {
            VertexRule::Corner => p,
            VertexRule::Crease => {
                let mut ends = es
                    .iter()
                    .filter(|e| e.1 > 0.0)
                    .map(|e| self.points[e.0 as usize]);
                let (a, b) = (ends.next().unwrap_or(p), ends.next().unwrap_or(p));
                (a + 4.0 * p + b) / 6.0
            }
            VertexRule::Smooth => {
                let n = es.len() as f64;
                let mut sum = n * n * p;
                for (q, k) in self.around(v) {
                    let quad = self.quads[q];
                    sum += 4.0 * self.points[quad[(k + 1) % 4] as usize]
                        + self.points[quad[(k + 2) % 4] as usize];
                }
                sum / (n * (n + 5.0))
            }
            VertexRule::Dart => {
                // The one-ring shrinks onto the limit by the subdominant eigenvalue each
                // step (below 0.8 for every valence accepted): stop when it is within
                // rounding of a point.
                let mut ring = self.clone();
                let start = ring.hull_radius(p).max(f64::MIN_POSITIVE);
                for _ in 0..200 {
                    let q = ring.points[ring.quads[0][c] as usize];
                    if ring.hull_radius(q) <= 1e-15 * start {
                        return q;
                    }
                    ring = ring.children(scheme)[c].clone();
                }
                ring.points[ring.quads[0][c] as usize]
            }
        }
    }

    /// The largest distance from `center` to a point of the mesh. The limit surface over
    /// the target lies in the convex hull of these points wherever every subdivision
    /// weight is non-negative (every rule here, for the valences accepted, except
    /// Chaikin's decay of a sharpness above 1 to 0, which extrapolates), so this bounds
    /// `|S(u,v) - center|` there.
    pub fn hull_radius(&self, center: DVec3) -> f64 {
        self.points
            .iter()
            .map(|p| (*p - center).length())
            .fold(0.0, f64::max)
    }

    /// One Catmull-Clark step; returns the one-rings of the four children, child `c`
    /// covering the quadrant at target corner `c` (`[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`),
    /// each with its corners in the same order as the target's.
    pub fn children(&self, scheme: &Scheme) -> [LocalMesh; 4] {
        let faces: Vec<Vec<u32>> = self.quads.iter().map(|q| q.to_vec()).collect();
        let (r, sharp) = refine_sharp(&self.points, &faces, scheme, &self.sharp);
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
            LocalMesh::compact(&r.points, faces.into_iter(), &sharp)
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

    /// The face across the edge `b → a` of a face, unless that edge is infinitely
    /// sharp: the neighbour the B-spline net may read through.
    fn across(&self, a: u32, b: u32) -> Option<(usize, usize)> {
        if self.sharp.edge(a, b) >= SHARPNESS_INFINITE {
            return None;
        }
        self.face_with(a, b)
    }

    /// The 4×4 B-spline net (row-major, `i` along u) when every target corner is
    /// regular. Missing points beyond a boundary or an infinitely sharp crease are
    /// phantoms `2P - Q` (reflections), which make the tensor-product spline follow the
    /// boundary rules exactly (a crease subdivides its sides as boundaries).
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
            let Some((n, pos)) = self.across(b, a) else {
                continue;
            };
            let quad = self.quads[n];
            let (x, y) = (quad[(pos + 2) % 4], quad[(pos + 3) % 4]);
            let (ca, cb) = (CORNER[k], CORNER[(k + 1) % 4]);
            net[at(ca.0 + OUT[k].0, ca.1 + OUT[k].1)] = Some(self.points[x as usize]);
            net[at(cb.0 + OUT[k].0, cb.1 + OUT[k].1)] = Some(self.points[y as usize]);
            // Diagonal at a, across the edge a–x: [x, a, z, w].
            if let Some((d, dpos)) = self.across(x, a) {
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
    /// tangent plane; the normal is the sum of the fan's cross products (on a crease or
    /// at a corner, where the surface has no tangent plane, an average of its sides').
    pub fn corner_normal(&self, c: usize, scheme: &Scheme) -> DVec3 {
        let mut ring = self.clone();
        let mut normal = DVec3::ZERO;
        for _ in 0..48 {
            let s = ring.limit_point(c, scheme);
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
            ring = ring.children(scheme)[c].clone();
        }
        normal
    }
}
/// The entries of the mesh's `sharp` between points of the quads `faces`, found from
/// the quads around those points: what [`LocalMesh::compact`] keeps of it, without a
/// pass over every sharp edge of the mesh per patch (quadratic in a creased mesh).
fn ring_sharpness(
    sharp: &Sharpness,
    quads: &[[u32; 4]],
    point_quads: &[Vec<u32>],
    faces: &[u32],
) -> Sharpness {
    let mut out = Sharpness::default();
    if sharp.is_empty() {
        return out;
    }
    let mut ring: Vec<u32> = faces.iter().flat_map(|&q| quads[q as usize]).collect();
    ring.sort_unstable();
    ring.dedup();
    let local = |v: u32| ring.binary_search(&v).is_ok();
    for &a in &ring {
        if let Some(&s) = sharp.vertices.get(&a) {
            out.vertices.insert(a, s);
        }
        // Every edge from `a` is a side of a quad around it.
        for &q in &point_quads[a as usize] {
            let quad = quads[q as usize];
            let Some(k) = quad.iter().position(|&v| v == a) else {
                continue;
            };
            for b in [quad[(k + 1) % 4], quad[(k + 3) % 4]] {
                if !local(b) {
                    continue;
                }
                if let Some(&s) = sharp.edges.get(&edge_key(a, b)) {
                    out.edges.insert(edge_key(a, b), s);
                }
                if let Some(&s) = sharp.next.get(&(a, b)) {
                    out.next.insert((a, b), s);
                }
            }
        }
    }
    out
}
