//! The Bézier (displacement-map) tessellation stage: the GPU twin of
//! [`tessera_core::bezier::tessellate_adaptive`].
//!
//! [`BezierStage::prepare`] records one straight-line script into the caller's encoder:
//!
//! | # | kernel | per | writes |
//! |---|---|---|---|
//! | 0 | `bezier_map_cells` | map cell | the displacement-map atlas, built from the maps as uploaded (so that moved patches need only their maps written again) |
//! | 1 | clear + `bezier_edge_decide` | coarse edge | edge bit sets (in the `r32uint` scratch texture, after the triangles' words), edge vertex counts |
//! | 2 | `bezier_tri_roots` + `bezier_tri_mark` (indirect, over the triangles whose root may split) | coarse triangle | lattice points (bit sets in the scratch texture, cleared by copies of zeros before step 1), inner vertex and triangle counts, emit-order buckets |
//! | 3 | `scan` (two dispatches) | — | offsets of all three counts in one exclusive scan |
//! | 4 | `bezier_finish` | 1 | totals, overflow flags, draw arguments, vertex dispatch, the emit order's bucket slots |
//! | 4b | `bezier_tri_order` | coarse triangle | the emit order: those that make the most triangles first, the plain ones (no points; one triangle) last |
//! | 5 | copy + `bezier_edge_emit` + `bezier_tri_emit` + `bezier_tri_emit_plain` (in the emit order, both indirect) | edge / triangle | vertex records, indices |
//! | 6 | `bezier_vertex_eval` (indirect) | output vertex | vertices |
//!
//! Output sizes are not known in advance, and change with the threshold and depth. The
//! finish kernel compares what the run needs with the capacities; on overflow no emit
//! kernel writes anything, the draw has zero indices, and [`BezierStage::read_status`]
//! reports the sizes needed. The status of each run is read back without blocking, and
//! the next [`BezierStage::prepare`] that finds it grows the buffers, so the run after
//! that fits. After loading or a change of parameters, [`BezierStage::run_blocking`]
//! grows and reruns at once.
//!
//! ```no_run
//! use tessera_core::bezier::{AdaptiveParams, BezierModel, EdgeTest, PreparedBezier};
//! use tessera_wgpu::{bezier::BezierStage, headless::Gpu, Kernels};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let gpu = Gpu::new()?;
//! let model = BezierModel::load(std::path::Path::new("assets/teaset/teapot"))?;
//! let prepared = PreparedBezier::new(&model);
//! let params = AdaptiveParams { test: EdgeTest::Map4p, threshold: 0.01, max_depth: 6 };
//! let kernels = Kernels::new(&gpu.device);
//! let mut stage = BezierStage::new(&gpu.device, &gpu.queue, &kernels, &prepared, &params)?;
//! // Each frame (or when the threshold changes): record, then submit with your own work.
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! stage.prepare(&gpu.device, &gpu.queue, &mut encoder)?;
//! gpu.queue.submit([encoder.finish()]);
//! // After loading and after `set_params`: make sure the buffers were large enough
//! // (grow and rerun if not).
//! let status = stage.run_blocking(&gpu.device, &gpu.queue)?;
//! println!("{} triangles", status.indices / 3);
//! // Draw `stage.output()` with `draw_indexed_indirect`, e.g. through `render::MeshRenderer`.
//! # Ok(()) }
//! ```

use std::sync::{Arc, OnceLock};

use glam::Vec3;
use tessera_core::bezier::lattice::{inv_lattice, Lattice};
use tessera_core::bezier::{
    patch_thresholds, AdaptiveParams, BezierView, EdgeTest, PreparedBezier,
};
use tessera_core::gpu_types::{
    tally, BezierParams, BezierStatus, MapAtlas, MapHalves, NetTexture, OutVertex, TopologyTexture,
    VertexRecord, EDGE_BIT_WORDS, MAP_CELLS, MAX_DEPTH_LIMIT,
};
use tessera_core::Mesh;

use crate::error::{Error, Result};
use crate::kernel::{
    allocating, check_size, check_upload, init_buffer, storage, storage_texture, upload_texture,
    Kernel,
};
use crate::output::MeshBuffers;
use crate::readback::{read_buffer, read_texture};
use crate::scan::{PrefixSum, ScanKernels};
use crate::stage::{GrowingStage, Passes, RunTimestamps, StatusReadback};
use crate::Kernels;

/// Limits the stages need, within what `adapter` offers: large storage buffers and 2D
/// textures for big models (the Catmull-Clark nets lie in four pages as large as the
/// device's side allows, so it bounds the nets a model may derive); no more than 8
/// storage buffers and 4 storage textures per kernel, so WebGPU's defaults suffice there.
pub fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    wgpu::Limits {
        max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
        max_buffer_size: adapter.max_buffer_size,
        max_texture_dimension_2d: adapter.max_texture_dimension_2d,
        ..wgpu::Limits::default()
    }
}

const WORKGROUP: u32 = 64;

/// Binding numbers shared by every Bézier kernel (see `shaders/shared/types.wgsl`).
mod slot {
    pub const PARAMS: u32 = 0;
    pub const NETS: u32 = 1;
    pub const MAPS: u32 = 2;
    pub const TOPOLOGY: u32 = 3;
    pub const COUNTS: u32 = 7;
    pub const SCRATCH: u32 = 8;
    pub const RECORDS: u32 = 9;
    pub const VERTICES: u32 = 10;
    pub const INDICES: u32 = 11;
    pub const DRAW_ARGS: u32 = 12;
    pub const STATUS: u32 = 13;
    pub const TALLY: u32 = 14;
    pub const MAP_HALVES: u32 = 16;
    pub const MAP_ATLAS_STORE: u32 = 17;
    pub const THRESHOLDS: u32 = 18;
}

