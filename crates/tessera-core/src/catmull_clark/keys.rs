//! Canonical keys of surface points: the same point reached from any patch that touches
//! it gets the same key, which is how patches see each other's vertices (the paper's
//! "globalization") and how the output shares vertices across patch edges.
//!
//! A point of patch `p` at `(i, j) / n` is
//! - a level-1 vertex when it is a patch corner: `VERTEX | point`;
//! - on a level-1 edge `(a, b)`: `EDGE | edge << 32 | t`, with `t` counted in `1/n`
//!   from the edge's smaller end point, so both patches agree;
//! - otherwise inside the patch: `INTERIOR | p << 40 | i << 20 | j`.
//!
//! Keys of different `n` are never compared. `n < 2^20`, fewer than 2^22 patches.
//!
//! # Charts
//!
//! An output vertex is a point in one **chart**: the control face for a quad, the
//! sub-face (the level-1 patch) for a face of `n ≠ 4` sides, since those sub-faces are
//! separate tiles of the face's parameterisation ([`PatchMesh::face_point`]). A point on
//! a seam between charts has one vertex per chart, each with its own face and `(u, v)`.
//! [`chart_key`] is the point key with its chart: `chart << 32` added to a vertex key
//! (the chart named by its first patch), and for an edge key bit 31 set on the side of
//! the patch that runs the edge from its smaller end point, where the edge is a seam
//! (both sides of an edge inside a quad face are one chart). Interior keys name their
//! patch, hence their chart, already.

use super::gpu_uniform::{grid_place, GridPlace};
use super::topology::{face_coords, PatchMesh};
use crate::gpu_types::CcPatchTopo;

const VERTEX: u64 = 0;
const EDGE: u64 = 1 << 62;
const INTERIOR: u64 = 2 << 62;
/// The bit of an edge key that tells the two charts along a seam apart.
const EDGE_SIDE: u64 = 1 << 31;

/// The key of point `(i, j)/n` of patch `p`.
pub fn point_key(mesh: &PatchMesh, p: usize, i: u32, j: u32, n: u32) -> u64 {
    quad_point_key(mesh.quads[p], mesh.quad_edges[p], p, i, j, n)
}

/// [`point_key`] from the patch's level-1 points and edge ids alone (as the GPU's
/// [`CcPatchTopo`] holds them).
pub fn quad_point_key(quad: [u32; 4], edges: [u32; 4], p: usize, i: u32, j: u32, n: u32) -> u64 {
    key(quad, edges, None, p, i, j, n)
}

/// Patch `p`'s corner in its control face and that face's sides, as one word:
/// `corner | sides << 8` ([`CcPatchTopo::face_corner`]).
pub fn face_corner(mesh: &PatchMesh, p: usize) -> u32 {
    let (face, k) = mesh.face_of[p];
    k as u32 | (mesh.control_faces[face as usize].len() as u32) << 8
}

/// The chart of patch `p` (see the module docs), named by its first patch: the face's
/// first patch for a quad, `p` itself otherwise.
pub fn patch_chart(mesh: &PatchMesh, p: usize) -> u32 {
    chart_of(face_corner(mesh, p), p)
}

/// [`patch_chart`] of patch `p` from its [`face_corner`] word (twin of `cc_chart`).
pub fn chart_of(face_corner: u32, p: usize) -> u32 {
    let (k, sides) = (face_corner & 0xff, face_corner >> 8);
    if sides == 4 {
        p as u32 - k
    } else {
        p as u32
    }
}

/// Whether edge `k` of a patch is a seam between two charts: the halves of control
/// edges (edges 0 and 3) always are, the edges to the face point only in a face that is
/// not a quad (twin of `cc_seam`).
pub fn seam(face_corner: u32, k: usize) -> bool {
    k == 0 || k == 3 || face_corner >> 8 != 4
}

/// The key of point `(i, j)/n` of patch `p` in `p`'s chart: one output vertex.
pub fn chart_key(mesh: &PatchMesh, p: usize, i: u32, j: u32, n: u32) -> u64 {
    let corner = face_corner(mesh, p);
    key(mesh.quads[p], mesh.quad_edges[p], Some(corner), p, i, j, n)
}

