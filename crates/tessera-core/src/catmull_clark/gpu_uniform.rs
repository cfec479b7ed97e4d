//! Uniform tessellation as the GPU computes it: every surface patch sampled on an
//! `n × n` grid, one vertex per distinct surface point, each evaluated once. CPU twin of
//! `shaders/cc_uniform_points.wgsl` ([`uniform_point`]) and
//! `shaders/cc_uniform_cells.wgsl` ([`uniform_cell`]); the evaluation between them is
//! [`gpu_model::vertex_eval`](super::gpu_model::vertex_eval) (`cc_vertex_eval.wgsl`).
//!
//! No hash is needed: with one `n` everywhere, the numbering of the shared points follows
//! from the topology, fixed once per model by [`uniform_patches`]:
//! `[corners (a level-1 point in a chart)] [edge points: n - 1 per level-1 edge and side
//! of a seam] [interior points: (n - 1)² per patch]`, one vertex per point and chart as
//! in [`chart_key`](super::keys::chart_key). A point on an edge is numbered by `t`, its
//! distance in `1/n` from the edge's smaller end point (as in
//! [`point_key`](super::keys::point_key)), so both patches agree; the first patch of a
//! chart touching a corner or an edge writes its vertex, evaluated at the point's home
//! ([`point_homes`]) so that every chart's copy gets the same bits. The mesh is
//! [`tessellate_uniform`](super::tessellate_uniform)'s up to vertex order.

use std::collections::HashMap;

use bytemuck::Zeroable;
use glam::Vec3;

use super::gpu_model::{corner_home, edge_home, point_homes, vertex_eval, CcGpuModel};
use super::keys::{chart_of, face_corner, face_uv, seam};
use super::topology::{face_coords, PatchMesh};
use super::triangulate::DIAGONAL_MARGIN;
use super::uniform::MAX_SEGMENTS;
use crate::error::{Error, Result};
use crate::gpu_types::{CcUniformParams, CcUniformPatch, CcVertexPoint, OutVertex, CC_PARAM_ONE};
use crate::mesh::Mesh;

/// Flag bit of [`CcUniformPatch::flags`]: this patch writes the vertex of its corner `k`.
pub const OWNS_CORNER: u32 = 1;
/// Flag bit: this patch writes the vertices of its edge `k`.
pub const OWNS_EDGE: u32 = 1 << 4;
/// Flag bit: edge `k` runs from its larger end point (its `t` counts from corner `k + 1`).
pub const EDGE_REVERSED: u32 = 1 << 8;

/// The uniform kernels' view of a model: per surface patch (holes left out) where its
/// vertices are numbered, and the counts of corner and edge vertices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UniformLayout {
    /// The surface patches, in patch order (binding 71).
    pub patches: Vec<CcUniformPatch>,
    /// Distinct corner vertices: (level-1 point, chart) pairs of the surface patches.
    pub corners: u32,
    /// Distinct edge vertex rows: (level-1 edge, side of a seam) pairs.
    pub edges: u32,
}

/// Numbers the corner and edge vertices of the surface patches (a point in a chart,
/// [`chart_key`](super::keys::chart_key)), in order of first use, and gives each to the
/// first patch that touches it.
pub fn uniform_patches(mesh: &PatchMesh) -> UniformLayout {
    let homes = point_homes(mesh);
    let points = mesh.points.len();
    let mut corner_id: HashMap<(u32, u32), u32> = HashMap::new();
    let mut edge_id: HashMap<(u32, bool), u32> = HashMap::new();
    let patches = mesh
        .surface_patches()
        .map(|p| {
            let quad = mesh.quads[p];
            let word = face_corner(mesh, p);
            let chart = chart_of(word, p);
            let mut flags = 0;
            let (mut corners, mut edges) = ([0; 4], [0; 4]);
            for k in 0..4 {
                let next = corner_id.len() as u32;
                corners[k] = *corner_id.entry((quad[k], chart)).or_insert(next);
                if corners[k] == next {
                    flags |= OWNS_CORNER << k;
                }
                let forward = quad[k] < quad[(k + 1) % 4];
                let side = seam(word, k) && forward;
                let next = edge_id.len() as u32;
                edges[k] = *edge_id.entry((mesh.quad_edges[p][k], side)).or_insert(next);
                if edges[k] == next {
                    flags |= OWNS_EDGE << k;
                }
                if !forward {
                    flags |= EDGE_REVERSED << k;
                }
            }
            CcUniformPatch {
                patch_id: p as u32,
                corners,
                edges,
                flags,
                face: mesh.face_of[p].0,
                face_corner: word,
                corner_homes: quad.map(|q| homes[q as usize]),
                edge_homes: mesh.quad_edges[p].map(|e| homes[points + e as usize]),
            }
        })
        .collect();
    UniformLayout {
        patches,
        corners: corner_id.len() as u32,
        edges: edge_id.len() as u32,
    }
}

