// Displacement-map reads and the map edge tests (Espino et al. 2005, Eq. 1–3).
// Twin of `tessera_core::bezier::{prepare::map_read, edge_tests}`.
// Reads `maps: texture_storage_2d<rgba16float, read>`, the map atlas (declared by the
// kernel): per patch a tile of MAP_CELLS × MAP_CELLS texels, texel (i, j) the corners of
// cell (i, j), (d[i, j], d[i+1, j], d[i, j+1], d[i+1, j+1]) in half precision, divided by
// params.map_scale (`tessera_core::gpu_types::MapAtlas`).
// A read-only storage texture, not a sampled one: in these kernels a CPU device
// (llvmpipe) fetches a sampled texel in a called function that loads the mip level's
// row stride and offset lane by lane, even for the constant level 0; an image has one
// level.

// The cell of a bilinear read at (u, v), clamped to the patch, and where in it.
struct MapCell {
    ij: vec2u,
    f: vec2f,
}

fn map_cell(u: f32, v: f32) -> MapCell {
    let last = f32(MAP_RES - 1u);
    let x = clamp(u, 0.0, 1.0) * last;
    let y = clamp(v, 0.0, 1.0) * last;
    let i0 = min(floor(x), last - 1.0);
    let j0 = min(floor(y), last - 1.0);
    return MapCell(vec2u(u32(i0), u32(j0)), vec2f(x - i0, y - j0));
}

// Bilinear interpolation between the cell's corners: row0 = (d[i, j], d[i+1, j]),
// row1 the same at j + 1 (the texel's .xy and .zw).
fn map_bilinear(row0: vec2f, row1: vec2f, f: vec2f) -> f32 {
    let top = row0.x + (row0.y - row0.x) * f.x;
    let bottom = row1.x + (row1.y - row1.x) * f.x;
    return top + (bottom - top) * f.y;
}

fn map_read(p: u32, u: f32, v: f32) -> f32 {
    let cell = map_cell(u, v);
    let tile = vec2u(p % MAP_ATLAS_TILES_PER_ROW, p / MAP_ATLAS_TILES_PER_ROW) * (MAP_RES - 1u);
    // The cell's four corners in one fetch, rather than two fetches of pairs (rows j and
    // j + 1) or four storage reads, each a scalar loop over the lanes on a CPU device. Scaling by a power of two is exact: the
    // values are the CPU's bit for bit.
    let corners = textureLoad(maps, tile + cell.ij) * params.map_scale;
    return map_bilinear(corners.xy, corners.zw, cell.f);
}

// The affine function through the map values at a triangle's corners; the map tests
// inside a coarse triangle read the displacement from it (see `refine.rs`). d0..d2 are
// the map values at p0..p2, read once by the caller (they are also its segments' ends).
struct TrianglePlane {
    patch_id: u32,
    origin: vec2f,
    d0: f32,
    grad: vec2f,
    e1: vec2f,
    e2: vec2f,
    det: f32,
}

fn triangle_plane(p: u32, p0: vec2f, p1: vec2f, p2: vec2f, d0: f32, d1: f32, d2: f32) -> TrianglePlane {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let det = e1.x * e2.y - e1.y * e2.x;
    let g1 = d1 - d0;
    let g2 = d2 - d0;
    let grad = vec2f((g1 * e2.y - g2 * e1.y) / det, (e1.x * g2 - e2.x * g1) / det);
    return TrianglePlane(p, p0, d0, grad, e1, e2, det);
}

// A displacement; `valid` false outside the triangle.
struct MaybeF32 {
    valid: bool,
    value: f32,
}

fn plane_inside(pl: TrianglePlane, uv: vec2f) -> bool {
    let du = uv.x - pl.origin.x;
    let dv = uv.y - pl.origin.y;
    let s = (du * pl.e2.y - dv * pl.e2.x) / pl.det;
    let t = (pl.e1.x * dv - pl.e1.y * du) / pl.det;
    let slack = 1e-4;
    return !(s < -slack || t < -slack || s + t > 1.0 + slack);
}

// Displacement from the plane at `uv`, where the map value is `raw`.
fn plane_value(pl: TrianglePlane, uv: vec2f, raw: f32) -> MaybeF32 {
    let du = uv.x - pl.origin.x;
    let dv = uv.y - pl.origin.y;
    return MaybeF32(plane_inside(pl, uv), raw - (pl.d0 + pl.grad.x * du + pl.grad.y * dv));
}

