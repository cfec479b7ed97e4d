//! One Catmull-Clark step on a polygon mesh, with OpenSubdiv's rules for boundaries,
//! semi-sharp and infinitely sharp creases and corners ([`Scheme`], [`Sharpness`]).
//!
//! The rules are those of OpenSubdiv's `Sdc` (`Sdc::Crease`, `Sdc::Scheme<CATMARK>`),
//! read from its source: an open boundary edge is infinitely sharp and, under the
//! edge-and-corner rule, so is a vertex with one face; a vertex's rule (smooth, dart,
//! crease, corner) follows from its sharpness and how many of its edges are sharp; an
//! edge or vertex whose sharpness falls below 1 during the step blends the sharp rule
//! and the smooth one by its fraction. Sharpness is kept in single precision, as
//! OpenSubdiv keeps it, so that the same edges decay at the same level.
//!
//! Used twice: on the whole control mesh (the step that makes every face a quad, see
//! [`super::topology`]) and on the small one-ring meshes around a patch that the exact
//! evaluation subdivides again and again (see [`super::local`]). In a one-ring mesh the
//! vertices on its outer rim see only part of their faces; their new points come out
//! wrong and are never used, but computing them must not fail.

use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;

use super::control_mesh::{BoundaryRule, CreaseMethod, SHARPNESS_INFINITE};

/// The subdivision options that shape the surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Scheme {
    /// How open boundaries are subdivided.
    pub boundary: BoundaryRule,
    /// How semi-sharp sharpness decays.
    pub creasing: CreaseMethod,
    /// OpenSubdiv's smooth triangle rule for the edge points next to triangles.
    pub smooth_triangles: bool,
}

impl Scheme {
    /// The default scheme with this boundary rule.
    pub fn with_boundary(boundary: BoundaryRule) -> Self {
        Scheme {
            boundary,
            ..Scheme::default()
        }
    }
}

/// Sharpness of the edges and vertices of a mesh, sparse: what is absent is smooth.
/// Open boundary edges and edge-and-corner corners need no entry: their infinite
/// sharpness follows from the topology at every step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Sharpness {
    /// Per undirected edge ([`edge_key`]): its sharpness, when above 0.
    pub edges: HashMap<(u32, u32), f32>,
    /// Per directed edge `(v, w)`: the sharpness its half at `v` gets in the next step,
    /// where it was already known exactly (Chaikin's rule reads all edges at `v`, which a
    /// one-ring mesh holds for the vertices at its target's corners only). Absent: computed
    /// from the edges at `v`.
    pub next: HashMap<(u32, u32), f32>,
    /// Per vertex: its sharpness, when above 0.
    pub vertices: HashMap<u32, f32>,
}

impl Sharpness {
    /// Whether nothing is sharp.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty() && self.vertices.is_empty()
    }

    /// Sharpness of edge `(a, b)` (0 when smooth).
    pub fn edge(&self, a: u32, b: u32) -> f32 {
        self.edges.get(&edge_key(a, b)).copied().unwrap_or(0.0)
    }

    /// Sharpness of vertex `v` (0 when smooth).
    pub fn vertex(&self, v: u32) -> f32 {
        self.vertices.get(&v).copied().unwrap_or(0.0)
    }

    /// The sharpness of a control mesh's creases and corners (a later entry for the
    /// same edge or vertex replaces an earlier one, as OpenSubdiv's factory assigns).
    pub fn from_tags(creases: &[([u32; 2], f32)], corners: &[(u32, f32)]) -> Self {
        let mut out = Sharpness::default();
        for &([a, b], s) in creases {
            out.edges.insert(edge_key(a, b), s);
        }
        for &(v, s) in corners {
            out.vertices.insert(v, s);
        }
        out.edges.retain(|_, s| *s > 0.0);
        out.vertices.retain(|_, s| *s > 0.0);
        out
    }
}

/// Whether a sharpness is semi-sharp: above 0, below infinite.
pub fn is_semi_sharp(s: f32) -> bool {
    s > 0.0 && s < SHARPNESS_INFINITE
}