/// The compiled Bézier kernels of one device (part of [`Kernels`]). The kernels that run
/// the edge test are compiled for one test each (see [`TestKernels`]), the first time a
/// stage uses that test.
#[derive(Clone)]
pub(crate) struct BezierKernels(Arc<Pipelines>);

impl BezierKernels {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        BezierKernels(Arc::new(Pipelines::new(device)))
    }

    /// The kernels specialised for `params` (test and depth), compiled on first use.
    fn for_params(&self, device: &wgpu::Device, params: &AdaptiveParams) -> Arc<TestKernels> {
        let array_depth = array_depth(params.max_depth);
        let class = (array_depth - ARRAY_DEPTH_CLASSES[0]) as usize;
        self.0.by_test[params.test.index() as usize][class]
            .get_or_init(|| Arc::new(TestKernels::new(device, params.test, array_depth)))
            .clone()
    }
}

/// The lattice depths the triangle kernels' private arrays are sized for
/// (`ARRAY_DEPTH` in `shaders/shared/refine.wgsl`): a depth runs on the kernels of the
/// first class at or above it.
const ARRAY_DEPTH_CLASSES: [u32; 3] = [AdaptiveParams::DEFAULT_MAX_DEPTH, 7, MAX_DEPTH_LIMIT];

fn array_depth(max_depth: u32) -> u32 {
    max_depth.max(ARRAY_DEPTH_CLASSES[0])
}

struct Pipelines {
    by_test: [[OnceLock<Arc<TestKernels>>; ARRAY_DEPTH_CLASSES.len()]; EdgeTest::ALL.len()],
    scan: ScanKernels,
    finish: Kernel,
    tri_roots: Kernel,
    map_cells: Kernel,
    tri_order: Kernel,
    tri_emit_plain: Kernel,
    edge_emit: Kernel,
    vertex_eval: Kernel,
}

impl Pipelines {
    fn new(device: &wgpu::Device) -> Self {
        let make = |file: &str| Kernel::new(device, file, "main");
        Pipelines {
            by_test: Default::default(),
            scan: ScanKernels::new(device),
            finish: make("bezier_finish.wgsl"),
            // It runs no edge test (its roots are decided by their side's bits), but the
            // shared refinement code it includes declares the test's override.
            tri_roots: Kernel::with_constants(
                device,
                "bezier_tri_roots.wgsl",
                "main",
                &[("EDGE_TEST", EdgeTest::Map4p.index() as f64)],
            ),
            map_cells: make("bezier_map_cells.wgsl"),
            tri_order: make("bezier_tri_order.wgsl"),
            tri_emit_plain: make("bezier_tri_emit_plain.wgsl"),
            edge_emit: make("bezier_edge_emit.wgsl"),
            vertex_eval: make("bezier_vertex_eval.wgsl"),
        }
    }
}

/// The kernels that include `shaders/shared/need.wgsl`, with its `EDGE_TEST` constant
/// fixed. A CPU device runs both sides of every branch, so a test chosen at run time made
/// each decision pay for all four; fixed, the compiler drops the other three.
/// `tri_emit` runs no test but includes the file, so it needs the constant too.
///
/// The triangle kernels' private arrays are sized for `array_depth`: every invocation
/// zeroes them, so arrays sized for `MAX_DEPTH_LIMIT` would cost every run at the
/// common depths what only the deepest need.
struct TestKernels {
    edge_decide: Kernel,
    tri_mark: Kernel,
    tri_emit: Kernel,
}

impl TestKernels {
    fn new(device: &wgpu::Device, test: EdgeTest, array_depth: u32) -> Self {
        let constants = [("EDGE_TEST", test.index() as f64)];
        let sized = [("ARRAY_DEPTH", array_depth)];
        let make = |file: &str| Kernel::specialised(device, file, "main", &constants, &sized);
        TestKernels {
            edge_decide: Kernel::with_constants(
                device,
                "bezier_edge_decide.wgsl",
                "main",
                &constants,
            ),
            tri_mark: make("bezier_tri_mark.wgsl"),
            tri_emit: make("bezier_tri_emit.wgsl"),
        }
    }
}

/// The steps of the script, in order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Step {
    MapCells,
    EdgeDecide,
    TriMark,
    ScanFinish,
    TriOrder,
    EdgeEmit,
    TriEmit,
    VertexEval,
}

impl Step {
    const ALL: [Step; 8] = [
        Step::MapCells,
        Step::EdgeDecide,
        Step::TriMark,
        Step::ScanFinish,
        Step::TriOrder,
        Step::EdgeEmit,
        Step::TriEmit,
        Step::VertexEval,
    ];

    fn name(self) -> &'static str {
        match self {
            Step::MapCells => "map_cells",
            Step::EdgeDecide => "edge_decide",
            Step::TriMark => "tri_mark",
            Step::ScanFinish => "scan+finish",
            Step::TriOrder => "tri_order",
            Step::EdgeEmit => "edge_emit",
            Step::TriEmit => "tri_emit",
            Step::VertexEval => "vertex_eval",
        }
    }
}

struct BindGroups {
    edge_decide: wgpu::BindGroup,
    tri_roots: wgpu::BindGroup,
    tri_mark: wgpu::BindGroup,
    finish: wgpu::BindGroup,
    tri_order: wgpu::BindGroup,
    edge_emit: wgpu::BindGroup,
    tri_emit: wgpu::BindGroup,
    tri_emit_plain: wgpu::BindGroup,
    vertex_eval: wgpu::BindGroup,
}

