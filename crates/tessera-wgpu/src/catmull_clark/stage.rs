//! The adaptive Catmull-Clark stage: the GPU twin of
//! [`tessera_core::catmull_clark::tessellate_adaptive`], the same mesh up to vertex order.
//!
//! [`CcStage::prepare`] records one straight-line script into the caller's encoder, the
//! same [`CcStage::DISPATCHES`] dispatches for every model, tolerance, depth and first
//! split; nothing is read back to record it:
//!
//! | # | kernel | per | writes |
//! |---|---|---|---|
//! | 1 | `cc_stencil` level1 | level-1 point | the first subdivision step of the control points (only when they moved) |
//! | 2 | `cc_stencil` pieces | net, ball or corner | every patch's quadtree from its one-ring, through tables shared by patches alike (only when the points moved) |
//! | 3 | `cc_face_bound` | patch | with face leaves, each quad face's bound taken whole, once (kept until the points move) |
//! | 4 | `cc_traverse` (count) | patch and trial | the first-split search to full depth: best split, its leaves, its decisions |
//! | 5–6 | scan | patch | each patch's first leaf |
//! | 7 | `cc_traverse` (emit) | patch | the best split's leaves, its decisions replayed; leaf and item dispatch sizes |
//! | 8 | `cc_leaf_keys` (indirect) | leaf | corner keys in their charts (and across seams) and vertices |
//! | 9 | `cc_hash_insert` (indirect) | item | the vertex hash |
//! | 10 | `cc_hash_number` mark_first (indirect) | item | each key's first item |
//! | 11 | `cc_polygon` count (indirect) | leaf | points on each side (found in the hash) |
//! | 12–13 | scan of both | item, leaf | vertex numbers, polygon offsets |
//! | 14 | `cc_hash_number` assign_gather (indirect) | item | vertex ids, one point per vertex, the hash's outcome |
//! | 15 | `cc_polygon` emit (indirect) | leaf | polygons: corners + marked points on the sides; invocation 0: whether the mesh fits, what the run needed |
//! | 16 | `cc_vertex_eval` (indirect) | vertex | vertices (position, normal at the point's home; face, face u v) |
//! | 17 | `cc_triangulate` (indirect) | leaf | indices; invocation 0: the draw arguments |
//!
//! Only the control points move per frame ([`CcStage::update_points`] writes them and a
//! word): the tables they are derived through are built once per topology
//! ([`tessera_core::catmull_clark::stencil`]), as OpenSubdiv's stencil tables are.
//!
//! Marking walks each cell of a first split to full depth, depth first and without a
//! stack (twin [`tessera_core::catmull_clark::traverse`]), so the script does not grow
//! with the depth. The first split of each patch (`ku × kv` cells, up to 8 × 7) is the one with
//! the fewest leaves, ties to the earlier, as on the CPU: the count pass walks the
//! trials in an invocation each, skipping a trial that cannot beat a finished
//! one and stopping one once it cannot, and keeps every decision as a bit; the emit pass
//! replays the best trial's bits to write its leaves where the scan says, without
//! deciding again. No invocation waits on another.
//!
//! Capacities: the leaves, polygons, vertices, indices and the hash table. Kernels never
//! write past them, and the counters record what the run needed. The output (vertices,
//! indices, draw arguments) is written only when the whole mesh fits: a run that
//! overflows leaves the last complete mesh drawn. Each run's status is read back without
//! blocking, and the next [`CcStage::prepare`] that finds an overflow reallocates (the
//! last mesh copied over), so a later run fits ([`CcStage::run_blocking`] grows and
//! reruns at once).
//!
//! ```no_run
//! use tessera_core::{catmull_clark::{load_surface, CcParams}, Tolerance};
//! use tessera_wgpu::{catmull_clark::CcStage, headless::Gpu, Kernels};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let gpu = Gpu::new()?;
//! let model = load_surface(std::path::Path::new("assets/opensubdiv/catmark_car.obj"))?;
//! let params = CcParams {
//!     tolerance: Tolerance::Relative(1e-3),
//!     max_depth: 8,
//!     first_split: Default::default(),
//!     leaf_bound: Default::default(),
//! };
//! let kernels = Kernels::new(&gpu.device);
//! let mut stage = CcStage::new(&gpu.device, &gpu.queue, &kernels, &model, &params)?;
//! // Once (and after set_params): run to completion, growing buffers that were too small.
//! let status = stage.run_blocking(&gpu.device, &gpu.queue)?;
//! println!("{} triangles", status.indices / 3);
//! // Each frame, e.g. after `stage.update_points(...)`: record with your own work.
//! let mut encoder = gpu.device.create_command_encoder(&Default::default());
//! stage.prepare(&gpu.device, &gpu.queue, &mut encoder)?;
//! gpu.queue.submit([encoder.finish()]);
//! // Draw `stage.output()` with `draw_indexed_indirect`.
//! # Ok(()) }
//! ```

use std::sync::Arc;
use tessera_core::catmull_clark::gpu_model::{patch_topology, point_homes};
use tessera_core::catmull_clark::stencil::CcStencils;

use glam::Vec3;
use tessera_core::catmull_clark::{CcParams, LeafBound, PatchMesh, SurfaceModel, ViewTolerance};
use tessera_core::gpu_types::{
    CcCell, CcHashStatus, CcState, CcTessParams, CcVertexPoint, CcView, OutVertex,
    CC_VIEW_CULL_BACKFACES, CC_VIEW_CULL_FRUSTUM,
};
use tessera_core::Mesh;

use super::stencil::{CcStencilBuffers, CcStencilKernels};
use super::{CcHashBinds, CcHashKernels, CcModelBuffers, CcVertexEval, CcVertexHash, NetPages};
use crate::error::{Error, Result};
use crate::kernel::{allocating, check_size, init_buffer, storage, storage_limit, Kernel};
use crate::output::MeshBuffers;
use crate::scan::{PrefixSum, ScanKernels};
use crate::stage::{GrowingStage, Passes, RunTimestamps, StatusReadback};
use crate::Kernels;

/// Binding numbers of the pipeline's own buffers (`shaders/shared/cc_tess.wgsl`).
mod slot {
    pub const PARAMS: u32 = 50;
    pub const STATE: u32 = 51;
    pub const LEAVES: u32 = 55;
    pub const MARKS: u32 = 57;
    pub const ARGS: u32 = 58;
    pub const TOPO: u32 = 59;
    pub const ITEM_POINTS: u32 = 60;
    pub const POLY_OFFSETS: u32 = 62;
    pub const POLY_VERTS: u32 = 63;
    pub const VERTICES: u32 = 64;
    pub const INDICES: u32 = 65;
    pub const DRAW: u32 = 66;
    pub const HOMES: u32 = 67;
    pub const PASS: u32 = 68;
    // The vertex hash's and the vertex evaluation's (shared/cc_hash.wgsl, cc_vertex_eval).
    pub const KEYS: u32 = 40;
    pub const TABLE: u32 = 41;
    pub const ITEM_SLOT: u32 = 42;
    pub const HASH_STATUS: u32 = 43;
    pub const HASH_OFFSETS: u32 = 44;
    pub const IDS: u32 = 45;
    pub const UNIQUE_KEYS: u32 = 46;
    pub const VERTEX_POINTS: u32 = 30;
}

/// Offsets into the dispatch-arguments buffer (written by the emit pass of marking): the
/// leaves, then the hash items (eight per leaf).
const LEAF_ARGS: u64 = 12;
const ITEM_ARGS: u64 = 24;

