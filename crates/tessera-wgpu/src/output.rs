//! The buffers a tessellation stage leaves on the GPU, ready for any render pass.

use crate::kernel::init_buffer;
use tessera_core::gpu_types::{DrawIndexedIndirectArgs, OutVertex};
use tessera_core::Mesh;

/// Vertex buffer ([`OutVertex`]: position, normal, `u v` on the face, face id; 36
/// bytes, [`VERTEX_LAYOUT`](Self::VERTEX_LAYOUT)), `u32` index buffer, and one
/// [`DrawIndexedIndirectArgs`] written by the GPU.
///
/// Draw with `draw_indexed_indirect(buffers.indirect(), 0)`; nothing needs to be read
/// back. A stage reallocates its buffers when they grow: take them from the stage's
/// `output()` each frame rather than keeping them.
pub struct MeshBuffers {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    indirect: wgpu::Buffer,
    vertex_capacity: u32,
    index_capacity: u32,
}

impl MeshBuffers {
    /// The vertices ([`OutVertex`]), bound as vertex buffer 0 with
    /// [`VERTEX_LAYOUT`](Self::VERTEX_LAYOUT).
    pub fn vertices(&self) -> &wgpu::Buffer {
        &self.vertices
    }

    /// The `u32` indices, three per triangle.
    pub fn indices(&self) -> &wgpu::Buffer {
        &self.indices
    }

    /// One [`DrawIndexedIndirectArgs`]: the argument of `draw_indexed_indirect`.
    pub fn indirect(&self) -> &wgpu::Buffer {
        &self.indirect
    }

    /// Capacity of [`vertices`](Self::vertices), in vertices.
    pub fn vertex_capacity(&self) -> u32 {
        self.vertex_capacity
    }

    /// Capacity of [`indices`](Self::indices), in indices.
    pub fn index_capacity(&self) -> u32 {
        self.index_capacity
    }

    /// Records copies of `old`'s vertices, indices and draw arguments into these (at
    /// least as large) buffers: a stage that grew keeps drawing its last complete mesh
    /// until a run fills the new ones.
    pub(crate) fn copy_from(&self, encoder: &mut wgpu::CommandEncoder, old: &MeshBuffers) {
        for (from, to) in [
            (&old.vertices, &self.vertices),
            (&old.indices, &self.indices),
            (&old.indirect, &self.indirect),
        ] {
            let size = from.size().min(to.size());
            encoder.copy_buffer_to_buffer(from, 0, to, 0, size);
        }
    }

    /// Usage of the vertex buffer: drawable, writable by compute kernels, copyable.
    pub const VERTEX_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::VERTEX
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);
    /// Usage of the index buffer.
    pub const INDEX_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDEX
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);
    /// Usage of the draw-argument buffer.
    pub const INDIRECT_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDIRECT
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);

    /// Buffers assembled by hand, for the test that draws a buffer without vertex usage
    /// to see the validation error fail the render.
    #[doc(hidden)]
    pub fn from_buffers(
        vertices: wgpu::Buffer,
        indices: wgpu::Buffer,
        indirect: wgpu::Buffer,
    ) -> Self {
        MeshBuffers {
            vertex_capacity: (vertices.size() / std::mem::size_of::<OutVertex>() as u64) as u32,
            index_capacity: (indices.size() / 4) as u32,
            vertices,
            indices,
            indirect,
        }
    }

    /// Shader location of the position (`vec3<f32>`).
    pub const POSITION_LOCATION: u32 = 0;
    /// Shader location of the normal (`vec3<f32>`).
    pub const NORMAL_LOCATION: u32 = 1;
    /// Shader location of `u v` on the face (`vec2<f32>`): the Bézier patch's parameter,
    /// or the Catmull-Clark control face's own, in OpenSubdiv Bfr's parameterisation
    /// (Ptex's for quads), so a per-face texture or displacement reads it directly.
    pub const UV_LOCATION: u32 = 2;
    /// Shader location of the face id (`u32`): the Bézier patch, or the Catmull-Clark
    /// control face, by its index in the input. Every triangle lies in one face: a point
    /// on an edge between faces has a vertex per face, at the same position.
    pub const FACE_LOCATION: u32 = 3;

    /// The vertex layout of [`OutVertex`] at the locations above.
    pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<OutVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32
        ],
    };

    /// Empty buffers for up to `vertices` vertices and `indices` indices (at least one
    /// of each, so that bindings are never empty).
    pub(crate) fn with_capacity(device: &wgpu::Device, vertices: u32, indices: u32) -> Self {
        let (vertices, indices) = (vertices.max(1), indices.max(3));
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        MeshBuffers {
            vertices: buffer(
                "tessera vertices",
                vertices as u64 * std::mem::size_of::<OutVertex>() as u64,
                Self::VERTEX_USAGE,
            ),
            indices: buffer("tessera indices", indices as u64 * 4, Self::INDEX_USAGE),
            indirect: buffer(
                "tessera draw args",
                std::mem::size_of::<DrawIndexedIndirectArgs>() as u64,
                Self::INDIRECT_USAGE,
            ),
            vertex_capacity: vertices,
            index_capacity: indices,
        }
    }

    /// Copies the first `vertices` vertices and `indices` indices back (files and tests;
    /// drawing needs no readback).
    pub fn read_mesh(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        vertices: u32,
        indices: u32,
    ) -> crate::Result<Mesh> {
        let vsize = vertices as u64 * std::mem::size_of::<OutVertex>() as u64;
        let v = crate::readback::read_buffer(device, queue, &self.vertices, 0, vsize)?;
        let i = crate::readback::read_buffer(device, queue, &self.indices, 0, indices as u64 * 4)?;
        Ok(Mesh {
            vertices: bytemuck::pod_collect_to_vec(&v),
            indices: bytemuck::pod_collect_to_vec(&i),
        })
    }

    /// Uploads a mesh made on the CPU (the CPU reference backend, uniform tessellation).
    pub fn from_mesh(device: &wgpu::Device, mesh: &Mesh) -> Self {
        let init = |label, contents: &[u8], usage| init_buffer(device, label, contents, usage);
        let dummy_vertex = [OutVertex::zeroed_array()];
        let vertices: &[OutVertex] = if mesh.vertices.is_empty() {
            &dummy_vertex
        } else {
            &mesh.vertices
        };
        let indices: &[u32] = if mesh.indices.is_empty() {
            &[0, 0, 0]
        } else {
            &mesh.indices
        };
        let args = DrawIndexedIndirectArgs {
            index_count: mesh.indices.len() as u32,
            instance_count: 1,
            ..Default::default()
        };
        MeshBuffers {
            vertices: init(
                "tessera vertices",
                bytemuck::cast_slice(vertices),
                Self::VERTEX_USAGE,
            ),
            indices: init(
                "tessera indices",
                bytemuck::cast_slice(indices),
                Self::INDEX_USAGE,
            ),
            indirect: init(
                "tessera draw args",
                bytemuck::bytes_of(&args),
                Self::INDIRECT_USAGE,
            ),
            vertex_capacity: vertices.len() as u32,
            index_capacity: indices.len() as u32,
        }
    }
}

trait Zeroed {
    fn zeroed_array() -> Self;
}

impl Zeroed for OutVertex {
    fn zeroed_array() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}
