//! The patches as the GPU reads them: every patch's quadtree flattened into a few
//! arrays of [`gpu_types`](crate::gpu_types) structs, in single precision, uploaded once.
//! When only the control points move, [`CcGpuModel::new`] on the moved mesh gives arrays
//! of the same shape to re-upload.
//!
//! [`vertex_eval`] is the CPU twin of the kernel `shaders/cc_vertex_eval.wgsl` (and of
//! `cc_eval` in `shaders/shared/cc_patch.wgsl`): it reads the same arrays the same way.
//! [`leaf_items`] is the twin of `shaders/cc_leaf_keys.wgsl`, with the homes
//! ([`point_homes`]) that make every chart's copy of a point evaluate the same.

use glam::Vec3;

use super::gpu_uniform::{grid_place, GridPlace};
use super::keys::{face_corner, seam, topo_chart_key, topo_face_uv};
use super::patch::SurfaceModel;
use super::polygon::cell_corner;
use super::stencil::CcStencils;
use super::topology::PatchMesh;
use super::vertex_hash::split_key;
use crate::gpu_types::{
    CcCell, CcCorner, CcNode, CcPatchTopo, CcPoint, CcRoot, CcVertexPoint, GpuPatch, OutVertex,
    CC_CELL_FACE, CC_CHOSEN_FACE_LEAF, CC_NODE_BEZIER, CC_NODE_KIND_MASK, CC_NODE_SPLIT,
    CC_NO_HOME, CC_NO_KEY, CC_NO_NEIGHBOUR, CC_PARAM_ONE,
};

/// Flattened quadtrees of all patches.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CcGpuModel {
    /// Per patch, its root node ([`CC_NO_ROOT`](crate::gpu_types::CC_NO_ROOT) for a
    /// hole) and first net and corner (binding 20).
    pub roots: Vec<CcRoot>,
    /// The nodes, shared by patches alike (binding 21): a net's or corner's index counts
    /// from its patch's first.
    pub nodes: Vec<CcNode>,
    /// Children of split nodes, in quadrant order `[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`.
    pub splits: Vec<[u32; 4]>,
    /// Bézier nets, row-major `b[4j + i]` (`i` along u), `x y z` per point; point 0 is
    /// absolute, points 1..16 are offsets from it, so that the tiny pieces next to an
    /// extraordinary vertex keep their shape (and normals) in single precision.
    pub nets: Vec<GpuPatch>,
    /// Corner nodes and the balls of split nodes on a chain at an extraordinary vertex
    /// (binding 24).
    pub corners: Vec<CcCorner>,
}

impl CcGpuModel {
    /// The quadtrees of `model`'s patches as the GPU stage derives them from the control
    /// points ([`CcStencils`]: its tables, applied by the kernels' CPU twins); holes get
    /// [`CC_NO_ROOT`](crate::gpu_types::CC_NO_ROOT) and no nodes.
    pub fn new(model: &SurfaceModel) -> Self {
        let control = model.mesh.control_points_f32();
        CcStencils::new(&model.mesh, model.depth).model(&control)
    }

    /// Bytes of the arrays, as a stage that uploads them does.
    pub fn byte_size(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.roots.as_slice())
            + size_of_val(self.nodes.as_slice())
            + size_of_val(self.splits.as_slice())
            + size_of_val(self.nets.as_slice())
            + size_of_val(self.corners.as_slice())
    }
}

/// A parameter in `[0, 1]` as fixed point ([`CC_PARAM_ONE`]), rounded to nearest.
pub fn fixed_param(t: f64) -> u32 {
    (t.clamp(0.0, 1.0) * CC_PARAM_ONE as f64).round() as u32
}

fn bernstein(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

fn bernstein_d(t: f32) -> [f32; 4] {
    let s = 1.0 - t;
    [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * s * t,
        6.0 * s * t - 3.0 * t * t,
        3.0 * t * t,
    ]
}

/// Position and first derivatives of a net at local `(u, v)`: the offsets' Bézier sum
/// (the first offset is zero), then the origin added.
fn net_eval(net: &GpuPatch, u: f32, v: f32) -> (Vec3, Vec3, Vec3) {
    let (bu, bv, du, dv) = (bernstein(u), bernstein(v), bernstein_d(u), bernstein_d(v));
    let (mut p, mut pu, mut pv) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let k = 3 * (4 * j + i);
            if k == 0 {
                continue;
            }
            let c = Vec3::new(net.cp[k], net.cp[k + 1], net.cp[k + 2]);
            p += (bu[i] * bv[j]) * c;
            pu += (du[i] * bv[j]) * c;
            pv += (bu[i] * dv[j]) * c;
        }
    }
    (Vec3::new(net.cp[0], net.cp[1], net.cp[2]) + p, pu, pv)
}

