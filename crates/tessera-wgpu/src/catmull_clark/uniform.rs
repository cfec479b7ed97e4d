//! Uniform Catmull-Clark tessellation on the GPU: every surface patch on an `n × n`
//! grid. Five dispatches, no readback: the adaptive stage's two stencil steps (the
//! quadtrees from the control points, only after they moved), `cc_uniform_points` (each
//! vertex, a point in a chart, written once, by the patch that owns it), `cc_vertex_eval`
//! (exact evaluation at the point's home, the adaptive stage's kernel),
//! `cc_uniform_cells` (two triangles per cell and the draw arguments).
//! The output sizes follow from the topology and `n`, so the buffers are allocated
//! exactly and never grow. CPU twin: [`tessera_core::catmull_clark::gpu_uniform`].
//!
//! ```no_run
//! # fn demo(device: &wgpu::Device, queue: &wgpu::Queue,
//! #         model: &tessera_core::catmull_clark::SurfaceModel) -> tessera_wgpu::Result<()> {
//! use tessera_wgpu::{catmull_clark::{CcUniformStage, UniformParams}, Kernels};
//! let kernels = Kernels::new(device);
//! let mut stage = CcUniformStage::new(device, queue, &kernels, model, &UniformParams { segments: 8 })?;
//! let mut encoder = device.create_command_encoder(&Default::default());
//! stage.prepare(device, queue, &mut encoder)?;
//! queue.submit([encoder.finish()]);
//! // Draw `stage.output()` with `draw_indexed_indirect(stage.output().indirect(), 0)`.
//! # Ok(()) }
//! ```

use glam::Vec3;
use tessera_core::catmull_clark::gpu_uniform::{uniform_patches, UniformLayout};
use tessera_core::catmull_clark::stencil::CcStencils;
use tessera_core::catmull_clark::{PatchMesh, SurfaceModel};
use tessera_core::gpu_types::{CcUniformParams, CcVertexPoint, OutVertex};
use tessera_core::Mesh;

use super::{CcModelBuffers, CcStencilBuffers, CcStencilKernels, CcVertexEval, NetPages};
use crate::error::{Error, Result};
use crate::kernel::{allocating, check_size, init_buffer, storage, Kernel};
use crate::output::MeshBuffers;
use crate::stage::{Passes, RunTimestamps};
use crate::Kernels;

/// Binding numbers of the uniform kernels (`shaders/shared/cc_uniform.wgsl`).
mod slot {
    pub const PARAMS: u32 = 70;
    pub const PATCHES: u32 = 71;
    pub const POINTS: u32 = 72;
    pub const COUNTS: u32 = 73;
    pub const VERTICES: u32 = 74;
    pub const INDICES: u32 = 75;
    pub const DRAW: u32 = 76;
}

/// The compiled kernels of [`CcUniformStage`] (part of [`Kernels`]).
pub(crate) struct CcUniformKernels {
    points: Kernel,
    eval: CcVertexEval,
    cells: Kernel,
}

impl CcUniformKernels {
    pub fn new(device: &wgpu::Device, pages: NetPages) -> Self {
        CcUniformKernels {
            points: Kernel::new(device, "cc_uniform_points.wgsl", "main"),
            eval: CcVertexEval::new(device, pages),
            cells: Kernel::new(device, "cc_uniform_cells.wgsl", "main"),
        }
    }
}

/// What [`CcUniformStage`] tessellates with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UniformParams {
    /// Segments per patch side (`1..=4096`).
    pub segments: u32,
}

/// The uniform tessellation stage: the model uploaded once, `n` changeable, output
/// buffers ready to draw after each [`prepare`](Self::prepare).
pub struct CcUniformStage {
    kernels: std::sync::Arc<CcUniformKernels>,
    stencil_kernels: std::sync::Arc<CcStencilKernels>,
    model: CcModelBuffers,
    /// The control points and the tables the quadtrees are derived through on the GPU.
    stencil: CcStencilBuffers,
    stencil_binds: [wgpu::BindGroup; 2],
    /// The patches as built, to check moved control points against.
    patches_cpu: PatchMesh,
    layout: UniformLayout,
    patches: wgpu::Buffer,
    params: CcUniformParams,
    params_buffer: wgpu::Buffer,
    sized: Sized,
}

/// What depends on `n`: the output and the bind groups over it and the points (which
/// the bind groups keep alive).
struct Sized {
    output: MeshBuffers,
    binds: [wgpu::BindGroup; 3],
}

