//! The first step of the adaptive stage's script: every patch's quadtree (its Bézier
//! nets, balls and corners) derived on the GPU from the control points, through the
//! stencil tables uploaded once per topology (`shaders/cc_stencil.wgsl`, twin
//! [`tessera_core::catmull_clark::stencil`]). Moving the points uploads the points and
//! the step's indirect dispatch arguments (six words); after the step they are cleared
//! to no workgroups, so a run whose points did not move costs the step nothing but two
//! empty dispatches.

use glam::Vec3;
use tessera_core::catmull_clark::stencil::CcStencils;

use super::{CcModelBuffers, NetPages};
use crate::error::{Error, Result};
use crate::kernel::{check_upload, groups_2d, init_buffer, init_storage, storage, Kernel};

/// The step's two kernels, compiled once per device.
pub(crate) struct CcStencilKernels {
    level1: Kernel,
    pieces: Kernel,
}

impl CcStencilKernels {
    pub fn new(device: &wgpu::Device, pages: NetPages) -> Self {
        let k = |entry| Kernel::specialised(device, "cc_stencil.wgsl", entry, &[], &pages.consts());
        CcStencilKernels {
            level1: k("level1"),
            pieces: k("pieces"),
        }
    }
}

/// The tables on the GPU, the control points, and the dispatch arguments that say they
/// moved.
#[doc(hidden)]
pub struct CcStencilBuffers {
    control: wgpu::Buffer,
    /// A uniform: 0, the records, the level-1 points.
    step: wgpu::Buffer,
    /// Both kernels' workgroups (x, y, z each): `dispatch_args` after the points moved,
    /// x cleared to 0 after the step.
    args: wgpu::Buffer,
    dispatch_args: [u32; 6],
    tables: Vec<wgpu::Buffer>,
    level1_points: wgpu::Buffer,
    control_count: usize,
    table_bytes: usize,
    derived_nets: usize,
}

/// Binding numbers of the tables, in the order [`CcStencilBuffers::tables`] holds them.
const TABLE_SLOTS: [u32; 7] = [71, 72, 74, 75, 77, 78, 79];

