// Numbering of coarse vertices and edges, computed from the patch topology (no tables).
// Twin of `tessera_core::bezier::coarse_edges` and `PreparedBezier::coarse_vertex`.
// Reads the topology through `topo.wgsl`, included before this file.

fn curve_owner_side(c: u32) -> u32 {
    return curve_at(c).flags & 3u;
}

fn curve_collapsed(c: u32) -> bool {
    return (curve_at(c).flags & 4u) != 0u;
}

fn side_uv(side: u32, t: f32) -> vec2f {
    switch side {
        case 0u: { return vec2f(t, 0.0); }
        case 1u: { return vec2f(1.0, t); }
        case 2u: { return vec2f(t, 1.0); }
        default: { return vec2f(0.0, t); }
    }
}

// An edge id and whether a → b runs along its canonical direction.
struct EdgeRef {
    edge: u32,
    forward: bool,
}

fn side_edge(curve: u32, reversed: bool, seg: u32, along_side: bool) -> EdgeRef {
    let canonical_seg = select(seg, COARSE_SEGMENTS - 1u - seg, reversed);
    return EdgeRef(3u * curve + canonical_seg, along_side != reversed);
}

fn coarse_edge_of(p: u32, a: vec2u, b: vec2u) -> EdgeRef {
    let n = COARSE_SEGMENTS;
    let interior = 3u * params.curves + INTERIOR_EDGES_PER_PATCH * p;
    let lo = min(a, b);
    if a.y == b.y {
        let j = a.y;
        if j == 0u || j == n {
            let side = select(2u, 0u, j == 0u);
            return side_edge(side_curve(p, side), side_reversed(p, side), lo.x, b.x > a.x);
        }
        return EdgeRef(interior + (j - 1u) * 3u + lo.x, b.x > a.x);
    }
    if a.x == b.x {
        let i = a.x;
        if i == 0u || i == n {
            let side = select(1u, 3u, i == 0u);
            return side_edge(side_curve(p, side), side_reversed(p, side), lo.y, b.y > a.y);
        }
        return EdgeRef(interior + 6u + (i - 1u) * 3u + lo.y, b.y > a.y);
    }
    return EdgeRef(interior + 12u + lo.y * 3u + lo.x, b.x > a.x);
}

// Patch and grid end points (canonical order) of an edge inside a patch.
struct GridEdge {
    patch_id: u32,
    a: vec2u,
    b: vec2u,
}

fn interior_edge_grid(e: u32) -> GridEdge {
    let k = e - 3u * params.curves;
    let p = k / INTERIOR_EDGES_PER_PATCH;
    let local = k % INTERIOR_EDGES_PER_PATCH;
    if local < 6u {
        let i = local % 3u;
        let j = local / 3u + 1u;
        return GridEdge(p, vec2u(i, j), vec2u(i + 1u, j));
    }
    if local < 12u {
        let i = (local - 6u) / 3u + 1u;
        let j = (local - 6u) % 3u;
        return GridEdge(p, vec2u(i, j), vec2u(i, j + 1u));
    }
    let i = (local - 12u) % 3u;
    let j = (local - 12u) / 3u;
    return GridEdge(p, vec2u(i, j), vec2u(i + 1u, j + 1u));
}

// The evaluating patch and the end points of edge e in its (u, v), canonical order.
struct EdgeEnds {
    patch_id: u32,
    uv0: vec2f,
    uv1: vec2f,
}

// k/3 for k in 0..=3 as the CPU's correctly rounded division gives it: round(1/3) times
// 2 or 3 rounds to round(2/3) and exactly 1.
const THIRD: f32 = 1.0 / 3.0;

fn edge_endpoints(e: u32) -> EdgeEnds {
    if e < 3u * params.curves {
        let c = e / 3u;
        let s = f32(e % 3u);
        let side = curve_owner_side(c);
        return EdgeEnds(curve_at(c).owner, side_uv(side, s * THIRD), side_uv(side, (s + 1.0) * THIRD));
    }
    let g = interior_edge_grid(e);
    return EdgeEnds(g.patch_id, vec2f(g.a) * THIRD, vec2f(g.b) * THIRD);
}

