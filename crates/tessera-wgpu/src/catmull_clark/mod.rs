//! The Catmull-Clark stages on the GPU: [`CcStage`] (the adaptive tessellation, module
//! `stage`) and [`CcUniformStage`] (the uniform peer, module `uniform`).
//!
//! Their parts are public for the tests that compare each kernel with its CPU twin, and
//! hidden from the docs: the patches' quadtrees uploaded once ([`CcModelBuffers`]), the
//! kernel that evaluates surface points exactly ([`CcVertexEval`],
//! `shaders/cc_vertex_eval.wgsl`, twin [`tessera_core::catmull_clark::gpu_model::vertex_eval`])
//! and the global vertex hash ([`CcVertexHash`], `shaders/cc_hash_*.wgsl`, twin
//! [`tessera_core::catmull_clark::vertex_hash`]).

mod stage;
mod stencil;
mod uniform;

pub(crate) use stage::CcKernels;
#[doc(hidden)]
pub use stage::{CcCapacities, CcPolygons};
pub use stage::{CcStage, CcStatus};
#[doc(hidden)]
pub use stencil::CcStencilBuffers;
pub(crate) use stencil::CcStencilKernels;
pub(crate) use uniform::CcUniformKernels;
pub use uniform::{CcUniformStage, UniformParams};

use tessera_core::catmull_clark::gpu_model::CcGpuModel;
use tessera_core::gpu_types::{CcHashSlot, CcHashStatus, CcNetLayout, CC_NET_PAGES};

use crate::error::{Error, Result};
use crate::kernel::{check_size, check_upload, init_storage, storage, storage_texture, Kernel};
use crate::scan::{PrefixSum, ScanKernels};

/// The flattened quadtrees on the GPU (bindings 20–27 of the Catmull-Clark kernels).
#[doc(hidden)]
pub struct CcModelBuffers {
    pub roots: wgpu::Buffer,
    pub nodes: wgpu::Buffer,
    pub splits: wgpu::Buffer,
    /// The Bézier nets in [`CC_NET_PAGES`] pages laid out as [`layout`](Self::layout)
    /// says (bindings 23, 25, 26, 27): read-only `rgba32float` storage textures, where a
    /// storage buffer read at per-lane addresses is a loop over the lanes on a CPU
    /// device, and the mark kernel reads nets more than anything else.
    pub nets: [wgpu::Texture; CC_NET_PAGES as usize],
    /// Where each net lies in the pages: the layout the kernels of this device read.
    pub layout: CcNetLayout,
    /// The pages the nets take, which the kernels reading them are compiled for.
    pub pages: NetPages,
    nets_views: [wgpu::TextureView; CC_NET_PAGES as usize],
    pub corners: wgpu::Buffer,
    sizes: [usize; 5],
}

/// The net pages a model takes, as the kernels that read them are compiled: kernels for
/// one page read it without a branch (the branches on the page cost lavapipe's marking
/// about a fifth of its time), kernels for four read any.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NetPages {
    /// Every net in the first page.
    One,
    /// Nets past the first page.
    Four,
}

impl NetPages {
    fn of(layout: &CcNetLayout, nets: usize) -> Self {
        if nets as u64 <= layout.nets_per_page() {
            NetPages::One
        } else {
            NetPages::Four
        }
    }

    /// Index of the kernels compiled for these pages.
    pub(crate) fn index(self) -> usize {
        self as usize
    }

