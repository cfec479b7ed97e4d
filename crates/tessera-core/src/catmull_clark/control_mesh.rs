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

/// A polygon control mesh: faces of any size, counter-clockwise seen from the front.
#[derive(Clone, Debug, Default)]
pub struct ControlMesh {
    /// The file it came from (names it in errors).
    pub source: PathBuf,
    pub positions: Vec<DVec3>,
    /// Vertex indices of each face, 0-based.
    pub faces: Vec<Vec<u32>>,
    /// 1-based line of each face in `source` (0 where there is no line, e.g. glTF).
    pub face_lines: Vec<usize>,
    /// Faces tagged `hole`: they shape their neighbours but produce no surface.
    pub holes: Vec<bool>,
    pub boundary: BoundaryRule,
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
            warnings: Vec::new(),
        }
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
}
