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

use super::topology::PatchMesh;

const VERTEX: u64 = 0;
const EDGE: u64 = 1 << 62;
const INTERIOR: u64 = 2 << 62;

/// The key of point `(i, j)/n` of patch `p`.
pub fn point_key(mesh: &PatchMesh, p: usize, i: u32, j: u32, n: u32) -> u64 {
    quad_point_key(mesh.quads[p], mesh.quad_edges[p], p, i, j, n)
}

/// [`point_key`] from the patch's level-1 points and edge ids alone (as the GPU's
/// [`CcPatchTopo`](crate::gpu_types::CcPatchTopo) holds them).
pub fn quad_point_key(quad: [u32; 4], edges: [u32; 4], p: usize, i: u32, j: u32, n: u32) -> u64 {
    debug_assert!(i <= n && j <= n && n < 1 << 20 && p < 1 << 22);
    let corner = match (i, j) {
        (0, 0) => Some(0),
        (i, 0) if i == n => Some(1),
        (i, j) if i == n && j == n => Some(2),
        (0, j) if j == n => Some(3),
        _ => None,
    };
    if let Some(c) = corner {
        return VERTEX | quad[c] as u64;
    }
    // Edge k runs from corner k to corner k+1; t is the distance from corner k.
    let edge = if j == 0 {
        Some((0, i))
    } else if i == n {
        Some((1, j))
    } else if j == n {
        Some((2, n - i))
    } else if i == 0 {
        Some((3, n - j))
    } else {
        None
    };
    match edge {
        Some((k, t)) => {
            let (a, b) = (quad[k], quad[(k + 1) % 4]);
            let t = if a < b { t } else { n - t };
            EDGE | (edges[k] as u64) << 32 | t as u64
        }
        None => INTERIOR | (p as u64) << 40 | (i as u64) << 20 | j as u64,
    }
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

/// Decodes a key of [`point_key`].
pub fn key_place(key: u64) -> KeyPlace {
    let low = key & ((1 << 62) - 1);
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