impl CcUniformStage {
    /// Uploads `model` through `queue` and sizes the buffers for `params.segments` per
    /// patch side; compiles the stage's kernels into `kernels` if no stage has.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        model: &SurfaceModel,
        params: &UniformParams,
    ) -> Result<Self> {
        allocating(device, "the stage's model and buffers", || {
            kernels.check_device(device)?;
            let layout = uniform_patches(&model.mesh);
            let params = layout.params(params.segments)?;
            // As the adaptive stage: the tables once per topology, the quadtrees derived from
            // the control points by the first dispatches of a run after they move.
            let stencils = CcStencils::new(&model.mesh, model.depth);
            let model_buffers = CcModelBuffers::derived(device, queue, &stencils.structure)?;
            let stencil_kernels = kernels.cc_stencil(model_buffers.pages);
            let kernels = kernels.cc_uniform(model_buffers.pages);
            let stencil =
                CcStencilBuffers::new(device, &stencils, &model.mesh.control_points_f32())?;
            let stencil_binds = stencil.bind(device, &stencil_kernels, &model_buffers);
            // Never empty: a model of holes only binds one zeroed patch it never reads.
            let zero = [tessera_core::gpu_types::CcUniformPatch::default()];
            let patches = init_buffer(
                device,
                "tessera cc uniform patches",
                bytemuck::cast_slice(if layout.patches.is_empty() {
                    &zero
                } else {
                    &layout.patches
                }),
                wgpu::BufferUsages::STORAGE,
            );
            let params_buffer = init_buffer(
                device,
                "tessera cc uniform params",
                bytemuck::bytes_of(&params),
                wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            );
            let sized = Sized::new(
                device,
                &kernels,
                &model_buffers,
                &patches,
                &params_buffer,
                &params,
            )?;
            Ok(CcUniformStage {
                kernels,
                stencil_kernels,
                model: model_buffers,
                stencil,
                stencil_binds,
                patches_cpu: model.mesh.clone(),
                layout,
                patches,
                params,
                params_buffer,
                sized,
            })
        })
    }

    /// Segments per patch side of the next runs, written through `queue`; the output
    /// buffers are reallocated when the size changes.
    pub fn set_params(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &UniformParams,
    ) -> Result<()> {
        let params = self.layout.params(params.segments)?;
        if params == self.params {
            return Ok(());
        }
        self.sized = allocating(device, "the stage's resized output", || {
            Sized::new(
                device,
                &self.kernels,
                &self.model,
                &self.patches,
                &self.params_buffer,
                &params,
            )
        })?;
        queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&params));
        self.params = params;
        Ok(())
    }

    /// The parameters of the next runs.
    pub fn params(&self) -> UniformParams {
        UniformParams {
            segments: self.params.segments,
        }
    }

    /// New positions of the control vertices (same topology and order): written through
    /// `queue` as they are, 12 bytes a point and a word; the next
    /// [`prepare`](Self::prepare) derives the patches from them on the GPU. The CPU only
    /// checks them.
    pub fn update_points(&mut self, queue: &wgpu::Queue, points: &[Vec3]) -> Result<()> {
        self.patches_cpu
            .check_control_points(points.iter().map(|p| p.as_dvec3()))?;
        self.stencil.update(queue, points)
    }

    /// Vertices and indices every run writes.
    pub fn vertex_count(&self) -> u32 {
        self.params.vertex_count()
    }

    /// Indices every run writes (3 per triangle).
    pub fn index_count(&self) -> u32 {
        self.params.index_count()
    }

    /// The vertex, index and draw-argument buffers.
    pub fn output(&self) -> &MeshBuffers {
        &self.sized.output
    }

    /// Bytes uploaded when the stage is made: the stencil tables, the quadtrees' shape,
    /// the control points and the patches' numbering.
    pub fn upload_bytes(&self) -> usize {
        self.stencil.table_bytes()
            + self.stencil.update_bytes()
            + std::mem::size_of_val(self.layout.patches.as_slice())
    }

    /// Records the five dispatches into `encoder`. Submits nothing; the sizes follow
    /// from the parameters, so there is nothing to grow and no error.
    pub fn prepare(
        &mut self,
        _device: &wgpu::Device,
        _queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.record_run(encoder, None);
        Ok(())
    }

    /// As [`prepare`](Self::prepare), writing the run's GPU timestamps into
    /// `timestamps` (see [`crate::GpuTimer`]).
    pub fn prepare_timed(
        &mut self,
        _device: &wgpu::Device,
        _queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: RunTimestamps<'_>,
    ) -> Result<()> {
        self.record_run(encoder, Some(timestamps));
        Ok(())
    }

    fn record_run(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<RunTimestamps<'_>>,
    ) {
        let mut passes = Passes::new(timestamps);
        let p = &self.params;
        let side = p.segments + 1;
        let [points, eval, cells] = &self.sized.binds;
        {
            // The quadtrees from the control points (nothing to do unless they moved).
            let mut pass = passes.begin(encoder, "tessera cc stencils", false);
            self.stencil
                .record(&mut pass, &self.stencil_kernels, &self.stencil_binds);
        }
        self.stencil.settle(encoder);
        {
            let mut pass = passes.begin(encoder, "tessera cc_uniform_points", false);
            // At least one invocation: it writes the vertex count.
            let items = (p.patch_count * side * side).max(1);
            self.kernels.points.dispatch(&mut pass, points, items, 64);
        }
        self.kernels
            .eval
            .record_bound(encoder, eval, self.vertex_count());
        let mut pass = passes.begin(encoder, "tessera cc_uniform_cells", true);
        let items = (p.patch_count * p.segments * p.segments).max(1);
        self.kernels.cells.dispatch(&mut pass, cells, items, 64);
    }

    /// Copies the output mesh back (files and tests; drawing needs no readback).
    pub fn read_mesh(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Mesh> {
        if self.index_count() == 0 {
            return Ok(Mesh::default());
        }
        self.sized
            .output
            .read_mesh(device, queue, self.vertex_count(), self.index_count())
    }
}