// One read of the displacement: the raw map (`use_plane` false) or from the plane.
fn displacement(pl: TrianglePlane, use_plane: bool, uv: vec2f) -> MaybeF32 {
    let raw = map_read(pl.patch_id, uv.x, uv.y);
    if use_plane {
        return plane_value(pl, uv, raw);
    }
    return MaybeF32(true, raw);
}

fn differs_from(d: MaybeF32, d12: f32, th: f32) -> bool {
    return d.valid && abs(d.value - d12) > th;
}

fn differs(pl: TrianglePlane, use_plane: bool, uv: vec2f, d12: f32, th: f32) -> bool {
    return differs_from(displacement(pl, use_plane, uv), d12, th);
}

// The test of two points mirrored across the segment. When the segment is a side of the
// plane's triangle (`one_inside`), at most one of them is inside (the other lies half
// the side's length beyond it) and only that one is read: a CPU device would read both.
fn mirrored_differ(pl: TrianglePlane, use_plane: bool, p: vec2f, q: vec2f, d12: f32, th: f32, one_inside: bool) -> bool {
    if one_inside {
        return differs(pl, use_plane, select(q, p, plane_inside(pl, p)), d12, th);
    }
    return differs(pl, use_plane, p, d12, th) || differs(pl, use_plane, q, d12, th);
}

// Map2p / Map4p / Map8p on the segment uv1 → uv2, whose ends have displacements d1, d2
// (twin of `map_test_with`).
fn map_test_with(test: u32, th: f32, uv1: vec2f, uv2: vec2f, d1: MaybeF32, d2: MaybeF32, pl: TrianglePlane, use_plane: bool, one_inside: bool) -> bool {
    let m = vec2f((uv1.x + uv2.x) * 0.5, (uv1.y + uv2.y) * 0.5);
    let mid = displacement(pl, use_plane, m);
    if !mid.valid {
        return false;
    }
    let d12 = mid.value;
    if differs_from(d1, d12, th) || differs_from(d2, d12, th) {
        return true;
    }
    if test == TEST_MAP2P {
        return false;
    }
    let ue = uv1.x - m.x;
    let ve = uv1.y - m.y;
    if mirrored_differ(pl, use_plane, vec2f(m.x - ve, m.y + ue), vec2f(m.x + ve, m.y - ue), d12, th, one_inside) {
        return true;
    }
    if test == TEST_MAP4P {
        return false;
    }
    // d5..d8: (a, b) = (1, ±1) and (-1, ±1), each pair mirrored across the segment.
    for (var k = 0u; k < 2u; k++) {
        let a = select(1.0, -1.0, k == 1u);
        let p = vec2f(m.x + 0.5 * (a * ue - ve), m.y + 0.5 * (a * ve + ue));
        let q = vec2f(m.x + 0.5 * (a * ue + ve), m.y + 0.5 * (a * ve - ue));
        if mirrored_differ(pl, use_plane, p, q, d12, th, one_inside) {
            return true;
        }
    }
    return false;
}

// The raw-map test of patch `p` (the coarse-edge stage's own test).
fn map_test(test: u32, p: u32, th: f32, uv1: vec2f, uv2: vec2f) -> bool {
    let unused = TrianglePlane(p, vec2f(0.0), 0.0, vec2f(0.0), vec2f(0.0), vec2f(0.0), 1.0);
    let d1 = MaybeF32(true, map_read(p, uv1.x, uv1.y));
    let d2 = MaybeF32(true, map_read(p, uv2.x, uv2.y));
    return map_test_with(test, th, uv1, uv2, d1, d2, unused, false, false);
}

// The edge test on uv1 → uv2 (twin of `segment_test`): map tests read the map; the
// flat test compares the surface midpoint with the chord midpoint.
// Surface evaluations this invocation made (the kernel adds them to `evaluations`).
var<private> flat_evaluations: u32;

fn segment_test(test: u32, p: u32, th: f32, uv1: vec2f, uv2: vec2f) -> bool {
    if test == TEST_FLAT {
        flat_evaluations += 3u;
        let m = vec2f((uv1.x + uv2.x) * 0.5, (uv1.y + uv2.y) * 0.5);
        let chord = (eval_frame(p, uv1.x, uv1.y).pos + eval_frame(p, uv2.x, uv2.y).pos) * 0.5;
        return length(eval_frame(p, m.x, m.y).pos - chord) > th;
    }
    return map_test(test, p, th, uv1, uv2);
}