impl BindGroups {
    /// Every buffer under its binding number; each kernel takes the ones its entry point
    /// uses (see [`Kernel::bind`]).
    fn new(device: &wgpu::Device, p: &Pipelines, t: &TestKernels, b: &Buffers) -> Self {
        use slot::*;
        let all = [
            (PARAMS, &b.uniform),
            (COUNTS, &b.counts),
            (RECORDS, &b.records),
            (VERTICES, b.output.vertices()),
            (INDICES, b.output.indices()),
            (DRAW_ARGS, b.output.indirect()),
            (STATUS, &b.status),
            (TALLY, &b.tally),
            (THRESHOLDS, &b.thresholds),
        ];
        let textures = [
            (NETS, &b.nets),
            (TOPOLOGY, &b.topology),
            (MAPS, &b.map_atlas),
            (SCRATCH, &b.scratch.view),
        ];
        let bind = |k: &Kernel| k.bind_with_textures(device, &all, &textures);
        BindGroups {
            edge_decide: bind(&t.edge_decide),
            tri_roots: bind(&p.tri_roots),
            tri_mark: bind(&t.tri_mark),
            finish: bind(&p.finish),
            tri_order: bind(&p.tri_order),
            edge_emit: bind(&p.edge_emit),
            tri_emit: bind(&t.tri_emit),
            tri_emit_plain: bind(&p.tri_emit_plain),
            vertex_eval: bind(&p.vertex_eval),
        }
    }
}

/// The embeddable Bézier stage: uploads a prepared model once, records its kernels into
/// the caller's encoder, and leaves [`MeshBuffers`] on the GPU.
pub struct BezierStage {
    /// See [`BezierParams::map_scale`].
    map_scale: f32,
    /// The maps as uploaded ([`MapHalves`]), bound to the kernel that builds the map
    /// atlas from them at the start of every run.
    map_cells: wgpu::BindGroup,
    /// The parameters last written to their uniform.
    written: Option<BezierParams>,
    readback: StatusReadback,
    /// The newest status read back, and whether the buffers are still to grow for it.
    latest: Option<(BezierStatus, bool)>,
    growths: u32,
    prepared_layout: tessera_core::bezier::prepare::CoarseLayout,
    params: AdaptiveParams,
    /// The control points, which the view's thresholds are scaled from, and whether each
    /// patch's winding is flipped (which way it faces).
    control_points: Vec<[Vec3; 16]>,
    flipped: Vec<bool>,
    /// The view the thresholds are in, if any.
    view: Option<BezierView>,
    buffers: Buffers,
    pipelines: BezierKernels,
    /// The test-specific kernels of `params.test`.
    test_kernels: Arc<TestKernels>,
    bind_groups: BindGroups,
}

/// Every buffer of a stage: the upload, the working buffers, the output.
struct Buffers {
    uniform: wgpu::Buffer,
    /// The control points ([`NetTexture`]).
    nets: wgpu::TextureView,
    /// The displacement maps as half-precision cells ([`MapAtlas`]).
    map_atlas: wgpu::TextureView,
    map_atlas_texture: wgpu::Texture,
    /// Patch topology and curves ([`TopologyTexture`]).
    topology: wgpu::TextureView,
    coarse_records: wgpu::Buffer,
    counts: wgpu::Buffer,
    scan: PrefixSum,
    scratch: Scratch,
    records: wgpu::Buffer,
    status: wgpu::Buffer,
    /// The maps as uploaded, the atlas's source.
    map_halves: wgpu::Buffer,
    /// Atomic counters, zeroed each run: the flat test's evaluations, the emit order's
    /// buckets and the mark kernel's list length ([`tally`]).
    tally: wgpu::Buffer,
    /// Each patch's edge-test threshold ([`tessera_core::bezier::patch_thresholds`]).
    thresholds: wgpu::Buffer,
    output: MeshBuffers,
}

/// Words per coarse triangle in the scratch texture at `depth`: lattice points, then
/// collapsed-side points; one word of the points' nonzero groups follows them
/// (`TriScratch::words`).
fn triangle_words(depth: u32) -> (u32, u32) {
    let points = Lattice::points_words(depth) as u32;
    let pole = (3 * ((1u32 << depth) + 1)).div_ceil(32);
    (points, pole)
}

/// A coarse triangle's words in the scratch texture, its group word included.
fn triangle_stride(depth: u32) -> u32 {
    let (points, pole) = triangle_words(depth);
    points + pole + 1
}

/// Where the scratch's words are (twin of `scratch_texel`'s callers in the shaders): each
/// coarse triangle's `triangle_stride` words, then each coarse edge's bit set,
/// `EDGE_BIT_WORDS` words from `edge_sets` on (`edge_set_word`).
#[derive(Clone, Copy)]
struct ScratchLayout {
    edge_sets: u64,
    words: u64,
}

impl ScratchLayout {
    fn new(depth: u32, l: tessera_core::bezier::prepare::CoarseLayout) -> Self {
        let edge_sets = triangle_stride(depth) as u64 * l.coarse_triangles as u64;
        ScratchLayout {
            edge_sets,
            words: edge_sets + EDGE_BIT_WORDS as u64 * l.coarse_edges as u64,
        }
    }
}

/// The coarse triangles' bit sets, then the coarse edges' ([`ScratchLayout`]): word `w`
/// is texel `(w mod width, w / width)` of an `r32uint` storage texture, `width = 1 <<
/// shift`. A texture, not a buffer: a CPU device (llvmpipe) reads a storage buffer at
/// per-lane addresses in a loop over the lanes that stalls on each lane's insert, and
/// reads a storage texture with plain loads.
struct Scratch {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    shift: u32,
    /// The rows that hold the triangles' words, the ones each run clears (the edge
    /// kernel writes every word of the edges' sets).
    triangle_rows: u32,
    /// Zeros for clearing it, `ZERO_ROWS` rows at most: copied over the texture in
    /// bands, since clearing a texture directly needs a feature WebGPU lacks.
    zeros: wgpu::Buffer,
}