/// Every kernel of the stage, compiled once per device (part of [`Kernels`]).
pub(crate) struct CcKernels {
    face_bound: Kernel,
    traverse: Kernel,
    leaf_keys: Kernel,
    assign_gather: Kernel,
    polygon_count: Kernel,
    polygon_emit: Kernel,
    triangulate: Kernel,
    hash: CcHashKernels,
    eval: CcVertexEval,
    scan: ScanKernels,
    /// Shared with the uniform stage (compiled once per device).
    stencil: std::sync::Arc<CcStencilKernels>,
}

impl CcKernels {
    pub fn new(
        device: &wgpu::Device,
        stencil: std::sync::Arc<CcStencilKernels>,
        pages: NetPages,
    ) -> Self {
        let k = |file, entry| Kernel::specialised(device, file, entry, &[], &pages.consts());
        let [used] = pages.consts();
        CcKernels {
            // Its walk feeds the face's sums: the one kernel compiled with them.
            face_bound: Kernel::specialised(
                device,
                "cc_face_bound.wgsl",
                "main",
                &[],
                &[("CC_FACE_SINK", 1), used],
            ),
            traverse: k("cc_traverse.wgsl", "main"),
            leaf_keys: k("cc_leaf_keys.wgsl", "main"),
            assign_gather: k("cc_hash_number.wgsl", "assign_gather"),
            polygon_count: k("cc_polygon.wgsl", "count"),
            polygon_emit: k("cc_polygon.wgsl", "emit"),
            triangulate: k("cc_triangulate.wgsl", "main"),
            hash: CcHashKernels::new(device),
            eval: CcVertexEval::new(device, pages),
            scan: ScanKernels::new(device),
            stencil,
        }
    }
}

/// How many of each thing the buffers hold (the tests start from tiny ones).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CcCapacities {
    /// Leaves of the final tessellation.
    pub leaves: u32,
    /// Polygon vertices (leaf corners plus the points on their sides).
    pub poly: u32,
    /// Output vertices (one per point and chart).
    pub vertices: u32,
    /// Indices (3 per triangle).
    pub indices: u32,
    /// Slots of the vertex hash (rounded up to a power of two).
    pub hash_slots: u32,
}

impl CcCapacities {
    /// A first guess for a model of `patches` patches; runs grow what is too small.
    pub fn guess(patches: u32) -> Self {
        let p = patches.max(1);
        CcCapacities {
            leaves: 16 * p,
            poly: 96 * p,
            vertices: 48 * p,
            indices: 3 * 96 * p,
            hash_slots: 2 * 64 * p,
        }
    }

    /// The same proportions, shrunk until every buffer they size holds at most `limit`
    /// bytes: a first guess for a large model must not refuse what a smaller start
    /// would grow to.
    fn within(self, limit: u64) -> Self {
        // Bytes per unit: a leaf's eight hash items (the largest per-leaf buffer), a
        // polygon vertex, an index, a vertex, a hash slot.
        let item = 8 * std::mem::size_of::<CcVertexPoint>() as u64;
        let vertex = std::mem::size_of::<OutVertex>() as u64;
        let need = [
            self.leaves as u64 * item,
            self.poly as u64 * 16,
            self.indices as u64 * 4,
            self.vertices as u64 * vertex,
            self.hash_slots.next_power_of_two() as u64 * 12,
        ];
        let most = need.into_iter().max().unwrap_or(0);
        if most <= limit {
            return self;
        }
        let f = 0.9 * limit as f64 / most as f64;
        let scale = |n: u32| ((n as f64 * f) as u32).max(1);
        let mut hash_slots = scale(self.hash_slots).next_power_of_two();
        if hash_slots as u64 * 12 > limit {
            hash_slots /= 2;
        }
        CcCapacities {
            leaves: scale(self.leaves),
            poly: scale(self.poly),
            vertices: scale(self.vertices),
            indices: scale(self.indices),
            hash_slots,
        }
    }
}

/// What a run needed and reported (read back by [`CcStage::read_status`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct CcStatus {
    /// The run's counters: leaves, bounds computed, what each buffer needed, overflow.
    pub state: CcState,
    /// The vertex hash's counters: distinct vertices, overflow.
    pub hash: CcHashStatus,
    /// Indices of the mesh drawn after the run: its own, or after an overflow the last
    /// complete run's.
    pub indices: u32,
}

impl CcStatus {
    /// Whether a buffer was too small: the run left the last complete mesh in place.
    pub fn overflowed(&self) -> bool {
        self.state.overflow != 0 || self.hash.overflow != 0
    }
    /// Distinct output vertices.
    pub fn vertices(&self) -> u32 {
        self.hash.unique
    }
    /// The largest flatness bound of a leaf: the guaranteed error of the output.
    pub fn max_bound(&self) -> f32 {
        f32::from_bits(self.state.max_bound_bits)
    }
}

/// Buffers that depend on the capacities.
struct Buffers {
    caps: CcCapacities,
    /// The first-split trials the marks have room for.
    trials: u32,
    params: wgpu::Buffer,
    leaves: wgpu::Buffer,
    keys: wgpu::Buffer,
    item_points: wgpu::Buffer,
    vertex_points: wgpu::Buffer,
    poly_offsets: wgpu::Buffer,
    poly_verts: wgpu::Buffer,
    hash: CcVertexHash,
    output: MeshBuffers,
    /// The hash's first-item flags and the polygon sizes, in one scan.
    number_scan: PrefixSum,
    /// Marking's words ([`marks_words`]), which grow with the leaves.
    marks: wgpu::Buffer,
    marks_scan: PrefixSum,
}

/// Bind groups of every dispatch, rebuilt when buffers are reallocated.
struct Binds {
    face_bound: wgpu::BindGroup,
    /// The count pass, then the emit pass.
    traverse: [wgpu::BindGroup; 2],
    leaf_keys: wgpu::BindGroup,
    assign_gather: wgpu::BindGroup,
    polygon_count: wgpu::BindGroup,
    polygon_emit: wgpu::BindGroup,
    triangulate: wgpu::BindGroup,
    hash: CcHashBinds,
    eval: wgpu::BindGroup,
    /// The stencil step's two kernels.
    stencil: [wgpu::BindGroup; 2],
}

/// What the stage keeps for its whole life (the model's size fixes it).
struct Fixed<'a> {
    topo: &'a wgpu::Buffer,
    homes: &'a wgpu::Buffer,
    state: &'a wgpu::Buffer,
    args: &'a wgpu::Buffer,
    passes: &'a [wgpu::Buffer; 2],
    stencil: &'a CcStencilBuffers,
}

/// The adaptive Catmull-Clark tessellation stage of one model.
pub struct CcStage {
    kernels: Arc<CcKernels>,
    model: CcModelBuffers,
    /// The tables the quadtrees are derived from, and the control points.
    stencil: CcStencilBuffers,
    /// The patches as built, kept to check parameters.
    patches: PatchMesh,
    /// Levels of the uploaded quadtrees.
    depth: u32,
    patch_count: u32,
    /// Level-1 points: where the edges' homes start.
    point_count: u32,
    params: CcParams,
    /// The view of the runs, as the kernels read it (all zero for none).
    view: CcView,
    /// The view as set, and the pixels the runs use now: the ones asked for, or coarser
    /// by powers of √2 where the view's triangle cap or the device's loop limit needs it.
    view_set: Option<(ViewTolerance, f64)>,
    /// The coarsest pixels at which the device cut a marking walk short, for the view's
    /// pixels and cap as set (0 if none): the runs never refine to them again.
    walk_floor: f64,
    /// The parameters changed since they were last written (the pixels, by the cap).
    params_dirty: bool,
    topo: wgpu::Buffer,
    homes: wgpu::Buffer,
    state: wgpu::Buffer,
    args: wgpu::Buffer,
    /// The pass number of `cc_traverse` (0 count, 1 emit), one uniform each.
    passes: [wgpu::Buffer; 2],
    readback: StatusReadback,
    /// The newest status read back, and whether the buffers are still to grow for it.
    latest: Option<(CcStatus, bool)>,
    growths: u32,
    /// Dispatches the last recorded run held.
    dispatches: u32,
    /// The control points moved since the last run was recorded: the root bounds the
    /// marks keep are stale.
    points_moved: bool,
    buffers: Buffers,
    binds: Binds,
}

