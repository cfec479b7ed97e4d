// Structs shared with Rust (`tessera_core::gpu_types`), the stage's parameters, and the
// bindings every Bézier kernel names by the same number. A test checks the struct
// layouts against the Rust `#[repr(C)]` twins through naga's reflection.

const MAP_RES: u32 = 16u;
const MAP_ATLAS_TILES_PER_ROW: u32 = 256u;
const NET_TEXTURE_PATCHES_PER_ROW: u32 = 512u;
// The Catmull-Clark nets' pages (`tessera_core::gpu_types::CcNetLayout`): replaced by the
// device's layout when a kernel is built; these are WebGPU's default limits' values.
const CC_NETS_PER_ROW: u32 = 512u;
const CC_NET_PAGE_ROWS: u32 = 8192u;
// Pages the model's nets take: 1 (most models), or 4 for the kernels that read any page.
// A kernel compiled for one page has no branch on the page: lavapipe pays about a fifth
// of the marking's time for the branches, taken or not.
const CC_NET_PAGES_USED: u32 = 4u;
const TOPOLOGY_TEXTURE_WIDTH: u32 = 1024u;
const TOPO_TEXELS: u32 = 3u;
const COARSE_SEGMENTS: u32 = 3u;
const COARSE_TRIANGLES_PER_PATCH: u32 = 18u;
const INTERIOR_EDGES_PER_PATCH: u32 = 21u;
const INTERIOR_COARSE_VERTICES_PER_PATCH: u32 = 4u;
const MAX_DEPTH_LIMIT: u32 = 8u;
const EDGE_BIT_WORDS: u32 = 8u;
const DYADIC_SCALE: u32 = 256u;
const NO_SIDE: u32 = 0xffffffffu;

const TEST_MAP2P: u32 = 0u;
const TEST_MAP4P: u32 = 1u;
const TEST_MAP8P: u32 = 2u;
const TEST_FLAT: u32 = 3u;

struct GpuPatch {
    cp: array<f32, 48>,
}

struct GpuPatchTopo {
    corners: array<u32, 4>,
    sides: array<u32, 4>,
    flags: u32,
}

struct GpuCurve {
    owner: u32,
    flags: u32,
    coarse_vertex: u32,
    other: u32,
}

struct VertexRecord {
    patch_id: u32,
    u: f32,
    v: f32,
}

// `uv` is the point's (u, v) on `face`: the Bézier patch, or the Catmull-Clark control
// face in OpenSubdiv Bfr's parameterisation (`tessera_core::gpu_types::OutVertex`).
struct OutVertex {
    position: array<f32, 3>,
    normal: array<f32, 3>,
    uv: array<f32, 2>,
    face: u32,
}