impl CcStencilBuffers {
    /// Uploads the tables and the control points `control`; the first run derives the
    /// quadtrees. [`Error::ModelTooLarge`] if a table is larger than a storage buffer the
    /// device can bind.
    pub fn new(device: &wgpu::Device, stencils: &CcStencils, control: &[Vec3]) -> Result<Self> {
        use bytemuck::cast_slice;
        let parts: [(&'static str, &[u8]); 7] = [
            (
                "level-1 stencil offsets",
                cast_slice(&stencils.level1_offsets),
            ),
            ("level-1 stencils", cast_slice(&stencils.level1_weights)),
            ("patch one-rings", cast_slice(&stencils.rings)),
            ("patch stencils", cast_slice(&stencils.patches)),
            ("stencil tables", cast_slice(&stencils.tables)),
            ("stencil records", cast_slice(&stencils.records)),
            ("stencil weights", cast_slice(&stencils.weights)),
        ];
        let level1_bytes = 16 * stencils.level1_count() as u64;
        for (what, bytes) in parts {
            check_upload(device, what, bytes.len() as u64)?;
        }
        check_upload(device, "level-1 points", level1_bytes)?;
        check_upload(device, "control points", 12 * control.len() as u64)?;
        let init = |label: &str, bytes: &[u8]| init_storage(device, label, bytes);
        let tables = parts
            .iter()
            .map(|(what, bytes)| init(what, bytes))
            .collect();
        let control_buffer = init("tessera cc control points", cast_slice(control));
        let level1_count = stencils.level1_count() as u32;
        let step = init_buffer(
            device,
            "tessera cc stencil step",
            cast_slice(&[0u32, stencils.record_count, level1_count, 0]),
            wgpu::BufferUsages::UNIFORM,
        );
        let (l1x, l1y) = groups_2d(level1_count.max(1), 64);
        let (px, py) = groups_2d(stencils.record_count.max(1), 64);
        let dispatch_args = [l1x, l1y, 1, px, py, 1];
        // The first run derives the quadtrees.
        let args = init_buffer(
            device,
            "tessera cc stencil dispatch args",
            cast_slice(&dispatch_args),
            wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
        );
        Ok(CcStencilBuffers {
            control: control_buffer,
            step,
            args,
            dispatch_args,
            tables,
            level1_points: storage(device, "tessera cc level-1 points", level1_bytes),
            control_count: control.len(),
            table_bytes: stencils.upload_bytes(),
            derived_nets: stencils.derived_nets(),
        })
    }

    /// New positions of the control points (same count; the stage checks them first):
    /// written through `queue`, with the word that makes the next run derive the
    /// quadtrees again. Nothing else moves.
    pub fn update(&self, queue: &wgpu::Queue, control: &[Vec3]) -> Result<()> {
        if control.len() != self.control_count {
            return Err(Error::Core(tessera_core::Error::Param(format!(
                "{} control points given, the mesh has {}",
                control.len(),
                self.control_count
            ))));
        }
        queue.write_buffer(&self.control, 0, bytemuck::cast_slice(control));
        queue.write_buffer(&self.args, 0, bytemuck::cast_slice(&self.dispatch_args));
        Ok(())
    }

    /// Bytes [`update`](Self::update) writes per frame.
    pub fn update_bytes(&self) -> usize {
        12 * self.control_count + std::mem::size_of_val(&self.dispatch_args)
    }

    /// Bytes uploaded once: the tables and the quadtrees' shape.
    pub fn table_bytes(&self) -> usize {
        self.table_bytes
    }

    /// Nets the step derives into the nets' pages (device memory, not upload).
    pub fn derived_nets(&self) -> usize {
        self.derived_nets
    }

    /// The bind groups of both kernels, writing into `model`.
    pub(crate) fn bind(
        &self,
        device: &wgpu::Device,
        kernels: &CcStencilKernels,
        model: &CcModelBuffers,
    ) -> [wgpu::BindGroup; 2] {
        let mut entries: Vec<(u32, &wgpu::Buffer)> = TABLE_SLOTS
            .iter()
            .zip(&self.tables)
            .map(|(&slot, buffer)| (slot, buffer))
            .collect();
        entries.extend([
            (70, &self.control),
            (73, &self.level1_points),
            (81, &model.corners),
            (82, &self.step),
        ]);
        let nets = model.net_outputs();
        [
            kernels.level1.bind(device, &entries),
            kernels.pieces.bind_with_textures(device, &entries, &nets),
        ]
    }

    /// Records the step into `pass`; returns the dispatches recorded (two).
    pub(crate) fn record(
        &self,
        pass: &mut wgpu::ComputePass,
        kernels: &CcStencilKernels,
        binds: &[wgpu::BindGroup; 2],
    ) -> u32 {
        kernels
            .level1
            .dispatch_indirect(pass, &binds[0], &self.args, 0)
            + kernels
                .pieces
                .dispatch_indirect(pass, &binds[1], &self.args, 12)
    }

    /// The step alone on its own submission, writing into `model` (made by
    /// [`CcModelBuffers::derived`] from the same tables): for the tests that compare the
    /// kernels with their twins.
    pub fn run(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &crate::Kernels,
        model: &CcModelBuffers,
    ) -> u32 {
        let stencil = kernels.cc_stencil(model.pages);
        let binds = self.bind(device, &stencil, model);
        let mut encoder = device.create_command_encoder(&Default::default());
        let dispatches = {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record(&mut pass, &stencil, &binds)
        };
        self.settle(&mut encoder);
        queue.submit([encoder.finish()]);
        dispatches
    }

    /// After the step, in the same encoder: the next run skips it unless the points move.
    pub(crate) fn settle(&self, encoder: &mut wgpu::CommandEncoder) {
        // Both steps' x counts to zero: no workgroups until the points move again.
        encoder.clear_buffer(&self.args, 0, Some(4));
        encoder.clear_buffer(&self.args, 12, Some(4));
    }
}
