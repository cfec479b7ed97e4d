//! The buffers a tessellation stage leaves on the GPU, ready for any render pass.

use tessera_core::gpu_types::{DrawIndexedIndirectArgs, OutVertex};
use tessera_core::Mesh;
use wgpu::util::DeviceExt;

/// Vertex buffer ([`OutVertex`]: position, normal, patch `u v`, patch id; 36 bytes),
/// `u32` index buffer, and one [`DrawIndexedIndirectArgs`] written by the GPU.
///
/// Draw with `draw_indexed_indirect(&indirect, 0)`; nothing needs to be read back.
pub struct MeshBuffers {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub indirect: wgpu::Buffer,
    /// Capacity of `vertices`, in vertices.
    pub vertex_capacity: u32,
    /// Capacity of `indices`, in indices.
    pub index_capacity: u32,
}

impl MeshBuffers {
    /// Usages of the three buffers: drawable, writable by compute kernels, copyable.
    pub const VERTEX_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::VERTEX
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);
    pub const INDEX_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDEX
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);
    pub const INDIRECT_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::INDIRECT
        .union(wgpu::BufferUsages::STORAGE)
        .union(wgpu::BufferUsages::COPY_SRC)
        .union(wgpu::BufferUsages::COPY_DST);

    /// The vertex layout of [`OutVertex`] at shader locations 0 (position), 1 (normal),
    /// 2 (uv) and 3 (patch).
    pub const VERTEX_LAYOUT: wgpu::VertexBufferLayout<'static> = wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<OutVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Uint32
        ],
    };

    /// Empty buffers for up to `vertices` vertices and `indices` indices (at least one
    /// of each, so that bindings are never empty).
    pub fn with_capacity(device: &wgpu::Device, vertices: u32, indices: u32) -> Self {
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
        let v = crate::headless::read_buffer(device, queue, &self.vertices, 0, vsize)?;
        let i = crate::headless::read_buffer(device, queue, &self.indices, 0, indices as u64 * 4)?;
        Ok(Mesh {
            vertices: bytemuck::pod_collect_to_vec(&v),
            indices: bytemuck::pod_collect_to_vec(&i),
        })
    }

    /// Uploads a mesh made on the CPU (the CPU reference backend, uniform tessellation).
    pub fn from_mesh(device: &wgpu::Device, mesh: &Mesh) -> Self {
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
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