impl Scratch {
    /// Rows of zeros copied at once when the texture is cleared.
    const ZERO_ROWS: u32 = 64;

    fn new(device: &wgpu::Device, layout: ScratchLayout) -> Result<Self> {
        let words = layout.words;
        let max_side = device.limits().max_texture_dimension_2d;
        // As wide as the words need up to the widest power of two the device allows
        // (and 64 words at least: copy rows are multiples of 256 bytes).
        let widest = 1u32 << (31 - max_side.leading_zeros());
        let width = (words.next_power_of_two() as u32).clamp(64, widest);
        let height = words.div_ceil(width as u64);
        if height > max_side as u64 {
            return Err(Error::OutputTooLarge {
                what: "scratch",
                bytes: 4 * words,
                limit: 4 * widest as u64 * max_side as u64,
            });
        }
        let texture = storage_texture(
            device,
            "tessera scratch",
            wgpu::TextureFormat::R32Uint,
            (width, height as u32),
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        );
        let triangle_rows = layout.edge_sets.div_ceil(width as u64) as u32;
        let zero_rows = triangle_rows.clamp(1, Self::ZERO_ROWS);
        Ok(Scratch {
            view: texture.create_view(&Default::default()),
            texture,
            shift: width.trailing_zeros(),
            triangle_rows,
            zeros: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera scratch zeros"),
                size: 4 * width as u64 * zero_rows as u64,
                usage: wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
        })
    }

