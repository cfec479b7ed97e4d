//! The output of every tessellator: an indexed triangle mesh in the GPU vertex layout.

use glam::Vec3;

use crate::error::{Error, Result};
use crate::gpu_types::OutVertex;

/// The most triangles a tessellation whose size is known in advance (uniform grids) may
/// have: 2^27 triangles take 1.5 GiB of indices and about 2.4 GiB of vertices. Larger
/// requests are refused before anything is allocated.
pub const MAX_OUTPUT_TRIANGLES: u64 = 1 << 27;

/// Refuses `triangles` above [`MAX_OUTPUT_TRIANGLES`]; `what` says what asked for them.
pub fn check_output_triangles(triangles: u64, what: &str) -> Result<()> {
    if triangles > MAX_OUTPUT_TRIANGLES {
        return Err(Error::Param(format!(
            "{what} would make {triangles} triangles, more than the {MAX_OUTPUT_TRIANGLES} allowed"
        )));
    }
    Ok(())
}

/// Indexed triangles; three indices per triangle, counter-clockwise seen from the front.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The vertices, as the GPU stages write them.
    pub vertices: Vec<OutVertex>,
    /// Indices into `vertices`, three per triangle.
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Triangles in the mesh.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The vertex positions, in vertex order.
    pub fn positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.vertices.iter().map(|v| Vec3::from_array(v.position))
    }

    /// Each triangle's three vertex indices.
    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]])
    }

    /// Distinct vertex positions (bit for bit): the surface points, where vertices also
    /// count the copies of a point on a seam between faces
    /// ([`OutVertex`]).
    pub fn distinct_positions(&self) -> usize {
        let mut bits: Vec<[u32; 3]> = self
            .vertices
            .iter()
            .map(|v| v.position.map(f32::to_bits))
            .collect();
        bits.sort_unstable();
        bits.dedup();
        bits.len()
    }

    /// Axis-aligned bounds of the vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        )
    }
}
