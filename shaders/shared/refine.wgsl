// Refinement of one coarse triangle by right-triangle bisection on its lattice.
// Twin of `tessera_core::bezier::refine` (read that file for the why).
// Reads `scratch` (an r32uint storage texture of words: points, pole and group words per
// coarse triangle, then the coarse edges' bit sets, see `scratch_word` and
// `edge_set_word`). Kernels that include this
// file define the sink: `fn sink_triangle(a: VRef, b: VRef, c: VRef)` and
// `fn inner_rank(ctx: TriCtx, i: u32) -> u32`.

// A side's set, loaded once per coarse triangle (`EdgeSet` is in coarse.wgsl) as eight
// texel fetches: a storage-buffer load at a per-lane address is a loop over the lanes
// on a CPU device, with an insert per word.
fn edge_set(e: u32) -> EdgeSet {
    let w = edge_set_word(e);
    return EdgeSet(
        vec4u(scratch_word(w), scratch_word(w + 1u), scratch_word(w + 2u), scratch_word(w + 3u)),
        vec4u(scratch_word(w + 4u), scratch_word(w + 5u), scratch_word(w + 6u), scratch_word(w + 7u)),
    );
}

// What the triangle stages of one coarse triangle read (twin of `TriContext`).
// Per side k (or corner k) as vector components, read through `pick`: an array indexed
// by a per-lane k is a memory gather on a CPU device, three selects are not.
struct TriCtx {
    tri: u32,
    l: Lattice,
    side_edges: vec3u,
    sides_forward: vec3<bool>,
    sides_collapsed: vec3<bool>,
    corner_ids: vec3u,
    // The sides' edge sets.
    set0: EdgeSet,
    set1: EdgeSet,
    set2: EdgeSet,
    flipped: bool,
    // Offsets of this triangle's lattice points, pole points and group word in `scratch`.
    points_base: u32,
    pole_base: u32,
    groups_index: u32,
}

fn tri_ctx(t: u32) -> TriCtx {
    var c: TriCtx;
    c.tri = t;
    c.l = lattice_new(t, params.max_depth);
    let p = c.l.patch_id;
    let r0 = coarse_edge_of(p, c.l.g0, c.l.g1);
    let r1 = coarse_edge_of(p, c.l.g1, c.l.g2);
    let r2 = coarse_edge_of(p, c.l.g2, c.l.g0);
    c.side_edges = vec3u(r0.edge, r1.edge, r2.edge);
    c.sides_forward = vec3<bool>(r0.forward, r1.forward, r2.forward);
    c.sides_collapsed = vec3<bool>(edge_collapsed(r0.edge), edge_collapsed(r1.edge), edge_collapsed(r2.edge));
    c.corner_ids = vec3u(coarse_vertex(p, c.l.g0), coarse_vertex(p, c.l.g1), coarse_vertex(p, c.l.g2));
    c.set0 = edge_set(r0.edge);
    c.set1 = edge_set(r1.edge);
    c.set2 = edge_set(r2.edge);
    c.flipped = patch_flipped(p);
    c.points_base = t * (params.points_words + params.pole_words + 1u);
    c.pole_base = c.points_base + params.points_words;
    c.groups_index = c.pole_base + params.pole_words;
    return c;
}

fn pick(v: vec3u, k: u32) -> u32 {
    return select(select(v.z, v.y, k == 1u), v.x, k == 0u);
}

fn pick_bool(v: vec3<bool>, k: u32) -> bool {
    return select(select(v.z, v.y, k == 1u), v.x, k == 0u);
}

fn tri_side_edge(c: TriCtx, k: u32) -> u32 {
    return pick(c.side_edges, k);
}

fn side_collapsed(c: TriCtx, k: u32) -> bool {
    return pick_bool(c.sides_collapsed, k);
}

fn side_set(c: TriCtx, k: u32) -> EdgeSet {
    let lo = select(select(c.set2.lo, c.set1.lo, k == 1u), c.set0.lo, k == 0u);
    let hi = select(select(c.set2.hi, c.set1.hi, k == 1u), c.set0.hi, k == 0u);
    return EdgeSet(lo, hi);
}

fn corner_id(c: TriCtx, k: u32) -> u32 {
    return pick(c.corner_ids, k);
}

