//! Topology (OpenSubdiv's "Far" layer): validation of the control mesh, the first
//! Catmull-Clark step, and the patches with their connectivity.
//!
//! # Patch structure
//!
//! One Catmull-Clark step turns a face with `n` sides into `n` quads. Every quad of
//! that first level is one **patch**, so a control face `f` owns the patches
//! `first_patch[f] .. first_patch[f] + n`, one per corner `k`. Patch `first_patch[f] + k`
//! has its corners at `[V(f[k]), E(f[k], f[k+1]), F(f), E(f[k-1], f[k])]` (vertex
//! point, edge point, face point, edge point) at parameters `(0,0), (1,0), (1,1), (0,1)`.
//! So `(u, v)` of that patch is the point of the control face reached by going `u` of
//! the way from its corner `k` towards the middle of the edge `(k, k+1)` and `v` of the way
//! towards the middle of the edge `(k-1, k)`, on the subdivided surface. For a quad face
//! with corners `(0,0), (1,0), (1,1), (0,1)` in face coordinates `(s, t)`: corner 0 gives
//! `(s, t) = (u, v)/2`, corner 1 `(1 - v/2, u/2)`, corner 2 `(1 - u/2, 1 - v/2)`,
//! corner 3 `(v/2, 1 - u/2)`.
//!
//! A patch can have two extraordinary corners: `V(f[k])` when that vertex's valence is
//! not 4 and `F(f)` when `f` is not a quad. The exact evaluation ([`super::patch`])
//! subdivides such patches further, so nothing here needs a second global step.

use std::collections::HashMap;

use glam::DVec3;

use super::control_mesh::{BoundaryRule, ControlMesh};
use super::refine::{edge_key, refine_sharp, Scheme, Sharpness};
use crate::error::{Error, Result};

/// The largest vertex valence (and face size) accepted. The evaluation has no limit of
/// its own; this bounds the work per patch and is the range the tests cover.
pub const MAX_VALENCE: usize = 64;

/// A validated mesh after its first Catmull-Clark step: all quads, one patch each.
#[derive(Clone, Debug)]
pub struct PatchMesh {
    /// How the mesh is subdivided: its boundary rule, crease method and triangle rule.
    pub scheme: Scheme,
    /// Sharpness of the control mesh's edges and vertices (its creases and corners).
    pub control_sharpness: Sharpness,
    /// Sharpness of the level-1 edges and points, after the first step.
    pub sharpness: Sharpness,
    /// Level-1 points: `[vertex points] [edge points] [face points]` of the control mesh.
    pub points: Vec<DVec3>,
    /// Level-1 quads, one per patch, counter-clockwise. Holes included (see `hole`).
    pub quads: Vec<[u32; 4]>,
    /// The control face of each quad and its corner in that face.
    pub face_of: Vec<(u32, u8)>,
    /// First quad of each control face.
    pub first_patch: Vec<u32>,
    /// Quads of faces tagged `hole`: they shape their neighbours, but are not tessellated.
    pub hole: Vec<bool>,
    /// Quads around each level-1 point.
    pub point_quads: Vec<Vec<u32>>,
    /// Level-1 edges, numbered: `(min, max)` point pair to edge id.
    pub edges: HashMap<(u32, u32), u32>,
    /// Per quad: the ids of its edges `(q[k], q[k+1])`.
    pub quad_edges: Vec<[u32; 4]>,
    /// How many edges each level-1 edge has: 1 on an open boundary.
    pub edge_uses: Vec<u8>,
    /// Control vertices no face uses (ignored).
    pub unreferenced_vertices: usize,
    /// The control faces, kept so that moved control points refine to the same quads
    /// ([`PatchMesh::with_control_points`]).
    pub control_faces: Vec<Vec<u32>>,
    /// Control vertices, unreferenced ones included.
    pub control_vertices: usize,
    /// Their positions, as loaded or last moved: what the GPU stage's stencils
    /// ([`super::stencil`]) start from.
    pub control_points: Vec<DVec3>,
    /// Diagonal of the bounding box of the control points that faces use, as loaded:
    /// what a relative tolerance is a fraction of ([`crate::Tolerance`]). Moving the
    /// points keeps it.
    pub control_diag: f64,
}

impl PatchMesh {
    /// The control points in single precision, as a GPU stage takes them.
    pub fn control_points_f32(&self) -> Vec<glam::Vec3> {
        self.control_points.iter().map(|p| p.as_vec3()).collect()
    }

