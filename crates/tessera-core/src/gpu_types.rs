//! `#[repr(C)]` Pod structs shared with WGSL, and the buffer-size math around them.
//!
//! Each struct here has a twin of the same name in `shaders/shared/*.wgsl`; a test in the
//! wgpu crate checks sizes and field offsets against naga's reflection of the shaders.
//! All fields are 4-byte scalars or arrays of them, so WGSL lays them out exactly as
//! `#[repr(C)]` does (no vec3 padding surprises).

use bytemuck::{Pod, Zeroable};

/// Displacement-map resolution per patch side (the paper's 16×16).
pub const MAP_RES: usize = 16;

/// Coarse grid: the patch is sampled at `u, v ∈ {0, 1/3, 2/3, 1}`.
pub const COARSE_SEGMENTS: usize = 3;
/// Coarse triangles per patch (3×3 quads, two triangles each).
pub const COARSE_TRIANGLES_PER_PATCH: usize = 18;
/// Coarse edges inside a patch (not on its sides): 6 horizontal, 6 vertical, 9 diagonal.
pub const INTERIOR_EDGES_PER_PATCH: usize = 21;
/// Coarse vertices strictly inside a patch.
pub const INTERIOR_COARSE_VERTICES_PER_PATCH: usize = 4;
/// Largest supported recursion depth of the edge tests (2^8 segments per coarse edge).
pub const MAX_DEPTH_LIMIT: u32 = 8;
/// Words of the per-edge bit set of inserted dyadic points at `MAX_DEPTH_LIMIT`.
pub const EDGE_BIT_WORDS: usize = (1 << MAX_DEPTH_LIMIT) / 32;

/// The Bézier stage's tally buffer: atomic counters the kernels add to, as `u32` words
/// (twin of the `TALLY_*` constants in `shaders/shared/types.wgsl`).
pub mod tally {
    /// The flat test's surface evaluations.
    pub const EVALUATIONS: usize = 0;
    /// Coarse triangles per emit-order bucket, from here on
    /// (`tessera_core::bezier::tessellate::order_bucket`).
    pub const ORDER: usize = 1;
    /// Emit-order buckets: the plain coarse triangles one, the others by triangles
    /// made, 0..=253 one bucket each and 254 and more one.
    pub const ORDER_BUCKETS: u32 = 256;
    /// Coarse triangles whose bisection the mark kernel walks (the root kernel decides
    /// the others).
    pub const MARKED: usize = ORDER + ORDER_BUCKETS as usize;
    /// Patches culled by the view (counted by each one's first coarse triangle).
    pub const CULLED: usize = MARKED + 1;
    /// Coarse vertices that a coarse triangle in view has as a corner: the only ones
    /// evaluated (each counted by the triangle that marks it first).
    pub const USED: usize = CULLED + 1;
    /// From here on, one bit per coarse vertex: set by the triangles in view at their
    /// corners (bit `v % 32` of word `USED_BITS + v / 32`).
    pub const USED_BITS: usize = USED + 1;

    /// Words in the buffer for a model with `coarse_vertices` coarse vertices.
    pub fn words(coarse_vertices: u32) -> usize {
        USED_BITS + (coarse_vertices as usize).div_ceil(32)
    }
}

/// Control points of one bicubic patch, row-major, `x y z` per point.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuPatch {
    /// The 16 control points `b[4j + i]` (`i` along u), three floats each.
    pub cp: [f32; 48],
}

/// The 16×16 signed displacement map of one patch, `d[16 * j + i]` at
/// `(u, v) = (i / 15, j / 15)`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct DisplacementMap {
    /// Signed distances from the coarse mesh to the surface, model units, row-major
    /// (`j` along v).
    pub d: [f32; MAP_RES * MAP_RES],
}

/// Cells per side of a displacement map: a bilinear read interpolates the four corners
/// of one cell.
pub const MAP_CELLS: usize = MAP_RES - 1;
/// Patches per row of the map atlas: a power of two, so that the shaders find a patch's
/// tile with a mask and a shift (an integer division is a scalar loop over the lanes on
/// a CPU device).
pub const MAP_ATLAS_TILES_PER_ROW: u32 = 256;

/// The displacement maps as they go up: each map's `MAP_RES × MAP_RES` values divided by
/// `map_scale`, in half precision, two to a word (value `2k` in the low half): 512 bytes
/// per patch. The kernels read the maps from a [`MapAtlas`], which a one-time kernel
/// (`shaders/bezier_map_cells.wgsl`) builds from these words on the device, so the
/// atlas's fourfold copies never cross the bus.
#[derive(Clone, Debug, PartialEq)]
pub struct MapHalves {
    /// `WORDS_PER_PATCH` words per patch, in patch order.
    pub words: Vec<u32>,
}

impl MapHalves {
    /// Two halves to a word.
    pub const WORDS_PER_PATCH: usize = MAP_RES * MAP_RES / 2;

    /// The words of `maps`, whose values are half-precision multiples of `map_scale`
    /// with no subnormal half, as [`crate::bezier::prepare::quantize_maps`] leaves them:
    /// the device's atlas kernel reads normal halves and zero only.
    pub fn new(maps: &[DisplacementMap], map_scale: f32) -> Self {
        let half = |d: f32| half::f16::from_f32(d / map_scale).to_bits() as u32;
        let words = maps
            .iter()
            .flat_map(|m| m.d.chunks_exact(2).map(|d| half(d[0]) | half(d[1]) << 16))
            .collect();
        MapHalves { words }
    }

    /// The half-precision bits of value `k` (`MAP_RES * j + i`) of patch `p`.
    pub fn value_bits(&self, p: usize, k: usize) -> u16 {
        let word = self.words[p * Self::WORDS_PER_PATCH + k / 2];
        (word >> (16 * (k % 2))) as u16
    }

    /// Bytes uploaded for `patches` maps.
    pub fn bytes(patches: usize) -> u64 {
        (patches * Self::WORDS_PER_PATCH * 4) as u64
    }
}

/// The displacement maps as the GPU kernels read them: an `rgba16float` texture whose
/// texel `(i, j)` of a patch's tile holds the four corners of map cell `(i, j)`,
/// `(d[i, j], d[i+1, j], d[i, j+1], d[i+1, j+1]) / map_scale`, for `i, j < MAP_CELLS`.
/// Patch `p`'s tile, `MAP_CELLS` × `MAP_CELLS` texels, is at column
/// `p % MAP_ATLAS_TILES_PER_ROW`, row `p / MAP_ATLAS_TILES_PER_ROW`.
///
/// A bilinear read is then one texel fetch, where a storage buffer takes four reads: on a
/// CPU device (lavapipe) a read at a per-lane address is a scalar loop over the lanes
/// whatever its width, and the decision kernels spend most of their time in map reads
/// (an atlas of pairs, `d[i, j], d[i+1, j]`, would take two fetches). Cells in half
/// precision take 1800 bytes per patch of device memory; what is uploaded is the maps
/// themselves ([`MapHalves`], 512 bytes per patch), and the atlas is built from them on
/// the device ([`MapAtlas::from_halves`] is the kernel's twin). The maps are rounded to half precision when prepared
/// ([`crate::bezier::prepare::quantize_maps`]), so the texels hold their values exactly
/// and the reads stay bit-identical to the CPU twin ([`crate::bezier::prepare::map_read`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MapAtlas {
    /// Texture width in texels (see [`MapAtlas::size`]).
    pub width: u32,
    /// Texture height in texels.
    pub height: u32,
    /// Row-major, `width × height` texels, each four `f16` bit patterns.
    pub texels: Vec<[u16; 4]>,
}

