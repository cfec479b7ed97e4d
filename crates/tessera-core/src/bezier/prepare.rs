//! The CPU stage of the map-based tessellator: everything uploaded once per model.
//!
//! Per patch: its control points, its topology, and the 16×16 signed displacement map
//! from the surface to the coarse tessellation (the patch sampled on the 4×4 grid
//! `u, v ∈ {0, 1/3, 2/3, 1}`, 18 triangles). Coarse vertices and coarse edges are never
//! stored: their ids follow from the patch and curve numbering (see [`CoarseLayout`]).

use glam::DVec3;

use super::model::BezierModel;
use super::patch::eval_frame_f64;
use super::topology::{grid_point, side_uv, GridPoint};
use bytemuck::Zeroable;

use crate::gpu_types::*;

/// How coarse vertices and coarse edges are numbered, globally and without tables.
///
/// Coarse vertices: `[0, corners)` the patch corners; then two per non-collapsed curve
/// (at canonical fractions 1/3, 2/3); then four per patch (the inner grid points).
/// Coarse edges: three per curve (canonical order), then 21 per patch for the edges
/// inside it (6 horizontal, 6 vertical, 9 diagonal).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CoarseLayout {
    /// Patches in the model.
    pub patches: u32,
    /// Boundary curves (shared patch sides).
    pub curves: u32,
    /// Distinct patch corners: the first coarse vertex ids.
    pub corners: u32,
    /// First id of the inner grid points of patch 0.
    pub interior_vertex_base: u32,
    /// Coarse vertices in all: corners, curve points, inner grid points.
    pub coarse_vertices: u32,
    /// Coarse edges in all: `3 · curves + 21 · patches`.
    pub coarse_edges: u32,
    /// Coarse triangles in all: `18 · patches`.
    pub coarse_triangles: u32,
}

/// Everything the tessellation kernels read: the upload.
#[derive(Clone, Debug)]
pub struct PreparedBezier {
    /// How the coarse vertices and edges are numbered.
    pub layout: CoarseLayout,
    /// Control points of each patch, as uploaded (in the [`NetTexture`]).
    pub patches: Vec<GpuPatch>,
    /// Connectivity of each patch (in the [`TopologyTexture`]).
    pub topo: Vec<GpuPatchTopo>,
    /// The displacement maps, in half precision scaled by `map_scale` (see
    /// [`quantize_maps`]): every value is `f16 · map_scale` exactly.
    pub maps: Vec<DisplacementMap>,
    /// The power of two the maps' half-precision values are multiplied by.
    pub map_scale: f32,
    /// The boundary curves (in the [`TopologyTexture`], after the patches).
    pub curves: Vec<GpuCurve>,
    /// Where each corner is evaluated.
    pub corners: Vec<VertexRecord>,
}

