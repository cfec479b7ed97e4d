//! Watertightness checks: cracks, T-junctions, degenerate triangles, non-manifold edges.
//!
//! An edge used by one triangle only is a boundary edge. It is legitimate only where the
//! surface itself has an open boundary (a patch side no other patch shares), given here
//! as polylines; anywhere else it is a crack. A vertex lying inside a boundary edge is a
//! T-junction. The edge analysis runs twice: by index (vertices must be shared as the
//! tessellators promise) and after welding vertices by position.
//!
//! "By index" counts vertices of bit-identical position as one: the Catmull-Clark
//! output has one vertex per control face (or sub-face) at a point on a seam between
//! them, each copy with the same position bits and its own face coordinates
//! ([`OutVertex`](crate::gpu_types::OutVertex)). Such copies are counted in
//! [`WatertightReport::seam_copies`], not as cracks; a copy off by a single bit is a
//! crack by index (and a duplicate vertex), one moved further a crack by position too.
//! The Bézier path shares every vertex by index: it makes no copies.

use std::collections::HashMap;

use glam::{DVec3, IVec3};

use crate::weld::weld_points;

/// What the checks found. `is_watertight()` when every count but `boundary_edges` is 0.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WatertightReport {
    /// Triangles with a repeated vertex or (near) zero area.
    pub degenerate_triangles: usize,
    /// Edges (after welding) used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Boundary edges (by index, vertices of bit-identical positions as one) that do not
    /// lie on an open boundary of the surface.
    pub cracks_by_index: usize,
    /// Boundary edges (after welding) that do not lie on an open boundary.
    pub cracks_by_position: usize,
    /// Vertices strictly inside a boundary edge.
    pub t_junctions: usize,
    /// Where those vertices are.
    pub t_junction_points: Vec<DVec3>,
    /// Vertices at one position (within the tolerance) whose position bits differ.
    pub duplicate_vertices: usize,
    /// Vertices whose position bits repeat another's: the copies of a point on a seam
    /// between charts. Not a defect (see the module docs).
    pub seam_copies: usize,
    /// Boundary edges that do lie on the surface's open boundary.
    pub boundary_edges: usize,
}

impl WatertightReport {
    /// No degenerate triangle, non-manifold edge, crack, T-junction or duplicate vertex
    /// (seam copies are allowed).
    pub fn is_watertight(&self) -> bool {
        self.degenerate_triangles == 0
            && self.non_manifold_edges == 0
            && self.cracks_by_index == 0
            && self.cracks_by_position == 0
            && self.t_junctions == 0
            && self.duplicate_vertices == 0
    }
}

/// Checks a triangle mesh. `open_boundary`: polylines densely sampling the surface's
/// open boundary curves; `tol`: the distance below which points are one (for example
/// 1e-5 of the model's size).
pub fn check_watertight(
    positions: &[glam::Vec3],
    indices: &[u32],
    open_boundary: &[Vec<DVec3>],
    tol: f64,
) -> WatertightReport {
    let mut report = WatertightReport::default();
    let pos: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    // Vertices by their position's bits: the first of each, for every copy.
    let mut first: HashMap<[u32; 3], u32> = HashMap::new();
    let exact: Vec<u32> = positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            *first
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(i as u32)
        })
        .collect();
    let tris: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]].map(|i| exact[i as usize]))
        .collect();
    for t in &tris {
        let [a, b, c] = t.map(|i| pos[i as usize]);
        let area2 = (b - a).cross(c - a).length();
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || area2 <= tol * tol {
            report.degenerate_triangles += 1;
        }
    }
    let (weld_id, _) = weld_points(positions, tol as f32);
    let indexed: std::collections::HashSet<u32> = indices.iter().copied().collect();
    let used: std::collections::HashSet<u32> = tris.iter().flatten().copied().collect();
    let welded_used: std::collections::HashSet<u32> =
        used.iter().map(|&i| weld_id[i as usize]).collect();
    report.seam_copies = indexed.len() - used.len();
    report.duplicate_vertices = used.len() - welded_used.len();

    let on_open = |p: DVec3| -> Vec<usize> {
        open_boundary
            .iter()
            .enumerate()
            .filter(|(_, line)| {
                line.windows(2)
                    .any(|s| segment_distance(p, s[0], s[1]) <= tol)
            })
            .map(|(k, _)| k)
            .collect()
    };
    let legit = |a: DVec3, b: DVec3| {
        let (ca, cb) = (on_open(a), on_open(b));
        ca.iter().any(|k| cb.contains(k))
    };

    // By index.
    let by_index = edge_uses(&tris, |i| i);
    let mut boundary: Vec<[u32; 2]> = Vec::new();
    for (&[a, b], &n) in &by_index {
        if n == 1 {
            if legit(pos[a as usize], pos[b as usize]) {
                report.boundary_edges += 1;
            } else {
                report.cracks_by_index += 1;
            }
            boundary.push([a, b]);
        }
    }
    // By position.
    let by_pos = edge_uses(&tris, |i| weld_id[i as usize]);
    let rep: HashMap<u32, u32> = (0..positions.len() as u32)
        .map(|i| (weld_id[i as usize], i))
        .collect();
    for (&[a, b], &n) in &by_pos {
        if n > 2 {
            report.non_manifold_edges += 1;
        } else if n == 1 && !legit(pos[rep[&a] as usize], pos[rep[&b] as usize]) {
            report.cracks_by_position += 1;
        }
    }
    let found = find_t_junctions(&pos, &used, &boundary, tol);
    report.t_junctions = found.len();
    report.t_junction_points = found.iter().map(|&v| pos[v as usize]).collect();
    report
}

