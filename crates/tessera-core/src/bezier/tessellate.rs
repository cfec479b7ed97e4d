//! The map-based adaptive tessellator as a straight-line script of stages, each the CPU
//! twin of one compute kernel. The wgpu stage records the same stages as dispatches.
//!
//! | stage | kernel | work item |
//! |---|---|---|
//! | [`edge_decide`] | `bezier_edge_decide.wgsl` | coarse edge |
//! | [`exclusive_scan`] | `scan.wgsl` | — |
//! | [`tri_count`] | `bezier_tri_count.wgsl` | coarse triangle |
//! | [`coarse_vertex_records`](PreparedBezier::coarse_vertex_records), [`edge_emit`], [`tri_emit`] | `bezier_*_emit.wgsl` | vertex / edge / triangle |
//! | [`vertex_eval`] | `bezier_vertex_eval.wgsl` | output vertex |

use glam::Vec3;

use super::coarse_edges::{edge_collapsed, edge_endpoints};
use super::edge_tests::{
    bit_count, bit_positions, lerp_uv, subdivide_segment, EdgeBits, EdgeTest, TestInputs,
};
use super::layer_strip::{layer_strip, StripSink, VertexRef};
use super::patch::{eval_frame_f32, frame_normal_f32};
use super::prepare::PreparedBezier;
use crate::error::{Error, Result};
use crate::gpu_types::{OutVertex, VertexRecord, EDGE_BIT_WORDS, MAX_DEPTH_LIMIT};
use crate::mesh::Mesh;

/// Parameters of the adaptive (map or flat) tessellator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveParams {
    pub test: EdgeTest,
    /// `th`: map-distance difference (map tests) or chord deviation (flat), model units.
    pub threshold: f32,
    /// Levels of recursive bisection per coarse edge (at most 2^depth segments).
    pub max_depth: u32,
}

impl AdaptiveParams {
    pub const DEFAULT_MAX_DEPTH: u32 = 6;

    pub fn validate(&self) -> Result<()> {
        if !(self.threshold.is_finite() && self.threshold > 0.0) {
            return Err(Error::Param(format!(
                "threshold must be a positive number, got {}",
                self.threshold
            )));
        }
        if self.max_depth > MAX_DEPTH_LIMIT {
            return Err(Error::Param(format!(
                "max depth {} is beyond the supported {MAX_DEPTH_LIMIT}",
                self.max_depth
            )));
        }
        Ok(())
    }
}

/// A tessellated mesh and what it cost.
#[derive(Clone, Debug, Default)]
pub struct Tessellation {
    pub mesh: Mesh,
    /// Surface evaluations: one per output vertex, plus the flat test's candidates.
    pub evaluations: u64,
}

/// Inputs of the tests on patch `p`.
pub fn test_inputs<'a>(
    prep: &'a PreparedBezier,
    cps: &'a [[Vec3; 16]],
    params: &AdaptiveParams,
    p: u32,
) -> TestInputs<'a> {
    TestInputs {
        test: params.test,
        threshold: params.threshold,
        max_depth: params.max_depth,
        map: &prep.maps[p as usize],
        cp: &cps[p as usize],
    }
}

/// Stage 1, one work item per coarse edge: recursive edge tests on the owner patch.
/// Collapsed edges are never split.
pub fn edge_decide(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    params: &AdaptiveParams,
    e: u32,
) -> (EdgeBits, u32) {
    if edge_collapsed(prep, e) {
        return ([0; EDGE_BIT_WORDS], 0);
    }
    let (p, uv0, uv1) = edge_endpoints(prep, e);
    subdivide_segment(&test_inputs(prep, cps, params, p), uv0, uv1)
}

/// Exclusive prefix sum; returns the total. (On the GPU: `scan.wgsl`.)
pub fn exclusive_scan(values: &mut [u32]) -> u32 {
    let mut sum = 0u32;
    for v in values {
        let x = *v;
        *v = sum;
        sum += x;
    }
    sum
}

#[derive(Default)]
struct CountSink {
    inner_vertices: u32,
    triangles: u32,
    evaluations: u32,
}

impl StripSink for CountSink {
    fn inner_vertex(&mut self, _local: u32, _record: VertexRecord) {
        self.inner_vertices += 1;
    }
    fn triangle(&mut self, _tri: [VertexRef; 3]) {
        self.triangles += 1;
    }
    fn evaluations(&mut self, n: u32) {
        self.evaluations += n;
    }
}

/// Stage 3, one work item per coarse triangle: inner vertices and triangles it makes.
/// Returns `(inner vertices, triangles, evaluations)`.
pub fn tri_count(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    bits: &[EdgeBits],
    params: &AdaptiveParams,
    t: u32,
) -> (u32, u32, u32) {
    let mut sink = CountSink::default();
    let p = t / crate::gpu_types::COARSE_TRIANGLES_PER_PATCH as u32;
    layer_strip(prep, bits, &test_inputs(prep, cps, params, p), t, &mut sink);
    (sink.inner_vertices, sink.triangles, sink.evaluations)
}

/// Where the vertices and indices of one coarse triangle go.
struct EmitSink<'a> {
    records: &'a mut [VertexRecord],
    indices: &'a mut [u32],
    edge_vertex_base: u32,
    edge_offsets: &'a [u32],
    inner_base: u32,
    next_index: usize,
    evaluations: u32,
}

impl EmitSink<'_> {
    fn index(&self, v: VertexRef) -> u32 {
        match v {
            VertexRef::Coarse(id) => id,
            VertexRef::Edge { edge, rank } => {
                self.edge_vertex_base + self.edge_offsets[edge as usize] + rank
            }
            VertexRef::Inner(n) => self.inner_base + n,
        }
    }
}