impl UniformLayout {
    /// The kernels' parameters for `n` segments per patch side; an error if `n` is out
    /// of range or the output would not fit 32-bit indices.
    pub fn params(&self, n: u32) -> Result<CcUniformParams> {
        if n == 0 || n > MAX_SEGMENTS {
            return Err(Error::Param(format!(
                "segments per patch side must be in 1..={MAX_SEGMENTS}, got {n}"
            )));
        }
        crate::mesh::check_output_triangles(
            2 * u64::from(n).pow(2) * self.patches.len() as u64,
            &format!("{n} segments per patch side"),
        )?;
        let params = CcUniformParams {
            segments: n,
            patch_count: self.patches.len() as u32,
            corner_count: self.corners,
            edge_count: self.edges,
        };
        let too_big = params.vertex_count_u64() > u32::MAX as u64
            || params.index_count_u64() > u32::MAX as u64
            || params.patch_count as u64 * (n as u64 + 1).pow(2) > u32::MAX as u64;
        if too_big {
            return Err(Error::Param(format!(
                "{n} segments per patch side make more than 2^32 vertices or indices"
            )));
        }
        Ok(params)
    }
}

impl CcUniformParams {
    fn vertex_count_u64(&self) -> u64 {
        let inner = self.segments as u64 - 1;
        self.corner_count as u64
            + self.edge_count as u64 * inner
            + self.patch_count as u64 * inner * inner
    }

    fn index_count_u64(&self) -> u64 {
        6 * self.patch_count as u64 * (self.segments as u64).pow(2)
    }

    /// Output vertices (checked to fit by [`UniformLayout::params`]).
    pub fn vertex_count(&self) -> u32 {
        self.vertex_count_u64() as u32
    }

    /// Output indices, six per grid cell.
    pub fn index_count(&self) -> u32 {
        self.index_count_u64() as u32
    }
}

/// `i / n` in fixed point (`1 = 2^31`), rounded down, in 32-bit arithmetic as the kernel
/// does it: `i · ⌊2^31 / n⌋ + ⌊i · (2^31 mod n) / n⌋`.
pub fn grid_param(i: u32, n: u32) -> u32 {
    let (q, r) = (CC_PARAM_ONE / n, CC_PARAM_ONE % n);
    i * q + i * r / n
}

/// Where grid point `(i, j)` of a patch is: corner `k`, point `t` (from corner `k`) of
/// edge `k`, or inside.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridPlace {
    /// Corner `k` (0..4, at `(0,0), (1,0), (1,1), (0,1)`).
    Corner(usize),
    /// Edge `k` and the point's distance `t` from corner `k`, in `1..n`.
    Edge(usize, u32),
    /// Strictly inside the patch.
    Inside,
}

/// Twin of `grid_place` in `cc_uniform_points.wgsl`.
pub fn grid_place(i: u32, j: u32, n: u32) -> GridPlace {
    match (i, j) {
        (0, 0) => GridPlace::Corner(0),
        (i, 0) if i == n => GridPlace::Corner(1),
        (i, j) if i == n && j == n => GridPlace::Corner(2),
        (0, j) if j == n => GridPlace::Corner(3),
        (i, 0) => GridPlace::Edge(0, i),
        (i, j) if i == n => GridPlace::Edge(1, j),
        (i, j) if j == n => GridPlace::Edge(2, n - i),
        (_, j) if i == 0 => GridPlace::Edge(3, n - j),
        _ => GridPlace::Inside,
    }
}

/// The output vertex of grid point `(i, j)` of dense patch `d` (twin of
/// `grid_vertex`), and whether patch `d` evaluates it.
pub fn grid_vertex(
    params: &CcUniformParams,
    patch: &CcUniformPatch,
    d: u32,
    i: u32,
    j: u32,
) -> (u32, bool) {
    let n = params.segments;
    match grid_place(i, j, n) {
        GridPlace::Corner(k) => (patch.corners[k], patch.flags & (OWNS_CORNER << k) != 0),
        GridPlace::Edge(k, t) => {
            let t = if patch.flags & (EDGE_REVERSED << k) != 0 {
                n - t
            } else {
                t
            };
            let index = params.corner_count + patch.edges[k] * (n - 1) + t - 1;
            (index, patch.flags & (OWNS_EDGE << k) != 0)
        }
        GridPlace::Inside => {
            let first = params.corner_count + params.edge_count * (n - 1);
            let index = first + (d * (n - 1) + j - 1) * (n - 1) + i - 1;
            (index, true)
        }
    }
}