impl Sized {
    fn new(
        device: &wgpu::Device,
        kernels: &CcUniformKernels,
        model: &CcModelBuffers,
        patches: &wgpu::Buffer,
        params_buffer: &wgpu::Buffer,
        params: &CcUniformParams,
    ) -> Result<Self> {
        let (vertices, indices) = (params.vertex_count(), params.index_count());
        for (what, bytes) in [
            (
                "vertex",
                vertices as u64 * std::mem::size_of::<OutVertex>() as u64,
            ),
            (
                "point",
                vertices as u64 * std::mem::size_of::<CcVertexPoint>() as u64,
            ),
            ("index", indices as u64 * 4),
        ] {
            check_size(device, what, bytes)?;
        }
        let points = storage(
            device,
            "tessera cc uniform points",
            vertices.max(1) as u64 * std::mem::size_of::<CcVertexPoint>() as u64,
        );
        let counts = storage(device, "tessera cc uniform counts", 4);
        let output = MeshBuffers::with_capacity(device, vertices, indices);
        fn entries<'a>(
            shared: [(u32, &'a wgpu::Buffer); 2],
            extra: &[(u32, &'a wgpu::Buffer)],
        ) -> Vec<(u32, &'a wgpu::Buffer)> {
            shared.iter().chain(extra).copied().collect()
        }
        let shared = [(slot::PARAMS, params_buffer), (slot::PATCHES, patches)];
        let binds = [
            kernels.points.bind(
                device,
                &entries(shared, &[(slot::POINTS, &points), (slot::COUNTS, &counts)]),
            ),
            kernels
                .eval
                .bind(device, model, &points, &counts, output.vertices()),
            kernels.cells.bind(
                device,
                &entries(
                    shared,
                    &[
                        (slot::VERTICES, output.vertices()),
                        (slot::INDICES, output.indices()),
                        (slot::DRAW, output.indirect()),
                    ],
                ),
            ),
        ];
        Ok(Sized { output, binds })
    }
}

/// The uniform stage knows its output sizes before it runs, so it never grows; it takes
/// part in [`run_blocking`](crate::stage::run_blocking) like the adaptive stages.
impl crate::stage::GrowingStage for CcUniformStage {
    /// Vertices and indices the run wrote.
    type Status = (u32, u32);
    const MAX_GROWTHS: u32 = 1;
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.prepare(device, queue, encoder)
    }
    fn status(&mut self, device: &wgpu::Device) -> Result<(u32, u32)> {
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Readback(e.to_string()))?;
        Ok((self.vertex_count(), self.index_count()))
    }
    fn grow_to(&mut self, _device: &wgpu::Device, _status: &(u32, u32)) -> Result<bool> {
        Ok(false)
    }
}