/// Words of the marks buffer (`shaders/shared/cc_tess.wgsl`) for `patches` patches and
/// `leaves` leaves, `trials` first splits tried: per patch the key of its best trial (scanned into
/// its first leaf; the total after them), the same key kept, the key of the best trial
/// cut short, the trial chosen, its root bound and its face's bound (kept); per patch
/// and trial three words of what its leaves guarantee (and how many are culled) and a
/// block of 32 decisions; then the pool of blocks ([`pool_blocks`]).
fn marks_words(patches: u32, leaves: u32, trials: u32) -> u64 {
    let p = patches.max(1) as u64;
    let trials = trials as u64;
    6 * p + 1 + 3 * p * trials + 2 * (p * trials + pool_blocks(patches, leaves))
}

/// Where the marks buffer keeps the bounds that depend on the surface alone, in words:
/// each patch's root bound, then each quad face's bound (at its first patch), from run
/// to run.
fn marks_kept_bounds(patches: u32) -> (u64, u64) {
    let p = patches.max(1) as u64;
    (4 * p + 1, 2 * p)
}

/// The words of the marks buffer cleared before each run (the keys).
fn marks_cleared(patches: u32) -> u64 {
    3 * patches.max(1) as u64 + 1
}

/// Blocks of 32 decisions for the walks longer than one block: as many as leaves, and
/// four per patch. A walk of `d` decisions takes `d / 32` of them, and each trial stops
/// once its leaves reach the best, so a patch's trials take about a block per 8 leaves.
fn pool_blocks(patches: u32, leaves: u32) -> u64 {
    4 * patches.max(1) as u64 + leaves as u64
}

impl CcStage {
    /// Dispatches in every run, whatever the model, tolerance, depth or first split.
    pub const DISPATCHES: u32 = 13 + 2 * PrefixSum::DISPATCHES;

    /// Phases [`profile_phases`](Self::profile_phases) times: marking, vertices (keys,
    /// hash, numbering, evaluation), polygons and triangles.
    #[doc(hidden)]
    pub const TIMED_PHASES: u32 = 3;