    /// The kernels' constant.
    pub(crate) fn consts(self) -> [(&'static str, u32); 1] {
        let used = match self {
            NetPages::One => 1,
            NetPages::Four => CC_NET_PAGES,
        };
        [("CC_NET_PAGES_USED", used)]
    }
}

/// Binding numbers of the nets' pages where the kernels read them, and where the
/// stencil step writes them.
const NET_PAGE_SLOTS: [u32; CC_NET_PAGES as usize] = [23, 25, 26, 27];
const NET_OUT_SLOTS: [u32; CC_NET_PAGES as usize] = [80, 83, 84, 85];

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
    /// Uploads `model`; [`Error::ModelTooLarge`] if one of its arrays is larger than a
    /// storage buffer the device can bind, [`Error::TooManyNets`] if its nets are more
    /// than the pages hold (before anything is created).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, model: &CcGpuModel) -> Result<Self> {
        Self::create(device, queue, model, true)
    }

    /// As [`new`](Self::new) for the quadtrees the stencil step derives: the shape is
    /// uploaded, the nets and corners are only made room for.
    pub fn derived(device: &wgpu::Device, queue: &wgpu::Queue, shape: &CcGpuModel) -> Result<Self> {
        Self::create(device, queue, shape, false)
    }

    fn create(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        model: &CcGpuModel,
        geometry: bool,
    ) -> Result<Self> {
        // The nets are textures: their count is what the device limits (`CcNetLayout`).
        let names = [
            Some("patch roots"),
            Some("quadtree nodes"),
            Some("node splits"),
            None,
            Some("corner rings"),
        ];
        for (what, bytes) in names.into_iter().zip(byte_sizes(model)) {
            if let Some(what) = what {
                check_upload(device, what, bytes as u64)?;
            }
        }
        let layout = CcNetLayout::new(device.limits().max_texture_dimension_2d);
        if model.nets.len() as u64 > layout.capacity() {
            return Err(Error::TooManyNets {
                nets: model.nets.len() as u64,
                capacity: layout.capacity(),
            });
        }
        let init = |label: &str, bytes: &[u8]| init_storage(device, label, bytes);
        let format = wgpu::TextureFormat::Rgba32Float;
        let sizes = layout.page_sizes(model.nets.len());
        // Written through the queue when uploaded; read back by the tests that compare
        // the stencil step with its twin.
        let nets: [wgpu::Texture; CC_NET_PAGES as usize] = std::array::from_fn(|page| {
            storage_texture(
                device,
                "tessera cc net page",
                format,
                sizes[page],
                wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
            )
        });
        let corners = if geometry {
            init("tessera cc corners", bytemuck::cast_slice(&model.corners))
        } else {
            // Never smaller than one corner: bindings are never empty.
            let bytes = std::mem::size_of_val(model.corners.as_slice())
                .max(std::mem::size_of::<tessera_core::gpu_types::CcCorner>());
            storage(device, "tessera cc corners", bytes as u64)
        };
        let buffers = CcModelBuffers {
            roots: init("tessera cc roots", bytemuck::cast_slice(&model.roots)),
            nodes: init("tessera cc nodes", bytemuck::cast_slice(&model.nodes)),
            splits: init("tessera cc splits", bytemuck::cast_slice(&model.splits)),
            nets_views: std::array::from_fn(|page| nets[page].create_view(&Default::default())),
            nets,
            layout,
            pages: NetPages::of(&layout, model.nets.len()),
            corners,
            sizes: byte_sizes(model),
        };
        if geometry {
            buffers.write_nets(queue, &model.nets);
        }
        Ok(buffers)
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
        write(&self.corners, bytemuck::cast_slice(&model.corners));
        self.write_nets(queue, &model.nets);
        Ok(())
    }

    fn write_nets(&self, queue: &wgpu::Queue, nets: &[tessera_core::gpu_types::GpuPatch]) {
        for (texture, texels) in self.nets.iter().zip(self.layout.pages(nets)) {
            queue.write_texture(
                texture.as_image_copy(),
                bytemuck::cast_slice(&texels),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(16 * texture.width()),
                    rows_per_image: None,
                },
                texture.size(),
            );
        }
    }

    /// Bytes on the GPU.
    pub fn byte_size(&self) -> usize {
        self.sizes.iter().sum()
    }

    fn entries(&self) -> [(u32, &wgpu::Buffer); 4] {
        [
            (20, &self.roots),
            (21, &self.nodes),
            (22, &self.splits),
            (24, &self.corners),
        ]
    }

    fn textures(&self) -> [(u32, &wgpu::TextureView); CC_NET_PAGES as usize] {
        std::array::from_fn(|page| (NET_PAGE_SLOTS[page], &self.nets_views[page]))
    }

    /// The pages where the stencil step writes them.
    fn net_outputs(&self) -> [(u32, &wgpu::TextureView); CC_NET_PAGES as usize] {
        std::array::from_fn(|page| (NET_OUT_SLOTS[page], &self.nets_views[page]))
    }
}

/// The kernel that evaluates vertices (a point `(patch, u, v)` with its face and face
/// `(u, v)`) into output vertices.
#[doc(hidden)]
pub struct CcVertexEval {
    kernel: Kernel,
}

