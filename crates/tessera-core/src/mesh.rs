//! The output of every tessellator: an indexed triangle mesh in the GPU vertex layout.

use glam::Vec3;

use crate::gpu_types::OutVertex;

/// Indexed triangles; three indices per triangle, counter-clockwise seen from the front.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub vertices: Vec<OutVertex>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn positions(&self) -> impl Iterator<Item = Vec3> + '_ {
        self.vertices.iter().map(|v| Vec3::from_array(v.position))
    }

    pub fn triangles(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        self.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]])
    }

    /// Axis-aligned bounds of the vertices.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p), hi.max(p)),
        )
    }
}