    /// Uploads `model` through `queue`, sizes the buffers with a first guess (grown on
    /// demand), and compiles the stage's kernels into `kernels` if no stage has. A
    /// relative tolerance is resolved against the model's control box, now and for the
    /// stage's lifetime. A model larger than the device's limits is refused before
    /// anything is allocated ([`Error::ModelTooLarge`], [`Error::TooManyNets`]), and one
    /// the device cannot allocate is [`Error::OutOfMemory`].
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        model: &SurfaceModel,
        params: &CcParams,
    ) -> Result<Self> {
        let caps =
            CcCapacities::guess(model.mesh.patch_count() as u32).within(storage_limit(device));
        Self::with_capacity(device, queue, kernels, model, params, caps)
    }

    /// As [`new`](Self::new) with given capacities (the tests grow from tiny ones).
    #[doc(hidden)]
    pub fn with_capacity(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        kernels: &Kernels,
        model: &SurfaceModel,
        params: &CcParams,
        caps: CcCapacities,
    ) -> Result<Self> {
        allocating(device, "the stage's model and buffers", || {
            kernels.check_device(device)?;
            params.validate(model)?;
            gpu_leaf_bound(params)?;
            let patch_count = model.mesh.patch_count() as u32;
            // Built once per topology; every run's first step derives the quadtrees from
            // the control points through them.
            let stencils = CcStencils::new(&model.mesh, model.depth);
            let model_buffers = CcModelBuffers::derived(device, queue, &stencils.structure)?;
            let kernels = kernels.cc(model_buffers.pages);
            let control = model.mesh.control_points_f32();
            let stencil = CcStencilBuffers::new(device, &stencils, &control)?;
            let topo = init_buffer(
                device,
                "tessera cc topology",
                bytemuck::cast_slice(&patch_topology(&model.mesh)),
                wgpu::BufferUsages::STORAGE,
            );
            let point_count = model.mesh.points.len() as u32;
            let homes = init_buffer(
                device,
                "tessera cc homes",
                bytemuck::cast_slice(&point_homes(&model.mesh)),
                wgpu::BufferUsages::STORAGE,
            );
            let state = storage(
                device,
                "tessera cc state",
                std::mem::size_of::<CcState>() as u64,
            );

            let args = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("tessera cc dispatch args"),
                size: 36,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::INDIRECT
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let passes = [0u32, 1].map(|pass| {
                init_buffer(
                    device,
                    "tessera cc traverse pass",
                    bytemuck::cast_slice(&[pass, 0, 0, 0]),
                    wgpu::BufferUsages::UNIFORM,
                )
            });
            let eps = params.epsilon(model);
            let counts = (patch_count, point_count);
            let view = CcView::default();
            let buffers = Buffers::new(
                device,
                &kernels,
                (counts, &state),
                (params, eps, view),
                caps,
            )?;
            let fixed = Fixed {
                topo: &topo,
                homes: &homes,
                state: &state,
                args: &args,
                passes: &passes,
                stencil: &stencil,
            };
            let binds = Binds::new(device, &kernels, &model_buffers, &fixed, &buffers);
            Ok(CcStage {
                kernels,
                model: model_buffers,
                stencil,
                patches: model.mesh.clone(),
                depth: model.depth,
                patch_count,
                point_count,
                params: *params,
                view,
                view_set: None,
                walk_floor: 0.0,
                params_dirty: false,
                topo,
                homes,
                state,
                args,
                passes,
                readback: StatusReadback::new("tessera cc status readback", status_size()),
                latest: None,
                growths: 0,
                dispatches: 0,
                points_moved: false,
                buffers,
                binds,
            })
        })
    }

    /// The tolerance, depth and first split of the next runs, written through `queue`.
    /// A finer tolerance or a greater depth can need larger buffers: the `prepare` after
    /// the overflowing run grows them (or call [`run_blocking`](Self::run_blocking)).
    /// A search after midpoint splits alone takes new marks at once (through `device`).
    pub fn set_params(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        params: &CcParams,
    ) -> Result<()> {
        params.validate_for(&self.patches, self.depth)?;
        gpu_leaf_bound(params)?;
        let trials = params.first_split.trials();
        if trials > self.buffers.trials {
            self.grow_marks(device, trials)?;
        }
        self.params = *params;
        self.write_params(queue);
        Ok(())
    }

    /// New marks with room for `trials` first splits (a search after midpoint splits
    /// alone): the marks take five words per patch and trial, so they are sized for the
    /// trials of the params, not for every trial there is. Only the bounds kept in them
    /// are lost (computed again).
    fn grow_marks(&mut self, device: &wgpu::Device, trials: u32) -> Result<()> {
        let (patches, leaves) = (self.patch_count, self.buffers.caps.leaves);
        let words = marks_words(patches, leaves, trials);
        check_size(device, "patch marks", 4 * words)?;
        let (marks, marks_scan) = allocating(device, "the stage's grown marks", || {
            let marks = storage(device, "tessera cc patch marks", 4 * words);
            let scan = PrefixSum::of_keys(device, &self.kernels.scan, &marks, patches + 1, (!0, 5));
            Ok((marks, scan))
        })?;
        let b = &mut self.buffers;
        (b.marks, b.marks_scan, b.trials) = (marks, marks_scan, trials);
        self.rebind(device);
        Ok(())
    }

    /// The bind groups again, after buffers were replaced.
    fn rebind(&mut self, device: &wgpu::Device) {
        let fixed = Fixed {
            topo: &self.topo,
            homes: &self.homes,
            state: &self.state,
            args: &self.args,
            passes: &self.passes,
            stencil: &self.stencil,
        };
        self.binds = Binds::new(device, &self.kernels, &self.model, &fixed, &self.buffers);
    }

    /// The view of the next runs, written through `queue` (no reallocation: once per
    /// frame as the camera moves), or `None` for the world tolerance alone. Place the
    /// model with [`View::with_model`](tessera_core::View::with_model). Each cell's
    /// tolerance becomes the smaller of the world tolerance and its share of
    /// `view.pixels`, and with `view.cull` the cells wholly outside the frustum emit
    /// nothing: the mesh of
    /// [`tessellate_adaptive_in_view`](tessera_core::catmull_clark::tessellate_adaptive_in_view),
    /// in the same dispatches.
    ///
    /// With `view.max_triangles`, a run that needs more triangles does not grow the
    /// buffers: the pixels are coarsened by √2 for the next run (the `prepare` after
    /// its status arrives, or at once in [`run_blocking`](Self::run_blocking), which
    /// starts from the pixels asked for and so gives the CPU reference's mesh), and a run
    /// with room for twice its triangles refines them by √2 again, down to those asked
    /// for. [`tolerance_px`](Self::tolerance_px) is what the runs use. The same view with
    /// the same pixels and cap keeps the coarsening reached.
    ///
    /// A device that stops every loop after a number of iterations (lavapipe: 65 535 per
    /// group of eight invocations) can cut a patch's marking walk short where cells split
    /// deep, as at the near plane. In pixels, such a run coarsens them by √2 as the cap
    /// does, and the runs never refine back to pixels that were cut while the pixels and
    /// cap asked for stay the same: the mesh is then the CPU reference's at
    /// [`tolerance_px`](Self::tolerance_px). With a world tolerance alone the run is an
    /// error.
    pub fn set_view(&mut self, queue: &wgpu::Queue, view: Option<&ViewTolerance>) -> Result<()> {
        let (gpu, set) = match view {
            None => (CcView::default(), None),
            Some(v) => {
                let kept = self.view_set.filter(|(old, _)| {
                    (old.pixels, old.max_triangles) == (v.pixels, v.max_triangles)
                });
                let px = kept.map_or(v.pixels.unwrap_or(0.0), |(_, px)| px);
                if kept.is_none() {
                    self.walk_floor = 0.0;
                }
                if v.max_triangles.is_some() && v.pixels.is_none() {
                    return Err(tessera_core::Error::Param(
                        "a triangle cap needs a pixel tolerance to coarsen".into(),
                    )
                    .into());
                }
                let at = ViewTolerance {
                    pixels: v.pixels.map(|_| px),
                    ..*v
                };
                (gpu_view(&at)?, Some((*v, px)))
            }
        };
        self.view = gpu;
        self.view_set = set;
        self.write_params(queue);
        Ok(())
    }

    /// The pixel tolerance of the runs: the view's, or coarser where its triangle cap
    /// needed it; `None` without a view in pixels.
    pub fn tolerance_px(&self) -> Option<f64> {
        self.view_set.and_then(|(v, px)| v.pixels.map(|_| px))
    }

    /// Where the view has a triangle cap: the pixels of the next run after `status`,
    /// if they change (coarser when the run needed more than the cap, finer when it had
    /// room for twice its triangles); an error when even the coarsest does not fit.
    fn capped_pixels(&self, status: &CcStatus) -> Result<Option<f64>> {
        let Some((v, px)) = self.view_set else {
            return Ok(None);
        };
        let Some(asked) = v.pixels else {
            return Ok(None);
        };
        let s = &status.state;
        // Past the viewport's diagonal, coarser pixels change little.
        let coarsest = v.view.viewport().length();
        if s.overflow & OVERFLOW_WALK_CUT != 0 {
            if px > coarsest {
                return Err(walk_cut_error(Some(px)));
            }
            return Ok(Some(px * std::f64::consts::SQRT_2));
        }
        let Some(cap) = v.max_triangles else {
            return Ok(None);
        };
        // Leaves cut at their capacity leave the triangles unknown: grow first, up to
        // twice the cap (a leaf in view has two triangles at least; the culled ones
        // have none, and past that many the run counts as over the cap all the same).
        let cut = s.leaves > self.buffers.caps.leaves;
        if cut && s.leaves as u64 <= 2 * cap as u64 {
            return Ok(None);
        }
        let triangles = s.need_indices as u64 / 3;
        if cut || triangles > cap as u64 {
            if px > coarsest {
                return Err(tessera_core::Error::Param(format!(
                    "at most {cap} triangles: not met even at {px:.0} pixels ({asked} asked): the patches in view need more"
                ))
                .into());
            }
            return Ok(Some(px * std::f64::consts::SQRT_2));
        }
        let finer = (px / std::f64::consts::SQRT_2).max(asked);
        if px > asked
            && finer > self.walk_floor
            && 2 * triangles <= cap as u64
            && !status.overflowed()
        {
            return Ok(Some(finer));
        }
        Ok(None)
    }

    /// Moves the next runs to `px` pixels, the step [`capped_pixels`](Self::capped_pixels)
    /// gave for `status`: a walk cut short there raises the floor to the pixels it was
    /// cut at.
    fn step_pixels(&mut self, status: &CcStatus, px: f64) {
        if status.state.overflow & OVERFLOW_WALK_CUT != 0 {
            if let Some(now) = self.tolerance_px() {
                self.walk_floor = self.walk_floor.max(now);
            }
        }
        self.set_pixels(px);
    }

    /// Moves the next runs to `px` pixels (written by the next `prepare`); statuses of
    /// earlier runs no longer count.
    fn set_pixels(&mut self, px: f64) {
        if let Some((v, _)) = self.view_set {
            self.view_set = Some((v, px));
            self.view.pixels = px as f32;
            self.params_dirty = true;
            self.readback.new_generation();
            self.latest = None;
        }
    }

    fn write_params(&self, queue: &wgpu::Queue) {
        let p = tess_params(
            (self.patch_count, self.point_count),
            (&self.params, self.epsilon(), self.view),
            self.buffers.caps,
        );
        queue.write_buffer(&self.buffers.params, 0, bytemuck::bytes_of(&p));
    }

    /// ε in model units: a relative tolerance is a fraction of the control box as loaded.
    pub fn epsilon(&self) -> f64 {
        self.params.tolerance.resolve(self.patches.control_diag)
    }

    /// New positions of the control vertices, same topology and order as the mesh the
    /// stage was made from: written through `queue` as they are, with the dispatch
    /// arguments that make the next [`prepare`](Self::prepare) derive the patches from
    /// them on the GPU (see [`update_bytes`](Self::update_bytes)). The CPU only checks
    /// them.
    pub fn update_points(&mut self, queue: &wgpu::Queue, points: &[Vec3]) -> Result<()> {
        self.patches
            .check_control_points(points.iter().map(|p| p.as_dvec3()))?;
        self.stencil.update(queue, points)?;
        self.points_moved = true;
        Ok(())
    }

    /// Bytes [`update_points`](Self::update_points) writes: 12 per control point and 24
    /// of dispatch arguments.
    pub fn update_bytes(&self) -> usize {
        self.stencil.update_bytes()
    }

    /// The tolerance, depth and first split of the next runs.
    pub fn params(&self) -> &CcParams {
        &self.params
    }

    /// What the buffers hold now.
    #[doc(hidden)]
    pub fn capacities(&self) -> CcCapacities {
        self.buffers.caps
    }

    /// The vertex, index and draw-argument buffers.
    pub fn output(&self) -> &MeshBuffers {
        &self.buffers.output
    }

    /// Bytes uploaded when the stage is made: the stencil tables, the quadtrees' shape
    /// and the control points (the nets and corners are derived on the GPU).
    pub fn upload_bytes(&self) -> usize {
        self.stencil.table_bytes() + self.stencil.update_bytes()
    }

    /// Nets the stencil step derives on the device (the bench's memory figure).
    #[doc(hidden)]
    pub fn derived_nets(&self) -> usize {
        self.stencil.derived_nets()
    }

    /// Dispatches the last recorded run held ([`DISPATCHES`](Self::DISPATCHES)), counted
    /// as they were recorded; 0 before the first.
    pub fn dispatches(&self) -> u32 {
        self.dispatches
    }

    /// Records the whole tessellation into `encoder` (see the module docs), and a copy of
    /// its counters read back without blocking. Submits nothing. A status an earlier run
    /// left grows the buffers first if that run overflowed (an error only when the device
    /// cannot hold what it needed).
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.grow_from_readback(device, encoder)?;
        self.write_params_if_dirty(queue);
        self.record_run(device, encoder, None, None);
        Ok(())
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
        self.grow_from_readback(device, encoder)?;
        self.write_params_if_dirty(queue);
        self.record_run(device, encoder, None, Some(timestamps));
        Ok(())
    }

    /// As [`prepare`](Self::prepare), writing a timestamp into `stamps` before the first
    /// phase and after each: the bench's profile. The device needs
    /// `TIMESTAMP_QUERY_INSIDE_ENCODERS`, and `stamps` at least
    /// [`TIMED_PHASES`](Self::TIMED_PHASES)` + 1` queries. Returns the phase names, one
    /// per timestamp after the first.
    #[doc(hidden)]
    pub fn profile_phases(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        stamps: &wgpu::QuerySet,
    ) -> Vec<String> {
        let mut names = Vec::new();
        self.record_run(device, encoder, Some((stamps, &mut names)), None);
        names
    }

    fn write_params_if_dirty(&mut self, queue: &wgpu::Queue) {
        if self.params_dirty {
            self.write_params(queue);
            self.params_dirty = false;
        }
    }

    fn grow_from_readback(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.poll_status(device);
        // Over the view's triangle cap (or with room to refine): other pixels, not
        // larger buffers.
        if let Some((status, _)) = self.latest {
            if let Some(px) = self.capped_pixels(&status)? {
                self.step_pixels(&status, px);
                return Ok(());
            }
        }
        if let Some((status, true)) = self.latest {
            let old = self.grow(device, &status)?;
            // The mesh drawn until a run fits the new buffers.
            if let Some(old) = old {
                self.buffers.output.copy_from(encoder, &old.output);
            }
        }
        Ok(())
    }

    /// The newest run's status that has arrived, without waiting (a frame or so late);
    /// `None` before the first. After an overflow the next [`prepare`](Self::prepare)
    /// grows the buffers, and the mesh drawn until then is the last complete one.
    pub fn poll_status(&mut self, device: &wgpu::Device) -> Option<CcStatus> {
        if let Some(bytes) = self.readback.poll(device) {
            let status = status_from_bytes(&bytes);
            self.latest = Some((status, status.overflowed()));
        }
        self.latest.map(|(s, _)| s)
    }

    /// How many times the buffers have been reallocated to fit a run.
    pub fn growths(&self) -> u32 {
        self.growths
    }

    /// Whether the newest status [`poll_status`](Self::poll_status) read is an overflow
    /// that the buffers have not yet grown for: the mesh drawn now is the last complete
    /// one, not this surface's, and a render loop that tessellates only on change records
    /// one more run (its `prepare` grows first). False again once that `prepare` has
    /// grown, so a status that arrives late from before the growth does not ask twice.
    pub fn grow_pending(&self) -> bool {
        match self.latest {
            Some((_, true)) => true,
            // The view's triangle cap asks for other pixels.
            Some((status, false)) => matches!(self.capped_pixels(&status), Ok(Some(_)) | Err(_)),
            None => false,
        }
    }

    fn record_run(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        mut stamps: Option<(&wgpu::QuerySet, &mut Vec<String>)>,
        timestamps: Option<RunTimestamps<'_>>,
    ) {
        let mut passes = Passes::new(timestamps);
        let mut stamp = |encoder: &mut wgpu::CommandEncoder, name: &str| {
            if let Some((set, names)) = stamps.as_mut() {
                if !name.is_empty() {
                    names.push(name.to_string());
                }
                encoder.write_timestamp(set, names.len() as u32);
            }
        };
        let b = &self.buffers;
        let k = &self.kernels;
        let binds = &self.binds;
        let args = &self.args;
        let mut dispatches = 0;
        encoder.clear_buffer(&self.state, 0, None);
        // The trials' keys start from none (atomics in the count pass).
        encoder.clear_buffer(&b.marks, 0, Some(4 * marks_cleared(self.patch_count)));
        // The bounds kept are of the surface before its control points moved.
        if self.points_moved {
            let (at, words) = marks_kept_bounds(self.patch_count);
            encoder.clear_buffer(&b.marks, 4 * at, Some(4 * words));
            self.points_moved = false;
        }
        encoder.clear_buffer(&b.hash.status, 0, None);
        encoder.clear_buffer(&b.hash.table, 0, None);
        stamp(encoder, "");
        {
            // The quadtrees from the control points (nothing to do unless they moved).
            let mut pass = passes.begin(encoder, "tessera cc stencils", false);
            dispatches += self.stencil.record(&mut pass, &k.stencil, &binds.stencil);
        }
        self.stencil.settle(encoder);
        {
            let mut pass = passes.begin(encoder, "tessera cc marking", false);
            let patches = self.patch_count;
            // The bounds of the faces, once (nothing to do without face leaves).
            dispatches += k
                .face_bound
                .dispatch(&mut pass, &binds.face_bound, patches.max(1), 64);
            // `cc_traverse.wgsl`: blocks of 8 patches, one invocation per trial.
            let trials = self.params.first_split.trials();
            let counting = patches.max(1).div_ceil(8) * 8 * trials;
            dispatches += k
                .traverse
                .dispatch(&mut pass, &binds.traverse[0], counting, 64);
            dispatches += b.marks_scan.record(&mut pass, &k.scan);
            dispatches += k
                .traverse
                .dispatch(&mut pass, &binds.traverse[1], patches.max(1), 64);
        }
        stamp(encoder, "marking");
        {
            let mut pass = passes.begin(encoder, "tessera cc vertices", false);
            let hash = &binds.hash;
            dispatches +=
                k.leaf_keys
                    .dispatch_indirect(&mut pass, &binds.leaf_keys, args, LEAF_ARGS);
            dispatches += k
                .hash
                .insert
                .dispatch_indirect(&mut pass, &hash.insert, args, ITEM_ARGS);
            dispatches +=
                k.hash
                    .mark_first
                    .dispatch_indirect(&mut pass, &hash.mark_first, args, ITEM_ARGS);
            dispatches +=
                k.polygon_count
                    .dispatch_indirect(&mut pass, &binds.polygon_count, args, LEAF_ARGS);
            dispatches += b.number_scan.record(&mut pass, &k.scan);
            dispatches +=
                k.assign_gather
                    .dispatch_indirect(&mut pass, &binds.assign_gather, args, ITEM_ARGS);
            // Its invocation 0 decides whether everything fits: only then is the output
            // written.
            dispatches +=
                k.polygon_emit
                    .dispatch_indirect(&mut pass, &binds.polygon_emit, args, LEAF_ARGS);
            // At most one vertex per item.
            dispatches += k
                .eval
                .kernel
                .dispatch_indirect(&mut pass, &binds.eval, args, ITEM_ARGS);
        }
        stamp(encoder, "vertices");
        {
            let mut pass = passes.begin(encoder, "tessera cc triangles", true);
            dispatches +=
                k.triangulate
                    .dispatch_indirect(&mut pass, &binds.triangulate, args, LEAF_ARGS);
        }
        stamp(encoder, "triangles");
        self.dispatches = dispatches;
        let state_size = std::mem::size_of::<CcState>() as u64;
        let hash_size = std::mem::size_of::<CcHashStatus>() as u64;
        let (state, hash, indirect) = (&self.state, &b.hash.status, b.output.indirect());
        self.readback.record(device, encoder, |encoder, readback| {
            encoder.copy_buffer_to_buffer(state, 0, readback, 0, state_size);
            encoder.copy_buffer_to_buffer(hash, 0, readback, state_size, hash_size);
            encoder.copy_buffer_to_buffer(indirect, 0, readback, state_size + hash_size, 4);
        });
    }

    /// What the last recorded run needed and wrote, once its submission has run (waits
    /// for the GPU).
    pub fn read_status(&mut self, device: &wgpu::Device) -> Result<CcStatus> {
        Ok(status_from_bytes(&self.readback.wait_last(device)?))
    }

    /// After an overflow, reallocates what was too small to what the run needed (with
    /// headroom). Returns the buffers replaced, if any; an error if the device cannot
    /// hold what is needed.
    fn grow(&mut self, device: &wgpu::Device, status: &CcStatus) -> Result<Option<Buffers>> {
        let grown = self.grow_buffers(device, status);
        if grown.is_err() {
            // Reported once, by the call that grew: the statuses of the runs recorded so
            // far are dropped, and the stage goes on with the buffers it has (a run that
            // needs less, at other parameters or in another view, fits them).
            self.readback.new_generation();
            self.latest = self.latest.map(|(s, _)| (s, false));
        }
        grown
    }

    fn grow_buffers(
        &mut self,
        device: &wgpu::Device,
        status: &CcStatus,
    ) -> Result<Option<Buffers>> {
        if !status.overflowed() {
            return Ok(None);
        }
        if status.state.overflow & OVERFLOW_WALK_CUT != 0 {
            return Err(walk_cut_error(None));
        }
        // A pool of decision blocks too small (bit 8) leaves replays short: that
        // disagreement is grown away, any other is a bug.
        if status.state.overflow & 2 != 0 && status.state.overflow & 8 == 0 {
            return Err(Error::Wgpu(
                "the marking's two passes disagreed on a patch's leaves".into(),
            ));
        }
        let s = &status.state;
        let old = self.buffers.caps;
        let grow = |need: u32, have: u32| {
            if need > have {
                need.saturating_add(need / 4)
            } else {
                have
            }
        };
        // With the leaves cut at their capacity, the rest counted only what was kept:
        // scale it to all the leaves.
        let kept = s.leaves.min(old.leaves).max(1) as u64;
        let scaled = |need: u32| {
            let all = need as u64 * s.leaves.max(1) as u64 / kept;
            all.min(u32::MAX as u64) as u32
        };
        // The pool of decision blocks grows with the leaves.
        let blocks = s
            .decision_blocks
            .saturating_sub(4 * self.patch_count.max(1));
        let mut caps = CcCapacities {
            leaves: grow(s.leaves.max(blocks), old.leaves),
            poly: grow(scaled(s.need_poly), old.poly),
            vertices: grow(scaled(s.vertices), old.vertices),
            indices: grow(scaled(s.need_indices), old.indices),
            hash_slots: old.hash_slots,
        };
        // Under the view's triangle cap, nothing grows past what a mesh within it needs
        // (a run that needs more coarsens the pixels instead): polygons of `m` points
        // make `m − 2` triangles, so at most the cap plus two per leaf.
        if let Some(cap) = self.view_set.and_then(|(v, _)| v.max_triangles) {
            let cap = (cap as u64 + cap as u64 / 4).min(u32::MAX as u64 / 8) as u32;
            let bound = |grown: u32, had: u32, most: u32| grown.min(had.max(most));
            caps.leaves = bound(caps.leaves, old.leaves, 2 * cap);
            caps.indices = bound(caps.indices, old.indices, 3 * cap);
            caps.poly = bound(caps.poly, old.poly, 5 * cap);
            caps.vertices = bound(caps.vertices, old.vertices, 5 * cap);
        }
        // The hash's items are eight per leaf, about half of them without a key, and
        // the keys distinct are fewer still: a table of eight slots per leaf keeps it
        // at most half full.
        if status.hash.overflow != 0 || caps.hash_slots < 8 * caps.leaves {
            caps.hash_slots = (2 * old.hash_slots).max(8 * caps.leaves);
        }
        if caps == old {
            return Err(Error::Wgpu(
                "the run overflowed but reports nothing larger than the buffers".into(),
            ));
        }
        let buffers = allocating(device, "the stage's grown buffers", || {
            Buffers::new(
                device,
                &self.kernels,
                ((self.patch_count, self.point_count), &self.state),
                (&self.params, self.epsilon(), self.view),
                caps,
            )
        })?;
        let old = std::mem::replace(&mut self.buffers, buffers);
        self.rebind(device);
        self.readback.new_generation();
        self.latest = self.latest.map(|(s, _)| (s, false));
        self.growths += 1;
        Ok(Some(old))
    }

    /// Runs to completion on its own submission, growing and rerunning until everything
    /// fits. For loading, tools and tests; a renderer records [`prepare`](Self::prepare).
    pub fn run_blocking(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<CcStatus> {
        // Under a triangle cap, from the pixels asked for: the CPU reference's ladder.
        if let Some((v, px)) = self.view_set {
            if let (Some(_), Some(asked)) = (v.max_triangles, v.pixels) {
                if px != asked {
                    self.set_pixels(asked);
                }
            }
        }
        crate::stage::run_blocking(self, device, queue)
    }

    /// Copies the output mesh back (files and tests).
    pub fn read_mesh(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        status: &CcStatus,
    ) -> Result<Mesh> {
        completed(status)?;
        self.buffers
            .output
            .read_mesh(device, queue, status.vertices(), status.indices)
    }
}