/// Columns and rows of `patches` tiles laid out `per_row` to a row; at least one tile.
fn tile_grid(patches: usize, per_row: u32) -> (u32, u32) {
    let per_row = per_row as usize;
    (
        patches.clamp(1, per_row) as u32,
        patches.div_ceil(per_row).max(1) as u32,
    )
}

impl MapAtlas {
    /// Texels per tile side: (width, height).
    pub const TILE: (u32, u32) = (MAP_CELLS as u32, MAP_CELLS as u32);

    /// Texture size (width, height) in texels for `patches` maps; at least one tile.
    pub fn size(patches: usize) -> (u32, u32) {
        let (columns, rows) = tile_grid(patches, MAP_ATLAS_TILES_PER_ROW);
        (columns * Self::TILE.0, rows * Self::TILE.1)
    }

    /// Texel coordinates of cell `(i, j)` of patch `p` (twin of the shader's `map_read`).
    pub fn texel_of(p: u32, i: u32, j: u32) -> (u32, u32) {
        (
            (p % MAP_ATLAS_TILES_PER_ROW) * Self::TILE.0 + i,
            (p / MAP_ATLAS_TILES_PER_ROW) * Self::TILE.1 + j,
        )
    }

    /// The atlas of `maps`, whose values are half-precision multiples of `map_scale`.
    pub fn new(maps: &[DisplacementMap], map_scale: f32) -> Self {
        Self::from_halves(&MapHalves::new(maps, map_scale))
    }

    /// The atlas of the uploaded maps: twin of `shaders/bezier_map_cells.wgsl`, one
    /// texel per work item.
    pub fn from_halves(halves: &MapHalves) -> Self {
        let patches = halves.words.len() / MapHalves::WORDS_PER_PATCH;
        let (width, height) = Self::size(patches);
        let mut texels = vec![[0u16; 4]; width as usize * height as usize];
        let cells = MAP_CELLS * MAP_CELLS;
        for item in 0..patches * cells {
            let (p, cell) = (item / cells, item % cells);
            let (i, j) = (cell % MAP_CELLS, cell / MAP_CELLS);
            let k = MAP_RES * j + i;
            let below = k + MAP_RES;
            let (x, y) = Self::texel_of(p as u32, i as u32, j as u32);
            texels[y as usize * width as usize + x as usize] =
                [k, k + 1, below, below + 1].map(|k| halves.value_bits(p, k));
        }
        MapAtlas {
            width,
            height,
            texels,
        }
    }

    /// Bytes of the texture.
    pub fn bytes(patches: usize) -> u64 {
        let (w, h) = Self::size(patches);
        w as u64 * h as u64 * std::mem::size_of::<[u16; 4]>() as u64
    }
}

/// Patches per row of the control-net texture (a power of two, like
/// [`MAP_ATLAS_TILES_PER_ROW`]).
pub const NET_TEXTURE_PATCHES_PER_ROW: u32 = 512;

/// The control points as the GPU kernels read them: an `rgba32float` texture, one row of
/// [`NET_TEXTURE_PATCHES_PER_ROW`] patches per texel row, each patch 12 texels holding
/// its [`GpuPatch::cp`] in order (a row of the net, four points `x y z`, is three
/// texels). On a CPU device (lavapipe) a storage read at a per-lane address is a scalar
/// loop over the lanes for each 32-bit word, and a net is 48 words, which would make
/// reading it most of the vertex kernel's work; a texel fetch is vectorised.
/// The same 192 bytes per patch as a storage buffer would hold.
#[derive(Clone, Debug, PartialEq)]
pub struct NetTexture {
    /// Texture width in texels (see [`NetTexture::size`]).
    pub width: u32,
    /// Texture height in texels.
    pub height: u32,
    /// Row-major, `width × height` texels.
    pub texels: Vec<[f32; 4]>,
}

impl NetTexture {
    /// Texels per patch.
    pub const TEXELS_PER_PATCH: u32 = 12;

    /// Texture size (width, height) in texels for `patches` nets; at least one texel row.
    pub fn size(patches: usize) -> (u32, u32) {
        let (columns, rows) = tile_grid(patches, NET_TEXTURE_PATCHES_PER_ROW);
        (columns * Self::TEXELS_PER_PATCH, rows)
    }

    /// Texel coordinates of texel `k` of patch `p` (twin of the shader's `net_texel`).
    pub fn texel_of(p: u32, k: u32) -> (u32, u32) {
        (
            (p % NET_TEXTURE_PATCHES_PER_ROW) * Self::TEXELS_PER_PATCH + k,
            p / NET_TEXTURE_PATCHES_PER_ROW,
        )
    }

    /// The texture of `patches`, patch `p` in texels `texel_of(p, 0..12)`; the texels
    /// past the last patch are zero.
    pub fn new(patches: &[GpuPatch]) -> Self {
        let (width, height) = Self::size(patches.len());
        let mut texels = vec![[0.0f32; 4]; width as usize * height as usize];
        for (p, patch) in patches.iter().enumerate() {
            for (k, texel) in patch.cp.chunks_exact(4).enumerate() {
                let (x, y) = Self::texel_of(p as u32, k as u32);
                texels[y as usize * width as usize + x as usize].copy_from_slice(texel);
            }
        }
        NetTexture {
            width,
            height,
            texels,
        }
    }

    /// Bytes of the texture.
    pub fn bytes(patches: usize) -> u64 {
        let (w, h) = Self::size(patches);
        w as u64 * h as u64 * std::mem::size_of::<[f32; 4]>() as u64
    }
}

/// Textures the Catmull-Clark nets are spread over: WebGPU's default limit of storage
/// textures per kernel, so every kernel that reads nets binds all of them.
pub const CC_NET_PAGES: u32 = 4;

/// The largest side of one page of Catmull-Clark nets: 16384 rows of 512 nets are 1.6 GB,
/// under the 2 GiB a single allocation may take on some devices (lavapipe among them),
/// where one texture as large as the device's side allows could not be allocated.
pub const CC_NET_PAGE_SIDE: u32 = 16384;