impl CcVertexEval {
    pub fn new(device: &wgpu::Device, pages: NetPages) -> Self {
        CcVertexEval {
            kernel: Kernel::specialised(
                device,
                "cc_vertex_eval.wgsl",
                "main",
                &[],
                &pages.consts(),
            ),
        }
    }

    /// Records the evaluation of the first `counts[0]` of `points` ([`CcVertexPoint`]s;
    /// at most `max_points` invocations) into `out` ([`OutVertex`]s).
    ///
    /// [`CcVertexPoint`]: tessera_core::gpu_types::CcVertexPoint
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
        let bind = self.bind(device, model, points, counts, out);
        self.record_bound(encoder, &bind, max_points);
    }

    /// The bind group of [`record`](Self::record), to keep across frames.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        model: &CcModelBuffers,
        points: &wgpu::Buffer,
        counts: &wgpu::Buffer,
        out: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let mut entries = model.entries().to_vec();
        entries.extend([(30, points), (31, out), (32, counts)]);
        self.kernel
            .bind_with_textures(device, &entries, &model.textures())
    }

    /// [`record`](Self::record) with a bind group made by [`bind`](Self::bind).
    pub fn record_bound(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind: &wgpu::BindGroup,
        max_points: u32,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessera cc_vertex_eval"),
            timestamp_writes: None,
        });
        self.kernel.dispatch(&mut pass, bind, max_points, 64);
    }

    /// [`record_bound`](Self::record_bound) with the number of workgroups read from
    /// `args` at `offset` (indirect dispatch arguments written by an earlier kernel).
    pub fn record_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind: &wgpu::BindGroup,
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessera cc_vertex_eval"),
            timestamp_writes: None,
        });
        self.kernel.dispatch_indirect(&mut pass, bind, args, offset);
    }
}

/// The vertex-hash kernels (`cc_hash_insert.wgsl`, `cc_hash_number.wgsl`) and the scan.
#[doc(hidden)]
pub struct CcHashKernels {
    insert: Kernel,
    mark_first: Kernel,
    assign: Kernel,
    scan: ScanKernels,
}

impl CcHashKernels {
    pub fn new(device: &wgpu::Device) -> Self {
        CcHashKernels {
            insert: Kernel::new(device, "cc_hash_insert.wgsl", "main"),
            mark_first: Kernel::new(device, "cc_hash_number.wgsl", "mark_first"),
            assign: Kernel::new(device, "cc_hash_number.wgsl", "assign"),
            scan: ScanKernels::new(device),
        }
    }
}

/// Bind groups of the vertex-hash kernels over one set of buffers.
#[doc(hidden)]
pub struct CcHashBinds {
    insert: wgpu::BindGroup,
    mark_first: wgpu::BindGroup,
    assign: wgpu::BindGroup,
}

/// The global vertex hash: canonical keys in, a vertex number per key and the distinct
/// keys in order of first occurrence out (twin:
/// [`tessera_core::catmull_clark::vertex_hash`]). The table overflowing is reported in
/// the status and fixed by [`grow`](Self::grow) and a rerun, like every other buffer.
#[doc(hidden)]
pub struct CcVertexHash {
    /// Slots (a power of two).
    pub capacity: u32,
    /// Items (keys) the item buffers hold.
    pub item_capacity: u32,
    pub table: wgpu::Buffer,
    pub item_slot: wgpu::Buffer,
    pub offsets: wgpu::Buffer,
    /// Vertex number per item.
    pub ids: wgpu::Buffer,
    /// Distinct keys (`[hi, lo]`), in order of first occurrence.
    pub unique_keys: wgpu::Buffer,
    /// [`CcHashStatus`](tessera_core::gpu_types::CcHashStatus).
    pub status: wgpu::Buffer,
    prefix: PrefixSum,
}