// Canonical position (in 1/256ths) of the point f lattice steps along side k.
fn side_canonical(c: TriCtx, k: u32, f: u32) -> u32 {
    // DYADIC_SCALE / n as a shift: an integer division is a scalar loop over the lanes.
    let q = f << (countTrailingZeros(DYADIC_SCALE) - c.l.depth);
    return select(DYADIC_SCALE - q, q, pick_bool(c.sides_forward, k));
}

fn side_point(c: TriCtx, k: u32, f: u32) -> bool {
    return set_has(side_set(c, k), side_canonical(c, k, f));
}

fn pole_index(l: Lattice, k: u32, f: u32) -> u32 {
    return k * (l.n + 1u) + f;
}

// Word w of the scratch (`scratch_texel`), which the kernel declares as an r32uint
// storage texture (read-write in `bezier_tri_mark`, read-only elsewhere).
fn scratch_word(w: u32) -> u32 {
    return textureLoad(scratch, scratch_texel(w)).x;
}

fn scratch_bit(base: u32, i: u32) -> bool {
    return ((scratch_word(base + i / 32u) >> (i % 32u)) & 1u) != 0u;
}

// Whether lattice point p is a vertex, given the points marked so far (twin of
// `TriContext::exists`). One storage read whatever the place, its word chosen by
// `select`: a masked device runs every branch, and each read is a loop over the lanes,
// so a read for the pole word and one for the points word would both be paid.
fn exists(c: TriCtx, p: vec2u) -> bool {
    let pl = place(c.l, p);
    let pole = pl.kind == PLACE_SIDE && side_collapsed(c, pl.k);
    let i = select(pl.f, pole_index(c.l, pl.k, pl.f), pole);
    let marked = scratch_bit(select(c.points_base, c.pole_base, pole), i);
    let marked_here = pole || pl.kind == PLACE_INSIDE;
    return pl.kind == PLACE_CORNER || select(side_point(c, pl.k, pl.f), marked, marked_here);
}

// A vertex before global numbering: coarse id, (edge, rank) or inner rank.
const VREF_COARSE: u32 = 0u;
const VREF_EDGE: u32 = 1u;
const VREF_INNER: u32 = 2u;

struct VRef {
    kind: u32,
    a: u32,
    b: u32,
}

fn vref_eq(x: VRef, y: VRef) -> bool {
    return x.kind == y.kind && x.a == y.a && x.b == y.b;
}

fn vertex_ref(c: TriCtx, p: vec2u) -> VRef {
    let pl = place(c.l, p);
    if pl.kind == PLACE_CORNER {
        return VRef(VREF_COARSE, corner_id(c, pl.k), 0u);
    }
    if pl.kind == PLACE_SIDE {
        if side_collapsed(c, pl.k) {
            return VRef(VREF_COARSE, corner_id(c, pl.k), 0u);
        }
        let e = tri_side_edge(c, pl.k);
        return VRef(VREF_EDGE, e, set_rank(side_set(c, pl.k), side_canonical(c, pl.k, pl.f)));
    }
    return VRef(VREF_INNER, inner_rank(c, pl.f), 0u);
}

// The bisection decision of right triangle t at `level` (twin of `splits`).
fn splits(c: TriCtx, t: Tri, level: u32) -> bool {
    if level >= 2u * c.l.depth {
        return false;
    }
    let side = common_side(c.l, t.a, t.b);
    if side < 3u && !side_collapsed(c, side) {
        let pl = place(c.l, lattice_mid(t.a, t.b));
        return side_point(c, side, pl.f);
    }
    return interior_need(c.l, t);
}

// Whether the root of the bisection is known to be a leaf without the interior test:
// its hypotenuse is a coarse side (the cell's diagonal), whose own decision says (twin
// of `root_known_leaf`). False where that does not decide (a collapsed side).
fn root_known_leaf(c: TriCtx) -> bool {
    let root = lattice_root(c.l);
    let side = common_side(c.l, root.a, root.b);
    if c.l.depth == 0u {
        return true;
    }
    if side >= 3u || side_collapsed(c, side) {
        return false;
    }
    return !side_point(c, side, place(c.l, lattice_mid(root.a, root.b)).f);
}