impl PreparedBezier {
    /// Builds the coarse tessellation numbering and the displacement maps.
    pub fn new(model: &BezierModel) -> Self {
        let t = &model.topology;
        let corners = t.corner_owner.len() as u32;
        let mut next = corners;
        let mut curves: Vec<GpuCurve> = t
            .curves
            .iter()
            .map(|c| {
                let coarse_vertex = if c.collapsed {
                    // Every point of the curve is its (single) corner.
                    let side = c.owner_side as usize;
                    let slot = super::topology::SIDE_CORNERS[side][0];
                    t.patch_corners[c.owner as usize][slot]
                } else {
                    next += 2;
                    next - 2
                };
                GpuCurve {
                    owner: c.owner,
                    flags: c.owner_side as u32 | (c.collapsed as u32) << 2,
                    coarse_vertex,
                    other: GpuCurve::NO_SIDE,
                }
            })
            .collect();
        for (p, sides) in t.patch_sides.iter().enumerate() {
            for (s, side) in sides.iter().enumerate() {
                let c = &mut curves[side.curve as usize];
                let is_owner = c.owner == p as u32 && c.owner_side() == s;
                if !is_owner && c.other == GpuCurve::NO_SIDE {
                    c.other = (p as u32) << 2 | s as u32;
                }
            }
        }
        let patches = model.patches.len() as u32;
        let layout = CoarseLayout {
            patches,
            curves: curves.len() as u32,
            corners,
            interior_vertex_base: next,
            coarse_vertices: next + patches * INTERIOR_COARSE_VERTICES_PER_PATCH as u32,
            coarse_edges: 3 * curves.len() as u32 + patches * INTERIOR_EDGES_PER_PATCH as u32,
            coarse_triangles: patches * COARSE_TRIANGLES_PER_PATCH as u32,
        };
        let topo = (0..model.patches.len())
            .map(|p| GpuPatchTopo {
                corners: t.patch_corners[p],
                sides: t.patch_sides[p].map(|s| s.curve << 1 | s.reversed as u32),
                flags: t.flip[p] as u32,
            })
            .collect();
        let gpu_patches = model
            .patches
            .iter()
            .map(|p| {
                let mut cp = [0f32; 48];
                for (k, c) in p.cp.iter().enumerate() {
                    cp[3 * k..3 * k + 3].copy_from_slice(&c.to_array());
                }
                GpuPatch { cp }
            })
            .collect();
        let mut maps: Vec<DisplacementMap> = model
            .patches
            .iter()
            .map(|p| displacement_map(&p.cp_f64()))
            .collect();
        let map_scale = quantize_maps(&mut maps);
        let corner_records = t
            .corner_owner
            .iter()
            .map(|c| VertexRecord {
                patch: c.patch,
                u: c.uv[0],
                v: c.uv[1],
            })
            .collect();
        PreparedBezier {
            layout,
            patches: gpu_patches,
            topo,
            maps,
            map_scale,
            curves,
            corners: corner_records,
        }
    }

    /// Bytes this model uploads to the GPU.
    pub fn upload_bytes(&self) -> usize {
        // The GPU stage uploads the evaluation record of every coarse vertex.
        bezier_upload_bytes(
            self.patches.len(),
            self.curves.len(),
            self.layout.coarse_vertices as usize,
        )
    }

    /// Control points of patch `p` as vectors.
    pub fn control_points(&self, p: u32) -> [glam::Vec3; 16] {
        let cp = &self.patches[p as usize].cp;
        std::array::from_fn(|k| glam::Vec3::new(cp[3 * k], cp[3 * k + 1], cp[3 * k + 2]))
    }

    /// Global id of coarse grid point `(i, j)` (`u = i/3`, `v = j/3`) of patch `p`.
    pub fn coarse_vertex(&self, p: u32, i: u32, j: u32) -> u32 {
        let topo = &self.topo[p as usize];
        let n = COARSE_SEGMENTS as u32;
        match grid_point(i, j, n) {
            GridPoint::Corner(slot) => topo.corners[slot],
            GridPoint::Side(side, k) => {
                let curve = &self.curves[topo.side_curve(side) as usize];
                if curve.collapsed() {
                    return curve.coarse_vertex;
                }
                let kk = if topo.side_reversed(side) { n - k } else { k };
                curve.coarse_vertex + kk - 1
            }
            GridPoint::Interior => {
                self.layout.interior_vertex_base
                    + INTERIOR_COARSE_VERTICES_PER_PATCH as u32 * p
                    + (j - 1) * 2
                    + (i - 1)
            }
        }
    }
    /// Where every coarse vertex is evaluated, in id order. Mirrors the three emit
    /// loops of the coarse-vertex kernel: one per corner, per curve, per patch.
    pub fn coarse_vertex_records(&self) -> Vec<VertexRecord> {
        let l = &self.layout;
        let mut out = vec![VertexRecord::zeroed(); l.coarse_vertices as usize];
        out[..self.corners.len()].copy_from_slice(&self.corners);
        for c in self.curves.iter().filter(|c| !c.collapsed()) {
            for k in 0..2 {
                let t = (k + 1) as f32 / COARSE_SEGMENTS as f32;
                let [u, v] = side_uv(c.owner_side(), t);
                out[(c.coarse_vertex + k) as usize] = VertexRecord {
                    patch: c.owner,
                    u,
                    v,
                };
            }
        }
        for p in 0..l.patches {
            for local in 0..INTERIOR_COARSE_VERTICES_PER_PATCH as u32 {
                let id =
                    l.interior_vertex_base + INTERIOR_COARSE_VERTICES_PER_PATCH as u32 * p + local;
                out[id as usize] = VertexRecord {
                    patch: p,
                    u: (local % 2 + 1) as f32 / COARSE_SEGMENTS as f32,
                    v: (local / 2 + 1) as f32 / COARSE_SEGMENTS as f32,
                };
            }
        }
        out
    }
}