impl CcVertexHash {
    /// Buffers for `item_capacity` keys and a table of at least `capacity` slots.
    pub fn new(
        device: &wgpu::Device,
        kernels: &CcHashKernels,
        item_capacity: u32,
        capacity: u32,
    ) -> Self {
        let capacity = capacity.max(1).next_power_of_two();
        let items = item_capacity.max(1) as u64;
        let slot_bytes = std::mem::size_of::<CcHashSlot>() as u64;
        let offsets = storage(device, "tessera cc hash offsets", 4 * items);
        let status = storage(
            device,
            "tessera cc hash status",
            std::mem::size_of::<CcHashStatus>() as u64,
        );
        // Scanned as far as there are items (CcHashStatus::items, word 0).
        let prefix =
            PrefixSum::with_live_count(device, &kernels.scan, &offsets, items as u32, (&status, 0));
        CcVertexHash {
            capacity,
            item_capacity: items as u32,
            table: storage(
                device,
                "tessera cc hash table",
                slot_bytes * capacity as u64,
            ),
            item_slot: storage(device, "tessera cc hash item slots", 4 * items),
            offsets,
            ids: storage(device, "tessera cc vertex ids", 4 * items),
            unique_keys: storage(device, "tessera cc unique keys", 8 * items),
            status,
            prefix,
        }
    }

    /// Writes the status for a run over the first `items` keys (at most the item
    /// capacity).
    pub fn start(&self, queue: &wgpu::Queue, items: u32) {
        let status = CcHashStatus {
            items: items.min(self.item_capacity),
            ..Default::default()
        };
        queue.write_buffer(&self.status, 0, bytemuck::bytes_of(&status));
    }

    /// Records insertion and numbering of `keys` (`[hi, lo]` pairs) into `encoder`.
    /// [`start`](Self::start) sets how many.
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        kernels: &CcHashKernels,
        keys: &wgpu::Buffer,
    ) {
        let binds = self.bind(device, kernels, keys);
        self.record_bound(encoder, kernels, &binds);
    }

    /// The bind groups of [`record`](Self::record), to keep across frames (valid until
    /// [`grow`](Self::grow)).
    pub fn bind(
        &self,
        device: &wgpu::Device,
        kernels: &CcHashKernels,
        keys: &wgpu::Buffer,
    ) -> CcHashBinds {
        let entries = [
            (40, keys),
            (41, &self.table),
            (42, &self.item_slot),
            (43, &self.status),
            (44, &self.offsets),
            (45, &self.ids),
            (46, &self.unique_keys),
        ];
        CcHashBinds {
            insert: kernels.insert.bind(device, &entries),
            mark_first: kernels.mark_first.bind(device, &entries),
            assign: kernels.assign.bind(device, &entries),
        }
    }

    /// [`record`](Self::record) with bind groups made by [`bind`](Self::bind).
    pub fn record_bound(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kernels: &CcHashKernels,
        binds: &CcHashBinds,
    ) {
        self.record_dispatch(encoder, kernels, binds, None);
    }

    /// [`record_bound`](Self::record_bound) with the number of workgroups read from
    /// `args` at `offset` (indirect dispatch arguments for the item count an earlier
    /// kernel wrote), so that a run costs what it holds rather than the capacity.
    pub fn record_indirect(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kernels: &CcHashKernels,
        binds: &CcHashBinds,
        args: &wgpu::Buffer,
        offset: u64,
    ) {
        self.record_dispatch(encoder, kernels, binds, Some((args, offset)));
    }

    fn record_dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kernels: &CcHashKernels,
        binds: &CcHashBinds,
        args: Option<(&wgpu::Buffer, u64)>,
    ) {
        encoder.clear_buffer(&self.table, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tessera cc vertex hash"),
            timestamp_writes: None,
        });
        let n = self.item_capacity;
        let run = |pass: &mut wgpu::ComputePass, kernel: &Kernel, bind: &wgpu::BindGroup| match args
        {
            Some((buffer, offset)) => kernel.dispatch_indirect(pass, bind, buffer, offset),
            None => kernel.dispatch(pass, bind, n, 64),
        };
        run(&mut pass, &kernels.insert, &binds.insert);
        run(&mut pass, &kernels.mark_first, &binds.mark_first);
        self.prefix.record(&mut pass, &kernels.scan);
        run(&mut pass, &kernels.assign, &binds.assign);
    }

    /// After an overflow: a table twice as large (and at least twice the items), same
    /// item buffers. Errors past the device's buffer size limit.
    pub fn grow(&mut self, device: &wgpu::Device) -> Result<()> {
        let capacity = (2 * self.capacity).max((2 * self.item_capacity).next_power_of_two());
        let bytes = capacity as u64 * std::mem::size_of::<CcHashSlot>() as u64;
        check_size(device, "vertex hash", bytes)?;
        self.table = storage(device, "tessera cc hash table", bytes);
        self.capacity = capacity;
        Ok(())
    }
}