    /// Records the copies that zero the triangles' words (and the first edge words that
    /// share their last row, which the edge kernel writes after).
    fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        let (width, height) = (self.texture.width(), self.triangle_rows);
        let band = Self::ZERO_ROWS.min(height).max(1);
        for y in (0..height).step_by(band as usize) {
            let rows = band.min(height - y);
            encoder.copy_buffer_to_texture(
                wgpu::TexelCopyBufferInfo {
                    buffer: &self.zeros,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(4 * width),
                        rows_per_image: None,
                    },
                },
                wgpu::TexelCopyTextureInfo {
                    texture: &self.texture,
                    mip_level: 0,
                    origin: wgpu::Origin3d { x: 0, y, z: 0 },
                    aspect: wgpu::TextureAspect::All,
                },
                wgpu::Extent3d {
                    width,
                    height: rows,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
}

/// Never empty (`init_buffer` pads to 4 bytes). COPY_DST: moved patches write them again
/// (`update_model`).
fn upload(device: &wgpu::Device, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    init_buffer(device, label, bytes, usage)
}

impl BezierStage {
    /// Uploads `prepared` through `queue`, with output capacity estimated from the model
    /// (grown on demand), and compiles the Bézier kernels into `kernels` if no stage has.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        prepared: &PreparedBezier,
        params: &AdaptiveParams,
    ) -> Result<Self> {
        let l = prepared.layout;
        Self::with_capacity(
            device,
            queue,
            kernels,
            prepared,
            params,
            (4 * l.coarse_vertices, 3 * 8 * l.coarse_triangles),
        )
    }

    /// As [`BezierStage::new`] with explicit initial capacities (vertices, indices), for
    /// the tests that grow from one-element buffers.
    #[doc(hidden)]
    pub fn with_capacity(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        prepared: &PreparedBezier,
        params: &AdaptiveParams,
        (vertex_capacity, index_capacity): (u32, u32),
    ) -> Result<Self> {
        allocating(device, "the stage's model and buffers", || {
            kernels.check_device(device)?;
            params.validate()?;
            let l = prepared.layout;
            let counts_len = l.coarse_edges + 2 * l.coarse_triangles + 1;
            let pipelines = kernels.bezier().clone();
            let test_kernels = pipelines.for_params(device, params);
            // The scan's values, then the emit order and each triangle's bucket in it.
            let counts_bytes = 4 * (counts_len as u64 + 2 * l.coarse_triangles as u64);
            check_size(device, "count", counts_bytes)?;
            let counts = storage(device, "tessera counts", counts_bytes);
            let scan = PrefixSum::new(device, &pipelines.0.scan, &counts, counts_len);
            let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera bezier params"),
                size: std::mem::size_of::<BezierParams>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let vertex_capacity = vertex_capacity.max(l.coarse_vertices);
            let output = MeshBuffers::with_capacity(device, vertex_capacity, index_capacity);
            let status = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera bezier status"),
                size: std::mem::size_of::<BezierStatus>() as u64,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::INDIRECT
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let coarse_records = prepared.coarse_vertex_records();
            for (what, bytes) in [
                (
                    "patch topology",
                    TopologyTexture::bytes(prepared.topo.len(), prepared.curves.len()) as usize,
                ),
                (
                    "coarse vertices",
                    std::mem::size_of_val(coarse_records.as_slice()),
                ),
                (
                    "displacement maps",
                    MapHalves::bytes(prepared.maps.len()) as usize,
                ),
            ] {
                check_upload(device, what, bytes as u64)?;
            }
            let (width, height) = MapAtlas::size(prepared.maps.len());
            let max_side = device.limits().max_texture_dimension_2d;
            if width > max_side || height > max_side {
                return Err(Error::MapAtlasTooLarge {
                    patches: l.patches,
                    width,
                    height,
                    limit: max_side,
                });
            }
            // The atlas is built on the device from the maps as uploaded (`MapHalves`, 512
            // of its 1800 bytes per patch), by `bezier_map_cells` at the start of each run:
            // written by it, read by the kernels, a storage texture both ways.
            let map_atlas = storage_texture(
                device,
                "tessera displacement-map atlas",
                wgpu::TextureFormat::Rgba16Float,
                (width, height),
                wgpu::TextureUsages::COPY_SRC,
            );
            let map_atlas_view = map_atlas.create_view(&Default::default());
            let halves = MapHalves::new(&prepared.maps, prepared.map_scale);
            let map_halves = upload(
                device,
                "tessera displacement maps",
                bytemuck::cast_slice(&halves.words),
            );
            let map_cells = pipelines.0.map_cells.bind_with_textures(
                device,
                &[(slot::PARAMS, &uniform), (slot::MAP_HALVES, &map_halves)],
                &[(slot::MAP_ATLAS_STORE, &map_atlas_view)],
            );
            // Smaller than the atlas both ways: its size check covers this one.
            let nets = NetTexture::new(&prepared.patches);
            let nets_texture = upload_texture(
                device,
                queue,
                "tessera control-net texture",
                wgpu::TextureFormat::Rgba32Float,
                (nets.width, nets.height),
                bytemuck::cast_slice(&nets.texels),
            );
            // Narrower than the atlas and fewer rows (at most 7 texels per patch, 1024 per
            // row, where the atlas has 15 rows per 256 patches): its size check covers it.
            let topology = TopologyTexture::new(&prepared.topo, &prepared.curves);
            let topology_texture = upload_texture(
                device,
                queue,
                "tessera topology texture",
                wgpu::TextureFormat::Rgba32Uint,
                (topology.width, topology.height),
                bytemuck::cast_slice(&topology.texels),
            );
            let buffers = Buffers {
                uniform,
                nets: nets_texture.create_view(&Default::default()),
                map_atlas: map_atlas_view,
                map_atlas_texture: map_atlas,
                topology: topology_texture.create_view(&Default::default()),
                coarse_records: upload(
                    device,
                    "tessera coarse vertices",
                    bytemuck::cast_slice(&coarse_records),
                ),
                counts,
                scan,
                scratch: Scratch::new(device, ScratchLayout::new(params.max_depth, l))?,
                records: storage(
                    device,
                    "tessera vertex records",
                    vertex_capacity as u64 * std::mem::size_of::<VertexRecord>() as u64,
                ),
                status,
                map_halves,
                tally: storage(
                    device,
                    "tessera tally",
                    4 * tally::words(l.coarse_vertices) as u64,
                ),
                thresholds: device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("tessera bezier thresholds"),
                    size: 4 * l.patches.max(1) as u64,
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                output,
            };
            let mut stage = BezierStage {
                map_scale: prepared.map_scale,
                map_cells,
                written: None,
                latest: None,
                growths: 0,
                readback: StatusReadback::new(
                    "tessera bezier status readback",
                    std::mem::size_of::<BezierStatus>() as u64,
                ),
                prepared_layout: l,
                params: *params,
                control_points: (0..l.patches).map(|p| prepared.control_points(p)).collect(),
                flipped: prepared.topo.iter().map(|t| t.flipped()).collect(),
                view: None,
                bind_groups: BindGroups::new(device, &pipelines.0, &test_kernels, &buffers),
                test_kernels,
                buffers,
                pipelines,
            };
            stage.write_params(queue);
            stage.write_thresholds(queue)?;
            Ok(stage)
        })
    }

    /// The view of the next runs, or `None`: each patch's threshold becomes the smaller
    /// of the world threshold and the view's pixels over the pixels per model unit of the
    /// box of its control points ([`tessera_core::bezier::patch_thresholds`]), written
    /// through `queue` (four bytes per patch). The paper's heuristic scaled by distance,
    /// not a guarantee in pixels; crack-free as without a view.
    pub fn set_view(&mut self, queue: &wgpu::Queue, view: Option<&BezierView>) -> Result<()> {
        let old = self.view;
        self.view = view.copied();
        if let Err(e) = self.write_thresholds(queue) {
            self.view = old;
            return Err(e);
        }
        Ok(())
    }

    fn write_thresholds(&mut self, queue: &wgpu::Queue) -> Result<()> {
        let thresholds = patch_thresholds(
            &self.control_points,
            &self.flipped,
            self.params.threshold,
            self.view.as_ref(),
        )?;
        queue.write_buffer(
            &self.buffers.thresholds,
            0,
            bytemuck::cast_slice(&thresholds),
        );
        Ok(())
    }

    /// Changes the test, threshold or depth, written through `queue`; takes effect at the
    /// next [`prepare`](Self::prepare). A lower threshold or a greater depth can need
    /// larger output buffers: the next `prepare` after the overflowing run grows them (or
    /// call [`run_blocking`](Self::run_blocking) after the change, as after loading).
    pub fn set_params(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &AdaptiveParams,
    ) -> Result<()> {
        params.validate()?;
        let mut rebind = false;
        if params.max_depth != self.params.max_depth {
            let l = self.prepared_layout;
            self.buffers.scratch = Scratch::new(device, ScratchLayout::new(params.max_depth, l))?;
            rebind = true;
        }
        if params.test != self.params.test
            || array_depth(params.max_depth) != array_depth(self.params.max_depth)
        {
            self.test_kernels = self.pipelines.for_params(device, params);
            rebind = true;
        }
        self.params = *params;
        if rebind {
            self.rebind(device);
        }
        self.write_params(queue);
        self.write_thresholds(queue)
    }

    /// New control nets and maps for the same patches (animation): the CPU prepares the
    /// moved model again ([`PreparedBezier::new`]) and only its nets, coarse vertices
    /// and maps are written; the next [`prepare`](Self::prepare) tessellates it. A model
    /// with another layout (patch, edge or triangle counts) is an error.
    pub fn update_model(&mut self, queue: &wgpu::Queue, prepared: &PreparedBezier) -> Result<()> {
        if prepared.layout != self.prepared_layout {
            return Err(tessera_core::Error::Param(
                "the prepared model's layout changed; make a new stage".into(),
            )
            .into());
        }
        let nets = NetTexture::new(&prepared.patches);
        queue.write_texture(
            self.buffers.nets.texture().as_image_copy(),
            bytemuck::cast_slice(&nets.texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16 * nets.width),
                rows_per_image: None,
            },
            self.buffers.nets.texture().size(),
        );
        // Orientation (which way a patch's normal faces) follows the geometry.
        let topology = TopologyTexture::new(&prepared.topo, &prepared.curves);
        queue.write_texture(
            self.buffers.topology.texture().as_image_copy(),
            bytemuck::cast_slice(&topology.texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(16 * topology.width),
                rows_per_image: None,
            },
            self.buffers.topology.texture().size(),
        );
        queue.write_buffer(
            &self.buffers.coarse_records,
            0,
            bytemuck::cast_slice(&prepared.coarse_vertex_records()),
        );
        let halves = MapHalves::new(&prepared.maps, prepared.map_scale);
        queue.write_buffer(
            &self.buffers.map_halves,
            0,
            bytemuck::cast_slice(&halves.words),
        );
        self.map_scale = prepared.map_scale;
        self.write_params(queue);
        // A view's thresholds follow the moved control points.
        let l = self.prepared_layout;
        self.control_points = (0..l.patches).map(|p| prepared.control_points(p)).collect();
        self.write_thresholds(queue)
    }