/// The leaves, hash items and polygons of a run as the kernels left them, for the tests
/// that compare `cc_traverse`, `cc_leaf_keys` and `cc_polygon` with their CPU twins
/// ([`tessera_core::catmull_clark::traverse`],
/// [`tessera_core::catmull_clark::gpu_model::leaf_items`],
/// [`tessera_core::catmull_clark::polygon`]).
#[doc(hidden)]
#[derive(Clone, Debug, Default)]
pub struct CcPolygons {
    pub leaves: Vec<CcCell>,
    /// Eight per leaf: the hash items' keys, their vertex ids and vertices.
    pub item_keys: Vec<[u32; 2]>,
    pub item_ids: Vec<u32>,
    pub item_points: Vec<CcVertexPoint>,
    /// Per patch: its first leaf; one more entry for the end.
    pub first_leaf: Vec<u32>,
    /// Per patch: the trial of its first split.
    pub first_trial: Vec<u32>,
    /// Per leaf: where its polygon starts in `verts`; one more entry for the end.
    pub offsets: Vec<u32>,
    /// Per leaf: the points found on each side.
    pub side_counts: Vec<[u32; 4]>,
    /// `[vertex id, i, j, 0]` per polygon vertex.
    pub verts: Vec<[u32; 4]>,
}