fn edge_collapsed(e: u32) -> bool {
    return e < 3u * params.curves && curve_collapsed(e / 3u);
}

// Up to two coarse triangles beside an edge: (triangle, its side k, forward).
struct EdgeSide {
    tri: u32,
    k: u32,
    forward: bool,
}

struct EdgeSides {
    count: u32,
    s: array<EdgeSide, 2>,
}

fn grid_on_side(side: u32, t: u32) -> vec2u {
    let n = COARSE_SEGMENTS;
    switch side {
        case 0u: { return vec2u(t, 0u); }
        case 1u: { return vec2u(n, t); }
        case 2u: { return vec2u(t, n); }
        default: { return vec2u(0u, t); }
    }
}

// The sides of patch q's coarse triangles that join grid points a and b, appended to
// `out` (at most two in all). The search only notes where they are, and the side's
// direction is looked up after it: a CPU device runs every iteration's body under a
// mask, and the lookup (storage reads) inside made that 54 lookups per call.
fn add_sides_in_patch(out: ptr<function, EdgeSides>, q: u32, a: vec2u, b: vec2u) {
    var found = 0u;
    var first = vec2u(0u);
    var second = vec2u(0u);
    for (var local = 0u; local < COARSE_TRIANGLES_PER_PATCH; local++) {
        let grid = coarse_triangle_grid(local);
        for (var k = 0u; k < 3u; k++) {
            let x = grid[k];
            let y = grid[(k + 1u) % 3u];
            if (all(x == a) && all(y == b)) || (all(x == b) && all(y == a)) {
                second = select(second, vec2u(local, k), found == 1u);
                first = select(first, vec2u(local, k), found == 0u);
                found += 1u;
            }
        }
    }
    for (var f = 0u; f < min(found, 2u); f++) {
        let at = select(second, first, f == 0u);
        if (*out).count < 2u {
            let grid = coarse_triangle_grid(at.x);
            let x = grid[at.y];
            let y = grid[(at.y + 1u) % 3u];
            let side = EdgeSide(q * COARSE_TRIANGLES_PER_PATCH + at.x, at.y, coarse_edge_of(q, x, y).forward);
            if (*out).count == 0u {
                (*out).s[0] = side;
            } else {
                (*out).s[1] = side;
            }
            (*out).count += 1u;
        }
    }
}

fn coarse_edge_sides(e: u32) -> EdgeSides {
    let n = COARSE_SEGMENTS;
    var out: EdgeSides;
    out.count = 0u;
    if e < 3u * params.curves {
        let c = e / 3u;
        let seg = e % 3u;
        let curve = curve_at(c);
        var qs = array<vec2u, 2>(vec2u(curve.owner, curve.flags & 3u), vec2u(0u));
        var users = 1u;
        if curve.other != NO_SIDE {
            qs[1] = vec2u(curve.other >> 2u, curve.other & 3u);
            users = 2u;
        }
        for (var u = 0u; u < users; u++) {
            let q = qs[u].x;
            let side = qs[u].y;
            let s = select(seg, n - 1u - seg, side_reversed(q, side));
            add_sides_in_patch(&out, q, grid_on_side(side, s), grid_on_side(side, s + 1u));
        }
    } else {
        let g = interior_edge_grid(e);
        add_sides_in_patch(&out, g.patch_id, g.a, g.b);
    }
    return out;
}

