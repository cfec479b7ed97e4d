//! What a tessellation's face coordinates claim, checked against the surface: each
//! vertex's `(face, u, v)` ([`OutVertex`](crate::gpu_types::OutVertex)) evaluated through
//! [`SurfaceModel::eval_face`], a path that shares nothing with the tessellators but the
//! patches, must land on the vertex; every triangle must lie in one chart; the copies of
//! a point on a seam must agree bit for bit.

use std::collections::HashMap;

use super::keys::{chart_key, patch_chart, point_key};
use super::patch::SurfaceModel;
use crate::mesh::Mesh;

/// What [`check_faces`] found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FaceReport {
    /// Vertices that triangles use, all checked.
    pub vertices: usize,
    /// The largest distance from a vertex to the surface at its `(face, u, v)`.
    pub max_distance: f64,
    /// Vertices whose `(face, u, v)` is outside the face's domain, on a hole, or not
    /// within a quarter of a grid step of a grid point.
    pub off_grid: usize,
    /// Triangles whose corners are not in one chart (one control face, and for a face
    /// that is not a quad one sub-face).
    pub mixed_triangles: usize,
    /// Two vertices for one point in one chart.
    pub repeated: usize,
    /// Points with a vertex in more than one chart.
    pub seam_points: usize,
    /// Of those, points on a seam inside a control face (between its sub-faces).
    pub inner_seam_points: usize,
    /// Vertices beyond the first of each point: the seam copies.
    pub seam_copies: usize,
    /// Points whose copies differ in a bit of position or normal.
    pub unequal_copies: usize,
}

impl FaceReport {
    /// Within `tol` of the surface everywhere, on the grid, one chart per triangle, one
    /// vertex per point and chart, copies equal.
    pub fn is_consistent(&self, tol: f64) -> bool {
        self.max_distance <= tol
            && self.off_grid == 0
            && self.mixed_triangles == 0
            && self.repeated == 0
            && self.unequal_copies == 0
    }
}

/// Checks `mesh`, a tessellation of `model` whose vertices lie on the grid of `grid`
/// steps per patch side (`n` for the uniform method, [`super::CcParams::grid`] for the
/// adaptive one): each vertex's `(face, u, v)` names a grid point of a patch, from which
/// it is grouped with the other vertices of its point.
pub fn check_faces(model: &SurfaceModel, mesh: &Mesh, grid: u32) -> FaceReport {
    let pm = &model.mesh;
    let mut report = FaceReport::default();
    let mut used = vec![false; mesh.vertices.len()];
    for &i in &mesh.indices {
        used[i as usize] = true;
    }
    // Per vertex: its chart, if it named a grid point.
    let mut chart = vec![None; mesh.vertices.len()];
    let mut by_chart: HashMap<u64, usize> = HashMap::new();
    let mut by_point: HashMap<u64, Vec<usize>> = HashMap::new();
    for (k, v) in mesh.vertices.iter().enumerate() {
        if !used[k] {
            continue;
        }
        report.vertices += 1;
        let (u, w) = (v.uv[0] as f64, v.uv[1] as f64);
        let Some(exact) = model.eval_face(v.face, u, w) else {
            report.off_grid += 1;
            continue;
        };
        let position = glam::DVec3::from(v.position.map(f64::from));
        report.max_distance = report
            .max_distance
            .max((exact.position - position).length());
        let (p, pu, pv) = pm.patch_at(v.face, u, w).expect("eval_face found it");
        let (x, y) = (pu * grid as f64, pv * grid as f64);
        let (i, j) = (x.round(), y.round());
        if (x - i).abs() > 0.25 || (y - j).abs() > 0.25 {
            report.off_grid += 1;
            continue;
        }
        let (i, j) = (i as u32, j as u32);
        chart[k] = Some(patch_chart(pm, p));
        *by_chart.entry(chart_key(pm, p, i, j, grid)).or_default() += 1;
        by_point
            .entry(point_key(pm, p, i, j, grid))
            .or_default()
            .push(k);
    }
    report.repeated = by_chart.values().map(|&c| c - 1).sum();
    for copies in by_point.values() {
        if copies.len() < 2 {
            continue;
        }
        report.seam_points += 1;
        report.seam_copies += copies.len() - 1;
        let first = &mesh.vertices[copies[0]];
        let faces: Vec<u32> = copies.iter().map(|&k| mesh.vertices[k].face).collect();
        if (1..faces.len()).any(|a| faces[..a].contains(&faces[a])) {
            report.inner_seam_points += 1;
        }
        let bits = |v: &crate::gpu_types::OutVertex| {
            (v.position.map(f32::to_bits), v.normal.map(f32::to_bits))
        };
        if copies
            .iter()
            .any(|&k| bits(&mesh.vertices[k]) != bits(first))
        {
            report.unequal_copies += 1;
        }
    }
    for t in mesh.indices.chunks_exact(3) {
        let c = [0, 1, 2].map(|q| chart[t[q] as usize]);
        if c.iter().any(Option::is_none) || c[0] != c[1] || c[1] != c[2] {
            report.mixed_triangles += 1;
        }
    }
    report
}