/// Where the Catmull-Clark stages keep their Bézier nets: [`CC_NET_PAGES`] `rgba32float`
/// textures ("pages"), each [`nets_per_row`](Self::nets_per_row) nets of 12 texels across
/// (as in [`NetTexture`]) and up to [`rows`](Self::rows) rows down. Net `k` lies in page
/// `k / nets_per_page`. The sides follow the device's largest texture side, so a model
/// may derive four times the nets one texture holds; the kernels are built with the same
/// layout (their constants `CC_NETS_PER_ROW` and `CC_NET_PAGE_ROWS`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CcNetLayout {
    /// Nets per texel row: [`NET_TEXTURE_PATCHES_PER_ROW`], fewer on a device whose
    /// textures are narrower than its 6144 texels.
    pub nets_per_row: u32,
    /// Rows of a full page.
    pub rows: u32,
}

impl CcNetLayout {
    /// The layout for a device whose 2D textures have sides of at most `max_side`.
    pub fn new(max_side: u32) -> Self {
        let side = max_side.min(CC_NET_PAGE_SIDE);
        CcNetLayout {
            nets_per_row: (side / NetTexture::TEXELS_PER_PATCH)
                .clamp(1, NET_TEXTURE_PATCHES_PER_ROW),
            rows: side.max(1),
        }
    }

    /// Nets a full page holds.
    pub fn nets_per_page(&self) -> u64 {
        self.nets_per_row as u64 * self.rows as u64
    }

    /// Nets the pages hold together.
    pub fn capacity(&self) -> u64 {
        CC_NET_PAGES as u64 * self.nets_per_page()
    }

    /// Page and texel coordinates of texel `t` (0..12) of net `k`: twin of the kernels'
    /// `cc_net_page` and `cc_net_at`.
    pub fn texel_of(&self, k: u32, t: u32) -> (u32, u32, u32) {
        let per_page = self.nets_per_page() as u32;
        let (page, i) = (k / per_page, k % per_page);
        (
            page,
            (i % self.nets_per_row) * NetTexture::TEXELS_PER_PATCH + t,
            i / self.nets_per_row,
        )
    }

    /// Nets of `nets` that page `page` holds.
    pub fn page_nets(&self, nets: usize, page: u32) -> usize {
        let per_page = self.nets_per_page() as usize;
        nets.saturating_sub(page as usize * per_page).min(per_page)
    }

    /// Size (width, height) in texels of each page for `nets` nets; a page without nets
    /// is one texel (a binding is never empty).
    pub fn page_sizes(&self, nets: usize) -> [(u32, u32); CC_NET_PAGES as usize] {
        std::array::from_fn(|page| match self.page_nets(nets, page as u32) {
            0 => (1, 1),
            n => {
                let (columns, rows) = tile_grid(n, self.nets_per_row);
                (columns * NetTexture::TEXELS_PER_PATCH, rows)
            }
        })
    }

    /// The texels of each page holding `nets` (row-major, without padding; past the
    /// last net, zero).
    pub fn pages(&self, nets: &[GpuPatch]) -> Vec<Vec<[f32; 4]>> {
        let sizes = self.page_sizes(nets.len());
        let mut pages: Vec<Vec<[f32; 4]>> = sizes
            .iter()
            .map(|&(w, h)| vec![[0.0; 4]; w as usize * h as usize])
            .collect();
        for (k, net) in nets.iter().enumerate() {
            for (t, texel) in net.cp.chunks_exact(4).enumerate() {
                let (page, x, y) = self.texel_of(k as u32, t as u32);
                let width = sizes[page as usize].0;
                pages[page as usize][(y * width + x) as usize].copy_from_slice(texel);
            }
        }
        pages
    }
}

/// Texels per row of the [`TopologyTexture`] (a power of two, like
/// [`MAP_ATLAS_TILES_PER_ROW`]).
pub const TOPOLOGY_TEXTURE_WIDTH: u32 = 1024;

/// Texels of a [`GpuPatchTopo`] in the [`TopologyTexture`]: corners, sides, flags.
pub const TOPO_TEXELS: u32 = 3;

/// Patch topology and boundary curves as the GPU kernels read them: one `rgba32uint`
/// texture, texel `i` at `(i mod 1024, i / 1024)`; patch `p`'s [`GpuPatchTopo`] in texels
/// `3p .. 3p + 2` (corners, sides, then flags zero-padded), then curve `c`'s [`GpuCurve`]
/// in texel `3 · patches + c`. The kernels read them at per-lane addresses, and on a CPU
/// device a storage buffer read there is a loop over the lanes, a texel fetch a plain
/// load (see [`NetTexture`]). One texture for both, since WebGPU's default limit is 4
/// storage textures per kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct TopologyTexture {
    /// Texture width in texels, at most [`TOPOLOGY_TEXTURE_WIDTH`].
    pub width: u32,
    /// Texture height in texels.
    pub height: u32,
    /// Row-major, `width × height` texels.
    pub texels: Vec<[u32; 4]>,
}

impl TopologyTexture {
    /// Texture size (width, height) in texels; at least one texel.
    pub fn size(patches: usize, curves: usize) -> (u32, u32) {
        let texels = (TOPO_TEXELS as usize * patches + curves).max(1);
        let width = TOPOLOGY_TEXTURE_WIDTH as usize;
        (texels.min(width) as u32, texels.div_ceil(width) as u32)
    }

    /// The texture of the patches' topology `topo` followed by `curves`; unused texels
    /// are zero.
    pub fn new(topo: &[GpuPatchTopo], curves: &[GpuCurve]) -> Self {
        let (width, height) = Self::size(topo.len(), curves.len());
        let mut texels = vec![[0u32; 4]; width as usize * height as usize];
        for (p, t) in topo.iter().enumerate() {
            let at = TOPO_TEXELS as usize * p;
            texels[at] = t.corners;
            texels[at + 1] = t.sides;
            texels[at + 2] = [t.flags, 0, 0, 0];
        }
        let first_curve = TOPO_TEXELS as usize * topo.len();
        for (c, curve) in curves.iter().enumerate() {
            texels[first_curve + c] = [curve.owner, curve.flags, curve.coarse_vertex, curve.other];
        }
        TopologyTexture {
            width,
            height,
            texels,
        }
    }

    /// Bytes of the texture.
    pub fn bytes(patches: usize, curves: usize) -> u64 {
        let (w, h) = Self::size(patches, curves);
        w as u64 * h as u64 * 16
    }
}

/// Connectivity of one patch.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct GpuPatchTopo {
    /// Global corner ids at (0,0), (1,0), (1,1), (0,1).
    pub corners: [u32; 4],
    /// Per side: `curve << 1 | reversed`.
    pub sides: [u32; 4],
    /// Bit 0: the patch's winding is flipped.
    pub flags: u32,
}

