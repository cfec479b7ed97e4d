//! One Catmull-Clark step on a polygon mesh, with the boundary rules of [`BoundaryRule`].
//!
//! Used twice: on the whole control mesh (the step that makes every face a quad, see
//! [`super::topology`]) and on the small one-ring meshes around a patch that the exact
//! evaluation subdivides again and again (see [`super::local`]). In a one-ring mesh the
//! vertices on its outer rim see only part of their faces; their new points come out
//! wrong and are never used, but computing them must not fail.

use std::collections::HashMap;

use glam::DVec3;

use super::control_mesh::BoundaryRule;

/// The result of one step. Points are laid out as
/// `[vertex points (one per input vertex)] [edge points] [face points]`; the sub-quad
/// of face `f` at its corner `k` is `quads[face_start[f] + k]`, written
/// `[V(f[k]), E(f[k], f[k+1]), F(f), E(f[k-1], f[k])]`, counter-clockwise like `f`.
#[derive(Clone, Debug)]
pub struct Refined {
    /// The new points: vertex points, then edge points, then face points.
    pub points: Vec<DVec3>,
    /// The sub-quads, one per corner of each input face, as indices into `points`.
    pub quads: Vec<[u32; 4]>,
    /// First sub-quad of each input face.
    pub face_start: Vec<u32>,
}

/// Undirected edge key.
pub fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// The faces and edges incident to each vertex, for the vertex rule.
struct Incidence {
    /// Per undirected edge: its index and how many faces use it.
    edges: HashMap<(u32, u32), (u32, u32)>,
    /// Per vertex: incident faces.
    vertex_faces: Vec<Vec<u32>>,
    /// Per vertex: the other ends of its edges, each once.
    vertex_neighbors: Vec<Vec<u32>>,
}

fn incidence(vertex_count: usize, faces: &[Vec<u32>]) -> Incidence {
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    let mut vertex_faces = vec![Vec::new(); vertex_count];
    let mut vertex_neighbors: Vec<Vec<u32>> = vec![Vec::new(); vertex_count];
    for (f, face) in faces.iter().enumerate() {
        let n = face.len();
        for k in 0..n {
            let (a, b) = (face[k], face[(k + 1) % n]);
            vertex_faces[a as usize].push(f as u32);
            let next = edges.len() as u32;
            let e = edges.entry(edge_key(a, b)).or_insert((next, 0));
            e.1 += 1;
            if e.1 == 1 {
                vertex_neighbors[a as usize].push(b);
                vertex_neighbors[b as usize].push(a);
            }
        }
    }
    Incidence {
        edges,
        vertex_faces,
        vertex_neighbors,
    }
}

/// One Catmull-Clark step of `points`/`faces`.
pub fn refine(points: &[DVec3], faces: &[Vec<u32>], rule: BoundaryRule) -> Refined {
    let nv = points.len();
    let inc = incidence(nv, faces);
    let ne = inc.edges.len();
    let face_points: Vec<DVec3> = faces
        .iter()
        .map(|f| f.iter().map(|&v| points[v as usize]).sum::<DVec3>() / f.len() as f64)
        .collect();

    // Edge points: the average of the ends and the two face points; boundary: midpoint.
    let mut edge_faces: Vec<[Option<u32>; 2]> = vec![[None, None]; ne];
    for (f, face) in faces.iter().enumerate() {
        for k in 0..face.len() {
            let e = inc.edges[&edge_key(face[k], face[(k + 1) % face.len()])].0 as usize;
            let slot = if edge_faces[e][0].is_none() { 0 } else { 1 };
            edge_faces[e][slot] = Some(f as u32);
        }
    }
    let mut edge_points = vec![DVec3::ZERO; ne];
    for (&(a, b), &(e, count)) in &inc.edges {
        let mid = (points[a as usize] + points[b as usize]) * 0.5;
        edge_points[e as usize] = match (count, edge_faces[e as usize]) {
            (2, [Some(f0), Some(f1)]) => {
                (mid + (face_points[f0 as usize] + face_points[f1 as usize]) * 0.5) * 0.5
            }
            _ => mid,
        };
    }

    let vertex_points: Vec<DVec3> = (0..nv)
        .map(|v| vertex_point(v as u32, points, &inc, &face_points, rule))
        .collect();

    let mut out = Refined {
        points: Vec::with_capacity(nv + ne + faces.len()),
        quads: Vec::new(),
        face_start: Vec::with_capacity(faces.len()),
    };
    out.points.extend(vertex_points);
    out.points.extend(edge_points);
    out.points.extend(face_points);
    let edge_index = |a: u32, b: u32| nv as u32 + inc.edges[&edge_key(a, b)].0;
    for (f, face) in faces.iter().enumerate() {
        out.face_start.push(out.quads.len() as u32);
        let n = face.len();
        let fp = (nv + ne + f) as u32;
        for k in 0..n {
            let (prev, v, next) = (face[(k + n - 1) % n], face[k], face[(k + 1) % n]);
            out.quads
                .push([v, edge_index(v, next), fp, edge_index(prev, v)]);
        }
    }
    out
}

/// The vertex rule. Interior: `(F + 2R + (n-3)P)/n` (face-point and edge-midpoint
/// averages); smooth boundary: `(a + 6P + b)/8` over the two boundary neighbours;
/// corner (edge-and-corner rule, one face): `P`.
fn vertex_point(
    v: u32,
    points: &[DVec3],
    inc: &Incidence,
    face_points: &[DVec3],
    rule: BoundaryRule,
) -> DVec3 {
    let p = points[v as usize];
    let faces = &inc.vertex_faces[v as usize];
    let neighbors = &inc.vertex_neighbors[v as usize];
    if faces.is_empty() {
        return p;
    }
    let boundary: Vec<u32> = neighbors
        .iter()
        .copied()
        .filter(|&w| inc.edges[&edge_key(v, w)].1 == 1)
        .collect();
    match boundary.len() {
        0 if neighbors.len() == faces.len() => {
            let n = neighbors.len() as f64;
            let f = faces
                .iter()
                .map(|&f| face_points[f as usize])
                .sum::<DVec3>()
                / n;
            let r = neighbors
                .iter()
                .map(|&w| (p + points[w as usize]) * 0.5)
                .sum::<DVec3>()
                / n;
            (f + 2.0 * r + (n - 3.0) * p) / n
        }
        2 if rule == BoundaryRule::EdgeAndCorner && faces.len() == 1 => p,
        2 => (points[boundary[0] as usize] + 6.0 * p + points[boundary[1] as usize]) / 8.0,
        // Only rim vertices of a one-ring mesh get here; their points are never used.
        _ => p,
    }
}