struct DrawIndexedIndirectArgs {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

// Twin of `tessera_core::gpu_types::BezierParams`.
struct BezierParams {
    test: u32,
    threshold: f32,
    max_depth: u32,
    patches: u32,
    curves: u32,
    coarse_vertices: u32,
    coarse_edges: u32,
    coarse_triangles: u32,
    // Words per coarse triangle in `scratch`: lattice points, then collapsed-side points.
    points_words: u32,
    pole_words: u32,
    // 1 / (3 · 2^max_depth), rounded once on the CPU: lattice coordinates are scaled by
    // it (a multiplication is correctly rounded in WGSL, a division need not be).
    inv_lattice: f32,
    vertex_capacity: u32,
    index_capacity: u32,
    // What the map atlas's half-precision values are multiplied by (a power of two).
    map_scale: f32,
    // Word w of `scratch` is texel (w mod 2^scratch_shift, w >> scratch_shift).
    scratch_shift: u32,
    _pad: u32,
}

// What the run needed and whether it fit; read back only when the caller asks.
struct BezierStatus {
    vertices: u32,
    indices: u32,
    // Bit 0: vertices did not fit; bit 1: indices did not fit.
    overflow: u32,
    edge_vertices: u32,
    // Indirect dispatch of the vertex kernel (x, y, z workgroups).
    dispatch_x: u32,
    dispatch_y: u32,
    dispatch_z: u32,
    // The flat test's evaluations plus one per vertex (twin of `Tessellation::evaluations`).
    evaluations: u32,
    // Coarse triangles `tri_emit` takes (the emit order's first slots); the plain ones
    // after them go to `tri_emit_plain`. Each kernel's indirect dispatch.
    general_triangles: u32,
    emit_dispatch_x: u32,
    emit_dispatch_y: u32,
    emit_dispatch_z: u32,
    plain_dispatch_x: u32,
    plain_dispatch_y: u32,
    plain_dispatch_z: u32,
    // The mark kernel's indirect dispatch, raised by the root kernel with atomics
    // (through a word view of the buffer: STATUS_MARK_DISPATCH is its first word).
    mark_dispatch_x: u32,
    mark_dispatch_y: u32,
    mark_dispatch_z: u32,
    // Patches wholly outside a culling view's frustum.
    culled_patches: u32,
}

const STATUS_MARK_DISPATCH: u32 = 15u;

@group(0) @binding(0) var<uniform> params: BezierParams;

// Workgroups in x at most per dispatch; more spill into y, which the kernels fold back
// (twin of `MAX_GROUPS_X` in `tessera-wgpu`'s kernel.rs).
const MAX_GROUPS_X: u32 = 32768u;

// The tally buffer (binding 14; twin of `tessera_core::gpu_types::tally`): the flat
// test's evaluations, then how many coarse triangles fall in each emit-order bucket
// (turned into each bucket's first slot by the finish kernel), then how many the mark
// kernel walks.
const TALLY_EVALUATIONS: u32 = 0u;
const TALLY_ORDER: u32 = 1u;
const ORDER_BUCKETS: u32 = 256u;
// Coarse triangles the mark kernel walks, listed by the root kernel.
const TALLY_MARKED: u32 = TALLY_ORDER + ORDER_BUCKETS;
// Patches culled by the view, counted by the root kernel.
const TALLY_CULLED: u32 = TALLY_MARKED + 1u;
// Coarse vertices at a corner of a coarse triangle in view, then one bit per coarse
// vertex saying so, set by the root kernel: the others are not evaluated.
const TALLY_USED: u32 = TALLY_CULLED + 1u;
const TALLY_USED_BITS: u32 = TALLY_USED + 1u;

const PLAIN_BUCKET: u32 = ORDER_BUCKETS - 1u;

// The emit-order bucket of a coarse triangle that makes `made` triangles: plain ones
// last, in a bucket of their own; the others the most first, every count from
// ORDER_BUCKETS - 2 up in bucket 0 (twin of `order_bucket`).
fn order_bucket(made: u32, plain: bool) -> u32 {
    return select(PLAIN_BUCKET - 1u - min(made, PLAIN_BUCKET - 1u), PLAIN_BUCKET, plain);
}

// Where the emit order starts in `counts`, after the scan's
// [edge vertices | inner vertices | triangles | total]; each triangle's bucket follows.
fn order_base() -> u32 {
    return params.coarse_edges + 2u * params.coarse_triangles + 1u;
}

fn order_keys_base() -> u32 {
    return order_base() + params.coarse_triangles;
}

// Catmull-Clark (`tessera_core::gpu_types`, `tessera_core::catmull_clark::gpu_model`).
const CC_NODE_BEZIER: u32 = 0u;
const CC_NODE_SPLIT: u32 = 1u;
const CC_NODE_CORNER: u32 = 2u;
const CC_NODE_KIND_MASK: u32 = 0xffu;
const CC_NODE_BALL_SHIFT: u32 = 8u;
const CC_NO_ROOT: u32 = 0xffffffffu;
const CC_ROOT_CREASED: u32 = 1u;
// `tessera_core::gpu_types::{CC_ROOT_QUAD_FACE, CC_ROOT_CORNER_SHIFT}`.
const CC_ROOT_QUAD_FACE: u32 = 2u;
const CC_ROOT_CORNER_SHIFT: u32 = 8u;
const CC_PARAM_ONE: u32 = 0x80000000u;

struct CcNode {
    kind: u32,
    index: u32,
}

struct CcCorner {
    limit: array<f32, 3>,
    corner: u32,
    normal: array<f32, 3>,
    hull_radius: f32,
}

struct CcRoot {
    node: u32,
    nets: u32,
    corners: u32,
    flags: u32,
}

struct CcWeight {
    point: u32,
    weight: f32,
}

struct CcPatchStencil {
    ring: u32,
    table: u32,
    nets: u32,
    corners: u32,
    records: u32,
}

struct CcStencilTable {
    records: u32,
    record_count: u32,
    columns: u32,
    pad: u32,
}

const CC_RECORD_NET: u32 = 0u;
const CC_RECORD_BALL: u32 = 1u;
const CC_RECORD_CORNER: u32 = 2u;

struct CcPieceRecord {
    kind: u32,
    weights: u32,
    counts: u32,
    out: u32,
}

struct CcPoint {
    patch_id: u32,
    u: u32,
    v: u32,
}

// An output vertex to write: evaluated at its point's home (patch_id, u, v), carrying
// its face and face (u, v).
struct CcVertexPoint {
    patch_id: u32,
    u: u32,
    v: u32,
    face: u32,
    face_u: f32,
    face_v: f32,
}

const CC_NO_HOME: u32 = 0xffffffffu;

const CC_HASH_MAX_PROBES: u32 = 64u;
const CC_NO_SLOT: u32 = 0xffffffffu;
// An item without a key: the hash passes it over.
const CC_NO_KEY: vec2u = vec2u(0xffffffffu, 0xffffffffu);

// Adaptive Catmull-Clark tessellation (`tessera_core::gpu_types::{CcCell, ...}`).
const CC_TRIALS: u32 = 18u;
const CC_NO_NEIGHBOUR: u32 = 0xffffffffu;

struct CcCell {
    patch_id: u32,
    trial_depth: u32,
    i: u32,
    j: u32,
}

// `face_corner`: the patch's corner in its control face | the face's sides << 8.
struct CcPatchTopo {
    quad: vec4u,
    edges: vec4u,
    across: vec4u,
    face: u32,
    face_corner: u32,
    pad0: u32,
    pad1: u32,
}

struct CcTessParams {
    grid: u32,
    max_depth: u32,
    tolerance: f32,
    patch_count: u32,
    leaf_capacity: u32,
    poly_capacity: u32,
    index_capacity: u32,
    trials: u32,
    points: u32,
    vertex_capacity: u32,
    pad0: u32,
    pad1: u32,
    view: CcView,
}

// `tessera_core::gpu_types::CcView`: a view for tolerances in pixels (`pixels` > 0)
// and culling (`cull`: bits `CC_VIEW_CULL_*`), all zero for none.
struct CcView {
    clip: mat4x4f,
    viewport: vec2f,
    pixels: f32,
    near_w: f32,
    cull: u32,
    // 1: quad control faces that meet their tolerance whole are one leaf each.
    face_leaves: u32,
    pad1: u32,
    pad2: u32,
}

// `tessera_core::gpu_types::{CC_VIEW_CULL_FRUSTUM, CC_VIEW_CULL_BACKFACES}`.
const CC_VIEW_CULL_FRUSTUM: u32 = 1u;
const CC_VIEW_CULL_BACKFACES: u32 = 2u;

// `tessera_core::gpu_types::{CC_CELL_CULLED, CC_CELL_PATCH_CULLED}`: a leaf outside the
// view, which emits no triangles (its corners still mark its neighbours' sides), and one
// of a patch wholly outside, which has no vertices either.
const CC_CELL_CULLED: u32 = 0x80000000u;
const CC_CELL_PATCH_CULLED: u32 = 0x40000000u;
// `tessera_core::gpu_types::{CC_CELL_FACE, CC_CHOSEN_FACE_LEAF}`: a face leaf (the
// whole quad face of the leaf's patch, its first), and the mark on the trial chosen of
// each patch of a face leaf.
const CC_CELL_FACE: u32 = 0x20000000u;
const CC_CHOSEN_FACE_LEAF: u32 = 0x100u;

// Uniform Catmull-Clark tessellation (`tessera_core::gpu_types::{CcUniformPatch,
// CcUniformParams}`, flags of `tessera_core::catmull_clark::gpu_uniform`).
const CC_OWNS_CORNER: u32 = 1u;
const CC_OWNS_EDGE: u32 = 16u;
const CC_EDGE_REVERSED: u32 = 256u;

struct CcUniformPatch {
    patch_id: u32,
    corners: array<u32, 4>,
    edges: array<u32, 4>,
    flags: u32,
    face: u32,
    face_corner: u32,
    corner_homes: array<u32, 4>,
    edge_homes: array<u32, 4>,
}

struct CcUniformParams {
    segments: u32,
    patch_count: u32,
    corner_count: u32,
    edge_count: u32,
}