impl CcStage {
    /// Copies the leaves and polygons of the last run back (tests only).
    #[doc(hidden)]
    pub fn read_polygons(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        status: &CcStatus,
    ) -> Result<CcPolygons> {
        completed(status)?;
        let b = &self.buffers;
        let read = |buffer: &wgpu::Buffer, offset: u64, size: u64| {
            crate::readback::read_buffer(device, queue, buffer, offset, size)
        };
        let leaves = status.state.leaves as u64;
        let p = self.patch_count as u64;
        let marks: Vec<u32> = bytemuck::pod_collect_to_vec(&read(
            &b.marks,
            0,
            4 * (marks_cleared(self.patch_count) + p),
        )?);
        let chosen_at = marks_cleared(self.patch_count) as usize;
        let first_trial = marks[chosen_at..chosen_at + p as usize].to_vec();
        let offsets: Vec<u32> =
            bytemuck::pod_collect_to_vec(&read(&b.poly_offsets, 0, 4 * (leaves + 1))?);
        let side_base = 4 * (b.caps.leaves as u64 + 1);
        let side_counts =
            bytemuck::pod_collect_to_vec(&read(&b.poly_offsets, side_base, 16 * leaves)?);
        let total = offsets.last().copied().unwrap_or(0) as u64;
        let items = 8 * leaves;
        let point_bytes = std::mem::size_of::<CcVertexPoint>() as u64;
        Ok(CcPolygons {
            leaves: bytemuck::pod_collect_to_vec(&read(&b.leaves, 0, 16 * leaves)?),
            item_keys: bytemuck::pod_collect_to_vec(&read(&b.keys, 0, 8 * items)?),
            item_ids: bytemuck::pod_collect_to_vec(&read(&b.hash.ids, 0, 4 * items)?),
            item_points: bytemuck::pod_collect_to_vec(&read(
                &b.item_points,
                0,
                point_bytes * items,
            )?),
            first_leaf: marks[..=p as usize].to_vec(),
            first_trial,
            offsets,
            side_counts,
            verts: bytemuck::pod_collect_to_vec(&read(&b.poly_verts, 0, 16 * total)?),
        })
    }
}

