//! The Catmull-Clark stage on the GPU (issue 5, in progress): the patches' quadtrees
//! uploaded once ([`CcModelBuffers`]), and the kernel that evaluates surface points
//! exactly ([`CcVertexEval`], `shaders/cc_vertex_eval.wgsl`, CPU twin
//! [`tessera_core::catmull_clark::gpu_model::vertex_eval`]).
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue, model: &tessera_core::catmull_clark::SurfaceModel,
//! #         points: &wgpu::Buffer, counts: &wgpu::Buffer, out: &wgpu::Buffer, n: u32) {
//! use tessera_core::catmull_clark::gpu_model::CcGpuModel;
//! use tessera_wgpu::catmull_clark::{CcModelBuffers, CcVertexEval};
//! let buffers = CcModelBuffers::new(device, &CcGpuModel::new(model));
//! let eval = CcVertexEval::new(device);
//! let mut encoder = device.create_command_encoder(&Default::default());
//! eval.record(device, &mut encoder, &buffers, points, counts, out, n);
//! queue.submit([encoder.finish()]);
//! # }
//! ```

use tessera_core::catmull_clark::gpu_model::CcGpuModel;
use wgpu::util::DeviceExt;

use crate::error::{Error, Result};
use crate::kernel::Kernel;

/// The flattened quadtrees on the GPU (bindings 20–24 of the Catmull-Clark kernels).
pub struct CcModelBuffers {
    pub roots: wgpu::Buffer,
    pub nodes: wgpu::Buffer,
    pub splits: wgpu::Buffer,
    pub nets: wgpu::Buffer,
    pub corners: wgpu::Buffer,
    sizes: [usize; 5],
}

fn byte_sizes(model: &CcGpuModel) -> [usize; 5] {
    use std::mem::size_of_val;
    [
        size_of_val(model.roots.as_slice()),
        size_of_val(model.nodes.as_slice()),
        size_of_val(model.splits.as_slice()),
        size_of_val(model.nets.as_slice()),
        size_of_val(model.corners.as_slice()),
    ]
}

impl CcModelBuffers {
    pub fn new(device: &wgpu::Device, model: &CcGpuModel) -> Self {
        let init = |label: &str, bytes: &[u8]| {
            // Bindings are never empty: an empty array (a model without extraordinary
            // vertices has no corners) binds one zeroed element of any of the types.
            let zero = [0u8; 256];
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: if bytes.is_empty() { &zero } else { bytes },
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            })
        };
        CcModelBuffers {
            roots: init("tessera cc roots", bytemuck::cast_slice(&model.roots)),
            nodes: init("tessera cc nodes", bytemuck::cast_slice(&model.nodes)),
            splits: init("tessera cc splits", bytemuck::cast_slice(&model.splits)),
            nets: init("tessera cc nets", bytemuck::cast_slice(&model.nets)),
            corners: init("tessera cc corners", bytemuck::cast_slice(&model.corners)),
            sizes: byte_sizes(model),
        }
    }

    /// Re-uploads a model of the same shape (the control points moved, the topology did
    /// not): nothing is reallocated. A different shape is an error; build new buffers.
    pub fn update(&self, queue: &wgpu::Queue, model: &CcGpuModel) -> Result<()> {
        if byte_sizes(model) != self.sizes {
            return Err(Error::Core(tessera_core::Error::Param(
                "the model's quadtrees changed shape (topology or depth); upload it anew".into(),
            )));
        }
        let write = |buffer: &wgpu::Buffer, bytes: &[u8]| {
            if !bytes.is_empty() {
                queue.write_buffer(buffer, 0, bytes);
            }
        };
        write(&self.roots, bytemuck::cast_slice(&model.roots));
        write(&self.nodes, bytemuck::cast_slice(&model.nodes));
        write(&self.splits, bytemuck::cast_slice(&model.splits));
        write(&self.nets, bytemuck::cast_slice(&model.nets));
        write(&self.corners, bytemuck::cast_slice(&model.corners));
        Ok(())
    }

    /// Bytes on the GPU.
    pub fn byte_size(&self) -> usize {
        self.sizes.iter().sum()
    }

    fn entries(&self) -> [(u32, &wgpu::Buffer); 5] {
        [
            (20, &self.roots),
            (21, &self.nodes),
            (22, &self.splits),
            (23, &self.nets),
            (24, &self.corners),
        ]
    }
}

/// The kernel that evaluates points `(patch, u, v)` into output vertices.
pub struct CcVertexEval {
    kernel: Kernel,
}

impl CcVertexEval {
    pub fn new(device: &wgpu::Device) -> Self {
        CcVertexEval {
            kernel: Kernel::new(device, "cc_vertex_eval.wgsl", "main"),
        }
    }

    /// Records the evaluation of the first `counts[0]` of `points` ([`CcPoint`]s; at
    /// most `max_points` invocations) into `out` ([`OutVertex`]s).
    ///
    /// [`CcPoint`]: tessera_core::gpu_types::CcPoint
    /// [`OutVertex`]: tessera_core::gpu_types::OutVertex
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        model: &CcModelBuffers,
        points: &wgpu::Buffer,
        counts: &wgpu::Buffer,
        out: &wgpu::Buffer,
        max_points: u32,
    ) {
        let mut entries = model.entries().to_vec();
        entries.extend([(30, points), (31, out), (32, counts)]);
        let bind = self.kernel.bind(device, &entries);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessera cc_vertex_eval"),
            timestamp_writes: None,
        });
        self.kernel.dispatch(&mut pass, &bind, max_points, 64);
    }
}
