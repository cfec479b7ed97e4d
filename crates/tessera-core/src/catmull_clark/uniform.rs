//! The peer of the adaptive method: the limit surface sampled on an `n × n` grid per
//! patch (any `n`, not only powers of two), two triangles per cell split along the
//! shorter diagonal, vertices shared across patch edges through the canonical keys
//! inside a chart, copied (one evaluation) across chart seams ([`super::keys`]).

use rustc_hash::FxHashMap as HashMap;

use glam::DVec3;

use super::adaptive::{out_vertex, CcTessellation};
use super::keys::{chart_key, point_of, vertex_face_uv};
use super::patch::{SurfaceModel, SurfacePoint};
use super::triangulate::{triangulate, PolyVertex};
use crate::error::{Error, Result};

/// The largest grid accepted (keys hold 15 bits per coordinate).
pub const MAX_SEGMENTS: u32 = 1 << 12;

/// Uniform tessellation with `n` segments per patch side (`n = 2^L` is "level L").
pub fn tessellate_uniform(model: &SurfaceModel, n: u32) -> Result<CcTessellation> {
    if n == 0 || n > MAX_SEGMENTS {
        return Err(Error::Param(format!(
            "segments per patch side must be in 1..={MAX_SEGMENTS}, got {n}"
        )));
    }
    let mesh = &model.mesh;
    crate::mesh::check_output_triangles(
        2 * u64::from(n).pow(2) * mesh.surface_patches().count() as u64,
        &format!("{n} segments per patch side"),
    )?;
    // Vertex ids by chart key; surface points by point key.
    let mut keys: HashMap<u64, u32> = HashMap::default();
    let mut points: HashMap<u64, SurfacePoint> = HashMap::default();
    let mut out = CcTessellation::default();
    let mut grid = vec![0u32; ((n + 1) * (n + 1)) as usize];
    for p in mesh.surface_patches() {
        for j in 0..=n {
            for i in 0..=n {
                let key = chart_key(mesh, p, i, j, n);
                let vertices = &mut out.mesh.vertices;
                let id = *keys.entry(key).or_insert_with(|| {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let sp = *points
                        .entry(point_of(key))
                        .or_insert_with(|| model.eval(p, u, v));
                    let (face, uv) = vertex_face_uv(mesh, p, i, j, n);
                    vertices.push(out_vertex(sp, face, uv));
                    vertices.len() as u32 - 1
                });
                grid[(j * (n + 1) + i) as usize] = id;
            }
        }
        let vertices = &out.mesh.vertices;
        let position = |id: u32| DVec3::from(vertices[id as usize].position.map(f64::from));
        for j in 0..n {
            for i in 0..n {
                let corner = |a: u32, b: u32| PolyVertex {
                    i: a as i64,
                    j: b as i64,
                    id: grid[(b * (n + 1) + a) as usize],
                };
                let cell = vec![
                    corner(i, j),
                    corner(i + 1, j),
                    corner(i + 1, j + 1),
                    corner(i, j + 1),
                ];
                triangulate(&cell, [0, 1, 2, 3], position, &mut out.mesh.indices);
            }
        }
        out.leaves += (n * n) as usize;
    }
    out.evaluations = points.len() as u64;
    Ok(out)
}