    /// The test, threshold and depth of the next runs.
    pub fn params(&self) -> &AdaptiveParams {
        &self.params
    }

    /// The buffers to draw: valid after the recorded work has run.
    pub fn output(&self) -> &MeshBuffers {
        &self.buffers.output
    }

    fn words_per_triangle(&self) -> (u32, u32) {
        triangle_words(self.params.max_depth)
    }

    fn rebind(&mut self, device: &wgpu::Device) {
        self.bind_groups =
            BindGroups::new(device, &self.pipelines.0, &self.test_kernels, &self.buffers);
    }

    fn gpu_params(&self) -> BezierParams {
        let l = self.prepared_layout;
        let (points_words, pole_words) = self.words_per_triangle();
        BezierParams {
            test: self.params.test.index(),
            threshold: self.params.threshold,
            max_depth: self.params.max_depth,
            patches: l.patches,
            curves: l.curves,
            coarse_vertices: l.coarse_vertices,
            coarse_edges: l.coarse_edges,
            coarse_triangles: l.coarse_triangles,
            points_words,
            pole_words,
            inv_lattice: inv_lattice(self.params.max_depth),
            vertex_capacity: self.buffers.output.vertex_capacity(),
            index_capacity: self.buffers.output.index_capacity(),
            map_scale: self.map_scale,
            scratch_shift: self.buffers.scratch.shift,
            _pad: 0,
        }
    }