// Global id of coarse grid point (i, j) of patch p (twin of `PreparedBezier::coarse_vertex`).
fn coarse_vertex(p: u32, g: vec2u) -> u32 {
    let n = COARSE_SEGMENTS;
    let on_u = g.x == 0u || g.x == n;
    let on_v = g.y == 0u || g.y == n;
    if on_u && on_v {
        var slot = 0u;
        if g.x == n && g.y != n { slot = 1u; }
        if g.x == n && g.y == n { slot = 2u; }
        if g.x != n && g.y == n { slot = 3u; }
        return topo_corner(p, slot);
    }
    var side = 4u;
    var k = 0u;
    if g.y == 0u { side = 0u; k = g.x; }
    else if g.x == n { side = 1u; k = g.y; }
    else if g.y == n { side = 2u; k = g.x; }
    else if g.x == 0u { side = 3u; k = g.y; }
    if side < 4u {
        let c = side_curve(p, side);
        let curve = curve_at(c);
        if (curve.flags & 4u) != 0u {
            return curve.coarse_vertex;
        }
        let kk = select(k, n - k, side_reversed(p, side));
        return curve.coarse_vertex + kk - 1u;
    }
    let interior_base = params.coarse_vertices - INTERIOR_COARSE_VERTICES_PER_PATCH * params.patches;
    return interior_base + INTERIOR_COARSE_VERTICES_PER_PATCH * p + (g.y - 1u) * 2u + (g.x - 1u);
}

// Point at fraction k / 256 of a → b (1/256 is exact, so CPU and GPU agree).
fn lerp_uv(a: vec2f, b: vec2f, k: u32) -> vec2f {
    let f = f32(k) * (1.0 / f32(DYADIC_SCALE));
    return vec2f(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f);
}

// A coarse edge's bit set of inserted points (EDGE_BIT_WORDS = 8 words), held in two
// vectors: the edge stage builds it and a triangle loads its sides' sets once, and
// both set, test and rank points without memory accesses (an array indexed per lane,
// or a storage access, is a scalar loop over the lanes on a CPU device).
const_assert EDGE_BIT_WORDS == 8u;

// Word w of the scratch: a texel of an r32uint storage texture, `scratch` in the
// kernels that declare it. A texture, not a storage buffer: a CPU device reads a buffer
// at per-lane addresses in a loop over the lanes, and a texture with plain loads.
fn scratch_texel(w: u32) -> vec2u {
    return vec2u(w & ((1u << params.scratch_shift) - 1u), w >> params.scratch_shift);
}

// The scratch holds each coarse triangle's words (`tri_ctx`), then each coarse edge's
// bit set, EDGE_BIT_WORDS words from this one (twin of `ScratchLayout`).
fn edge_set_word(e: u32) -> u32 {
    return params.coarse_triangles * (params.points_words + params.pole_words + 1u) + EDGE_BIT_WORDS * e;
}

struct EdgeSet {
    lo: vec4u,
    hi: vec4u,
}

fn set_word(b: EdgeSet, w: u32) -> u32 {
    let v = select(b.hi, b.lo, w < 4u);
    let i = w & 3u;
    return select(select(select(v.w, v.z, i == 2u), v.y, i == 1u), v.x, i == 0u);
}

fn set_has(b: EdgeSet, k: u32) -> bool {
    return ((set_word(b, k / 32u) >> (k % 32u)) & 1u) != 0u;
}

// Inserted points before position k.
fn set_rank(b: EdgeSet, k: u32) -> u32 {
    let w = vec4u(k / 32u);
    let lanes = vec4u(0u, 1u, 2u, 3u);
    let below = select(vec4u(0u), countOneBits(b.lo), lanes < w)
        + select(vec4u(0u), countOneBits(b.hi), lanes + 4u < w);
    let mask = (1u << (k % 32u)) - 1u;
    return dot(below, vec4u(1u)) + countOneBits(set_word(b, k / 32u) & mask);
}

fn set_count(b: EdgeSet) -> u32 {
    return dot(countOneBits(b.lo) + countOneBits(b.hi), vec4u(1u));
}

fn set_insert(b: EdgeSet, k: u32) -> EdgeSet {
    let w = vec4u(k / 32u);
    let bit = vec4u(1u << (k % 32u));
    let lanes = vec4u(0u, 1u, 2u, 3u);
    return EdgeSet(b.lo | select(vec4u(0u), bit, lanes == w), b.hi | select(vec4u(0u), bit, lanes + 4u == w));
}
