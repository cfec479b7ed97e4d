//! The input of the Catmull-Clark path: a polygon control mesh and its subdivision options.

use std::path::PathBuf;

use glam::DVec3;

/// How open boundaries are subdivided (OpenSubdiv's `interpolateboundary` tag).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryRule {
    /// Boundary edges are cubic B-spline curves and vertices with one face are sharp
    /// corners (OpenSubdiv `VTX_BOUNDARY_EDGE_AND_CORNER`, Blender's default; tag 1).
    #[default]
    EdgeAndCorner,
    /// Boundary edges are B-spline curves; no vertex is a corner (tag 2).
    EdgeOnly,
}

/// How semi-sharp sharpness decays from one subdivision level to the next (OpenSubdiv's
/// `creasemethod` tag, `Sdc::Options::CreasingMethod`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CreaseMethod {
    /// Every sharpness drops by 1 per level (`normal`, OpenSubdiv's `CREASE_UNIFORM`).
    #[default]
    Normal,
    /// Chaikin's rule: an edge's sharpness is first averaged, ¾ its own and ¼ that of the
    /// other semi-sharp edges at the same end vertex, then drops by 1 (`chaikin`).
    Chaikin,
}

/// Sharpness at or above which an edge or vertex is infinitely sharp (OpenSubdiv's
/// `Sdc::Crease::SHARPNESS_INFINITE`).
pub const SHARPNESS_INFINITE: f32 = 10.0;

/// A polygon control mesh: faces of any size, counter-clockwise seen from the front.
#[derive(Clone, Debug, Default)]
pub struct ControlMesh {
    /// The file it came from (names it in errors).
    pub source: PathBuf,
    /// Control vertex positions, model units.
    pub positions: Vec<DVec3>,
    /// Vertex indices of each face, 0-based.
    pub faces: Vec<Vec<u32>>,
    /// 1-based line of each face in `source` (0 where there is no line, e.g. glTF).
    pub face_lines: Vec<usize>,
    /// Faces tagged `hole`: they shape their neighbours but produce no surface.
    pub holes: Vec<bool>,
    /// How open boundaries are subdivided.
    pub boundary: BoundaryRule,
    /// Sharp edges: the two control vertices (either order) and the sharpness, as
    /// OpenSubdiv reads it (`t crease`): 0 smooth, up to [`SHARPNESS_INFINITE`]
    /// semi-sharp (the edge stays sharp for that many levels, fractions blending), at or
    /// above it infinitely sharp. A later entry for the same edge replaces an earlier one.
    pub creases: Vec<([u32; 2], f32)>,
    /// Sharp vertices (`t corner`): the control vertex and its sharpness, as for edges.
    pub corners: Vec<(u32, f32)>,
    /// How semi-sharp sharpness decays.
    pub crease_method: CreaseMethod,
    /// OpenSubdiv's smooth triangle rule (`t smoothtriangles smooth`,
    /// `Sdc::Options::TRI_SUB_SMOOTH`): the edge points next to triangles weight their
    /// face points more, for rounder triangles.
    pub smooth_triangles: bool,
    /// Things the loader read and ignored (unsupported tags), one line each.
    pub warnings: Vec<String>,
}

impl ControlMesh {
    /// A mesh from positions and faces, with the default boundary rule and no holes.
    pub fn new(positions: Vec<DVec3>, faces: Vec<Vec<u32>>) -> Self {
        let n = faces.len();
        ControlMesh {
            source: PathBuf::from("<memory>"),
            positions,
            faces,
            face_lines: vec![0; n],
            holes: vec![false; n],
            boundary: BoundaryRule::default(),
            creases: Vec::new(),
            corners: Vec::new(),
            crease_method: CreaseMethod::default(),
            smooth_triangles: false,
            warnings: Vec::new(),
        }
    }

    /// Whether any edge or vertex is sharp (a crease or corner of non-zero sharpness).
    pub fn has_creases(&self) -> bool {
        self.creases.iter().any(|c| c.1 > 0.0) || self.corners.iter().any(|c| c.1 > 0.0)
    }

    /// Drops every crease and corner, so that the smooth surface is tessellated, and
    /// says so in [`Self::warnings`], with `why`, when there were any. Boundaries keep
    /// their rule.
    pub fn drop_creases(&mut self, why: &str) {
        if self.has_creases() {
            let sharp_edges = self.creases.iter().filter(|c| c.1 > 0.0).count();
            let sharp_vertices = self.corners.iter().filter(|c| c.1 > 0.0).count();
            self.warnings.push(format!(
                "{}: {sharp_edges} sharp edges and {sharp_vertices} sharp vertices ignored ({why}): the smooth surface is tessellated",
                self.source.display()
            ));
        }
        self.creases.clear();
        self.corners.clear();
    }