/// Twin of `cc_uniform_points.wgsl`, one work item per grid point `g` of
/// `patch_count · (n + 1)²`: the vertex to write (its point's home, its face and face
/// `(u, v)`) and where it goes, if this patch owns it.
pub fn uniform_point(
    params: &CcUniformParams,
    patches: &[CcUniformPatch],
    g: u32,
) -> Option<(u32, CcVertexPoint)> {
    let n = params.segments;
    let side = n + 1;
    let d = g / (side * side);
    let (i, j) = (g % side, g / side % side);
    let patch = &patches[d as usize];
    let (index, owned) = grid_vertex(params, patch, d, i, j);
    owned.then(|| {
        let (home, hi, hj) = match grid_place(i, j, n) {
            GridPlace::Corner(k) => corner_home(patch.corner_homes[k], n),
            GridPlace::Edge(k, t) => {
                let t = if patch.flags & (EDGE_REVERSED << k) != 0 {
                    n - t
                } else {
                    t
                };
                edge_home(patch.edge_homes[k], t, n)
            }
            GridPlace::Inside => (patch.patch_id, i, j),
        };
        let (k, sides) = (patch.face_corner & 0xff, patch.face_corner >> 8);
        let (s, t) = face_coords(k as u64, sides as u64, i as u64, j as u64, n as u64);
        let [face_u, face_v] = face_uv(s, t, n as u64);
        let point = CcVertexPoint {
            patch_id: home,
            u: grid_param(hi, n),
            v: grid_param(hj, n),
            face: patch.face,
            face_u,
            face_v,
        };
        (index, point)
    })
}

/// The cut of a quad with space corners `c`: as
/// [`triangulate`](super::triangulate::triangulate) cuts a plain quad, along `0–2`
/// unless `1–3` is shorter by more than the margin; counter-clockwise in `(u, v)`.
pub fn quad_triangles(ids: [u32; 4], c: [Vec3; 4]) -> [u32; 6] {
    let d02 = (c[0] - c[2]).length_squared();
    let d13 = (c[1] - c[3]).length_squared();
    let [a, b, cc, d] = ids;
    if d02 <= d13 * (1.0 + DIAGONAL_MARGIN as f32) {
        [a, b, cc, cc, d, a]
    } else {
        [d, a, b, b, cc, d]
    }
}

/// Twin of `cc_uniform_cells.wgsl`, one work item per cell `c` of `patch_count · n²`:
/// its six indices (written from `6 c`), read from the evaluated vertices.
pub fn uniform_cell(
    params: &CcUniformParams,
    patches: &[CcUniformPatch],
    vertices: &[OutVertex],
    c: u32,
) -> [u32; 6] {
    let n = params.segments;
    let d = c / (n * n);
    let (i, j) = (c % n, c / n % n);
    let patch = &patches[d as usize];
    let corner = |a: u32, b: u32| grid_vertex(params, patch, d, a, b).0;
    let ids = [
        corner(i, j),
        corner(i + 1, j),
        corner(i + 1, j + 1),
        corner(i, j + 1),
    ];
    quad_triangles(ids, ids.map(|v| Vec3::from(vertices[v as usize].position)))
}

/// The whole uniform pipeline of the GPU, on the CPU: the points, their evaluation, the
/// cells. Returns the mesh the GPU writes, byte for byte up to the evaluation's rounding.
pub fn tessellate_uniform_gpu_twin(
    model: &CcGpuModel,
    layout: &UniformLayout,
    n: u32,
) -> Result<Mesh> {
    let params = layout.params(n)?;
    let grid_points = params.patch_count * (n + 1) * (n + 1);
    let mut points = vec![CcVertexPoint::zeroed(); params.vertex_count() as usize];
    for g in 0..grid_points {
        if let Some((index, point)) = uniform_point(&params, &layout.patches, g) {
            points[index as usize] = point;
        }
    }
    let vertices = vertex_eval(model, &points);
    let indices = (0..params.patch_count * n * n)
        .flat_map(|c| uniform_cell(&params, &layout.patches, &vertices, c))
        .collect();
    Ok(Mesh { vertices, indices })
}
