// The dyadic lattice of one coarse triangle. Twin of `tessera_core::bezier::lattice`.
// Points are vec2u (i, j), i + j <= N = 2^depth; side 0 is j = 0, side 1 is i + j = N,
// side 2 is i = 0.

struct Lattice {
    patch_id: u32,
    g0: vec2u,
    g1: vec2u,
    g2: vec2u,
    n: u32,
    depth: u32,
}

// Grid points of local coarse triangle `local` (twin of `coarse_triangle_grid`).
fn coarse_triangle_grid(local: u32) -> array<vec2u, 3> {
    let cell = local / 2u;
    let i = cell % 3u;
    let j = cell / 3u;
    if local % 2u == 0u {
        return array<vec2u, 3>(vec2u(i, j), vec2u(i + 1u, j), vec2u(i + 1u, j + 1u));
    }
    return array<vec2u, 3>(vec2u(i, j), vec2u(i + 1u, j + 1u), vec2u(i, j + 1u));
}

fn lattice_new(tri: u32, depth: u32) -> Lattice {
    let g = coarse_triangle_grid(tri % COARSE_TRIANGLES_PER_PATCH);
    return Lattice(tri / COARSE_TRIANGLES_PER_PATCH, g[0], g[1], g[2], 1u << depth, depth);
}

// Position in units of 1/(3N): exact integers.
fn patch_coords(l: Lattice, p: vec2u) -> vec2i {
    let n = i32(l.n);
    let g0 = vec2i(l.g0);
    let g1 = vec2i(l.g1);
    let g2 = vec2i(l.g2);
    let i = i32(p.x);
    let j = i32(p.y);
    return g0 * n + i * (g1 - g0) + j * (g2 - g0);
}

fn lattice_uv(l: Lattice, p: vec2u) -> vec2f {
    let c = patch_coords(l, p);
    return vec2f(f32(c.x) * params.inv_lattice, f32(c.y) * params.inv_lattice);
}

const PLACE_CORNER: u32 = 0u;
const PLACE_SIDE: u32 = 1u;
const PLACE_INSIDE: u32 = 2u;

// Corner(k), Side(k, f) or Inside(index).
struct Place {
    kind: u32,
    k: u32,
    f: u32,
}

fn lattice_index(l: Lattice, p: vec2u) -> u32 {
    let j = p.y;
    return j * (2u * l.n + 3u - j) / 2u + p.x;
}

// A cursor over the rows (j) for bit indices taken in increasing order, each row passed
// once (twin of `LatticeRows`): `start` is the index of point (0, j).
struct LatticeRows {
    j: u32,
    start: u32,
}

// The row holding bit `index`, searching forward from `r`.
fn rows_seek(l: Lattice, r0: LatticeRows, index: u32) -> LatticeRows {
    var r = r0;
    while r.start + (l.n + 1u - r.j) <= index {
        r.start += l.n + 1u - r.j;
        r.j += 1u;
    }
    return r;
}

fn rows_point(r: LatticeRows, index: u32) -> vec2u {
    return vec2u(index - r.start, r.j);
}

fn place(l: Lattice, p: vec2u) -> Place {
    let i = p.x;
    let j = p.y;
    let n = l.n;
    if i == 0u && j == 0u {
        return Place(PLACE_CORNER, 0u, 0u);
    }
    if i == n {
        return Place(PLACE_CORNER, 1u, 0u);
    }
    if j == n {
        return Place(PLACE_CORNER, 2u, 0u);
    }
    if j == 0u {
        return Place(PLACE_SIDE, 0u, i);
    }
    if i + j == n {
        return Place(PLACE_SIDE, 1u, j);
    }
    if i == 0u {
        return Place(PLACE_SIDE, 2u, n - j);
    }
    return Place(PLACE_INSIDE, 0u, lattice_index(l, p));
}

// The side both points lie on, or 3 (none).
fn common_side(l: Lattice, a: vec2u, b: vec2u) -> u32 {
    if a.y == 0u && b.y == 0u {
        return 0u;
    }
    if a.x + a.y == l.n && b.x + b.y == l.n {
        return 1u;
    }
    if a.x == 0u && b.x == 0u {
        return 2u;
    }
    return 3u;
}