/// Position and unit normal on a net; where the derivatives are parallel (a collapsed
/// edge) the normal is taken a little inside, as the double-precision evaluator does.
fn net_point(net: &GpuPatch, u: f32, v: f32) -> (Vec3, Vec3) {
    let (p, pu, pv) = net_eval(net, u, v);
    let mut n = pu.cross(pv);
    if n.length_squared() <= 1e-12 * pu.length_squared() * pv.length_squared() {
        let (_, qu, qv) = net_eval(net, u + (0.5 - u) * 1e-4, v + (0.5 - v) * 1e-4);
        n = qu.cross(qv);
    }
    (p, n.normalize_or_zero())
}

/// Twin of `cc_eval` (shaders/shared/cc_patch.wgsl): position and unit normal of a
/// point, walking the quadtree in fixed point. A point strictly inside the innermost
/// square at an extraordinary vertex gets the vertex (the stored depth puts every point
/// of the tessellators' grids outside it; see [`super::TREE_DEPTH`]).
pub fn cc_eval(model: &CcGpuModel, point: CcPoint) -> (Vec3, Vec3) {
    let root = model.roots[point.patch_id as usize];
    let (nets, corners) = (root.nets, root.corners);
    let mut nd = model.nodes[root.node as usize];
    let (mut x, mut y, mut size) = (point.u, point.v, CC_PARAM_ONE);
    // Down to the node holding the point, then one evaluation (as the kernel: there an
    // evaluation inside the loop would run on every level).
    while nd.kind & CC_NODE_KIND_MASK == CC_NODE_SPLIT {
        // Past 2^-31 (the chains at extraordinary vertices) the point is a corner of
        // the node and stays that corner of the child.
        let half = size >> 1;
        let (right, top) = if size == 1 {
            (x >= 1, y >= 1)
        } else {
            (x >= half, y >= half)
        };
        let c = match (right, top) {
            (false, false) => 0,
            (true, false) => 1,
            (true, true) => 2,
            (false, true) => 3,
        };
        if size > 1 {
            if right {
                x -= half;
            }
            if top {
                y -= half;
            }
            size = half;
        }
        nd = model.nodes[model.splits[nd.index as usize][c] as usize];
    }
    if nd.kind & CC_NODE_KIND_MASK == CC_NODE_BEZIER {
        let (u, v) = (x as f32 / size as f32, y as f32 / size as f32);
        return net_point(&model.nets[(nets + nd.index) as usize], u, v);
    }
    let c = model.corners[(corners + nd.index) as usize];
    (Vec3::from(c.limit), Vec3::from(c.normal))
}

/// Twin of the kernel `cc_vertex_eval`: one output vertex per point, evaluated at its
/// home, carrying its face and face `(u, v)`.
pub fn vertex_eval(model: &CcGpuModel, points: &[CcVertexPoint]) -> Vec<OutVertex> {
    points
        .iter()
        .map(|point| {
            let at = CcPoint {
                patch_id: point.patch_id,
                u: point.u,
                v: point.v,
            };
            let (p, n) = cc_eval(model, at);
            OutVertex {
                position: p.to_array(),
                normal: n.to_array(),
                uv: [point.face_u, point.face_v],
                face: point.face,
            }
        })
        .collect()
}

/// Where the points of each level-1 point and edge are evaluated, whichever chart's
/// vertex they are: per level-1 point, then per level-1 edge, the smallest surface patch
/// touching it, `patch << 3 | reversed << 2 | k` (`k` the point's corner or the edge's
/// index in that patch, `reversed` whether the patch runs the edge from its larger end
/// point); [`CC_NO_HOME`] where no surface patch touches it. One evaluation per key
/// rather than per copy would need the copies to find each other; evaluating every copy
/// at one home gives them the same bits.
pub fn point_homes(mesh: &PatchMesh) -> Vec<u32> {
    let points = mesh.points.len();
    let mut homes = vec![CC_NO_HOME; points + mesh.edge_uses.len()];
    for p in mesh.surface_patches() {
        let quad = mesh.quads[p];
        for k in 0..4 {
            let home = &mut homes[quad[k] as usize];
            if *home == CC_NO_HOME {
                *home = (p as u32) << 3 | k as u32;
            }
            let reversed = u32::from(quad[k] > quad[(k + 1) % 4]);
            let home = &mut homes[points + mesh.quad_edges[p][k] as usize];
            if *home == CC_NO_HOME {
                *home = (p as u32) << 3 | reversed << 2 | k as u32;
            }
        }
    }
    homes
}

