//! Uniform tessellation, the peer of every adaptive result: each patch an `N × N` grid
//! of quads split along the `(i, j) → (i+1, j+1)` diagonal, vertices shared by index
//! across patch boundaries, and triangles on a boundary collapsed to a point dropped.
//! For the 32-patch teapot this gives `64 N² − 8 N` triangles (three.js's count).

use glam::Vec3;

use super::model::BezierModel;
use super::prepare::PreparedBezier;
use super::tessellate::{vertex_eval, Tessellation};
use super::topology::{grid_point, GridPoint, SIDE_CORNERS};
use crate::error::{Error, Result};
use crate::gpu_types::VertexRecord;
use crate::mesh::Mesh;

/// Largest segment count accepted (about 2·10⁶ triangles per patch).
pub const MAX_SEGMENTS: u32 = 1024;

/// Every patch of `model` ([`PreparedBezier::new`] of it in `prep`) on a `segments ×
/// segments` grid; an error if `segments` is outside `1..=MAX_SEGMENTS` or the output
/// would be too large.
pub fn tessellate_uniform(
    model: &BezierModel,
    prep: &PreparedBezier,
    segments: u32,
) -> Result<Tessellation> {
    if segments == 0 || segments > MAX_SEGMENTS {
        return Err(Error::Param(format!(
            "segments must be in 1..={MAX_SEGMENTS}, got {segments}"
        )));
    }
    let n = segments;
    let t = &model.topology;
    crate::mesh::check_output_triangles(
        2 * u64::from(n).pow(2) * t.patch_corners.len() as u64,
        &format!("{n} segments per patch side"),
    )?;
    let corners = t.corner_owner.len() as u32;
    // Curve points: N-1 per curve that is not a single point.
    let mut curve_base = Vec::with_capacity(t.curves.len());
    let mut next = corners;
    for c in &t.curves {
        curve_base.push(next);
        if !c.collapsed {
            next += n - 1;
        }
    }
    let interior_base = next;
    let per_patch = (n - 1) * (n - 1);
    let vertex_count = interior_base + per_patch * t.patch_corners.len() as u32;
    let mut records = vec![
        VertexRecord {
            patch: 0,
            u: 0.0,
            v: 0.0
        };
        vertex_count as usize
    ];
    for (id, c) in t.corner_owner.iter().enumerate() {
        records[id] = VertexRecord {
            patch: c.patch,
            u: c.uv[0],
            v: c.uv[1],
        };
    }
    let frac = |k: u32| k as f32 / n as f32;
    for (ci, c) in t.curves.iter().enumerate() {
        if c.collapsed {
            continue;
        }
        for k in 1..n {
            let [u, v] = super::topology::side_uv(c.owner_side as usize, frac(k));
            records[(curve_base[ci] + k - 1) as usize] = VertexRecord {
                patch: c.owner,
                u,
                v,
            };
        }
    }
    let mut indices = Vec::with_capacity(model.patches.len() * 6 * (n * n) as usize);
    let mut grid = vec![0u32; ((n + 1) * (n + 1)) as usize];
    for p in 0..model.patches.len() {
        let id = |i: u32, j: u32| -> u32 {
            match grid_point(i, j, n) {
                GridPoint::Corner(slot) => t.patch_corners[p][slot],
                GridPoint::Side(side, k) => {
                    let s = t.patch_sides[p][side];
                    if t.curves[s.curve as usize].collapsed {
                        return t.patch_corners[p][SIDE_CORNERS[side][0]];
                    }
                    let kk = if s.reversed { n - k } else { k };
                    curve_base[s.curve as usize] + kk - 1
                }
                GridPoint::Interior => {
                    interior_base + per_patch * p as u32 + (j - 1) * (n - 1) + (i - 1)
                }
            }
        };
        for j in 0..=n {
            for i in 0..=n {
                let v = id(i, j);
                grid[(j * (n + 1) + i) as usize] = v;
                if i > 0 && i < n && j > 0 && j < n {
                    records[v as usize] = VertexRecord {
                        patch: p as u32,
                        u: frac(i),
                        v: frac(j),
                    };
                }
            }
        }
        let flip = t.flip[p];
        let mut push = |a: u32, b: u32, c: u32| {
            if a != b && b != c && a != c {
                indices.extend_from_slice(&if flip { [a, c, b] } else { [a, b, c] });
            }
        };
        let g = |i: u32, j: u32| grid[(j * (n + 1) + i) as usize];
        for j in 0..n {
            for i in 0..n {
                push(g(i, j), g(i + 1, j), g(i + 1, j + 1));
                push(g(i, j), g(i + 1, j + 1), g(i, j + 1));
            }
        }
    }
    let cps: Vec<[Vec3; 16]> = (0..prep.layout.patches)
        .map(|p| prep.control_points(p))
        .collect();
    let vertices: Vec<_> = records.iter().map(|r| vertex_eval(prep, &cps, r)).collect();
    let evaluations = vertices.len() as u64;
    Ok(Tessellation {
        mesh: Mesh { vertices, indices },
        evaluations,
        culled_patches: 0,
    })
}