impl GpuPatchTopo {
    /// The boundary curve on side `side` (0..4: `v = 0`, `u = 1`, `v = 1`, `u = 0`).
    pub fn side_curve(&self, side: usize) -> u32 {
        self.sides[side] >> 1
    }
    /// Whether side `side` runs against its curve's canonical direction.
    pub fn side_reversed(&self, side: usize) -> bool {
        self.sides[side] & 1 != 0
    }
    /// Whether the patch's winding is flipped (its normals are negated, its triangles
    /// emitted in reverse order).
    pub fn flipped(&self) -> bool {
        self.flags & 1 != 0
    }
}

/// A boundary curve shared by patch sides.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct GpuCurve {
    /// Patch that evaluates points on the curve.
    pub owner: u32,
    /// Bits 0..2: the owner's side; bit 2: collapsed to a point.
    pub flags: u32,
    /// Collapsed: the corner id of the point. Otherwise: the id of the first of its two
    /// interior coarse vertices (at canonical fractions 1/3 and 2/3).
    pub coarse_vertex: u32,
    /// The other patch side on the curve, `patch << 2 | side`, or [`GpuCurve::NO_SIDE`]
    /// on an open boundary. (A curve shared by three or more sides lists one of them:
    /// the others refine it from their own side only, see `bezier/refine.rs`.)
    pub other: u32,
}

impl GpuCurve {
    /// [`GpuCurve::other`] of a curve on an open boundary (`NO_SIDE` in WGSL).
    pub const NO_SIDE: u32 = u32::MAX;
    /// The side of [`owner`](GpuCurve::owner) that the curve is on (0..4).
    pub fn owner_side(&self) -> usize {
        (self.flags & 3) as usize
    }
    /// Whether the curve is collapsed to a point (a degenerate patch side).
    pub fn collapsed(&self) -> bool {
        self.flags & 4 != 0
    }
}

/// Where a vertex is evaluated: the patch and its parameter. The vertex kernel turns
/// one of these into one output vertex.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct VertexRecord {
    /// Patch index (`patch_id` in WGSL).
    pub patch: u32,
    /// Parameter along the patch's u, in `[0, 1]`.
    pub u: f32,
    /// Parameter along the patch's v, in `[0, 1]`.
    pub v: f32,
}

/// One output vertex, 36 bytes (the layer-strip paper's figure too).
///
/// `face` and `uv` say where on the input the vertex lies. Bézier path: the patch (in
/// the file's order) and its `(u, v)` in `[0, 1]²`. Catmull-Clark path: the control face
/// (in the input's order) and the face's own `(u, v)` in OpenSubdiv Bfr's
/// parameterisation ([`PatchMesh::face_point`](crate::catmull_clark::PatchMesh::face_point);
/// Ptex's for quads: `(0, 0)` at the face's first vertex, `u` toward its second, `v`
/// toward its last). A point on an edge between two control faces, or between the
/// sub-faces of a face that is not a quad, has one vertex per face or sub-face: the
/// copies have the same position and normal, bit for bit, and each its own `face` and
/// `uv`, so that every triangle lies in one face.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct OutVertex {
    /// Surface point, model units.
    pub position: [f32; 3],
    /// Unit surface normal, facing the front of the patch.
    pub normal: [f32; 3],
    /// The point's `(u, v)` on its face.
    pub uv: [f32; 2],
    /// The face the vertex lies in: the Bézier patch or the Catmull-Clark control face.
    pub face: u32,
}

/// `wgpu`'s indexed indirect draw arguments, as the GPU writes them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
pub struct DrawIndexedIndirectArgs {
    /// Indices to draw (three per triangle; 0 after an overflow).
    pub index_count: u32,
    /// Instances to draw (1).
    pub instance_count: u32,
    /// First index read from the index buffer.
    pub first_index: u32,
    /// Added to each index before the vertex buffer is read.
    pub base_vertex: i32,
    /// First instance id.
    pub first_instance: u32,
}

/// Parameters of the Bézier kernels (`BezierParams` in `shaders/shared/types.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BezierParams {
    /// [`EdgeTest`](crate::bezier::EdgeTest) index. For readers of the buffer: the
    /// kernels take the test as their pipeline constant `EDGE_TEST` instead.
    pub test: u32,
    /// The edge tests' threshold `th`, model units
    /// ([`AdaptiveParams::threshold`](crate::bezier::AdaptiveParams::threshold)).
    pub threshold: f32,
    /// Levels of bisection per coarse edge, at most [`MAX_DEPTH_LIMIT`].
    pub max_depth: u32,
    /// Patches in the model.
    pub patches: u32,
    /// Boundary curves ([`GpuCurve`]s) in the topology texture.
    pub curves: u32,
    /// Coarse vertices: the first records of the vertex-record buffer (binding 9).
    pub coarse_vertices: u32,
    /// Coarse edges: three per curve, then [`INTERIOR_EDGES_PER_PATCH`] per patch.
    pub coarse_edges: u32,
    /// Coarse triangles: [`COARSE_TRIANGLES_PER_PATCH`] per patch.
    pub coarse_triangles: u32,
    /// Words of lattice points per coarse triangle in the scratch texture.
    pub points_words: u32,
    /// Words of collapsed-side points per coarse triangle in the scratch texture.
    pub pole_words: u32,
    /// `1 / (3 · 2^max_depth)` (see `lattice::inv_lattice`).
    pub inv_lattice: f32,
    /// Output vertices the vertex buffers hold (bindings 9 and 10).
    pub vertex_capacity: u32,
    /// Output indices the index buffer holds (binding 11).
    pub index_capacity: u32,
    /// What the map atlas's half-precision values are multiplied by (a power of two).
    pub map_scale: f32,
    /// Scratch word `w` is texel `(w mod 2^scratch_shift, w >> scratch_shift)` of the
    /// scratch texture.
    pub scratch_shift: u32,
    /// Padding to a multiple of 16 bytes; zero.
    pub _pad: u32,
}

impl BezierParams {
    /// Member names in WGSL order (the layout test compares them with the shader).
    pub const FIELD_NAMES: [&'static str; 16] = [
        "test",
        "threshold",
        "max_depth",
        "patches",
        "curves",
        "coarse_vertices",
        "coarse_edges",
        "coarse_triangles",
        "points_words",
        "pole_words",
        "inv_lattice",
        "vertex_capacity",
        "index_capacity",
        "map_scale",
        "scratch_shift",
        "_pad",
    ];
}