/// [`chart_key`] from the GPU's [`CcPatchTopo`] of patch `p` (twin of `cc_point_key`).
pub fn topo_chart_key(topo: &CcPatchTopo, p: usize, i: u32, j: u32, n: u32) -> u64 {
    key(topo.quad, topo.edges, Some(topo.face_corner), p, i, j, n)
}

fn key(
    quad: [u32; 4],
    edges: [u32; 4],
    chart: Option<u32>,
    p: usize,
    i: u32,
    j: u32,
    n: u32,
) -> u64 {
    debug_assert!(i <= n && j <= n && n < 1 << 20 && p < 1 << 22);
    match grid_place(i, j, n) {
        GridPlace::Corner(c) => {
            let chart = chart.map_or(0, |w| chart_of(w, p) as u64);
            VERTEX | chart << 32 | quad[c] as u64
        }
        // Edge k runs from corner k to corner k+1; t is the distance from corner k.
        GridPlace::Edge(k, t) => {
            let forward = quad[k] < quad[(k + 1) % 4];
            let t = if forward { t } else { n - t };
            let side = chart.is_some_and(|w| seam(w, k) && forward);
            EDGE | (edges[k] as u64) << 32 | if side { EDGE_SIDE } else { 0 } | t as u64
        }
        GridPlace::Inside => INTERIOR | (p as u64) << 40 | (i as u64) << 20 | j as u64,
    }
}

/// The point key of a chart key: the point all its charts' vertices share.
pub fn point_of(key: u64) -> u64 {
    match key >> 62 {
        0 => key & 0xFFFF_FFFF,
        1 => key & !EDGE_SIDE,
        _ => key,
    }
}

/// The control face of grid point `(i, j)/n` of patch `p` and its `(u, v)` there, as an
/// output vertex carries them ([`face_uv`] of [`PatchMesh::face_point`]).
pub fn vertex_face_uv(mesh: &PatchMesh, p: usize, i: u32, j: u32, n: u32) -> (u32, [f32; 2]) {
    let (face, s, t) = mesh.face_point(p, i as u64, j as u64, n as u64);
    (face, face_uv(s, t, n as u64))
}

/// [`vertex_face_uv`] from the GPU's [`CcPatchTopo`] (twin of `cc_face_uv`).
pub fn topo_face_uv(topo: &CcPatchTopo, i: u32, j: u32, n: u32) -> (u32, [f32; 2]) {
    let (k, sides) = (topo.face_corner & 0xff, topo.face_corner >> 8);
    let (s, t) = face_coords(k as u64, sides as u64, i as u64, j as u64, n as u64);
    (topo.face, face_uv(s, t, n as u64))
}

/// Face coordinates in units of `1/(2·scale)` as the single-precision `(u, v)` of a
/// vertex. Both are integers below 2^24 (at most 8 tiles of `2·scale ≤ 2^21`), so the
/// quotient is the one rounding, and every patch of a face gives a shared point the
/// same bits.
pub fn face_uv(s: u64, t: u64, scale: u64) -> [f32; 2] {
    let m = (2 * scale) as f32;
    [s as f32 / m, t as f32 / m]
}

/// Where a key lies: on a level-1 edge at canonical `t`, inside a patch, or a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyPlace {
    /// A patch corner: the level-1 point.
    Vertex(u32),
    /// On a level-1 edge.
    Edge {
        /// Level-1 edge id.
        edge: u32,
        /// Distance from the edge's smaller end point, in `1/n`.
        t: u32,
    },
    /// Inside a patch.
    Interior {
        /// Patch index.
        patch: u32,
        /// Grid coordinate along u.
        i: u32,
        /// Grid coordinate along v.
        j: u32,
    },
}