    /// Bounds of the vertices that faces use.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.faces.iter().flatten().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| {
                let p = self.positions[v as usize];
                (lo.min(p), hi.max(p))
            },
        )
    }

    /// Diagonal of [`Self::bounds`].
    pub fn bbox_diag(&self) -> f64 {
        let (lo, hi) = self.bounds();
        (hi - lo).length()
    }

    /// Cuts the mesh along its non-manifold edges (edges of three faces or more), as
    /// OpenSubdiv treats them: as sharp edges where each sheet of faces ends. Faces
    /// joined through edges of exactly two faces form a sheet; each sheet gets its own
    /// copy of the vertices on cut edges (the first sheet by face order keeps the
    /// original index), so that each sheet meets the cut as a boundary. Returns the
    /// number of edges cut; a mesh without non-manifold edges is left as it is.
    ///
    /// The sheets' boundary curves along the cut coincide, so the surface does not
    /// open there, where every sheet subdivides each vertex of the cut alike: as a
    /// corner (one face in the sheet, under the edge-and-corner rule) in every sheet,
    /// or as a boundary vertex between the same two cut edges in every sheet. Elsewhere
    /// OpenSubdiv's rules and a sheet's boundary rule differ, and this is an error
    /// naming the vertex. Faces with an index out of range are left to
    /// [`super::PatchMesh::new`] to report.
    pub fn split_non_manifold(&mut self) -> crate::Result<usize> {
        use std::collections::{BTreeMap, HashMap};
        let nv = self.positions.len() as u32;
        if self.faces.iter().flatten().any(|&v| v >= nv) {
            return Ok(0);
        }
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        let mut edge_faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (f, face) in self.faces.iter().enumerate() {
            for k in 0..face.len() {
                let e = key(face[k], face[(k + 1) % face.len()]);
                edge_faces.entry(e).or_default().push(f);
            }
        }
        let cut: Vec<(u32, u32)> = {
            let mut c: Vec<_> = edge_faces
                .iter()
                .filter(|(_, fs)| fs.len() > 2)
                .map(|(e, _)| *e)
                .collect();
            c.sort_unstable();
            c
        };
        if cut.is_empty() {
            return Ok(0);
        }
        // Sheets: faces joined through edges of exactly two faces (union-find).
        let mut parent: Vec<usize> = (0..self.faces.len()).collect();
        fn root(parent: &mut [usize], mut f: usize) -> usize {
            while parent[f] != f {
                parent[f] = parent[parent[f]];
                f = parent[f];
            }
            f
        }
        for fs in edge_faces.values().filter(|fs| fs.len() == 2) {
            let (a, b) = (root(&mut parent, fs[0]), root(&mut parent, fs[1]));
            parent[a.max(b)] = a.min(b);
        }
        let sheet: Vec<usize> = (0..self.faces.len())
            .map(|f| root(&mut parent, f))
            .collect();
        let is_cut = |a: u32, b: u32| cut.binary_search(&key(a, b)).is_ok();
        let mut cut_vertices: Vec<u32> = cut.iter().flat_map(|&(a, b)| [a, b]).collect();
        cut_vertices.sort_unstable();
        cut_vertices.dedup();
        let on_cut = |v: u32| cut_vertices.binary_search(&v).is_ok();
        // How each sheet subdivides each vertex of the cut: as a corner, or as a
        // boundary vertex between two neighbours (its boundary edges in the sheet).
        let mut faces_at: BTreeMap<(u32, usize), usize> = BTreeMap::new();
        let mut boundary_at: BTreeMap<(u32, usize), Vec<u32>> = BTreeMap::new();
        for (f, face) in self.faces.iter().enumerate() {
            let n = face.len();
            for k in 0..n {
                let v = face[k];
                if !on_cut(v) {
                    continue;
                }
                *faces_at.entry((v, sheet[f])).or_default() += 1;
                for w in [face[(k + 1) % n], face[(k + n - 1) % n]] {
                    // An edge is a boundary of sheet s where only one face of s uses it.
                    let in_sheet = edge_faces[&key(v, w)]
                        .iter()
                        .filter(|&&g| sheet[g] == sheet[f])
                        .count();
                    if in_sheet == 1 {
                        boundary_at.entry((v, sheet[f])).or_default().push(w);
                    }
                }
            }
        }
        let corners = self.boundary == BoundaryRule::EdgeAndCorner;
        for &v in &cut_vertices {
            let mut modes = faces_at
                .range((v, 0)..=(v, usize::MAX))
                .map(|(&(_, s), &n)| {
                    if corners && n == 1 {
                        None
                    } else {
                        let mut b = boundary_at.get(&(v, s)).cloned().unwrap_or_default();
                        b.sort_unstable();
                        b.dedup();
                        Some(b)
                    }
                });
            let first = modes.next().flatten();
            let agree = modes.all(|m| m == first)
                && first
                    .as_ref()
                    .is_none_or(|b| b.len() == 2 && b.iter().all(|&w| is_cut(v, w)));
            if !agree {
                return Err(crate::Error::input(
                    &self.source,
                    format!(
                        "non-manifold edges at vertex {}: its sheets of faces would subdivide it differently (a corner in some, a boundary vertex in others, or with other neighbours), so they would not meet there",
                        v + 1
                    ),
                ));
            }
        }
        // One copy of each cut vertex per sheet.
        let mut copies: HashMap<(u32, usize), u32> = HashMap::new();
        let mut kept: HashMap<u32, usize> = HashMap::new();
        let positions = &mut self.positions;
        for (face, &s) in self.faces.iter_mut().zip(&sheet) {
            for v in face.iter_mut() {
                if !on_cut(*v) {
                    continue;
                }
                let owner = *kept.entry(*v).or_insert(s);
                if owner == s {
                    continue;
                }
                let original = *v;
                *v = *copies.entry((original, s)).or_insert_with(|| {
                    positions.push(positions[original as usize]);
                    positions.len() as u32 - 1
                });
            }
        }
        Ok(cut.len())
    }
}