/// What a GPU run needed and whether it fit (`BezierStatus` in WGSL), and the indirect
/// dispatches of the kernels whose sizes the run decides.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Default)]
pub struct BezierStatus {
    /// Output vertices the run made (or needed).
    pub vertices: u32,
    /// Output indices the run made (or needed).
    pub indices: u32,
    /// Bit 0: the vertices did not fit; bit 1: the indices did not fit.
    pub overflow: u32,
    /// Vertices inserted on the coarse edges (numbered after the coarse vertices).
    pub edge_vertices: u32,
    /// The vertex kernel's indirect dispatch, `x y z` workgroups (`dispatch_x` ..
    /// `dispatch_z` in WGSL).
    pub dispatch: [u32; 3],
    /// Surface evaluations: the flat test's (3 per tested chord) plus one per vertex a
    /// triangle uses (the coarse vertices only triangles of culled patches have as
    /// corners are not evaluated).
    pub evaluations: u32,
    /// Coarse triangles the general emit kernel takes (the first slots of the emit
    /// order); the plain ones after them go to the plain kernel.
    pub general_triangles: u32,
    /// The general emit kernel's indirect dispatch.
    pub emit_dispatch: [u32; 3],
    /// The plain emit kernel's indirect dispatch.
    pub plain_dispatch: [u32; 3],
    /// The mark kernel's indirect dispatch, over the coarse triangles whose root the
    /// root kernel could not decide alone (zeroed before each run).
    pub mark_dispatch: [u32; 3],
    /// Patches wholly outside a culling view's frustum
    /// ([`Tessellation::culled_patches`](crate::bezier::Tessellation::culled_patches)).
    pub culled_patches: u32,
}

/// Bytes uploaded per patch and once per model for the map-based tessellator: the
/// control-net texture, the maps (in half precision; the atlas is built on the device),
/// the topology texture (patches and curves), and coarse vertices.
pub fn bezier_upload_bytes(patches: usize, curves: usize, coarse_vertices: usize) -> usize {
    TopologyTexture::bytes(patches, curves) as usize
        + NetTexture::bytes(patches) as usize
        + MapHalves::bytes(patches) as usize
        + coarse_vertices * std::mem::size_of::<VertexRecord>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_are_what_the_shaders_expect() {
        assert_eq!(std::mem::size_of::<GpuPatch>(), 192);
        assert_eq!(std::mem::size_of::<DisplacementMap>(), 1024);
        assert_eq!(std::mem::size_of::<GpuPatchTopo>(), 36);
        assert_eq!(std::mem::size_of::<GpuCurve>(), 16);
        assert_eq!(std::mem::size_of::<VertexRecord>(), 12);
        assert_eq!(std::mem::size_of::<OutVertex>(), 36);
        assert_eq!(std::mem::size_of::<CcPatchTopo>(), 64);
        assert_eq!(std::mem::size_of::<CcUniformPatch>(), 80);
        assert_eq!(std::mem::size_of::<CcVertexPoint>(), 24);
        assert_eq!(std::mem::size_of::<DrawIndexedIndirectArgs>(), 20);
    }

    #[test]
    fn the_atlas_holds_each_map_cell_in_its_patch_tile() {
        // 300 maps of values that half precision holds exactly (integers under 2048,
        // scale 1/4): two rows of tiles, the second partly filled.
        let maps: Vec<DisplacementMap> = (0..300)
            .map(|p| DisplacementMap {
                d: std::array::from_fn(|k| ((p * 7 + k) % 2000) as f32 * 0.25),
            })
            .collect();
        let atlas = MapAtlas::new(&maps, 0.25);
        assert_eq!((atlas.width, atlas.height), (256 * 15, 2 * 15));
        assert_eq!(atlas.texels.len(), (atlas.width * atlas.height) as usize);
        assert_eq!(MapAtlas::size(1), (15, 15));
        assert_eq!(MapAtlas::size(0), (15, 15));
        let value = |bits: u16| half::f16::from_bits(bits).to_f32() * 0.25;
        for p in 0..300u32 {
            for (i, j) in [(0, 0), (14, 2), (7, 14), (14, 14)] {
                let (x, y) = MapAtlas::texel_of(p, i, j);
                let texel = atlas.texels[(y * atlas.width + x) as usize];
                let d = |i: u32, j: u32| maps[p as usize].d[(16 * j + i) as usize];
                assert_eq!(
                    texel.map(value),
                    [d(i, j), d(i + 1, j), d(i, j + 1), d(i + 1, j + 1)],
                    "patch {p} cell ({i}, {j})"
                );
            }
        }
        assert_eq!(MapAtlas::texel_of(256, 0, 0), (0, 15));
        // On the device; the upload is the maps themselves, in half precision.
        assert_eq!(MapAtlas::bytes(256) / 256, 1800);
        assert_eq!(MapHalves::bytes(256) / 256, 512);
        let halves = MapHalves::new(&maps, 0.25);
        for p in [0, 299] {
            for k in [0, 1, 17, 255] {
                let bits = halves.value_bits(p, k);
                assert_eq!(value(bits), maps[p].d[k], "patch {p} value {k}");
            }
        }
    }

    #[test]
    fn the_net_texture_holds_each_patch_in_twelve_texels() {
        let row = NET_TEXTURE_PATCHES_PER_ROW;
        let patches: Vec<GpuPatch> = (0..row + 44)
            .map(|p| GpuPatch {
                cp: std::array::from_fn(|k| (p as usize * 48 + k) as f32),
            })
            .collect();
        let nets = NetTexture::new(&patches);
        assert_eq!((nets.width, nets.height), (row * 12, 2));
        assert_eq!(NetTexture::size(1), (12, 1));
        for (p, patch) in patches.iter().enumerate() {
            for k in 0..48 {
                let (x, y) = NetTexture::texel_of(p as u32, k as u32 / 4);
                let texel = nets.texels[(y * nets.width + x) as usize];
                assert_eq!(texel[k % 4], patch.cp[k], "patch {p}, word {k}");
            }
        }
        assert_eq!(NetTexture::texel_of(row, 0), (0, 1));
        // As many bytes as the nets themselves.
        assert_eq!(
            NetTexture::bytes(row as usize) as usize,
            row as usize * std::mem::size_of::<GpuPatch>()
        );
    }

    #[test]
    fn the_net_pages_hold_each_net_once_in_page_order() {
        // A device of 40-texel sides: 3 nets per row, 40 rows, 120 nets per page.
        let layout = CcNetLayout::new(40);
        assert_eq!((layout.nets_per_row, layout.rows), (3, 40));
        assert_eq!(layout.capacity(), 480);
        let nets: Vec<GpuPatch> = (0..250)
            .map(|p| GpuPatch {
                cp: std::array::from_fn(|k| (p * 48 + k) as f32),
            })
            .collect();
        assert_eq!(
            layout.page_sizes(nets.len()),
            [(36, 40), (36, 40), (36, 4), (1, 1)]
        );
        let pages = layout.pages(&nets);
        let mut texels = std::collections::HashSet::new();
        for (k, net) in nets.iter().enumerate() {
            for w in 0..48 {
                let (page, x, y) = layout.texel_of(k as u32, w as u32 / 4);
                let width = layout.page_sizes(nets.len())[page as usize].0;
                assert_eq!(
                    pages[page as usize][(y * width + x) as usize][w % 4],
                    net.cp[w]
                );
                texels.insert((page, x, y));
            }
        }
        // No net shares a texel with another.
        assert_eq!(texels.len(), 250 * 12);
        assert_eq!(layout.texel_of(120, 0), (1, 0, 0));
        assert_eq!(layout.texel_of(241, 11), (2, 23, 0));
        // A full-size device: 512 nets of 6144 texels per row, pages capped at 1.6 GB.
        let big = CcNetLayout::new(32768);
        assert_eq!((big.nets_per_row, big.rows), (512, CC_NET_PAGE_SIDE));
        assert_eq!(big.nets_per_page() * 192, 1_610_612_736);
    }

    #[test]
    fn trials_are_the_cpu_first_splits_in_its_order() {
        let cpu: Vec<(u32, u32)> = crate::catmull_clark::first_splits().collect();
        let gpu: Vec<(u32, u32)> = (0..CC_TRIALS).map(cc_trial_split).collect();
        assert_eq!(gpu, cpu);
    }
}