/// The sharpness one level down under the normal rule (`Sdc::Crease::decrementSharpness`).
fn decrement(s: f32) -> f32 {
    if s <= 0.0 {
        0.0
    } else if s >= SHARPNESS_INFINITE {
        SHARPNESS_INFINITE
    } else if s > 1.0 {
        s - 1.0
    } else {
        0.0
    }
}

/// The sharpness one level down of an edge of sharpness `s` at a vertex whose edges
/// have sharpness `around` (`s` among them): `Sdc::Crease::SubdivideEdgeSharpnessAtVertex`.
fn subdivide_edge_at_vertex(s: f32, around: &[f32], method: CreaseMethod) -> f32 {
    if method == CreaseMethod::Normal || around.len() < 2 {
        return decrement(s);
    }
    if s <= 0.0 {
        return 0.0;
    }
    if s >= SHARPNESS_INFINITE {
        return SHARPNESS_INFINITE;
    }
    let (mut sum, mut count) = (0.0f32, 0);
    for &x in around {
        if is_semi_sharp(x) {
            sum += x;
            count += 1;
        }
    }
    let mut s = s;
    if count > 1 {
        let others = (sum - s) / (count - 1) as f32;
        s = 0.75 * s + 0.25 * others;
    }
    s -= 1.0;
    if s > 0.0 {
        s
    } else {
        0.0
    }
}

/// A vertex's subdivision rule (`Sdc::Crease::Rule`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRule {
    /// No sharp edge, no sharpness: the smooth rule.
    Smooth,
    /// One sharp edge: the smooth rule (the edge's own point is its midpoint).
    Dart,
    /// Two sharp edges: the point moves along the crease curve.
    Crease,
    /// A sharp vertex, or three sharp edges or more: the point stays.
    Corner,
}

/// `Sdc::Crease::DetermineVertexVertexRule`.
pub fn vertex_rule(vertex_sharpness: f32, edge_sharpness: &[f32]) -> VertexRule {
    if vertex_sharpness > 0.0 {
        return VertexRule::Corner;
    }
    match edge_sharpness.iter().filter(|&&s| s > 0.0).count() {
        0 => VertexRule::Smooth,
        1 => VertexRule::Dart,
        2 => VertexRule::Crease,
        _ => VertexRule::Corner,
    }
}

/// How much of the parent's rule a vertex whose rule changes in this step keeps
/// (`Sdc::Crease::ComputeFractionalWeightAtVertex`).
fn fractional_weight(
    parent_vertex: f32,
    child_vertex: f32,
    parent_edges: &[f32],
    child_edges: &[f32],
    method: CreaseMethod,
) -> f32 {
    let (mut count, mut sum) = (0, 0.0f32);
    if parent_vertex > 0.0 && child_vertex <= 0.0 {
        count = 1;
        sum = parent_vertex;
    }
    for (&p, &c) in parent_edges.iter().zip(child_edges) {
        let decays = match method {
            CreaseMethod::Normal => p <= 1.0,
            CreaseMethod::Chaikin => c <= 0.0,
        };
        if p > 0.0 && decays {
            sum += p;
            count += 1;
        }
    }
    if count == 0 {
        0.0
    } else {
        (sum / count as f32).min(1.0)
    }
}

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
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::default();
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

/// One smooth Catmull-Clark step of `points`/`faces` (no creases, `rule` at boundaries).
pub fn refine(points: &[DVec3], faces: &[Vec<u32>], rule: BoundaryRule) -> Refined {
    refine_sharp(
        points,
        faces,
        &Scheme::with_boundary(rule),
        &Sharpness::default(),
    )
    .0
}