/// Rounds every map value to half precision relative to a power-of-two scale, and
/// returns the scale: each value becomes `f16(d / scale) · scale` (zero where that half
/// is subnormal), so the GPU's `rgba16float` atlas holds it exactly and its reads equal
/// the CPU's bit for bit. The scale puts the largest magnitude in [2^13, 2^14), far
/// from the half range's ends whatever the model's units; a value keeps 11 significant
/// bits, a relative error of at most 2^-12 of the largest (about 1e-5 of the model size
/// on the teaset, far under any threshold).
pub fn quantize_maps(maps: &mut [DisplacementMap]) -> f32 {
    let largest = maps
        .iter()
        .flat_map(|m| m.d.iter())
        .fold(0.0f32, |a, d| a.max(d.abs()));
    let scale = if largest > 0.0 && largest.is_finite() {
        2f32.powi(largest.log2().floor() as i32 - 13)
    } else {
        1.0
    };
    for d in maps.iter_mut().flat_map(|m| m.d.iter_mut()) {
        let h = half::f16::from_f32(*d / scale);
        // Subnormal halves (under 2^-27 of the largest value) become zero: the device
        // converts the values when it builds its atlas, and need not keep them. (The
        // maps are finite distances: no infinity or NaN reaches here.)
        let h = if h.is_normal() { h } else { half::f16::ZERO };
        *d = h.to_f32() * scale;
    }
    scale
}

/// Bilinear read of a displacement map at `(u, v)`, clamped to the patch.
/// CPU twin of `map_read` in `shaders/shared/map.wgsl`.
pub fn map_read(map: &DisplacementMap, u: f32, v: f32) -> f32 {
    let last = (MAP_RES - 1) as f32;
    let x = u.clamp(0.0, 1.0) * last;
    let y = v.clamp(0.0, 1.0) * last;
    let i0 = x.floor().min(last - 1.0);
    let j0 = y.floor().min(last - 1.0);
    let (fx, fy) = (x - i0, y - j0);
    let (i0, j0) = (i0 as usize, j0 as usize);
    let at = |i: usize, j: usize| map.d[MAP_RES * j + i];
    let top = at(i0, j0) + (at(i0 + 1, j0) - at(i0, j0)) * fx;
    let bottom = at(i0, j0 + 1) + (at(i0 + 1, j0 + 1) - at(i0, j0 + 1)) * fx;
    top + (bottom - top) * fy
}

/// The coarse triangles of a patch as triples of grid points `(i, j)`, counter-clockwise
/// in `(u, v)`: cell `(i, j)` gives `(i,j) (i+1,j) (i+1,j+1)` and `(i,j) (i+1,j+1) (i,j+1)`.
pub fn coarse_triangle_grid(local: u32) -> [[u32; 2]; 3] {
    let cell = local / 2;
    let (i, j) = (cell % 3, cell / 3);
    if local.is_multiple_of(2) {
        [[i, j], [i + 1, j], [i + 1, j + 1]]
    } else {
        [[i, j], [i + 1, j + 1], [i, j + 1]]
    }
}