/// How many triangles use each undirected edge, with vertices mapped by `id`.
fn edge_uses(tris: &[[u32; 3]], id: impl Fn(u32) -> u32) -> HashMap<[u32; 2], u32> {
    let mut uses = HashMap::new();
    for t in tris {
        for k in 0..3 {
            let (a, b) = (id(t[k]), id(t[(k + 1) % 3]));
            if a != b {
                *uses.entry([a.min(b), a.max(b)]).or_insert(0) += 1;
            }
        }
    }
    uses
}

fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let t = if d.length_squared() > 0.0 {
        ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).length()
}

/// Vertices lying strictly inside a boundary edge (farther than `tol` from its ends).
fn find_t_junctions(
    pos: &[DVec3],
    used: &std::collections::HashSet<u32>,
    boundary: &[[u32; 2]],
    tol: f64,
) -> Vec<u32> {
    if boundary.is_empty() {
        return Vec::new();
    }
    let avg_len = boundary
        .iter()
        .map(|&[a, b]| (pos[a as usize] - pos[b as usize]).length())
        .sum::<f64>()
        / boundary.len() as f64;
    let cell = avg_len.max(tol * 4.0);
    let key = |p: DVec3| (p / cell).floor().as_ivec3();
    let mut grid: HashMap<IVec3, Vec<u32>> = HashMap::new();
    for &i in used {
        grid.entry(key(pos[i as usize])).or_default().push(i);
    }
    let mut found = std::collections::HashSet::new();
    for &[a, b] in boundary {
        let (pa, pb) = (pos[a as usize], pos[b as usize]);
        let (lo, hi) = (
            key(pa.min(pb) - DVec3::splat(tol)),
            key(pa.max(pb) + DVec3::splat(tol)),
        );
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    for &v in grid.get(&IVec3::new(x, y, z)).into_iter().flatten() {
                        let p = pos[v as usize];
                        if v != a
                            && v != b
                            && (p - pa).length() > tol
                            && (p - pb).length() > tol
                            && segment_distance(p, pa, pb) <= tol
                        {
                            found.insert(v);
                        }
                    }
                }
            }
        }
    }
    let mut found: Vec<u32> = found.into_iter().collect();
    found.sort_unstable();
    found
}

/// The open boundary curves of a Bézier model as polylines of `segments` pieces each.
pub fn bezier_open_boundary(
    model: &crate::bezier::BezierModel,
    segments: usize,
) -> Vec<Vec<DVec3>> {
    model
        .open_boundary_curves()
        .iter()
        .map(|c| {
            let c = c.map(|p| p.as_dvec3());
            (0..=segments)
                .map(|k| {
                    let t = k as f64 / segments as f64;
                    let s = 1.0 - t;
                    c[0] * (s * s * s)
                        + c[1] * (3.0 * t * s * s)
                        + c[2] * (3.0 * t * t * s)
                        + c[3] * (t * t * t)
                })
                .collect()
        })
        .collect()
}