/// One Catmull-Clark step of `points`/`faces` with the sharpness `sharp`; returns the
/// refined mesh and its sharpness (of the child edges and vertices, numbered as
/// [`Refined`] numbers the points).
pub fn refine_sharp(
    points: &[DVec3],
    faces: &[Vec<u32>],
    scheme: &Scheme,
    sharp: &Sharpness,
) -> (Refined, Sharpness) {
    let nv = points.len();
    let inc = incidence(nv, faces);
    let ne = inc.edges.len();
    let face_points: Vec<DVec3> = faces
        .iter()
        .map(|f| f.iter().map(|&v| points[v as usize]).sum::<DVec3>() / f.len() as f64)
        .collect();
    let mut edge_faces: Vec<[Option<u32>; 2]> = vec![[None, None]; ne];
    for (f, face) in faces.iter().enumerate() {
        for k in 0..face.len() {
            let e = inc.edges[&edge_key(face[k], face[(k + 1) % face.len()])].0 as usize;
            let slot = if edge_faces[e][0].is_none() { 0 } else { 1 };
            edge_faces[e][slot] = Some(f as u32);
        }
    }
    let creased = !sharp.is_empty();
    let ctx = Context {
        points,
        inc: &inc,
        scheme,
        sharp,
    };

    let mut edge_points = vec![DVec3::ZERO; ne];
    for (&(a, b), &(e, count)) in &inc.edges {
        let mid = (points[a as usize] + points[b as usize]) * 0.5;
        let [Some(f0), Some(f1)] = edge_faces[e as usize] else {
            edge_points[e as usize] = mid;
            continue;
        };
        if count != 2 {
            edge_points[e as usize] = mid;
            continue;
        }
        let (f0, f1) = (f0 as usize, f1 as usize);
        // The smooth mask: ends and face points, a quarter each, or OpenSubdiv's
        // smooth-triangle weights next to triangles.
        let tri = |f: usize| scheme.smooth_triangles && faces[f].len() == 3;
        let (vw, fw) = if tri(f0) || tri(f1) {
            let w = |f: usize| if tri(f) { 0.470 } else { 0.25 };
            let fw = 0.5 * (w(f0) + w(f1));
            (0.5 * (1.0 - 2.0 * fw), fw)
        } else {
            (0.25, 0.25)
        };
        let s = if creased { sharp.edge(a, b) } else { 0.0 };
        let (vw, fw) = if s <= 0.0 {
            (vw, fw)
        } else {
            let (ha, hb) = (ctx.next_half(a, b), ctx.next_half(b, a));
            if ha > 0.0 && hb > 0.0 {
                (0.5, 0.0)
            } else {
                // The child point is not a crease vertex: blend by the sharpness.
                let p = s as f64;
                (p * 0.5 + (1.0 - p) * vw, (1.0 - p) * fw)
            }
        };
        edge_points[e as usize] = vw * (points[a as usize] + points[b as usize])
            + fw * (face_points[f0] + face_points[f1]);
    }

    let vertex_points: Vec<DVec3> = (0..nv)
        .map(|v| ctx.vertex_point(v as u32, &face_points))
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

    // The children's sharpness: each half of a sharp edge, and what its own halves get
    // one step further where this step knows it exactly (at the edge point, whose only
    // sharp edges are the two halves; at the vertex point, from all edges at the vertex).
    let mut child = Sharpness::default();
    if creased {
        for (&(a, b), &(e, _)) in &inc.edges {
            let s = sharp.edge(a, b);
            if s <= 0.0 {
                continue;
            }
            let mid = nv as u32 + e;
            let (ha, hb) = (ctx.next_half(a, b), ctx.next_half(b, a));
            for (v, h) in [(a, ha), (b, hb)] {
                if h <= 0.0 {
                    continue;
                }
                child.edges.insert(edge_key(v, mid), h);
                let at_mid = [ha, hb, 0.0, 0.0];
                child.next.insert(
                    (mid, v),
                    subdivide_edge_at_vertex(h, &at_mid, scheme.creasing),
                );
                let at_vertex: Vec<f32> = inc.vertex_neighbors[v as usize]
                    .iter()
                    .map(|&w| ctx.next_half(v, w))
                    .collect();
                child.next.insert(
                    (v, mid),
                    subdivide_edge_at_vertex(h, &at_vertex, scheme.creasing),
                );
            }
        }
        for (&v, &s) in &sharp.vertices {
            let c = decrement(s);
            if c > 0.0 {
                child.vertices.insert(v, c);
            }
        }
    }
    (out, child)
}

/// What the point rules read.
struct Context<'a> {
    points: &'a [DVec3],
    inc: &'a Incidence,
    scheme: &'a Scheme,
    sharp: &'a Sharpness,
}