    /// Diagonal of the level-1 points' bounding box: the surface's size (the limit
    /// surface lies in their hull).
    pub fn bbox_diag(&self) -> f64 {
        let (lo, hi) = self.points.iter().fold(
            (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        (hi - lo).length()
    }

    /// Validates `mesh` and makes its first subdivision level.
    pub fn new(mesh: &ControlMesh) -> Result<Self> {
        let unreferenced_vertices = validate(mesh)?;
        if !mesh.holes.is_empty() && mesh.holes.iter().all(|&h| h) {
            return Err(Error::input(
                &mesh.source,
                "every face is tagged as a hole: there is no surface to tessellate",
            ));
        }
        let scheme = Scheme {
            boundary: mesh.boundary,
            creasing: mesh.crease_method,
            smooth_triangles: mesh.smooth_triangles,
        };
        let control_sharpness = Sharpness::from_tags(&mesh.creases, &mesh.corners);
        let (level1, sharpness) =
            refine_sharp(&mesh.positions, &mesh.faces, &scheme, &control_sharpness);
        let mut face_of = Vec::with_capacity(level1.quads.len());
        let mut hole = Vec::with_capacity(level1.quads.len());
        for (f, face) in mesh.faces.iter().enumerate() {
            for k in 0..face.len() {
                face_of.push((f as u32, k as u8));
                hole.push(mesh.holes.get(f).copied().unwrap_or(false));
            }
        }
        let mut point_quads = vec![Vec::new(); level1.points.len()];
        let mut edges = HashMap::new();
        let mut quad_edges = Vec::with_capacity(level1.quads.len());
        let mut edge_uses: Vec<u8> = Vec::new();
        for (q, quad) in level1.quads.iter().enumerate() {
            let mut ids = [0u32; 4];
            for k in 0..4 {
                point_quads[quad[k] as usize].push(q as u32);
                let next = edges.len() as u32;
                let id = *edges
                    .entry(edge_key(quad[k], quad[(k + 1) % 4]))
                    .or_insert(next);
                if id as usize == edge_uses.len() {
                    edge_uses.push(0);
                }
                edge_uses[id as usize] += 1;
                ids[k] = id;
            }
            quad_edges.push(ids);
        }
        Ok(PatchMesh {
            scheme,
            control_sharpness,
            sharpness,
            points: level1.points,
            quads: level1.quads,
            face_of,
            first_patch: level1.face_start,
            hole,
            point_quads,
            edges,
            quad_edges,
            edge_uses,
            unreferenced_vertices,
            control_faces: mesh.faces.clone(),
            control_vertices: mesh.positions.len(),
            control_points: mesh.positions.clone(),
            control_diag: mesh.bbox_diag(),
        })
    }

    /// Whether `positions` can replace the control points: one per control vertex, each
    /// coordinate finite and within the loaders' range.
    pub fn check_control_points(
        &self,
        positions: impl ExactSizeIterator<Item = DVec3>,
    ) -> Result<()> {
        if positions.len() != self.control_vertices {
            return Err(Error::Param(format!(
                "{} control points given, the mesh has {}",
                positions.len(),
                self.control_vertices
            )));
        }
        for (i, p) in positions.enumerate() {
            if !p.is_finite() || p.abs().max_element() > crate::io::MAX_COORDINATE {
                return Err(Error::Param(format!(
                    "control point {i} is {p}: coordinates must be finite and within ±{:e}",
                    crate::io::MAX_COORDINATE
                )));
            }
        }
        Ok(())
    }

    /// The same topology with the control points moved to `positions` (one per control
    /// vertex, in the input's order): only the first-level points are computed again.
    /// [`control_diag`](Self::control_diag) stays as loaded.
    pub fn with_control_points(&self, positions: &[DVec3]) -> Result<PatchMesh> {
        self.check_control_points(positions.iter().copied())?;
        let (level1, _) = refine_sharp(
            positions,
            &self.control_faces,
            &self.scheme,
            &self.control_sharpness,
        );
        Ok(PatchMesh {
            points: level1.points,
            control_points: positions.to_vec(),
            ..self.clone()
        })
    }

    /// The control face of patch `p` and the point `(u, v)` of the patch in that face's
    /// own parameterisation, OpenSubdiv Bfr's (and, for quads, Ptex's): a quad's `(0, 0)`
    /// is its first vertex, `u` runs toward its second and `v` toward its last; a face
    /// of `n ≠ 4` sides is `n` sub-faces, sub-face `k` (this face's patch `k`) the
    /// half-unit square at tile `(k mod d, k div d)` with `d` = 2 for triangles, 3 for
    /// 5 to 9 sides and `1 + ⌊√(n-1)⌋` above, its `(0, 0)` at vertex `k`, `u` toward
    /// vertex `k+1` and `v` toward vertex `k-1`.
    ///
    /// `(u, v)` in units of `1/scale` (a grid point `(i, j)/scale` of the patch) comes
    /// out in units of `1/(2·scale)`, exactly, so that every patch of a quad face gives
    /// the same coordinates for a point on their shared side: [`Self::face_point_at`]
    /// does the division.
    pub fn face_point(&self, p: usize, i: u64, j: u64, scale: u64) -> (u32, u64, u64) {
        let (face, k) = self.face_of[p];
        let sides = self.control_faces[face as usize].len();
        let (s, t) = face_coords(k as u64, sides as u64, i, j, scale);
        (face, s, t)
    }

    /// [`Self::face_point`] for real `(u, v) ∈ [0, 1]²`: the control face and its
    /// `(u, v)`.
    pub fn face_point_at(&self, p: usize, u: f64, v: f64) -> (u32, f64, f64) {
        let (face, k) = self.face_of[p];
        let sides = self.control_faces[face as usize].len();
        let (s, t) = if sides == 4 {
            match k {
                0 => (u, v),
                1 => (2.0 - v, u),
                2 => (2.0 - u, 2.0 - v),
                _ => (v, 2.0 - u),
            }
        } else {
            let d = sub_face_tiles(sides);
            let k = k as usize;
            ((k % d) as f64 * 2.0 + u, (k / d) as f64 * 2.0 + v)
        };
        (face, s / 2.0, t / 2.0)
    }

    /// The patch holding point `(u, v)` of control face `face` in the parameterisation
    /// of [`Self::face_point`], and the point's `(u, v)` in that patch; `None` when
    /// the face does not exist or the point lies outside its domain (for faces of
    /// `n ≠ 4` sides, outside every sub-face's half-unit square).
    pub fn patch_at(&self, face: u32, u: f64, v: f64) -> Option<(usize, f64, f64)> {
        let sides = self.control_faces.get(face as usize)?.len();
        let first = self.first_patch[face as usize] as usize;
        if !(u.is_finite() && v.is_finite()) {
            return None;
        }
        if sides == 4 {
            if !(0.0..=1.0).contains(&u) || !(0.0..=1.0).contains(&v) {
                return None;
            }
            let (s, t) = (2.0 * u, 2.0 * v);
            let (k, pu, pv) = match (s >= 1.0, t >= 1.0) {
                (false, false) => (0, s, t),
                (true, false) => (1, t, 2.0 - s),
                (true, true) => (2, 2.0 - s, 2.0 - t),
                (false, true) => (3, 2.0 - t, s),
            };
            return Some((first + k, pu, pv));
        }
        let d = sub_face_tiles(sides);
        let (tu, tv) = (u.floor(), v.floor());
        let (fu, fv) = (u - tu, v - tv);
        if tu < 0.0 || tv < 0.0 || fu > 0.5 || fv > 0.5 || tu >= d as f64 {
            return None;
        }
        let k = tv as usize * d + tu as usize;
        (k < sides).then_some((first + k, 2.0 * fu, 2.0 * fv))
    }

    /// Whether any control edge or vertex is sharp (creases or corners; open
    /// boundaries do not count).
    pub fn has_creases(&self) -> bool {
        !self.control_sharpness.is_empty()
    }

    /// How open boundaries are subdivided.
    pub fn boundary(&self) -> BoundaryRule {
        self.scheme.boundary
    }

    /// Patches (level-1 quads), holes included.
    pub fn patch_count(&self) -> usize {
        self.quads.len()
    }

    /// Patches that are tessellated (not holes).
    pub fn surface_patches(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.quads.len()).filter(|&p| !self.hole[p])
    }
}

/// [`PatchMesh::face_point`] for the patch at corner `k` of a face of `sides` sides: grid
/// point `(i, j)/scale` of the patch in the face's coordinates, units of `1/(2·scale)`.
/// Twin of `cc_face_coords` (`shaders/shared/cc_face.wgsl`).
pub fn face_coords(k: u64, sides: u64, i: u64, j: u64, scale: u64) -> (u64, u64) {
    let m = 2 * scale;
    if sides == 4 {
        match k {
            0 => (i, j),
            1 => (m - j, i),
            2 => (m - i, m - j),
            _ => (j, m - i),
        }
    } else {
        let d = sub_face_tiles(sides as usize) as u64;
        ((k % d) * m + i, (k / d) * m + j)
    }
}

/// Sub-face tiles per row of a face of `sides ≠ 4` sides in Bfr's parameterisation:
/// 2 for triangles, 3 for 5 to 9 sides, `1 + ⌊√(sides − 1)⌋` above (integer square root,
/// as the kernels take it).
pub fn sub_face_tiles(sides: usize) -> usize {
    if sides < 10 {
        2 + usize::from(sides > 4)
    } else {
        let mut r = 1;
        while (r + 1) * (r + 1) < sides {
            r += 1;
        }
        1 + r
    }
}

/// Checks what Catmull-Clark subdivision needs: faces of at least 3 distinct vertices,
/// every edge used by at most two faces in opposite directions, every vertex a single
/// fan of faces, valences in `3..=MAX_VALENCE` (2 allowed on a boundary). Returns the
/// number of vertices no face uses.
pub fn validate(mesh: &ControlMesh) -> Result<usize> {
    let file = &mesh.source;
    let line_of = |f: usize| mesh.face_lines.get(f).copied().unwrap_or(0);
    let face_err = |f: usize, msg: String| {
        let line = line_of(f);
        if line > 0 {
            Error::parse(file, line, msg)
        } else {
            Error::input(file, format!("face {f}: {msg}"))
        }
    };
    let nv = mesh.positions.len();
    for (i, p) in mesh.positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(Error::input(
                file,
                format!("vertex {} is not finite ({p})", i + 1),
            ));
        }
    }
    // Directed edge -> face using it.
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    let mut undirected: HashMap<(u32, u32), u32> = HashMap::new();
    for (f, face) in mesh.faces.iter().enumerate() {
        if face.len() < 3 {
            return Err(face_err(
                f,
                format!("face has {} vertices, at least 3 are needed", face.len()),
            ));
        }
        if face.len() > MAX_VALENCE {
            return Err(face_err(
                f,
                format!(
                    "face has {} vertices; at most {MAX_VALENCE} are supported",
                    face.len()
                ),
            ));
        }
        for (k, &v) in face.iter().enumerate() {
            if v as usize >= nv {
                return Err(face_err(
                    f,
                    format!("vertex index {} out of range ({nv} vertices)", v + 1),
                ));
            }
            if face[..k].contains(&v) {
                let distinct = {
                    let mut d = face.clone();
                    d.sort_unstable();
                    d.dedup();
                    d.len()
                };
                return Err(face_err(
                    f,
                    if distinct < 3 {
                        format!("face has only {distinct} distinct vertices")
                    } else {
                        format!("face uses vertex {} twice", v + 1)
                    },
                ));
            }
        }
        let n = face.len();
        for k in 0..n {
            let (a, b) = (face[k], face[(k + 1) % n]);
            let uses = undirected.entry(edge_key(a, b)).or_insert(0);
            *uses += 1;
            if *uses > 2 {
                return Err(face_err(
                    f,
                    format!(
                        "non-manifold edge {}-{}: used by more than two faces",
                        a + 1,
                        b + 1
                    ),
                ));
            }
        }
    }
    // Orientation after all uses are counted, so that an edge of three faces is reported
    // as non-manifold, not as the orientation clash its second use may look like.
    for (f, face) in mesh.faces.iter().enumerate() {
        let n = face.len();
        for k in 0..n {
            let (a, b) = (face[k], face[(k + 1) % n]);
            if let Some(&g) = directed.get(&(a, b)) {
                return Err(face_err(
                    f,
                    format!(
                        "edge {}-{} runs the same way in this face and in the face at line {}: inconsistent orientation",
                        a + 1,
                        b + 1,
                        line_of(g)
                    ),
                ));
            }
            directed.insert((a, b), f);
        }
    }

    // Each vertex: its faces must form one fan (linked through shared edges), and its
    // valence must be supported.
    let mut vertex_faces: Vec<Vec<usize>> = vec![Vec::new(); nv];
    for (f, face) in mesh.faces.iter().enumerate() {
        for &v in face {
            vertex_faces[v as usize].push(f);
        }
    }
    let mut unreferenced = 0;
    for (v, faces) in vertex_faces.iter().enumerate() {
        if faces.is_empty() {
            unreferenced += 1;
            continue;
        }
        let v = v as u32;
        // Walk the fan from one face across edges at v; the walk must reach every face.
        let prev_of = |f: usize| {
            let face = &mesh.faces[f];
            let k = face.iter().position(|&w| w == v).expect("face holds v");
            let n = face.len();
            (face[(k + n - 1) % n], face[(k + 1) % n])
        };
        let mut seen = vec![false; faces.len()];
        let mut stack = vec![0usize];
        seen[0] = true;
        while let Some(i) = stack.pop() {
            let (prev, next) = prev_of(faces[i]);
            for (j, &g) in faces.iter().enumerate() {
                if !seen[j] {
                    let (gp, gn) = prev_of(g);
                    if gp == next || gn == prev {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        let first_face = faces[0];
        if seen.iter().any(|s| !s) {
            return Err(face_err(
                first_face,
                format!(
                    "non-manifold vertex {}: its faces form separate fans",
                    v + 1
                ),
            ));
        }
        let boundary_edges = faces
            .iter()
            .flat_map(|&f| {
                let (p, n) = prev_of(f);
                [p, n]
            })
            .filter(|&w| undirected[&edge_key(v, w)] == 1)
            .count();
        let valence = faces.len() + usize::from(boundary_edges > 0);
        let interior = boundary_edges == 0;
        if valence > MAX_VALENCE {
            return Err(face_err(
                first_face,
                format!(
                    "vertex {} has valence {valence}; at most {MAX_VALENCE} is supported",
                    v + 1
                ),
            ));
        }
        if interior && valence < 3 {
            return Err(face_err(
                first_face,
                format!(
                    "interior vertex {} has valence {valence}; Catmull-Clark needs at least 3",
                    v + 1
                ),
            ));
        }
    }
    Ok(unreferenced)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quad, a triangle, a pentagon and a 12-gon side by side (a fan around vertex 0
    /// is not needed: only the face parameterisation is under test).
    fn faces_of_sizes(sizes: &[usize]) -> PatchMesh {
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for (f, &n) in sizes.iter().enumerate() {
            let base = positions.len() as u32;
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                positions.push(DVec3::new(3.0 * f as f64 + a.cos(), a.sin(), 0.0));
            }
            faces.push((0..n as u32).map(|k| base + k).collect());
        }
        PatchMesh::new(&ControlMesh::new(positions, faces)).unwrap()
    }

    #[test]
    fn face_points_and_patches_are_inverse() {
        let mesh = faces_of_sizes(&[4, 3, 5, 12]);
        let grid = [0.0, 0.125, 0.5, 0.75, 1.0];
        for p in 0..mesh.patch_count() {
            for &u in &grid {
                for &v in &grid {
                    let (face, fu, fv) = mesh.face_point_at(p, u, v);
                    assert_eq!(face, mesh.face_of[p].0);
                    let (q, qu, qv) = mesh.patch_at(face, fu, fv).unwrap();
                    // Points on a seam between a quad's patches may come back in the
                    // neighbour: same face point either way.
                    let back = mesh.face_point_at(q, qu, qv);
                    assert!((back.1 - fu).abs() < 1e-12 && (back.2 - fv).abs() < 1e-12);
                    if u < 1.0 && v < 1.0 {
                        assert_eq!((q, qu, qv), (p, u, v), "patch {p} at ({u}, {v})");
                    }
                    // The exact integer form gives the same point.
                    let (g, s, t) = mesh.face_point(p, (8.0 * u) as u64, (8.0 * v) as u64, 8);
                    assert_eq!((g, s as f64 / 16.0, t as f64 / 16.0), (face, fu, fv));
                }
            }
        }
    }

    #[test]
    fn the_face_parameterisation_follows_bfr() {
        let mesh = faces_of_sizes(&[4, 3, 5, 12]);
        // Quad: corners of the face at the patch corners (0, 0).
        let corner = |p: usize| {
            let (_, u, v) = mesh.face_point_at(p, 0.0, 0.0);
            (u, v)
        };
        assert_eq!(
            (0..4).map(corner).collect::<Vec<_>>(),
            [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
        );
        // Quad centre, from every patch.
        for p in 0..4 {
            assert_eq!(mesh.face_point_at(p, 1.0, 1.0), (0, 0.5, 0.5));
        }
        // Triangle: 2 tiles per row; pentagon: 3; 12-gon: 1 + ⌊√11⌋ = 4.
        assert_eq!(corner(4 + 2), (0.0, 1.0));
        assert_eq!(mesh.face_point_at(4 + 2, 1.0, 1.0), (1, 0.5, 1.5));
        assert_eq!(corner(7 + 4), (1.0, 1.0));
        assert_eq!(corner(12 + 11), (3.0, 2.0));
        // Outside every sub-face: no patch.
        assert_eq!(mesh.patch_at(1, 0.75, 0.25), None);
        assert_eq!(mesh.patch_at(1, 1.25, 1.25), None);
        assert_eq!(mesh.patch_at(0, 1.5, 0.5), None);
        assert_eq!(mesh.patch_at(9, 0.0, 0.0), None);
    }
}