/// Decodes a key of [`point_key`] (or of [`chart_key`], whose chart it leaves out).
pub fn key_place(key: u64) -> KeyPlace {
    let low = point_of(key) & ((1 << 62) - 1);
    match key >> 62 {
        0 => KeyPlace::Vertex(low as u32),
        1 => KeyPlace::Edge {
            edge: (low >> 32) as u32,
            t: low as u32,
        },
        _ => KeyPlace::Interior {
            patch: (low >> 40) as u32,
            i: ((low >> 20) & 0xF_FFFF) as u32,
            j: (low & 0xF_FFFF) as u32,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catmull_clark::gpu_model::patch_topology;
    use crate::catmull_clark::ControlMesh;
    use glam::DVec3;
    use std::collections::HashMap;

    /// A quad, two triangles and a pentagon sharing edges: quad-internal edges, seams
    /// between faces and seams inside faces that are not quads.
    fn mixed() -> PatchMesh {
        let positions = [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (2.0, 0.5),
            (0.5, 2.0),
            (-1.0, 1.5),
            (-1.0, 0.2),
        ]
        .map(|(x, y)| DVec3::new(x, y, 0.1 * x * y))
        .to_vec();
        let faces = vec![
            vec![0, 1, 2, 3],
            vec![1, 4, 2],
            vec![3, 2, 5],
            vec![0, 3, 5, 6, 7],
        ];
        PatchMesh::new(&ControlMesh::new(positions, faces)).unwrap()
    }

    #[test]
    fn a_point_has_one_chart_key_per_chart_it_lies_in() {
        let mesh = mixed();
        let topo = patch_topology(&mesh);
        let n = 6;
        // Per point: the charts around it; per chart key: the face coordinates every
        // patch gives it.
        let mut charts: HashMap<u64, Vec<u32>> = HashMap::new();
        let mut coords: HashMap<u64, (u32, [f32; 2])> = HashMap::new();
        for (p, tp) in topo.iter().enumerate() {
            for j in 0..=n {
                for i in 0..=n {
                    let key = chart_key(&mesh, p, i, j, n);
                    assert_eq!(key, topo_chart_key(tp, p, i, j, n));
                    assert_eq!(point_of(key), point_key(&mesh, p, i, j, n));
                    assert_eq!(key_place(key), key_place(point_of(key)));
                    let uv = vertex_face_uv(&mesh, p, i, j, n);
                    assert_eq!(uv, topo_face_uv(tp, i, j, n));
                    let before = coords.insert(key, uv);
                    assert!(
                        before.is_none_or(|b| b == uv),
                        "patch {p} ({i}, {j}): {before:?} and {uv:?}"
                    );
                    let c = charts.entry(point_of(key)).or_default();
                    let chart = patch_chart(&mesh, p);
                    if !c.contains(&chart) {
                        c.push(chart);
                    }
                }
            }
        }
        // Exactly as many chart keys per point as charts around it.
        let mut per_point: HashMap<u64, usize> = HashMap::new();
        for &key in coords.keys() {
            *per_point.entry(point_of(key)).or_default() += 1;
        }
        for (point, c) in &charts {
            assert_eq!(per_point[point], c.len(), "{:?}", key_place(*point));
        }
        // Face centres: the quad's one vertex, the triangles' three, the pentagon's five.
        let centre = |f: usize| VERTEX | mesh.quads[mesh.first_patch[f] as usize][2] as u64;
        assert_eq!([0, 1, 2, 3].map(|f| charts[&centre(f)].len()), [1, 3, 3, 5]);
        // Patch 0 (the quad at vertex 0): its edge 1 runs inside the quad, its edge 0
        // along the open boundary; patch 1's edge 0 is shared with a triangle.
        let charts_at = |p: usize, i: u32, j: u32| charts[&point_key(&mesh, p, i, j, n)].len();
        assert_eq!(charts_at(0, n, 2), 1, "inside the quad");
        assert_eq!(charts_at(0, 3, 0), 1, "open boundary");
        assert_eq!(charts_at(1, 3, 0), 2, "between the quad and a triangle");
    }

    #[test]
    fn sub_face_tiles_are_bfr_s() {
        let tiles: Vec<usize> = [3, 5, 9, 10, 17, 26, 64]
            .iter()
            .map(|&n| crate::catmull_clark::topology::sub_face_tiles(n))
            .collect();
        // Above 9 sides 1 + ⌊√(n − 1)⌋, at the perfect squares too.
        assert_eq!(tiles, [2, 3, 3, 4, 5, 6, 8]);
    }
}