fn from_patch_coords(l: Lattice, c: vec2i) -> vec2u {
    let n = i32(l.n);
    let g0 = vec2i(l.g0);
    let d = c - g0 * n;
    let e1 = vec2i(l.g1) - g0;
    let e2 = vec2i(l.g2) - g0;
    // A coarse triangle is half a grid cell: det is ±1, so dividing by it is multiplying
    // (an integer division is a scalar loop over the lanes on a CPU device).
    let det = e1.x * e2.y - e1.y * e2.x;
    let i = (d.x * e2.y - d.y * e2.x) * det;
    let j = (e1.x * d.y - e1.y * d.x) * det;
    return vec2u(u32(i), u32(j));
}

// A right triangle (r, a, b): right angle at r, hypotenuse a – b, counter-clockwise.
struct Tri {
    r: vec2u,
    a: vec2u,
    b: vec2u,
}

fn lattice_root(l: Lattice) -> Tri {
    let c0 = vec2u(0u, 0u);
    let c1 = vec2u(l.n, 0u);
    let c2 = vec2u(0u, l.n);
    if l.g1.y == l.g0.y {
        return Tri(c1, c2, c0);
    }
    return Tri(c2, c0, c1);
}

fn on_side(l: Lattice, side: u32, f: u32) -> vec2u {
    if side == 0u {
        return vec2u(f, 0u);
    }
    if side == 1u {
        return vec2u(l.n - f, f);
    }
    return vec2u(0u, l.n - f);
}

fn triangle_on_side(l: Lattice, side: u32, f0: u32, f1: u32) -> Tri {
    let a = on_side(l, side, f0);
    let b = on_side(l, side, f1);
    let pa = patch_coords(l, a);
    let pb = patch_coords(l, b);
    let h = (pb - pa) / 2;
    let r = vec2i(pa.x + h.x - h.y, pa.y + h.y + h.x);
    return Tri(from_patch_coords(l, r), a, b);
}

fn lattice_mid(a: vec2u, b: vec2u) -> vec2u {
    return (a + b) / 2u;
}

// The children (m, b, r) and (m, r, a).
fn bisect_first(t: Tri) -> Tri {
    return Tri(lattice_mid(t.a, t.b), t.b, t.r);
}

fn bisect_second(t: Tri) -> Tri {
    return Tri(lattice_mid(t.a, t.b), t.r, t.a);
}

// The parent of a second child (m, r, a) is (r, a, b) with b = 2m − a.
fn parent_of_second(c: Tri) -> Tri {
    return Tri(c.a, c.b, 2u * c.r - c.b);
}

// The second child beside a first child (m, b, r): (m, r, a) with a = 2m − b.
fn sibling_of_first(c: Tri) -> Tri {
    return Tri(c.r, c.b, 2u * c.r - c.a);
}

// A depth-first walk of a bisection tree without a stack (twin of `TreeWalk`): a
// parent is recomputed from its child, and bit i of `path` says whether the node at
// level i + 1 is a second child. A stack is an array indexed per lane, a memory access
// per lane and word on a CPU device.
struct TreeWalk {
    t: Tri,
    level: u32,
    path: u32,
    done: bool,
}

fn walk_start(root: Tri) -> TreeWalk {
    return TreeWalk(root, 0u, 0u, false);
}

// To the first child of the current node.
fn walk_down(w: TreeWalk) -> TreeWalk {
    return TreeWalk(bisect_first(w.t), w.level + 1u, w.path & ~(1u << w.level), false);
}

// Past the current node's subtree, to the next node in depth-first order (`done` when
// there is none).
fn walk_advance(w0: TreeWalk) -> TreeWalk {
    var w = w0;
    while w.level > 0u && ((w.path >> (w.level - 1u)) & 1u) != 0u {
        w.t = parent_of_second(w.t);
        w.level -= 1u;
    }
    if w.level == 0u {
        w.done = true;
        return w;
    }
    w.t = sibling_of_first(w.t);
    w.path |= 1u << (w.level - 1u);
    return w;
}

// Groups of 1 << word_group_shift words of the point set, at most 32, one bit each in
// the triangle's group word (twin of `Lattice::word_group_shift`).
fn word_group_shift(points_words: u32) -> u32 {
    let groups = (points_words + 31u) / 32u;
    return select(0u, 32u - countLeadingZeros(groups - 1u), groups > 1u);
}

fn points_words(depth: u32) -> u32 {
    let n = 1u << depth;
    return ((n + 1u) * (n + 2u) / 2u + 31u) / 32u;
}