/// The 16×16 signed distance map of a patch to its coarse tessellation (paper §2.1):
/// the distance to the plane of the coarse triangle whose normal passes through the
/// surface point; the nearest such triangle where several do; the distance to the
/// nearest coarse edge where none does. A containing triangle farther than the nearest
/// coarse edge (the patch curls round, as the spout does) is not local: the edge wins, so
/// the value is always the distance to the nearest point of the coarse mesh. The sign is that of the side of the
/// counter-clockwise triangle normal (for an edge, of its adjacent triangles' normals).
pub fn displacement_map(cp: &[DVec3; 16]) -> DisplacementMap {
    let n = COARSE_SEGMENTS;
    let grid: Vec<DVec3> = (0..(n + 1) * (n + 1))
        .map(|k| {
            eval_frame_f64(
                cp,
                (k % (n + 1)) as f64 / n as f64,
                (k / (n + 1)) as f64 / n as f64,
            )
            .pos
        })
        .collect();
    let g = |ij: [u32; 2]| ij[1] as usize * (n + 1) + ij[0] as usize;
    let tris: Vec<[usize; 3]> = (0..COARSE_TRIANGLES_PER_PATCH as u32)
        .map(|t| coarse_triangle_grid(t).map(g))
        .collect();
    let normals: Vec<Option<DVec3>> = tris
        .iter()
        .map(|t| {
            let nrm = (grid[t[1]] - grid[t[0]]).cross(grid[t[2]] - grid[t[0]]);
            let len = nrm.length();
            (len > 1e-12 * (1.0 + grid[t[0]].length())).then(|| nrm / len)
        })
        .collect();
    // Unique edges with the summed normals of their triangles.
    let mut edges: Vec<([usize; 2], DVec3)> = Vec::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
            let nrm = normals[t].unwrap_or(DVec3::ZERO);
            match edges.iter_mut().find(|(e, _)| *e == [a, b]) {
                Some((_, acc)) => *acc += nrm,
                None => edges.push(([a, b], nrm)),
            }
        }
    }
    let mut map = DisplacementMap {
        d: [0.0; MAP_RES * MAP_RES],
    };
    for j in 0..MAP_RES {
        for i in 0..MAP_RES {
            let last = (MAP_RES - 1) as f64;
            let s = eval_frame_f64(cp, i as f64 / last, j as f64 / last).pos;
            let mut best: Option<f64> = None;
            for (t, tri) in tris.iter().enumerate() {
                let Some(nrm) = normals[t] else { continue };
                let (a, b, c) = (grid[tri[0]], grid[tri[1]], grid[tri[2]]);
                let dist = (s - a).dot(nrm);
                let q = s - nrm * dist;
                if inside_triangle(q, a, b, c, nrm) && best.is_none_or(|d| dist.abs() < d.abs()) {
                    best = Some(dist);
                }
            }
            let mut nearest_edge = (f64::INFINITY, 1.0);
            for &([a, b], nrm) in &edges {
                let (pa, pb) = (grid[a], grid[b]);
                let ab = pb - pa;
                let t = if ab.length_squared() > 0.0 {
                    ((s - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let off = s - (pa + ab * t);
                if off.length() < nearest_edge.0 {
                    nearest_edge = (off.length(), if off.dot(nrm) < 0.0 { -1.0 } else { 1.0 });
                }
            }
            // A plane that a far-away triangle's normal reaches through is not the
            // surface's neighbourhood: the nearer of plane and edge wins.
            let d = match best {
                Some(d) if d.abs() <= nearest_edge.0 => d,
                _ => nearest_edge.0 * nearest_edge.1,
            };
            map.d[MAP_RES * j + i] = d as f32;
        }
    }
    map
}

/// Whether `q`, in the plane of `abc` with unit normal `n`, lies in the triangle
/// (with a relative tolerance so that points on a shared edge count for both).
fn inside_triangle(q: DVec3, a: DVec3, b: DVec3, c: DVec3, n: DVec3) -> bool {
    let area = (b - a).cross(c - a).dot(n);
    let eps = -1e-9 * area.abs();
    (b - a).cross(q - a).dot(n) >= eps
        && (c - b).cross(q - b).dot(n) >= eps
        && (a - c).cross(q - c).dot(n) >= eps
}