/// Grid point `(i, j)/n` at distance `t` from corner `k` along edge `k` (the inverse of
/// [`grid_place`] on an edge; twin of `cc_edge_point`).
pub fn edge_point(k: usize, t: u32, n: u32) -> (u32, u32) {
    match k {
        0 => (t, 0),
        1 => (n, t),
        2 => (n - t, n),
        _ => (0, n - t),
    }
}

/// The grid point `(patch, i, j)` of a level-1 point's home (twin of `cc_corner_home`).
pub fn corner_home(home: u32, n: u32) -> (u32, u32, u32) {
    let c = home & 3;
    let at = |on: bool| if on { n } else { 0 };
    (home >> 3, at(c == 1 || c == 2), at(c >= 2))
}

/// The grid point `(patch, i, j)` of the point at canonical `t` (from the smaller end
/// point) of a level-1 edge with this home (twin of `cc_edge_home`).
pub fn edge_home(home: u32, t: u32, n: u32) -> (u32, u32, u32) {
    let local = if home & 4 != 0 { n - t } else { t };
    let (i, j) = edge_point((home & 3) as usize, local, n);
    (home >> 3, i, j)
}

/// The home of grid point `(i, j)/n` of patch `p` (twin of `cc_home_point`): where every
/// chart's vertex of that surface point is evaluated.
pub fn home_point(
    topo: &CcPatchTopo,
    homes: &[u32],
    points: u32,
    p: u32,
    (i, j): (u32, u32),
    n: u32,
) -> (u32, u32, u32) {
    match grid_place(i, j, n) {
        GridPlace::Corner(c) => corner_home(homes[topo.quad[c] as usize], n),
        GridPlace::Edge(k, t) => {
            let t = if topo.quad[k] < topo.quad[(k + 1) % 4] {
                t
            } else {
                n - t
            };
            edge_home(homes[(points + topo.edges[k]) as usize], t, n)
        }
        GridPlace::Inside => (p, i, j),
    }
}

/// `i / grid` in fixed point ([`CC_PARAM_ONE`]), rounded to nearest (twin of
/// `cc_grid_fixed`; `grid` is `105 · 2^k`, odd times a power of two, so there are no
/// ties).
pub fn grid_fixed(i: u32, grid: u32) -> u32 {
    ((((i as u64) << 32) + grid as u64) / (2 * grid as u64)) as u32
}

/// Twin of `cc_leaf_keys` for one leaf of patch `cell.patch_id`: its eight hash items,
/// the keys and the vertices they stand for. Items `k < 4` are corner `k` in the leaf's
/// chart; item `4 + k` is the same point in the chart across, where corner `k` lies on a
/// seam edge of the patch (inside the edge: a level-1 point is a corner of a leaf in
/// every chart around it), else [`CC_NO_KEY`]. The polygons of the patch across then
/// find the point in their own chart. A face leaf ([`CC_CELL_FACE`]) has items of its own
/// (`face_items`); `chosen` is the trial each patch chose, as marking leaves it
/// ([`CC_CHOSEN_FACE_LEAF`] on the patches of face leaves).
pub fn leaf_items(
    topo: &[CcPatchTopo],
    homes: &[u32],
    points: u32,
    grid: u32,
    chosen: &[u32],
    cell: &CcCell,
) -> ([[u32; 2]; 8], [CcVertexPoint; 8]) {
    let p = cell.patch_id;
    let t = &topo[p as usize];
    let mut keys = [CC_NO_KEY; 8];
    let mut out = [CcVertexPoint::default(); 8];
    if cell.trial_depth & CC_CELL_FACE != 0 {
        return face_items(topo, homes, points, grid, chosen, p);
    }
    for k in 0..4 {
        let (i, j) = cell_corner(grid, cell, k as u32);
        let home = home_point(t, homes, points, p, (i, j), grid);
        keys[k] = split_key(topo_chart_key(t, p as usize, i, j, grid));
        out[k] = vertex_point(home, t, (i, j), grid);
        if let GridPlace::Edge(e, local) = grid_place(i, j, grid) {
            let across = t.across[e];
            if seam(t.face_corner, e) && across != CC_NO_NEIGHBOUR {
                let (q, eq) = (across >> 2, (across & 3) as usize);
                // The patch across runs the edge the other way.
                let (qi, qj) = edge_point(eq, grid - local, grid);
                let tq = &topo[q as usize];
                keys[4 + k] = split_key(topo_chart_key(tq, q as usize, qi, qj, grid));
                out[4 + k] = vertex_point(home, tq, (qi, qj), grid);
            }
        }
    }
    (keys, out)
}