/// Catmull-Clark quadtree node kind ([`CcNode::kind`]): a Bézier net.
pub const CC_NODE_BEZIER: u32 = 0;
/// Node kind: a split into four children.
pub const CC_NODE_SPLIT: u32 = 1;
/// Node kind: the innermost node at an extraordinary vertex (a [`CcCorner`]).
pub const CC_NODE_CORNER: u32 = 2;
/// [`CcNode::kind`] holds the kind in its low byte; a split node on the chain at an
/// extraordinary vertex holds `1 +` the index of its ball (a [`CcCorner`]) above
/// [`CC_NODE_BALL_SHIFT`] (0: none).
pub const CC_NODE_KIND_MASK: u32 = 0xff;
/// Bit position of a split node's ball index in [`CcNode::kind`].
pub const CC_NODE_BALL_SHIFT: u32 = 8;
/// A patch without a surface (a hole): its root is this.
pub const CC_NO_ROOT: u32 = u32::MAX;
/// [`CcRoot::flags`]: the patch's one-ring has sharp edges or vertices, so its pieces
/// need not be one smooth spline and its flatness bound also takes the deviation from
/// the bilinear quad (`PatchSurface::creased`).
pub const CC_ROOT_CREASED: u32 = 1;
/// [`CcRoot::flags`]: the patch's control face is a quad, whose four patches are
/// consecutive, this one at corner `flags >> CC_ROOT_CORNER_SHIFT` of them: marking finds
/// the face of a face leaf there.
pub const CC_ROOT_QUAD_FACE: u32 = 2;
/// Bit position of the patch's corner in its quad face in [`CcRoot::flags`].
pub const CC_ROOT_CORNER_SHIFT: u32 = 8;
/// Patch parameters are fixed point: `u = x / CC_PARAM_ONE`, so that the walk down the
/// quadtree is exact integer arithmetic, the same on the GPU and in its CPU twin.
pub const CC_PARAM_ONE: u32 = 1 << 31;

/// A node of a patch's quadtree: a Bézier net (`index` into the nets), a split (`index`
/// into the child quadruples) or the node at an extraordinary vertex (`index` into the
/// corners).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct CcNode {
    /// [`CC_NODE_BEZIER`], [`CC_NODE_SPLIT`] or [`CC_NODE_CORNER`] in the low byte
    /// ([`CC_NODE_KIND_MASK`]); for a split, `1 +` its ball's index above
    /// [`CC_NODE_BALL_SHIFT`] (0: no ball).
    pub kind: u32,
    /// Index into the nets (bindings 23, 25–27), the child quadruples (binding 22) or the
    /// corners (binding 24), by kind.
    pub index: u32,
}

/// The innermost node at an extraordinary vertex: the vertex's limit point and normal,
/// which node corner it is (0..4), and the radius of a ball around the limit point that
/// holds the surface over the node.
///
/// A split node's ball is stored as one of these too, with `limit` and `hull_radius`
/// set and `corner` and `normal` zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct CcCorner {
    /// Limit point of the extraordinary vertex, model units.
    pub limit: [f32; 3],
    /// Which node corner is the vertex: 0..4 at `(0,0), (1,0), (1,1), (0,1)`.
    pub corner: u32,
    /// Unit limit normal at the vertex.
    pub normal: [f32; 3],
    /// Radius of the ball around `limit` that holds the surface over the node, model
    /// units.
    pub hull_radius: f32,
}

/// Where patch `p`'s quadtree starts: its root node ([`CC_NO_ROOT`] for a hole), and its
/// first net and corner, which the nodes' indices count from (patches alike share their
/// nodes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct CcRoot {
    /// Root node.
    pub node: u32,
    /// First net (bindings 23, 25–27).
    pub nets: u32,
    /// First corner (binding 24).
    pub corners: u32,
    /// [`CC_ROOT_CREASED`], [`CC_ROOT_QUAD_FACE`] and the corner in the face above
    /// [`CC_ROOT_CORNER_SHIFT`], or 0.
    pub flags: u32,
}

/// One term of a level-1 point's stencil: weight `weight` on control point `point`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct CcWeight {
    /// Index of the control point.
    pub point: u32,
    /// Its weight.
    pub weight: f32,
}

/// What one patch's pieces are derived from: its one-ring (level-1 points) and the
/// table shared by the patches whose one-rings are alike.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct CcPatchStencil {
    /// First of the patch's one-ring points in the ring list.
    pub ring: u32,
    /// Its table.
    pub table: u32,
    /// Its first net (bindings 23, 25–27).
    pub nets: u32,
    /// Its first corner record (binding 24).
    pub corners: u32,
    /// Its first record among all patches': the stencil kernel's invocation `r` makes
    /// record `r - records` of the last patch whose `records` is at most `r`.
    pub records: u32,
}

/// A table shared by patches whose one-rings are alike: its records and how many
/// one-ring points its rows weigh.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct CcStencilTable {
    /// First record.
    pub records: u32,
    /// Records: one per Bézier net, ball and corner of the quadtree, in node order.
    pub record_count: u32,
    /// One-ring points: the length of every row.
    pub columns: u32,
    /// Padding.
    pub pad: u32,
}

/// A net: 16 rows, point 0 then the offsets of points 1..16 from it.
pub const CC_RECORD_NET: u32 = 0;
/// A split node's ball: the limit point, then the one-ring's offsets from it.
pub const CC_RECORD_BALL: u32 = 1;
/// A corner node: as a ball, then pairs of rows whose cross products sum to the normal.
pub const CC_RECORD_CORNER: u32 = 2;

