//! The patches as the GPU reads them: every patch's quadtree flattened into a few
//! arrays of [`gpu_types`](crate::gpu_types) structs, in single precision, uploaded once.
//! When only the control points move, [`CcGpuModel::new`] on the moved mesh gives arrays
//! of the same shape to re-upload.
//!
//! [`vertex_eval`] is the CPU twin of the kernel `shaders/cc_vertex_eval.wgsl` (and of
//! `cc_eval` in `shaders/shared/cc_patch.wgsl`): it reads the same arrays the same way.

use glam::Vec3;

use super::patch::{Node, SurfaceModel};
use super::topology::PatchMesh;
use crate::gpu_types::{
    CcCorner, CcNode, CcPatchTopo, CcPoint, GpuPatch, OutVertex, CC_NODE_BALL_SHIFT,
    CC_NODE_BEZIER, CC_NODE_CORNER, CC_NODE_KIND_MASK, CC_NODE_SPLIT, CC_NO_NEIGHBOUR, CC_NO_ROOT,
    CC_PARAM_ONE,
};

/// Flattened quadtrees of all patches.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CcGpuModel {
    /// Root node of each patch, [`CC_NO_ROOT`] for a hole.
    pub roots: Vec<u32>,
    /// Every patch's nodes, patch after patch (binding 21).
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
    /// Flattens the quadtrees of `model`; holes get [`CC_NO_ROOT`] and no nodes.
    pub fn new(model: &SurfaceModel) -> Self {
        let mut out = CcGpuModel::default();
        for (p, surface) in model.patches.iter().enumerate() {
            // Holes shape their neighbours (through the quadtrees built from their
            // one-rings) but have no surface of their own.
            if surface.nodes.is_empty() || model.mesh.hole[p] {
                out.roots.push(CC_NO_ROOT);
                continue;
            }
            let base = out.nodes.len() as u32;
            out.roots.push(base);
            for (id, node) in surface.nodes.iter().enumerate() {
                let f = |v: glam::DVec3| v.as_vec3().to_array();
                let gpu = match node {
                    Node::Bezier(net) => {
                        let mut cp = [0f32; 48];
                        cp[0..3].copy_from_slice(&f(net[0]));
                        for k in 1..16 {
                            cp[3 * k..3 * k + 3].copy_from_slice(&f(net[k] - net[0]));
                        }
                        out.nets.push(GpuPatch { cp });
                        CcNode {
                            kind: CC_NODE_BEZIER,
                            index: out.nets.len() as u32 - 1,
                        }
                    }
                    Node::Split(children) => {
                        out.splits.push(children.map(|c| base + c));
                        // A chain node's ball, as a corner record: kind's high bits.
                        let ball = surface.balls[id].map_or(0, |b| {
                            out.corners.push(CcCorner {
                                limit: f(b.limit),
                                corner: 0,
                                normal: [0.0; 3],
                                hull_radius: b.radius as f32,
                            });
                            out.corners.len() as u32
                        });
                        CcNode {
                            kind: CC_NODE_SPLIT | ball << CC_NODE_BALL_SHIFT,
                            index: out.splits.len() as u32 - 1,
                        }
                    }
                    Node::Corner(c) => {
                        out.corners.push(CcCorner {
                            limit: f(c.limit),
                            corner: c.corner as u32,
                            normal: f(c.normal),
                            hull_radius: c.hull_radius as f32,
                        });
                        CcNode {
                            kind: CC_NODE_CORNER,
                            index: out.corners.len() as u32 - 1,
                        }
                    }
                };
                out.nodes.push(gpu);
            }
        }
        out
    }

    /// Bytes uploaded ([`SurfaceModel::upload_bytes`] computes it without building this).
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
    let mut nd = model.nodes[model.roots[point.patch_id as usize] as usize];
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
        return net_point(&model.nets[nd.index as usize], u, v);
    }
    let c = model.corners[nd.index as usize];
    (Vec3::from(c.limit), Vec3::from(c.normal))
}

/// Twin of the kernel `cc_vertex_eval`: one output vertex per point.
pub fn vertex_eval(model: &CcGpuModel, points: &[CcPoint]) -> Vec<OutVertex> {
    points
        .iter()
        .map(|&point| {
            let (p, n) = cc_eval(model, point);
            let one = CC_PARAM_ONE as f32;
            OutVertex {
                position: p.to_array(),
                normal: n.to_array(),
                uv: [point.u as f32 / one, point.v as f32 / one],
                patch: point.patch_id,
            }
        })
        .collect()
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
            }
        })
        .collect()
}