/// The vertex of grid point `q` of the patch with topology `t` (its face and face
/// coordinates), evaluated at `home` (`vertex_point` in `cc_leaf_keys`).
fn vertex_point(home: (u32, u32, u32), t: &CcPatchTopo, q: (u32, u32), grid: u32) -> CcVertexPoint {
    let (face, uv) = topo_face_uv(t, q.0, q.1, grid);
    CcVertexPoint {
        patch_id: home.0,
        u: grid_fixed(home.1, grid),
        v: grid_fixed(home.2, grid),
        face,
        face_u: uv[0],
        face_v: uv[1],
    }
}

/// Twin of `face_items` in `cc_leaf_keys`: a face leaf of the quad face whose first patch
/// is `first`. Item `k` is vertex `k` (corner `(0, 0)` of patch `first + k`), item
/// `4 + k` the level-1 edge point at the end of that patch's side `v = 0` (its corner
/// `(n, 0)`), in its chart, where the face across is not a face leaf too, else
/// [`CC_NO_KEY`].
fn face_items(
    topo: &[CcPatchTopo],
    homes: &[u32],
    points: u32,
    grid: u32,
    chosen: &[u32],
    first: u32,
) -> ([[u32; 2]; 8], [CcVertexPoint; 8]) {
    let mut keys = [CC_NO_KEY; 8];
    let mut out = [CcVertexPoint::default(); 8];
    for k in 0..4 {
        let p = first + k as u32;
        let t = &topo[p as usize];
        let across = t.across[0];
        let needed =
            across != CC_NO_NEIGHBOUR && chosen[(across >> 2) as usize] & CC_CHOSEN_FACE_LEAF == 0;
        let corner = (0, 0);
        keys[k] = split_key(topo_chart_key(t, p as usize, 0, 0, grid));
        out[k] = vertex_point(
            home_point(t, homes, points, p, corner, grid),
            t,
            corner,
            grid,
        );
        if needed {
            let edge = (grid, 0);
            keys[4 + k] = split_key(topo_chart_key(t, p as usize, grid, 0, grid));
            out[4 + k] = vertex_point(home_point(t, homes, points, p, edge, grid), t, edge, grid);
        }
    }
    (keys, out)
}

/// Per patch: its level-1 points and edges, and the patch (and its edge) across each
/// edge; [`CC_NO_NEIGHBOUR`] on an open boundary or where the patch across is a hole,
/// which has no points to contribute.
pub fn patch_topology(mesh: &PatchMesh) -> Vec<CcPatchTopo> {
    let mut uses: Vec<Vec<u32>> = vec![Vec::new(); mesh.edge_uses.len()];
    for (p, edges) in mesh.quad_edges.iter().enumerate() {
        for (k, &e) in edges.iter().enumerate() {
            uses[e as usize].push((p as u32) << 2 | k as u32);
        }
    }
    (0..mesh.patch_count())
        .map(|p| {
            let across = std::array::from_fn(|k| {
                let me = (p as u32) << 2 | k as u32;
                uses[mesh.quad_edges[p][k] as usize]
                    .iter()
                    .copied()
                    .find(|&u| u != me && !mesh.hole[(u >> 2) as usize])
                    .unwrap_or(CC_NO_NEIGHBOUR)
            });
            CcPatchTopo {
                quad: mesh.quads[p],
                edges: mesh.quad_edges[p],
                across,
                face: mesh.face_of[p].0,
                face_corner: face_corner(mesh, p),
                pad: [0; 2],
            }
        })
        .collect()
}