/// One piece of a table: its rows (each `columns` weights, one per one-ring point) and
/// where in the patch's nets or corners it goes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq)]
pub struct CcPieceRecord {
    /// [`CC_RECORD_NET`], [`CC_RECORD_BALL`] or [`CC_RECORD_CORNER`]; for a corner,
    /// which node corner is the vertex in bits 8..16.
    pub kind: u32,
    /// First weight of its first row.
    pub weights: u32,
    /// Ball and corner: one-ring rows in the low 16 bits, normal pairs above.
    pub counts: u32,
    /// Index among the patch's nets (a net) or corner records (a ball or corner).
    pub out: u32,
}

/// A point to evaluate: patch and fixed-point parameters (see [`CC_PARAM_ONE`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq, Eq, Hash)]
pub struct CcPoint {
    /// Patch index in the mesh.
    pub patch_id: u32,
    /// Parameter along u, fixed point (`u / CC_PARAM_ONE`).
    pub u: u32,
    /// Parameter along v, fixed point.
    pub v: u32,
}

/// An output vertex to write (`cc_vertex_eval`): where its position and normal are
/// evaluated, and the face and face `(u, v)` it carries ([`OutVertex`]). The point
/// evaluated is the surface point's home (the same patch and parameter for every chart's
/// copy of it, so that the copies get the same bits), not necessarily a patch of the
/// vertex's own face.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct CcVertexPoint {
    /// Patch of the point's home.
    pub patch_id: u32,
    /// Parameter along that patch's u, fixed point.
    pub u: u32,
    /// Parameter along that patch's v, fixed point.
    pub v: u32,
    /// The vertex's control face.
    pub face: u32,
    /// The vertex's `(u, v)` on its face.
    pub face_u: f32,
    /// See `face_u`.
    pub face_v: f32,
}

/// A level-1 point or edge that no surface patch touches has no home
/// ([`crate::catmull_clark::gpu_model::point_homes`]).
pub const CC_NO_HOME: u32 = u32::MAX;

/// Probes an insertion into the vertex hash makes before it reports an overflow.
pub const CC_HASH_MAX_PROBES: u32 = 64;
/// An item whose key found no slot (the table overflowed), or that has no key.
pub const CC_NO_SLOT: u32 = u32::MAX;
/// An item without a key (`[hi, lo]`), which the hash passes over: no point key has a
/// word equal to `u32::MAX`.
pub const CC_NO_KEY: [u32; 2] = [u32::MAX; 2];

/// A slot of the vertex hash. Every field is stored bit-inverted so that an all-zero
/// buffer is an empty table (`clear_buffer` is all the reset there is): a word is
/// taken when non-zero, and `first` (the smallest item that inserted the key) is kept
/// with `atomicMax` of `!item`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcHashSlot {
    /// High word of the point key ([`crate::catmull_clark::keys::point_key`]), inverted.
    pub key_hi: u32,
    /// Low word of the point key, inverted.
    pub key_lo: u32,
    /// The smallest item that inserted the key, inverted (0: none yet).
    pub first: u32,
}

/// What the vertex-hash kernels report back.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcHashStatus {
    /// Items to insert (written by the host or an earlier kernel).
    pub items: u32,
    /// Non-zero when some key found no slot within [`CC_HASH_MAX_PROBES`].
    pub overflow: u32,
    /// Distinct keys, in order of first occurrence.
    pub unique: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

/// A cell of the adaptive Catmull-Clark tessellation on the GPU: patch, first split
/// (`trial` indexes [`cc_trial_split`]) and depth below it (`trial | depth << 8`), and
/// its lower-left corner in grid units (`1 / (840 · 2^max_depth)`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcCell {
    /// Patch index in the mesh.
    pub patch_id: u32,
    /// `trial | depth << 8`: the first-split trial (`0..CC_TRIALS`) in the low byte, the
    /// midpoint splits below it above; a culled leaf has [`CC_CELL_CULLED`] set too.
    pub trial_depth: u32,
    /// Lower-left corner along u, grid units.
    pub i: u32,
    /// Lower-left corner along v, grid units.
    pub j: u32,
}

/// First splits tried per patch: 4 odd squares, then the 14 near-square rectangles.
pub const CC_TRIALS: u32 = 18;
// Marking keys a trial as `leaves << 5 | trial`.
const _: () = assert!(CC_TRIALS <= 32);
/// No patch across an edge (an open boundary or a hole).
pub const CC_NO_NEIGHBOUR: u32 = u32::MAX;

/// `(ku, kv)` of trial `t`, in the order the CPU reference tries them
/// ([`crate::catmull_clark::first_splits`]): squares `1, 3, 5, 7`, then `k × (k + 1)`
/// and `(k + 1) × k` for `k = 1..=7`.
pub fn cc_trial_split(t: u32) -> (u32, u32) {
    if t < 4 {
        return (2 * t + 1, 2 * t + 1);
    }
    let k = (t - 4) / 2 + 1;
    if t.is_multiple_of(2) {
        (k, k + 1)
    } else {
        (k + 1, k)
    }
}

/// Connectivity of a patch for the GPU: its level-1 points, edge ids, per edge the
/// patch across it and that patch's edge index (`q << 2 | k`, or [`CC_NO_NEIGHBOUR`]),
/// and its control face.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcPatchTopo {
    /// Level-1 points at the corners `(0,0), (1,0), (1,1), (0,1)`
    /// ([`PatchMesh::quads`](crate::catmull_clark::PatchMesh::quads)).
    pub quad: [u32; 4],
    /// Level-1 edge ids, edge `k` from corner `k` to corner `k + 1`
    /// ([`PatchMesh::quad_edges`](crate::catmull_clark::PatchMesh::quad_edges)).
    pub edges: [u32; 4],
    /// Per edge: `q << 2 | k` of the patch `q` across it and its edge `k`, or
    /// [`CC_NO_NEIGHBOUR`].
    pub across: [u32; 4],
    /// The control face.
    pub face: u32,
    /// The patch's corner in its face and the face's sides, `corner | sides << 8`
    /// ([`crate::catmull_clark::keys::face_corner`]).
    pub face_corner: u32,
    /// Padding to a multiple of 16 bytes (`pad0`, `pad1` in WGSL).
    pub pad: [u32; 2],
}