// No point inside, none on the sides, no side collapsed, one triangle made: the mesh is
// the corners, and `tri_emit_plain` writes it (twin of `is_plain`).
fn is_plain(c: TriCtx, inner: u32, made: u32) -> bool {
    let side_points = set_count(c.set0) + set_count(c.set1) + set_count(c.set2);
    return inner == 0u && made == 1u && side_points == 0u && !any(c.sides_collapsed);
}

const NO_COUNT: u32 = 0xffffffffu;

// The triangle count from the vertex counts alone, NO_COUNT where the formula does not
// apply (twin of `euler_count`, which proves it): 2·I + 1 + the points of the open
// sides − the collapsed sides, while the only shared vertex is one collapsed side's.
fn euler_count(c: TriCtx, inner: u32) -> u32 {
    var count = 2u * inner + 1u;
    // A second collapsed side shares a corner with the first: all three corners are then
    // one vertex, and `applies` turns false.
    var applies = true;
    for (var k = 0u; k < 3u; k++) {
        let a = corner_id(c, k);
        let b = corner_id(c, (k + 1u) % 3u);
        let other = corner_id(c, (k + 2u) % 3u);
        if side_collapsed(c, k) {
            count -= 1u;
            applies = applies && a == b && other != a;
        } else {
            count += set_count(side_set(c, k));
            applies = applies && a != b;
        }
    }
    return select(NO_COUNT, count, applies);
}

// The deepest lattice the private arrays hold. The host sets it to the depth the
// kernel runs at (`TestKernels` in tessera-wgpu): every invocation zeroes its private
// arrays, and sized for MAX_DEPTH_LIMIT they were a sixth of tri_emit at depth 6.
const ARRAY_DEPTH: u32 = MAX_DEPTH_LIMIT;
const_assert ARRAY_DEPTH <= MAX_DEPTH_LIMIT;

// A leaf polygon: lattice points packed as i | j << 16. At most the corners plus every
// lattice point on the sides of the coarse triangle.
const POLY_MAX: u32 = 3u * (1u << ARRAY_DEPTH) + 3u;

fn pack_lp(p: vec2u) -> u32 {
    return p.x | (p.y << 16u);
}

fn unpack_lp(x: u32) -> vec2u {
    return vec2u(x & 0xffffu, x >> 16u);
}

fn collinear(a: vec2u, b: vec2u, c: vec2u) -> bool {
    let ax = i32(b.x) - i32(a.x);
    let ay = i32(b.y) - i32(a.y);
    let bx = i32(c.x) - i32(a.x);
    let by = i32(c.y) - i32(a.y);
    return ax * by - ay * bx == 0;
}

var<private> poly: array<u32, POLY_MAX>;
var<private> poly_len: u32;

// Point k mod poly_len for k < 3 · poly_len (every caller's range), by subtraction: an
// integer division is a scalar loop over the lanes on a CPU device.
fn poly_at(k: u32) -> vec2u {
    let n = poly_len;
    var i = select(k, k - n, k >= n);
    i = select(i, i - n, i >= n);
    return unpack_lp(poly[i]);
}

fn poly_push(p: vec2u) {
    if poly_len < POLY_MAX {
        poly[poly_len] = pack_lp(p);
        poly_len += 1u;
    }
}

// The points of segment a → b are a + s · unit, 0 <= s <= steps (twin of `side_steps`).
struct SideSteps {
    steps: u32,
    unit: vec2i,
}

// The gcd is a power of two, found by trailing zeros and divided by a shift (an integer
// division is a scalar loop over the lanes on a CPU device).
fn side_steps(a: vec2u, b: vec2u) -> SideSteps {
    let d = vec2i(i32(b.x) - i32(a.x), i32(b.y) - i32(a.y));
    let z = countTrailingZeros(bitcast<u32>(d.x | d.y));
    // A degenerate side (a = b) has no inner points.
    if z >= 32u {
        return SideSteps(1u, d);
    }
    return SideSteps(1u << z, d >> vec2u(z));
}

fn step_point(a: vec2u, unit: vec2i, s: u32) -> vec2u {
    return vec2u(vec2i(a) + unit * i32(s));
}