impl StripSink for EmitSink<'_> {
    fn inner_vertex(&mut self, local: u32, record: VertexRecord) {
        self.records[(self.inner_base + local) as usize] = record;
    }
    fn triangle(&mut self, tri: [VertexRef; 3]) {
        for v in tri {
            self.indices[self.next_index] = self.index(v);
            self.next_index += 1;
        }
    }
    fn evaluations(&mut self, n: u32) {
        self.evaluations += n;
    }
}

/// Stage 5b, one work item per coarse edge: records of its inserted points.
pub fn edge_emit(
    prep: &PreparedBezier,
    bits: &EdgeBits,
    e: u32,
    first: u32,
    records: &mut [VertexRecord],
) {
    let (p, uv0, uv1) = edge_endpoints(prep, e);
    for (rank, k) in bit_positions(bits).enumerate() {
        let [u, v] = lerp_uv(uv0, uv1, k);
        records[first as usize + rank] = VertexRecord { patch: p, u, v };
    }
}

/// Stage 5c, one work item per coarse triangle: inner vertex records and indices.
/// Returns the evaluations its inner tests made.
#[allow(clippy::too_many_arguments)]
pub fn tri_emit(
    prep: &PreparedBezier,
    cps: &[[Vec3; 16]],
    bits: &[EdgeBits],
    params: &AdaptiveParams,
    t: u32,
    edge_vertex_base: u32,
    edge_offsets: &[u32],
    inner_base: u32,
    first_index: u32,
    records: &mut [VertexRecord],
    indices: &mut [u32],
) -> u32 {
    let mut sink = EmitSink {
        records,
        indices,
        edge_vertex_base,
        edge_offsets,
        inner_base,
        next_index: first_index as usize,
        evaluations: 0,
    };
    let p = t / crate::gpu_types::COARSE_TRIANGLES_PER_PATCH as u32;
    layer_strip(prep, bits, &test_inputs(prep, cps, params, p), t, &mut sink);
    sink.evaluations
}

/// Stage 6, one work item per output vertex: position, normal (facing the patch's
/// front after orientation), parameter and patch.
pub fn vertex_eval(prep: &PreparedBezier, cps: &[[Vec3; 16]], r: &VertexRecord) -> OutVertex {
    let f = eval_frame_f32(&cps[r.patch as usize], r.u, r.v);
    let mut n = frame_normal_f32(&f, r.u, r.v);
    if prep.topo[r.patch as usize].flipped() {
        n = -n;
    }
    OutVertex {
        position: f.pos.to_array(),
        normal: n.to_array(),
        uv: [r.u, r.v],
        patch: r.patch,
    }
}

/// Runs the whole pipeline on the CPU.
pub fn tessellate_adaptive(prep: &PreparedBezier, params: &AdaptiveParams) -> Result<Tessellation> {
    params.validate()?;
    let l = prep.layout;
    let cps: Vec<[Vec3; 16]> = (0..l.patches).map(|p| prep.control_points(p)).collect();
    let mut evaluations = 0u64;

    // 1. Edge decisions.
    let mut bits = Vec::with_capacity(l.coarse_edges as usize);
    for e in 0..l.coarse_edges {
        let (b, ev) = edge_decide(prep, &cps, params, e);
        evaluations += ev as u64;
        bits.push(b);
    }
    // 2. Edge vertex offsets.
    let mut edge_offsets: Vec<u32> = bits.iter().map(bit_count).collect();
    let edge_vertices = exclusive_scan(&mut edge_offsets);
    // 3. Per-triangle counts, 4. their offsets.
    let mut inner_offsets = Vec::with_capacity(l.coarse_triangles as usize);
    let mut tri_offsets = Vec::with_capacity(l.coarse_triangles as usize);
    for t in 0..l.coarse_triangles {
        let (nv, nt, ev) = tri_count(prep, &cps, &bits, params, t);
        inner_offsets.push(nv);
        tri_offsets.push(nt);
        evaluations += ev as u64;
    }
    let inner_vertices = exclusive_scan(&mut inner_offsets);
    let triangles = exclusive_scan(&mut tri_offsets);
    let edge_vertex_base = l.coarse_vertices;
    let inner_vertex_base = edge_vertex_base + edge_vertices;
    let vertex_count = inner_vertex_base + inner_vertices;

    // 5. Emit vertex records and indices.
    let mut records = prep.coarse_vertex_records();
    records.resize(
        vertex_count as usize,
        VertexRecord {
            patch: 0,
            u: 0.0,
            v: 0.0,
        },
    );
    for e in 0..l.coarse_edges {
        edge_emit(
            prep,
            &bits[e as usize],
            e,
            edge_vertex_base + edge_offsets[e as usize],
            &mut records,
        );
    }
    let mut indices = vec![0u32; 3 * triangles as usize];
    for t in 0..l.coarse_triangles {
        evaluations += tri_emit(
            prep,
            &cps,
            &bits,
            params,
            t,
            edge_vertex_base,
            &edge_offsets,
            inner_vertex_base + inner_offsets[t as usize],
            3 * tri_offsets[t as usize],
            &mut records,
            &mut indices,
        ) as u64;
    }
    // 6. Evaluate each vertex once.
    let vertices: Vec<OutVertex> = records.iter().map(|r| vertex_eval(prep, &cps, r)).collect();
    evaluations += vertices.len() as u64;
    Ok(Tessellation {
        mesh: Mesh { vertices, indices },
        evaluations,
    })
}