impl GrowingStage for CcStage {
    type Status = CcStatus;
    // Growths, and the triangle cap's steps of √2 up to the viewport's diagonal.
    const MAX_GROWTHS: u32 = 40;
    fn record(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<()> {
        self.prepare(device, queue, encoder)
    }
    fn status(&mut self, device: &wgpu::Device) -> Result<CcStatus> {
        self.read_status(device)
    }
    fn grow_to(&mut self, device: &wgpu::Device, status: &CcStatus) -> Result<bool> {
        // Coarser pixels for a run over the view's triangle cap, never finer: the ladder
        // climbs from the pixels asked for, as the CPU reference's does.
        if let Some(px) = self.capped_pixels(status)? {
            if self.tolerance_px().is_some_and(|now| px > now) {
                self.step_pixels(status, px);
                return Ok(true);
            }
        }
        Ok(self.grow(device, status)?.is_some())
    }
}

/// The overflow bit of a marking walk the device cut short (`cc_traverse`).
const OVERFLOW_WALK_CUT: u32 = 4;

/// A marking walk cut short by the device's loop limit that coarser pixels cannot help:
/// a world tolerance, or pixels already past the viewport's diagonal.
fn walk_cut_error(pixels: Option<f64>) -> Error {
    let tried = match pixels {
        Some(px) => format!(" even at {px:.0} pixels"),
        None => String::new(),
    };
    Error::Wgpu(format!(
        "the device cut the marking's walk short{tried} (it stops loops after a number of iterations, as lavapipe's 65 535): a coarser tolerance, a smaller depth or midpoint splits walk less"
    ))
}

/// An error if the run overflowed: its buffers hold nothing whole of this run.
fn completed(status: &CcStatus) -> Result<()> {
    if status.overflowed() {
        return Err(Error::Wgpu(
            "the last run overflowed its buffers; grow and rerun".into(),
        ));
    }
    Ok(())
}

/// The word of the state buffer at this byte offset of [`CcState`].
fn state_word(offset: usize) -> u32 {
    (offset / 4) as u32
}

fn status_size() -> u64 {
    (std::mem::size_of::<CcState>() + std::mem::size_of::<CcHashStatus>() + 4) as u64
}

/// The stage decides every cell alone, by the flatness bound: the triangle bound's
/// check of each leaf against its neighbours' points is not on the GPU.
fn gpu_leaf_bound(params: &CcParams) -> Result<()> {
    if params.leaf_bound != LeafBound::Flatness {
        return Err(tessera_core::Error::Param(format!(
            "the GPU stage runs the flatness leaf bound only, not `{}` (a CPU option)",
            params.leaf_bound.name()
        ))
        .into());
    }
    Ok(())
}

/// A run's status from the bytes [`CcStage::record_run`] copies: the state, the hash's
/// status, the index count.
fn status_from_bytes(bytes: &[u8]) -> CcStatus {
    let state_size = std::mem::size_of::<CcState>();
    let hash_size = std::mem::size_of::<CcHashStatus>();
    CcStatus {
        state: bytemuck::pod_read_unaligned(&bytes[..state_size]),
        hash: bytemuck::pod_read_unaligned(&bytes[state_size..state_size + hash_size]),
        indices: bytemuck::pod_read_unaligned(&bytes[state_size + hash_size..][..4]),
    }
}

/// The kernels' parameters for `params` with ε resolved to `eps`, for a mesh of these
/// patches and level-1 points.
fn tess_params(
    (patch_count, points): (u32, u32),
    (params, eps, view): (&CcParams, f64, CcView),
    caps: CcCapacities,
) -> CcTessParams {
    CcTessParams {
        grid: params.grid(),
        max_depth: params.max_depth,
        tolerance: eps as f32,
        patch_count,
        leaf_capacity: caps.leaves,
        poly_capacity: caps.poly,
        index_capacity: caps.indices,
        trials: params.first_split.trials(),
        points,
        vertex_capacity: caps.vertices,
        pad: [0; 2],
        view,
    }
}

/// A view as the kernels read it: in single precision, the pixels 0 for none.
fn gpu_view(v: &ViewTolerance) -> Result<CcView> {
    let pixels = match v.pixels {
        None => 0.0,
        Some(px) if px.is_finite() && px > 0.0 => px as f32,
        Some(px) => {
            return Err(tessera_core::Error::Param(format!(
                "pixel tolerance must be a positive number, got {px}"
            ))
            .into())
        }
    };
    let view = &v.view;
    let clip = view.clip_matrix().as_mat4();
    if !clip.is_finite() {
        return Err(tessera_core::Error::Param(
            "view: the matrix does not fit single precision".into(),
        )
        .into());
    }
    Ok(CcView {
        clip: clip.to_cols_array_2d(),
        viewport: view.viewport().as_vec2().to_array(),
        pixels,
        near_w: view.near_w() as f32,
        cull: if v.cull { CC_VIEW_CULL_FRUSTUM } else { 0 }
            | if v.cull_backfaces {
                CC_VIEW_CULL_BACKFACES
            } else {
                0
            },
        face_leaves: v.face_leaves as u32,
        pad: [0; 2],
    })
}

impl Buffers {
    fn new(
        device: &wgpu::Device,
        kernels: &CcKernels,
        (counts, state): ((u32, u32), &wgpu::Buffer),
        params: (&CcParams, f64, CcView),
        caps: CcCapacities,
    ) -> Result<Self> {
        let trials = params.0.first_split.trials();
        let caps = CcCapacities {
            leaves: caps.leaves.max(1),
            poly: caps.poly.max(4),
            vertices: caps.vertices.max(1),
            indices: caps.indices.max(3),
            hash_slots: caps.hash_slots.max(1).next_power_of_two(),
        };
        // Eight hash items per leaf (`cc_leaf_keys`), about half of them keys.
        let items = 8 * caps.leaves;
        let point_bytes = std::mem::size_of::<CcVertexPoint>() as u64;
        for (what, bytes) in [
            ("leaf", caps.leaves as u64 * 16),
            ("hash item", items as u64 * point_bytes),
            ("polygon", caps.poly as u64 * 16),
            ("index", caps.indices as u64 * 4),
            (
                "vertex",
                caps.vertices as u64 * std::mem::size_of::<OutVertex>() as u64,
            ),
            ("vertex hash", caps.hash_slots as u64 * 12),
            (
                "patch marks",
                4 * marks_words(counts.0, caps.leaves, trials),
            ),
        ] {
            check_size(device, what, bytes)?;
        }
        let params = init_buffer(
            device,
            "tessera cc params",
            bytemuck::bytes_of(&tess_params(counts, params, caps)),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let cell_bytes = std::mem::size_of::<CcCell>() as u64;
        let poly_offsets = storage(
            device,
            "tessera cc polygon offsets",
            4 * (caps.leaves as u64 + 1 + 4 * caps.leaves as u64),
        );
        let hash = CcVertexHash::new(device, &kernels.hash, items, caps.hash_slots);
        // The hash's flags as far as there are items (CcHashStatus::items, word 0), the
        // polygon sizes as far as there are leaves (CcState::leaves).
        let number_scan = PrefixSum::pair(
            device,
            &kernels.scan,
            (&hash.offsets, hash.item_capacity, (&hash.status, 0)),
            (
                &poly_offsets,
                caps.leaves + 1,
                (state, state_word(std::mem::offset_of!(CcState, leaves))),
            ),
        );
        let marks = storage(
            device,
            "tessera cc patch marks",
            4 * marks_words(counts.0, caps.leaves, trials),
        );
        // Each patch's leaves, from the key of its best trial, and the total after them.
        let marks_scan = PrefixSum::of_keys(device, &kernels.scan, &marks, counts.0 + 1, (!0, 5));
        Ok(Buffers {
            caps,
            trials,
            params,
            leaves: storage(device, "tessera cc leaves", cell_bytes * caps.leaves as u64),
            keys: storage(device, "tessera cc keys", 8 * items as u64),
            item_points: storage(device, "tessera cc item points", point_bytes * items as u64),
            vertex_points: storage(
                device,
                "tessera cc vertex points",
                point_bytes * caps.vertices as u64,
            ),
            poly_offsets,
            poly_verts: storage(device, "tessera cc polygons", 16 * caps.poly as u64),
            hash,
            output: MeshBuffers::with_capacity(device, caps.vertices, caps.indices),
            number_scan,
            marks,
            marks_scan,
        })
    }
}

impl Binds {
    fn new<'a>(
        device: &wgpu::Device,
        k: &CcKernels,
        model: &'a CcModelBuffers,
        f: &Fixed<'a>,
        b: &'a Buffers,
    ) -> Self {
        let common = |pass: &'a wgpu::Buffer| -> Vec<(u32, &'a wgpu::Buffer)> {
            let mut e: Vec<(u32, &wgpu::Buffer)> = model.entries().to_vec();
            e.extend([
                (slot::PARAMS, &b.params),
                (slot::STATE, f.state),
                (slot::LEAVES, &b.leaves),
                (slot::MARKS, &b.marks),
                (slot::ARGS, f.args),
                (slot::TOPO, f.topo),
                (slot::HOMES, f.homes),
                (slot::PASS, pass),
                (slot::ITEM_POINTS, &b.item_points),
                (slot::POLY_OFFSETS, &b.poly_offsets),
                (slot::POLY_VERTS, &b.poly_verts),
                (slot::VERTICES, b.output.vertices()),
                (slot::INDICES, b.output.indices()),
                (slot::DRAW, b.output.indirect()),
                (slot::KEYS, &b.keys),
                (slot::TABLE, &b.hash.table),
                (slot::ITEM_SLOT, &b.hash.item_slot),
                (slot::HASH_STATUS, &b.hash.status),
                (slot::HASH_OFFSETS, &b.hash.offsets),
                (slot::IDS, &b.hash.ids),
                (slot::UNIQUE_KEYS, &b.hash.unique_keys),
                (slot::VERTEX_POINTS, &b.vertex_points),
            ]);
            e
        };
        let count = common(&f.passes[0]);
        let emit = common(&f.passes[1]);
        // The nets are textures (see `CcModelBuffers::nets`).
        let bind = |kernel: &Kernel, entries: &[(u32, &wgpu::Buffer)]| {
            kernel.bind_with_textures(device, entries, &model.textures())
        };
        Binds {
            face_bound: bind(&k.face_bound, &count),
            traverse: [bind(&k.traverse, &count), bind(&k.traverse, &emit)],
            leaf_keys: bind(&k.leaf_keys, &count),
            assign_gather: bind(&k.assign_gather, &count),
            polygon_count: bind(&k.polygon_count, &count),
            polygon_emit: bind(&k.polygon_emit, &count),
            triangulate: bind(&k.triangulate, &count),
            hash: b.hash.bind(device, &k.hash, &b.keys),
            eval: k.eval.bind(
                device,
                model,
                &b.vertex_points,
                // Its count is the counters' word 0, the vertices of a mesh that fits.
                f.state,
                b.output.vertices(),
            ),
            stencil: f.stencil.bind(device, &k.stencil, model),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_first_guess_for_many_patches_fits_the_device() {
        // Ten cars' patches: the plain guess asks for more than a 128 MiB binding, the
        // guess within it fits every buffer and keeps the small model's guess as it is.
        let limit = 128 << 20;
        let big = CcCapacities::guess(63_000);
        let item = 8 * std::mem::size_of::<CcVertexPoint>() as u64;
        assert!(big.leaves as u64 * item > limit);
        let fitted = big.within(limit);
        assert!(fitted.leaves as u64 * item <= limit);
        assert!(fitted.poly as u64 * 16 <= limit && fitted.indices as u64 * 4 <= limit);
        let vertex = std::mem::size_of::<OutVertex>() as u64;
        assert!(fitted.vertices as u64 * vertex <= limit);
        assert!(fitted.hash_slots.is_power_of_two() && fitted.hash_slots as u64 * 12 <= limit);
        assert!(fitted.leaves > 0 && fitted.leaves < big.leaves);
        let small = CcCapacities::guess(600);
        assert_eq!(small.within(limit), small);
    }
}