impl Context<'_> {
    /// Sharpness of edge `(v, w)`: infinite on an open boundary.
    fn edge_sharpness(&self, v: u32, w: u32) -> f32 {
        if self.inc.edges[&edge_key(v, w)].1 == 1 {
            SHARPNESS_INFINITE
        } else {
            self.sharp.edge(v, w)
        }
    }

    /// Sharpness of vertex `v`: infinite at a corner of the edge-and-corner rule.
    fn vertex_sharpness(&self, v: u32) -> f32 {
        let corner = self.scheme.boundary == BoundaryRule::EdgeAndCorner
            && self.inc.vertex_faces[v as usize].len() == 1
            && self.inc.vertex_neighbors[v as usize].len() == 2;
        if corner {
            SHARPNESS_INFINITE
        } else {
            self.sharp.vertex(v)
        }
    }

    /// The sharpness the half at `v` of edge `(v, w)` gets in this step.
    fn next_half(&self, v: u32, w: u32) -> f32 {
        let s = self.edge_sharpness(v, w);
        if s <= 0.0 || s >= SHARPNESS_INFINITE {
            return s;
        }
        if let Some(&h) = self.sharp.next.get(&(v, w)) {
            return h;
        }
        let around: Vec<f32> = self.inc.vertex_neighbors[v as usize]
            .iter()
            .map(|&u| self.edge_sharpness(v, u))
            .collect();
        subdivide_edge_at_vertex(s, &around, self.scheme.creasing)
    }

    /// The vertex rule, blended between this level's rule and the next's where
    /// sharpness decays below 1 (`Sdc::Scheme::ComputeVertexVertexMask`).
    fn vertex_point(&self, v: u32, face_points: &[DVec3]) -> DVec3 {
        let p = self.points[v as usize];
        let faces = &self.inc.vertex_faces[v as usize];
        let neighbors = &self.inc.vertex_neighbors[v as usize];
        if faces.is_empty() {
            return p;
        }
        let parent_edges: Vec<f32> = neighbors
            .iter()
            .map(|&w| self.edge_sharpness(v, w))
            .collect();
        let parent_vertex = self.vertex_sharpness(v);
        let parent_rule = vertex_rule(parent_vertex, &parent_edges);
        let smooth = || {
            // Only rim vertices of a one-ring mesh have a fan that does not close; their
            // points are never used.
            if neighbors.len() != faces.len() {
                return p;
            }
            let n = neighbors.len() as f64;
            let f = faces
                .iter()
                .map(|&f| face_points[f as usize])
                .sum::<DVec3>()
                / n;
            let r = neighbors
                .iter()
                .map(|&w| (p + self.points[w as usize]) * 0.5)
                .sum::<DVec3>()
                / n;
            (f + 2.0 * r + (n - 3.0) * p) / n
        };
        let mask = |rule: VertexRule, edges: &[f32]| match rule {
            VertexRule::Smooth | VertexRule::Dart => smooth(),
            VertexRule::Crease => {
                let mut ends = neighbors
                    .iter()
                    .zip(edges)
                    .filter(|(_, &s)| s > 0.0)
                    .map(|(&w, _)| self.points[w as usize]);
                let (a, b) = (ends.next().unwrap_or(p), ends.next().unwrap_or(p));
                0.75 * p + 0.125 * (a + b)
            }
            VertexRule::Corner => p,
        };
        if matches!(parent_rule, VertexRule::Smooth | VertexRule::Dart) {
            return smooth();
        }
        let at_parent = mask(parent_rule, &parent_edges);
        let child_edges: Vec<f32> = neighbors.iter().map(|&w| self.next_half(v, w)).collect();
        let child_vertex = decrement(parent_vertex);
        let child_rule = vertex_rule(child_vertex, &child_edges);
        if child_rule == parent_rule {
            return at_parent;
        }
        let w = fractional_weight(
            parent_vertex,
            child_vertex,
            &parent_edges,
            &child_edges,
            self.scheme.creasing,
        ) as f64;
        w * at_parent + (1.0 - w) * mask(child_rule, &child_edges)
    }
}