/// A surface patch as the uniform Catmull-Clark kernels see it
/// ([`crate::catmull_clark::gpu_uniform`]): its id, the dense ids of its corners' and
/// edges' vertices in its chart, which of them it writes, its face, and where the
/// points of its corners and edges are evaluated.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcUniformPatch {
    /// Patch index in the mesh.
    pub patch_id: u32,
    /// Dense ids of the corner vertices (a level-1 point in this patch's chart),
    /// numbered first in the output vertices.
    pub corners: [u32; 4],
    /// Dense ids of the edge vertex rows (a level-1 edge on this patch's side of it),
    /// edge `k` from corner `k` to corner `k + 1`.
    pub edges: [u32; 4],
    /// Bits `k` (writes corner `k`), `4 + k` (writes edge `k`'s points) and `8 + k`
    /// (edge `k` runs from its larger end point).
    pub flags: u32,
    /// The control face.
    pub face: u32,
    /// The patch's corner in its face and the face's sides, `corner | sides << 8`.
    pub face_corner: u32,
    /// Homes of the corners' level-1 points
    /// ([`crate::catmull_clark::gpu_model::point_homes`]).
    pub corner_homes: [u32; 4],
    /// Homes of the level-1 edges.
    pub edge_homes: [u32; 4],
}

/// Uniform parameters of the uniform Catmull-Clark kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcUniformParams {
    /// `n`: segments per patch side.
    pub segments: u32,
    /// Surface patches (holes left out).
    pub patch_count: u32,
    /// Distinct patch corners of the surface patches.
    pub corner_count: u32,
    /// Distinct level-1 edges of the surface patches.
    pub edge_count: u32,
}

/// Uniform parameters of the adaptive Catmull-Clark kernels.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct CcTessParams {
    /// Grid units per patch side: `840 << max_depth`.
    pub grid: u32,
    /// Most midpoint splits below the first split, at most
    /// [`MAX_DEPTH`](crate::catmull_clark::MAX_DEPTH).
    pub max_depth: u32,
    /// The absolute tolerance ε on the flatness bound, model units.
    pub tolerance: f32,
    /// Patches in the mesh, holes included.
    pub patch_count: u32,
    /// Leaves the output leaf list holds (binding 55).
    pub leaf_capacity: u32,
    /// Polygon vertices the polygon buffer holds (binding 63).
    pub poly_capacity: u32,
    /// Indices the index buffer holds (binding 65).
    pub index_capacity: u32,
    /// First splits tried, in order ([`cc_trial_split`]): 1 for midpoint splits alone,
    /// [`CC_TRIALS`] for the search.
    pub trials: u32,
    /// Level-1 points: where the edges' homes start in the homes (binding 67).
    pub points: u32,
    /// Output vertices the vertex buffer holds (binding 64).
    pub vertex_capacity: u32,
    /// Padding to a multiple of 16 bytes (`pad0`, `pad1` in WGSL).
    pub pad: [u32; 2],
    /// The view that sets each cell's tolerance in pixels and culls; all zero for none.
    pub view: CcView,
}

/// A view as the adaptive Catmull-Clark kernels read it (`shaders/shared/cc_view.wgsl`,
/// twin of [`View`](crate::View)): each cell's tolerance is the smaller of the world
/// tolerance and the one that keeps it within `pixels` of the mesh, and cells wholly
/// outside the frustum emit nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq)]
pub struct CcView {
    /// Model to clip space, column-major.
    pub clip: [[f32; 4]; 4],
    /// The viewport's width and height in pixels.
    pub viewport: [f32; 2],
    /// The tolerance in pixels; 0 for the world tolerance alone.
    pub pixels: f32,
    /// The least clip `w` of a point in the frustum.
    pub near_w: f32,
    /// What is culled: [`CC_VIEW_CULL_FRUSTUM`] and [`CC_VIEW_CULL_BACKFACES`], or 0.
    pub cull: u32,
    /// 1: quad control faces whose four patches meet their tolerance as one cell are
    /// one leaf ([`ViewTolerance::face_leaves`](crate::catmull_clark::ViewTolerance::face_leaves)); 0: none.
    pub face_leaves: u32,
    /// Padding to a multiple of 16 bytes (`pad1`, `pad2` in WGSL).
    pub pad: [u32; 2],
}

/// Bit of [`CcView::cull`]: cells wholly outside the frustum emit nothing.
pub const CC_VIEW_CULL_FRUSTUM: u32 = 1;

/// Bit of [`CcView::cull`]: patches facing away from the eye everywhere emit nothing
/// (`shaders/shared/cc_facing.wgsl`).
pub const CC_VIEW_CULL_BACKFACES: u32 = 2;

/// Bit of [`CcCell::trial_depth`] that marks a leaf outside the view's frustum: it keeps
/// its place in the leaf list, as its trial counted it, and emits no triangles. Its
/// corners still mark points on its neighbours' sides, unless its whole patch is out of
/// view ([`CC_CELL_PATCH_CULLED`]).
pub const CC_CELL_CULLED: u32 = 1 << 31;

/// Bit of [`CcCell::trial_depth`] set, with [`CC_CELL_CULLED`], on the leaves of a patch
/// wholly out of view: they have no vertices at all.
pub const CC_CELL_PATCH_CULLED: u32 = 1 << 30;

/// Bit of [`CcCell::trial_depth`] that marks a face leaf: the whole quad control face
/// whose first patch is [`CcCell::patch_id`], one polygon through its vertices' limit
/// points (its trial and depth are 0).
pub const CC_CELL_FACE: u32 = 1 << 29;

/// Bit of the trial each patch chose, as the marking leaves it for the later kernels:
/// the patch's face is a face leaf (in view or culled), and the patch has no leaves of
/// its own.
pub const CC_CHOSEN_FACE_LEAF: u32 = 1 << 8;

/// Counters of the adaptive Catmull-Clark kernels, read back to check capacities.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq)]
pub struct CcState {
    /// The output vertices to evaluate: `vertices` when the mesh fits, else 0 (word 0,
    /// which `cc_vertex_eval` reads as its count).
    pub drawn_vertices: u32,
    /// Leaves of the output: those of each patch's best trial (also beyond capacity:
    /// what is needed).
    pub leaves: u32,
    /// Non-zero if some buffer was too small (nothing was written out of bounds, and
    /// the output buffers were left as the last complete run wrote them).
    pub overflow: u32,
    /// Polygon vertices needed.
    pub need_poly: u32,
    /// Indices needed.
    pub need_indices: u32,
    /// Leaves stopped by `max_depth` with a bound above the tolerance.
    pub unmet: u32,
    /// Largest bound of any leaf (f32 bits; non-negative floats order as integers).
    pub max_bound_bits: u32,
    /// Output vertices needed (one per point and chart), as the vertex hash counted them.
    pub vertices: u32,
    /// Flatness bounds computed by the search, every trial included.
    pub bounds: u32,
    /// Cells split on the split proof alone, without a bound: with `bounds`, the cells
    /// tested.
    pub proven: u32,
    /// Blocks of 32 decisions the walks took from the pool, beyond each trial's own
    /// (also beyond capacity: what is needed).
    pub decision_blocks: u32,
    /// Leaves outside the view's frustum, in patches partly in view.
    pub culled_leaves: u32,
    /// Patches with no leaf in the view's frustum.
    pub culled_patches: u32,
}