// The vertices strictly inside side a → b, in order from a: from vertex to vertex,
// halving the step while the midpoint ahead exists (twin of `side_points`, which says
// why the points form a dyadic hierarchy).
fn side_points(c: TriCtx, a: vec2u, b: vec2u) {
    let st = side_steps(a, b);
    var s = 0u;
    while s < st.steps {
        var h = select(s & (0u - s), st.steps, s == 0u);
        while h > 1u && exists(c, step_point(a, st.unit, s + h / 2u)) {
            h /= 2u;
        }
        s += h;
        if s < st.steps {
            poly_push(step_point(a, st.unit, s));
        }
    }
}

// Corners of leaf t and every existing point on its sides, counter-clockwise (twin of
// `leaf_polygon`). Only the legs are walked: the hypotenuse a – b holds no point (see the
// twin), and the two walks are written out, where a loop over three sides ran the third
// walk too (masked) and indexed the corners per lane.
fn leaf_polygon(c: TriCtx, t: Tri) {
    poly_len = 0u;
    poly_push(t.r);
    side_points(c, t.r, t.a);
    poly_push(t.a);
    poly_push(t.b);
    side_points(c, t.b, t.r);
}

fn is_corner(k: u32) -> bool {
    let n = poly_len;
    return !collinear(poly_at(k + n - 1u), poly_at(k), poly_at(k + 1u));
}

fn emit_leaf_triangle(c: TriCtx, p0: vec2u, p1: vec2u, p2: vec2u) {
    let a = vertex_ref(c, p0);
    let b = vertex_ref(c, p1);
    let d = vertex_ref(c, p2);
    if vref_eq(a, b) || vref_eq(b, d) || vref_eq(a, d) {
        return;
    }
    if c.flipped {
        sink_triangle(a, d, b);
    } else {
        sink_triangle(a, b, d);
    }
}

// Ear clipping without new vertices (twin of `clip_ears`). One triangle per step, the
// last one (k = 1 of a triangle) included, so that emitting is written once: a SIMD
// device pays for every call site on every step.
fn clip_ears(c: TriCtx) {
    while poly_len >= 3u {
        let n = poly_len;
        var k = 1u;
        if n > 3u {
            k = best_ear(c);
        }
        emit_leaf_triangle(c, poly_at(k + n - 1u), poly_at(k), poly_at(k + 1u));
        if n == 3u {
            break;
        }
        for (var i = k; i + 1u < n; i++) {
            poly[i] = poly[i + 1u];
        }
        poly_len = n - 1u;
    }
}

// The ear to clip: a true corner whose removal leaves at least three, with the
// shortest new diagonal (the first on ties).
fn best_ear(c: TriCtx) -> u32 {
    let n = poly_len;
    var corners = 0u;
    for (var k = 0u; k < n; k++) {
        corners += u32(is_corner(k));
    }
    var best_d2 = 0xffffffffu;
    var best_k = 0u;
    var found = false;
    for (var k = 0u; k < n; k++) {
        if !is_corner(k) {
            continue;
        }
        let u = k + n - 1u;
        let w = k + 1u;
        let u_after = !collinear(poly_at(u + n - 1u), poly_at(u), poly_at(w));
        let w_after = !collinear(poly_at(u), poly_at(w), poly_at(w + 1u));
        let after = corners - 1u - u32(is_corner(u)) - u32(is_corner(w)) + u32(u_after) + u32(w_after);
        if after < 3u {
            continue;
        }
        let pu = patch_coords(c.l, poly_at(u));
        let pw = patch_coords(c.l, poly_at(w));
        let dx = pu.x - pw.x;
        let dy = pu.y - pw.y;
        let d2 = u32(dx * dx + dy * dy);
        if !found || d2 < best_d2 {
            best_d2 = d2;
            best_k = k;
            found = true;
        }
    }
    return best_k;
}

// Stage "count" / "emit": the triangles of every leaf in depth-first order (twin of
// `tri_triangles`), handed to the kernel's `sink_triangle`. The descent to the next leaf
// is a loop of its own, so that the leaf's polygon and ear clipping are paid once per
// leaf: a SIMD device runs every statement of a loop body on every step, masked.
fn tri_triangles(c: TriCtx) {
    let max_level = 2u * c.l.depth;
    var w = walk_start(lattice_root(c.l));
    loop {
        while w.level < max_level && exists(c, lattice_mid(w.t.a, w.t.b)) {
            w = walk_down(w);
        }
        leaf_polygon(c, w.t);
        clip_ears(c);
        w = walk_advance(w);
        if w.done {
            break;
        }
    }
}