    /// Records the whole tessellation into `encoder`: the straight-line script of the
    /// module docs. Nothing is submitted; the output is valid once the caller's
    /// submission has run. A status that an earlier run left, read without waiting, grows
    /// the buffers first if that run overflowed (an error only when the device cannot
    /// hold what it needed).
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.record_run(device, queue, encoder, None)
    }

    /// As [`prepare`](Self::prepare), writing the run's GPU timestamps into
    /// `timestamps` (see [`crate::GpuTimer`]).
    pub fn prepare_timed(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: RunTimestamps<'_>,
    ) -> Result<()> {
        self.record_run(device, queue, encoder, Some(timestamps))
    }

    fn record_run(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<RunTimestamps<'_>>,
    ) -> Result<()> {
        self.poll_status(device);
        if let Some((status, true)) = self.latest {
            self.grow(device, &status)?;
        }
        self.write_params(queue);
        let mut passes = Passes::new(timestamps);
        for step in Step::ALL {
            self.record_step(step, encoder, &mut passes);
        }
        let status = &self.buffers.status;
        self.readback.record(device, encoder, |encoder, readback| {
            encoder.copy_buffer_to_buffer(
                status,
                0,
                readback,
                0,
                std::mem::size_of::<BezierStatus>() as u64,
            )
        });
        Ok(())
    }

    /// Runs the script one step at a time, each on its own submission, and returns the
    /// wall time of each (ms): the per-kernel profile of the bench. Slower than
    /// [`prepare`](Self::prepare) (one wait per step); the output is the same.
    #[doc(hidden)]
    pub fn profile_kernels(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Vec<(&'static str, f64)>> {
        self.write_params(queue);
        let mut out = Vec::new();
        for step in Step::ALL {
            let t = std::time::Instant::now();
            let mut encoder = device.create_command_encoder(&Default::default());
            self.record_step(step, &mut encoder, &mut Passes::new(None));
            queue.submit([encoder.finish()]);
            device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| Error::Readback(e.to_string()))?;
            out.push((step.name(), t.elapsed().as_secs_f64() * 1e3));
        }
        Ok(out)
    }

    /// Writes the parameters (and the capacities they carry) through the queue when they
    /// changed: they land before the submission that runs the next recording.
    fn write_params(&mut self, queue: &wgpu::Queue) {
        let params = self.gpu_params();
        if self.written != Some(params) {
            queue.write_buffer(&self.buffers.uniform, 0, bytemuck::bytes_of(&params));
            self.written = Some(params);
        }
    }

    /// Records one step of the script (each in its own compute pass).
    fn record_step(&self, step: Step, encoder: &mut wgpu::CommandEncoder, passes: &mut Passes) {
        let l = self.prepared_layout;
        let b = &self.buffers;
        let bg = &self.bind_groups;
        let p = &*self.pipelines.0;
        let t = &*self.test_kernels;
        let counts_len = l.coarse_edges + 2 * l.coarse_triangles + 1;
        match step {
            Step::EdgeDecide => {
                // The scan's trailing slot collects the grand total: zero it each run.
                encoder.clear_buffer(&b.counts, 4 * (counts_len as u64 - 1), Some(4));
                encoder.clear_buffer(&b.tally, 0, None);
                // The triangles' bit sets start empty: a memset here, where zeroing them
                // in the kernel was a store per word and lane. Before the edge kernel,
                // which writes every edge's set into the same texture.
                b.scratch.clear(encoder);
            }
            Step::TriMark => {
                // The root kernel raises the mark kernel's dispatch from zero.
                let dispatch = std::mem::offset_of!(BezierStatus, mark_dispatch) as u64;
                encoder.clear_buffer(&b.status, dispatch, Some(12));
            }
            Step::EdgeEmit => encoder.copy_buffer_to_buffer(
                &b.coarse_records,
                0,
                &b.records,
                0,
                l.coarse_vertices as u64 * std::mem::size_of::<VertexRecord>() as u64,
            ),
            _ => {}
        }
        {
            let mut pass = passes.begin(encoder, step.name(), step == Step::VertexEval);
            match step {
                Step::MapCells => {
                    let cells = (MAP_CELLS * MAP_CELLS) as u32;
                    p.map_cells
                        .dispatch(&mut pass, &self.map_cells, l.patches * cells, WORKGROUP);
                }
                Step::EdgeDecide => {
                    t.edge_decide
                        .dispatch(&mut pass, &bg.edge_decide, l.coarse_edges, WORKGROUP);
                }
                Step::TriMark => {
                    p.tri_roots
                        .dispatch(&mut pass, &bg.tri_roots, l.coarse_triangles, WORKGROUP);
                    t.tri_mark.dispatch_indirect(
                        &mut pass,
                        &bg.tri_mark,
                        &b.status,
                        std::mem::offset_of!(BezierStatus, mark_dispatch) as u64,
                    );
                }
                Step::ScanFinish => {
                    b.scan.record(&mut pass, &p.scan);
                    p.finish.dispatch(&mut pass, &bg.finish, 1, 1);
                }
                Step::TriOrder => {
                    p.tri_order
                        .dispatch(&mut pass, &bg.tri_order, l.coarse_triangles, WORKGROUP);
                }
                Step::EdgeEmit => {
                    p.edge_emit
                        .dispatch(&mut pass, &bg.edge_emit, l.coarse_edges, WORKGROUP);
                }
                Step::TriEmit => {
                    // Sized by the finish kernel: the general triangles, then the plain.
                    t.tri_emit.dispatch_indirect(
                        &mut pass,
                        &bg.tri_emit,
                        &b.status,
                        std::mem::offset_of!(BezierStatus, emit_dispatch) as u64,
                    );
                    p.tri_emit_plain.dispatch_indirect(
                        &mut pass,
                        &bg.tri_emit_plain,
                        &b.status,
                        std::mem::offset_of!(BezierStatus, plain_dispatch) as u64,
                    );
                }
                Step::VertexEval => {
                    pass.set_pipeline(&p.vertex_eval.pipeline);
                    pass.set_bind_group(0, &bg.vertex_eval, &[]);
                    let dispatch = std::mem::offset_of!(BezierStatus, dispatch) as u64;
                    pass.dispatch_workgroups_indirect(&b.status, dispatch);
                }
            }
        }
    }

    /// What the last recorded run needed and wrote, once its submission has run (waits
    /// for the GPU).
    pub fn read_status(&mut self, device: &wgpu::Device) -> Result<BezierStatus> {
        let bytes = self.readback.wait_last(device)?;
        Ok(bytemuck::pod_read_unaligned(&bytes))
    }

    /// The newest run's status that has arrived, without waiting (a frame or so late);
    /// `None` before the first. After an overflow (`status.overflow != 0`) the next
    /// [`prepare`](Self::prepare) grows the buffers: record a run again to draw the mesh.
    pub fn poll_status(&mut self, device: &wgpu::Device) -> Option<BezierStatus> {
        if let Some(bytes) = self.readback.poll(device) {
            let status: BezierStatus = bytemuck::pod_read_unaligned(&bytes);
            self.latest = Some((status, status.overflow != 0));
        }
        self.latest.map(|(s, _)| s)
    }

    /// How many times the output buffers have been reallocated to fit a run.
    pub fn growths(&self) -> u32 {
        self.growths
    }

    /// Whether the newest status [`poll_status`](Self::poll_status) read is an overflow
    /// that the buffers have not yet grown for: the mesh drawn now is empty, and a render
    /// loop that tessellates only on change records one more run (its `prepare` grows
    /// first). False again once that `prepare` has grown, so a status that arrives late
    /// from before the growth does not ask twice.
    pub fn grow_pending(&self) -> bool {
        matches!(self.latest, Some((_, true)))
    }

    /// Grows the output buffers to what `status` says the run needed (with headroom).
    /// Returns whether anything was reallocated, or an error when the device cannot hold
    /// buffers that large (nothing is reallocated then). Public for the test that asks
    /// for more than the device holds; `prepare` calls it.
    #[doc(hidden)]
    pub fn grow(&mut self, device: &wgpu::Device, status: &BezierStatus) -> Result<bool> {
        let grown = self.grow_buffers(device, status);
        if grown.is_err() {
            // Reported once, by the call that grew: the statuses of the runs recorded so
            // far are dropped, and the stage goes on with the buffers it has.
            self.readback.new_generation();
            self.latest = self.latest.map(|(s, _)| (s, false));
        }
        grown
    }

    fn grow_buffers(&mut self, device: &wgpu::Device, status: &BezierStatus) -> Result<bool> {
        if status.overflow == 0 {
            return Ok(false);
        }
        let grow = |need: u32, have: u32| {
            if need > have {
                need.saturating_add(need / 4)
            } else {
                have
            }
        };
        let vertices = grow(status.vertices, self.buffers.output.vertex_capacity());
        let indices = grow(status.indices, self.buffers.output.index_capacity());
        check_size(
            device,
            "vertex",
            vertices as u64 * std::mem::size_of::<OutVertex>() as u64,
        )?;
        check_size(device, "index", indices as u64 * 4)?;
        let (output, records) = allocating(device, "the stage's grown buffers", || {
            let output = MeshBuffers::with_capacity(device, vertices, indices);
            let records = storage(
                device,
                "tessera vertex records",
                output.vertex_capacity() as u64 * std::mem::size_of::<VertexRecord>() as u64,
            );
            Ok((output, records))
        })?;
        self.buffers.output = output;
        self.buffers.records = records;
        self.rebind(device);
        self.readback.new_generation();
        self.latest = self.latest.map(|(s, _)| (s, false));
        self.growths += 1;
        Ok(true)
    }

    /// Runs the stage to completion on its own submission, growing and rerunning until
    /// the output fits. For loading, tools and tests; a renderer records
    /// [`prepare`](Self::prepare) into its own frame instead.
    pub fn run_blocking(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<BezierStatus> {
        crate::stage::run_blocking(self, device, queue)
    }

    /// Copies the output mesh back to the CPU (for files and tests). `status` is what
    /// the run reported.
    pub fn read_mesh(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        status: &BezierStatus,
    ) -> Result<Mesh> {
        if status.overflow != 0 {
            return Err(Error::Wgpu(
                "the last run overflowed its buffers; grow and rerun".into(),
            ));
        }
        self.buffers
            .output
            .read_mesh(device, queue, status.vertices, status.indices)
    }

    /// The map atlas's texels as built on the device, row-major (see [`MapAtlas`]).
    fn read_map_atlas(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<Vec<[u16; 4]>> {
        let texels = read_texture(device, queue, &self.buffers.map_atlas_texture)?;
        Ok(bytemuck::pod_collect_to_vec(&texels))
    }

    /// The scratch words in order: the triangles' words, then the edges' bit sets.
    fn read_scratch(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(Vec<u32>, Vec<u32>)> {
        let texels = read_texture(device, queue, &self.buffers.scratch.texture)?;
        let mut words: Vec<u32> = bytemuck::pod_collect_to_vec(&texels);
        let layout = ScratchLayout::new(self.params.max_depth, self.prepared_layout);
        words.truncate(layout.words as usize);
        let edge_sets = words.split_off(layout.edge_sets as usize);
        Ok((words, edge_sets))
    }

    /// The intermediate buffers, for the tests that compare them with the CPU twins: the
    /// map atlas, edge bit sets, the scanned counts, and each coarse triangle's scratch
    /// words.
    #[doc(hidden)]
    pub fn read_intermediates(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Intermediates> {
        let words = |b: &wgpu::Buffer| -> Result<Vec<u32>> {
            Ok(bytemuck::pod_collect_to_vec(&read_buffer(
                device,
                queue,
                b,
                0,
                b.size(),
            )?))
        };
        let (points_words, pole_words) = self.words_per_triangle();
        let mut counts = words(&self.buffers.counts)?;
        let l = self.prepared_layout;
        let mut order = counts.split_off((l.coarse_edges + 2 * l.coarse_triangles + 1) as usize);
        let order_buckets = order.split_off(l.coarse_triangles as usize);
        let (scratch, edge_bits) = self.read_scratch(device, queue)?;
        Ok(Intermediates {
            map_atlas: self.read_map_atlas(device, queue)?,
            edge_bits,
            counts,
            order,
            order_buckets,
            scratch,
            points_words,
            pole_words,
            stride: triangle_stride(self.params.max_depth),
        })
    }
}

impl GrowingStage for BezierStage {
    type Status = BezierStatus;
    const MAX_GROWTHS: u32 = 4;
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.prepare(device, queue, encoder)
    }
    fn status(&mut self, device: &wgpu::Device) -> Result<BezierStatus> {
        self.read_status(device)
    }
    fn grow_to(&mut self, device: &wgpu::Device, status: &BezierStatus) -> Result<bool> {
        self.grow(device, status)
    }
}

/// What the decision kernels wrote (see [`BezierStage::read_intermediates`]).
#[doc(hidden)]
#[non_exhaustive]
pub struct Intermediates {
    /// The map atlas's texels, row-major, as `bezier_map_cells` built them.
    pub map_atlas: Vec<[u16; 4]>,
    /// `EDGE_BIT_WORDS` words per coarse edge.
    pub edge_bits: Vec<u32>,
    /// The exclusive scan of `[edge vertices | inner vertices | triangles | 0]`.
    pub counts: Vec<u32>,
    /// By slot: the coarse triangles in the order the emit kernels take them
    /// (`emit_order`; within a bucket the order is the atomics' and may change from run
    /// to run).
    pub order: Vec<u32>,
    /// By coarse triangle: its bucket in that order (`order_bucket`).
    pub order_buckets: Vec<u32>,
    /// Per coarse triangle (`stride` words): `points_words` words of lattice points, then
    /// `pole_words`, then the points' nonzero groups (as `TriScratch::words`).
    pub scratch: Vec<u32>,
    pub points_words: u32,
    pub pole_words: u32,
    pub stride: u32,
}
