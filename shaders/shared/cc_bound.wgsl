// The flatness bound of a box of a patch: a guaranteed upper bound on the distance from
// the surface over it to any triangulation of its polygon, the smaller of a parametric
// and a slab bound (proof and walk: `tessera_core::catmull_clark::bound`, the CPU twin,
// in double precision; this file reads the same, function for function).

#include "shared/cc_patch.wgsl"

const CC_WALK_ONE: u32 = 220200960u; // 105 << 21
const CC_WALK_STACK: u32 = 32u;
const CC_SIDE_BOTTOM: u32 = 1u;
const CC_SIDE_RIGHT: u32 = 2u;
const CC_SIDE_TOP: u32 = 4u;
const CC_SIDE_LEFT: u32 = 8u;
const CC_F32_EPSILON: f32 = 1.1920929e-7;
const CC_INFINITY: f32 = 3.4028235e38;
// 1: the walk feeds the face bound's sums (`face_piece`, `face_vertex`) instead of a
// box's. Replaced in the source of the one kernel that takes the face bound
// (`cc_face_bound.wgsl`), so that no other kernel's walk carries that code.
const CC_FACE_SINK: u32 = 0u;

// BoundSum, as private state of the invocation.
var<private> bs_corners: array<vec3f, 4>;
var<private> bs_scale_rel: f32;
var<private> bs_scale_abs: f32;
var<private> bs_second: vec3f;
var<private> bs_dev: f32;
var<private> bs_dev_side: f32;
var<private> bs_has_vertex: bool;
// Whether the box may reach a vertex, so that bs_dev is needed.
var<private> bs_track_dev: bool;
var<private> bs_dev_everywhere: bool;
var<private> bs_slab: bool;
var<private> bs_normal: vec3f;
var<private> bs_e1: vec3f;
var<private> bs_e2: vec3f;
var<private> bs_chords: array<vec2f, 4>;
var<private> bs_lo: f32;
var<private> bs_hi: f32;
var<private> bs_hull: f32;
var<private> bs_band: array<vec2f, 4>;
// The piece being summed: its shape (points relative to its first, stored point) and
// that point relative to the box's first corner.
var<private> bs_net: array<vec3f, 16>;
var<private> bs_offset: vec3f;

fn cc_max_abs(p: vec3f) -> f32 {
    let a = abs(p);
    return max(a.x, max(a.y, a.z));
}

// Side s runs from corner cc_side_start(s) to corner cc_side_end(s).
fn cc_side_start(s: u32) -> u32 {
    return select(0u, select(1u, 3u, s == 2u), s == 1u || s == 2u);
}

fn cc_side_end(s: u32) -> u32 {
    return select(select(2u, 3u, s == 3u), 1u, s == 0u);
}

fn cc_project(p: vec3f) -> vec2f {
    return vec2f(dot(p, bs_e1), dot(p, bs_e2));
}

fn cc_perp_dot(a: vec2f, b: vec2f) -> f32 {
    return a.x * b.y - a.y * b.x;
}

fn bound_start(c: array<vec3f, 4>) {
    bs_scale_abs = max(max(cc_max_abs(c[0]), cc_max_abs(c[1])), max(cc_max_abs(c[2]), cc_max_abs(c[3])));
    for (var k = 0u; k < 4u; k++) {
        bs_corners[k] = c[k] - c[0];
    }
    bs_scale_rel = max(max(cc_max_abs(bs_corners[0]), cc_max_abs(bs_corners[1])),
        max(cc_max_abs(bs_corners[2]), cc_max_abs(bs_corners[3])));
    let cr = cross(bs_corners[2] - bs_corners[0], bs_corners[3] - bs_corners[1]);
    let len = length(cr);
    bs_slab = len > 0.0;
    bs_normal = vec3f(0.0, 0.0, 1.0);
    if bs_slab {
        bs_normal = cr / len;
    }
    // Orthonormal pair (Duff et al. 2017), as `bound::orthonormal_pair`.
    let n = bs_normal;
    let sgn = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    bs_e1 = vec3f(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
    bs_e2 = vec3f(b, sgn + n.y * n.y * a, -n.y);
    for (var s = 0u; s < 4u; s++) {
        let d = cc_project(bs_corners[cc_side_end(s)] - bs_corners[cc_side_start(s)]);
        let l = length(d);
        bs_chords[s] = vec2f(0.0);
        if l > 0.0 {
            bs_chords[s] = d / l;
        } else {
            bs_slab = false;
        }
        bs_band[s] = vec2f(0.0);
    }
    bs_second = vec3f(0.0);
    bs_dev = 0.0;
    bs_dev_side = 0.0;
    bs_has_vertex = false;
    bs_lo = CC_INFINITY;
    bs_hi = -CC_INFINITY;
    bs_hull = 0.0;
}

fn cc_bilinear(u: f32, v: f32) -> vec3f {
    let c = bs_corners;
    return (1.0 - v) * ((1.0 - u) * c[0] + u * c[1]) + v * ((1.0 - u) * c[3] + u * c[2]);
}

// `bicubic::second_derivatives` of bs_net.
fn cc_second_derivatives() -> vec3f {
    var r = vec3f(0.0);
    for (var j = 0u; j < 4u; j++) {
        for (var i = 0u; i < 2u; i++) {
            let d = bs_net[4u * j + i] - 2.0 * bs_net[4u * j + i + 1u] + bs_net[4u * j + i + 2u];
            r.x = max(r.x, 6.0 * length(d));
        }
    }
    for (var j = 0u; j < 2u; j++) {
        for (var i = 0u; i < 4u; i++) {
            let d = bs_net[4u * j + i] - 2.0 * bs_net[4u * (j + 1u) + i] + bs_net[4u * (j + 2u) + i];
            r.y = max(r.y, 6.0 * length(d));
        }
    }
    for (var j = 0u; j < 3u; j++) {
        for (var i = 0u; i < 3u; i++) {
            let d = bs_net[4u * j + i] - bs_net[4u * j + i + 1u] - bs_net[4u * (j + 1u) + i]
                + bs_net[4u * (j + 1u) + i + 1u];
            r.z = max(r.z, 9.0 * length(d));
        }
    }
    return r;
}

fn cc_hessian_bound(s: vec3f) -> f32 {
    return 0.5 * (s.x + s.y) + sqrt(0.25 * (s.x - s.y) * (s.x - s.y) + s.z * s.z);
}

// The points of side s of bs_net, from its start corner to its end corner.
fn cc_side_points(s: u32) -> array<vec3f, 4> {
    switch s {
        case 0u: { return array<vec3f, 4>(bs_net[0], bs_net[1], bs_net[2], bs_net[3]); }
        case 1u: { return array<vec3f, 4>(bs_net[3], bs_net[7], bs_net[11], bs_net[15]); }
        case 2u: { return array<vec3f, 4>(bs_net[12], bs_net[13], bs_net[14], bs_net[15]); }
        default: { return array<vec3f, 4>(bs_net[0], bs_net[4], bs_net[8], bs_net[12]); }
    }
}

// The range of the seven control values of a cubic split at its middle (twin of
// `halved_range`).
fn cc_halved_range(a: vec4f) -> vec2f {
    let b01 = 0.5 * (a.x + a.y);
    let b12 = 0.5 * (a.y + a.z);
    let b23 = 0.5 * (a.z + a.w);
    let c0 = 0.5 * (b01 + b12);
    let c1 = 0.5 * (b12 + b23);
    let m = 0.5 * (c0 + c1);
    let lo = min(min(min(a.x, b01), min(c0, m)), min(min(c1, b23), a.w));
    let hi = max(max(max(a.x, b01), max(c0, m)), max(max(c1, b23), a.w));
    return vec2f(lo, hi);
}

// Column i of the piece's heights above the slab's plane (rows v = 0..3 as components).
fn cc_heights(i: u32) -> vec4f {
    return vec4f(dot(bs_normal, bs_net[i] + bs_offset), dot(bs_normal, bs_net[4u + i] + bs_offset),
        dot(bs_normal, bs_net[8u + i] + bs_offset), dot(bs_normal, bs_net[12u + i] + bs_offset));
}

// The range of the 7 x 7 control values of a bicubic split at u = v = 1/2, from its four
// columns: split along u as vectors, then each of the seven along v (twin of
// `halved_grid_range`).
fn cc_halved_grid_range(c0: vec4f, c1: vec4f, c2: vec4f, c3: vec4f) -> vec2f {
    let b01 = 0.5 * (c0 + c1);
    let b12 = 0.5 * (c1 + c2);
    let b23 = 0.5 * (c2 + c3);
    let d0 = 0.5 * (b01 + b12);
    let d1 = 0.5 * (b12 + b23);
    let m = 0.5 * (d0 + d1);
    // Written out: an array indexed by a loop counter can become memory per lane.
    let r0 = cc_halved_range(c0);
    let r1 = cc_halved_range(b01);
    let r2 = cc_halved_range(d0);
    let r3 = cc_halved_range(m);
    let r4 = cc_halved_range(d1);
    let r5 = cc_halved_range(b23);
    let r6 = cc_halved_range(c3);
    let lo = min(min(min(r0.x, r1.x), min(r2.x, r3.x)), min(min(r4.x, r5.x), r6.x));
    let hi = max(max(max(r0.y, r1.y), max(r2.y, r3.y)), max(max(r4.y, r5.y), r6.y));
    return vec2f(lo, hi);
}

// Whether the piece keeps the slab bound's conditions; its heights and side bands
// summed. No early exit: loops of fixed length without one are unrolled by the
// compiler, so that every array index is a constant (on a CPU device an index that is
// not is a loop over the lanes).
// Where the piece fails, bs_slab turns false for good and the sums are never read.
fn cc_slab_piece(sides: u32) -> bool {
    // The heights of the net split at u = v = 1/2 (twin of `halved_grid_range`).
    let hr = cc_halved_grid_range(
        cc_heights(0u), cc_heights(1u), cc_heights(2u), cc_heights(3u));
    bs_lo = min(bs_lo, hr.x);
    bs_hi = max(bs_hi, hr.y);
    // n · (a × b) > 0 for every u-step a and v-step b: with (e1, e2, n) right-handed
    // that is the perp-dot of their projections, which is cheaper.
    var du: array<vec2f, 12>;
    var dv: array<vec2f, 12>;
    for (var j = 0u; j < 4u; j++) {
        for (var k = 0u; k < 3u; k++) {
            du[3u * j + k] = cc_project(bs_net[4u * j + k + 1u] - bs_net[4u * j + k]);
            dv[4u * k + j] = cc_project(bs_net[4u * (k + 1u) + j] - bs_net[4u * k + j]);
        }
    }
    // In linear passes (`bound::orientation_kept`): every a left of dv[0], so turning
    // counter-clockwise orders them; then every b left of the first and the last a.
    var ok = true;
    var first = du[0];
    var last = du[0];
    let b0 = dv[0];
    for (var k = 0u; k < 12u; k++) {
        let a = du[k];
        ok = ok && cc_perp_dot(a, b0) > 0.0;
        first = select(first, a, cc_perp_dot(a, first) > 0.0);
        last = select(last, a, cc_perp_dot(last, a) > 0.0);
    }
    for (var k = 0u; k < 12u; k++) {
        ok = ok && cc_perp_dot(first, dv[k]) > 0.0 && cc_perp_dot(last, dv[k]) > 0.0;
    }
    for (var s = 0u; s < 4u; s++) {
        let on = (sides & (1u << s)) != 0u;
        let d = bs_chords[s];
        let pts = cc_side_points(s);
        let start = bs_corners[cc_side_start(s)];
        for (var t = 0u; t < 3u; t++) {
            ok = ok && (!on || dot(cc_project(pts[t + 1u] - pts[t]), d) > 0.0);
        }
        // The side's offsets from its chord, split at its middle likewise.
        let off = vec4f(cc_perp_dot(d, cc_project(pts[0] + bs_offset - start)),
            cc_perp_dot(d, cc_project(pts[1] + bs_offset - start)),
            cc_perp_dot(d, cc_project(pts[2] + bs_offset - start)),
            cc_perp_dot(d, cc_project(pts[3] + bs_offset - start)));
        let r = cc_halved_range(off);
        let band = vec2f(min(bs_band[s].x, r.x), max(bs_band[s].y, r.y));
        bs_band[s] = select(bs_band[s], band, on);
    }
    return ok;
}

// A Bézier piece (bs_net, relative to the first corner) over `rect` in box coordinates.
fn bound_piece(rect: vec4f, sides: u32) {
    for (var k = 0u; k < 16u; k++) {
        bs_scale_rel = max(bs_scale_rel, cc_max_abs(bs_net[k] + bs_offset));
    }
    let fu = rect.y - rect.x;
    let fv = rect.w - rect.z;
    let sd = cc_second_derivatives();
    bs_second = vec3f(max(bs_second.x, sd.x / (fu * fu)), max(bs_second.y, sd.y / (fv * fv)),
        max(bs_second.z, sd.z / (fu * fv)));
    if bs_track_dev {
        for (var j = 0u; j < 4u; j++) {
            for (var i = 0u; i < 4u; i++) {
                let u = rect.x + fu * f32(i) / 3.0;
                let v = rect.z + fv * f32(j) / 3.0;
                let e = length(bs_net[4u * j + i] + bs_offset - cc_bilinear(u, v));
                bs_dev = max(bs_dev, e);
                let on_side = (i == 0u && (sides & CC_SIDE_LEFT) != 0u)
                    || (i == 3u && (sides & CC_SIDE_RIGHT) != 0u)
                    || (j == 0u && (sides & CC_SIDE_BOTTOM) != 0u)
                    || (j == 3u && (sides & CC_SIDE_TOP) != 0u);
                if on_side {
                    bs_dev_side = max(bs_dev_side, e);
                }
            }
        }
    }
    if bs_slab {
        bs_slab = cc_slab_piece(sides);
    }
}

fn bound_vertex(limit: vec3f, radius: f32, rect: vec4f, sides: u32) {
    bs_has_vertex = true;
    bs_scale_rel = max(bs_scale_rel, cc_max_abs(limit));
    var e = length(limit - cc_bilinear(rect.x, rect.z));
    e = max(e, length(limit - cc_bilinear(rect.y, rect.z)));
    e = max(e, length(limit - cc_bilinear(rect.y, rect.w)));
    e = max(e, length(limit - cc_bilinear(rect.x, rect.w)));
    bs_dev = max(bs_dev, radius + e);
    if sides != 0u {
        bs_dev_side = max(bs_dev_side, radius + e);
    }
    let at_corner = (sides & (CC_SIDE_LEFT | CC_SIDE_RIGHT)) != 0u
        && (sides & (CC_SIDE_BOTTOM | CC_SIDE_TOP)) != 0u;
    if !at_corner {
        bs_slab = false;
    }
    var near = CC_INFINITY;
    for (var k = 0u; k < 4u; k++) {
        near = min(near, length(bs_corners[k] - limit));
    }
    bs_hull = max(bs_hull, radius + near);
    let h = dot(bs_normal, limit);
    bs_lo = min(bs_lo, h - radius);
    bs_hi = max(bs_hi, h + radius);
}

// ---- The face bound (`bound::face_bound`, its sums `FaceDeviation`): a quad control
// face's four patches walked in turn against the bilinear quad through the face's
// corners, bs_corners relative to the first.

// Patch k of the face being walked, and its first corner relative to the face's.
var<private> fb_k: u32;
var<private> fb_shift: vec3f;

// The bilinear quad through the face's corners at (u, v) of its patch fb_k: patch k
// covers the quarter at vertex k, rotated.
fn cc_face_bilinear(u: f32, v: f32) -> vec3f {
    var st = vec2f(u, v);
    switch fb_k {
        case 1u: { st = vec2f(2.0 - v, u); }
        case 2u: { st = vec2f(2.0 - u, 2.0 - v); }
        case 3u: { st = vec2f(v, 2.0 - u); }
        default: {}
    }
    return cc_bilinear(0.5 * st.x, 0.5 * st.y);
}

// The seven control points of a cubic split at its middle.
fn cc_halved_cubic(a: array<vec3f, 4>) -> array<vec3f, 7> {
    let b0 = 0.5 * (a[0] + a[1]);
    let b1 = 0.5 * (a[1] + a[2]);
    let b2 = 0.5 * (a[2] + a[3]);
    let c0 = 0.5 * (b0 + b1);
    let c1 = 0.5 * (b1 + b2);
    return array<vec3f, 7>(a[0], b0, c0, 0.5 * (c0 + c1), c1, b2, a[3]);
}

// A piece: the surface less the bilinear quad degree-raised over it, split at u = v =
// 1/2, within the hulls of its quarters' control points (`bound::halved_grid`).
fn face_piece(rect: vec4f, sides: u32) {
    let fu = rect.y - rect.x;
    let fv = rect.w - rect.z;
    var rows: array<array<vec3f, 7>, 4>;
    for (var j = 0u; j < 4u; j++) {
        var d: array<vec3f, 4>;
        for (var i = 0u; i < 4u; i++) {
            let p = bs_net[4u * j + i] + bs_offset + fb_shift;
            bs_scale_rel = max(bs_scale_rel, cc_max_abs(p));
            let u = rect.x + fu * f32(i) / 3.0;
            let v = rect.z + fv * f32(j) / 3.0;
            d[i] = p - cc_face_bilinear(u, v);
        }
        rows[j] = cc_halved_cubic(d);
    }
    for (var i = 0u; i < 7u; i++) {
        let column = cc_halved_cubic(array<vec3f, 4>(rows[0][i], rows[1][i], rows[2][i], rows[3][i]));
        for (var j = 0u; j < 7u; j++) {
            let e = length(column[j]);
            bs_dev = max(bs_dev, e);
            let on_side = (i == 0u && (sides & CC_SIDE_LEFT) != 0u)
                || (j == 0u && (sides & CC_SIDE_BOTTOM) != 0u);
            if on_side {
                bs_dev_side = max(bs_dev_side, e);
            }
        }
    }
}

// The innermost square at a vertex: within `radius` of its limit point, and the
// bilinear quad over it within its corners' largest distance from that point.
fn face_vertex(limit: vec3f, radius: f32, rect: vec4f, sides: u32) {
    let l = limit + fb_shift;
    bs_scale_rel = max(bs_scale_rel, cc_max_abs(l));
    var e = length(l - cc_face_bilinear(rect.x, rect.z));
    e = max(e, length(l - cc_face_bilinear(rect.y, rect.z)));
    e = max(e, length(l - cc_face_bilinear(rect.y, rect.w)));
    e = max(e, length(l - cc_face_bilinear(rect.x, rect.w)));
    bs_dev = max(bs_dev, radius + e);
    // The patch sides on the face's boundary: v = 0 and u = 0.
    if (sides & (CC_SIDE_BOTTOM | CC_SIDE_LEFT)) != 0u {
        bs_dev_side = max(bs_dev_side, radius + e);
    }
}

fn bound_finish() -> f32 {
    let c = bs_corners;
    let twist = c[0] - c[1] + c[2] - c[3];
    let deviation = bs_dev + bs_dev_side + 0.25 * length(twist);
    var bound = 0.25 * cc_hessian_bound(bs_second);
    if bs_has_vertex {
        bound = deviation;
    } else if bs_dev_everywhere && bs_track_dev {
        bound = min(deviation, bound);
    }
    if bs_slab {
        var width = 0.0;
        for (var s = 0u; s < 4u; s++) {
            width = max(width, bs_band[s].y - bs_band[s].x);
        }
        let delta = width + 4.0 * bs_hull;
        let thick = bs_hi - bs_lo;
        bound = min(bound, max(sqrt(thick * thick + delta * delta), bs_hull));
    }
    return bound + 64.0 * CC_F32_EPSILON * bs_scale_rel + 8.0 * CC_F32_EPSILON * bs_scale_abs;
}

// `bound::split_proof`: a lower bound on cc_box_bound from the box's corners c, its
// centre and the midpoints of its sides (side k from corner k to corner k + 1); above the
// tolerance it proves the box must be split.
fn cc_split_proof(c: array<vec3f, 4>, centre: vec3f, mids: array<vec3f, 4>) -> f32 {
    var scale_abs = cc_max_abs(centre);
    var scale_rel = cc_max_abs(centre - c[0]);
    for (var k = 0u; k < 4u; k++) {
        scale_abs = max(scale_abs, max(cc_max_abs(c[k]), cc_max_abs(mids[k])));
        scale_rel = max(scale_rel, max(cc_max_abs(c[k] - c[0]), cc_max_abs(mids[k] - c[0])));
    }
    let s = centre - c[0];
    var parametric = length(s - 0.25 * ((c[1] - c[0]) + (c[2] - c[0]) + (c[3] - c[0])));
    for (var k = 0u; k < 4u; k++) {
        let side = (mids[k] - c[0]) - 0.5 * ((c[k] - c[0]) + (c[(k + 1u) % 4u] - c[0]));
        parametric = max(parametric, 2.0 * length(side));
    }
    // Without a normal the slab bound is off and the parametric bound is the bound.
    var proof = parametric;
    let cr = cross(c[2] - c[0], c[3] - c[1]);
    let len = length(cr);
    if len > 0.0 {
        let n = cr / len;
        var lo = min(0.0, dot(n, s));
        var hi = max(0.0, dot(n, s));
        for (var k = 0u; k < 4u; k++) {
            let hc = dot(n, c[k] - c[0]);
            let hm = dot(n, mids[k] - c[0]);
            lo = min(lo, min(hc, hm));
            hi = max(hi, max(hc, hm));
        }
        proof = min(proof, hi - lo);
    }
    return proof - 64.0 * CC_F32_EPSILON * scale_rel - 8.0 * CC_F32_EPSILON * scale_abs;
}

// ---- The walk (`bound::box_bound`).
//
// One node per iteration of one loop, whose body holds the piece and vertex code once:
// on a SIMD device that masks rather than branches (lavapipe), every call site of
// `bound_piece` costs its full price on every iteration, whatever the node. The path
// from the root to the node being visited is a stack of split nodes, each with the
// children still to visit.

struct CcWalkEntry {
    node: u32,
    level: u32,
    x: u32,
    y: u32,
    size: u32,
    inside: bool,
    rect: vec4f,
    sides: u32,
}

// A split node on the path: itself (placed), whether the box cuts it (its children are
// then placed by walk coordinates), and its children still to visit (bit c).
struct CcWalkFrame {
    entry: CcWalkEntry,
    cut: bool,
    children: vec4u,
    todo: u32,
}

var<private> walk_box: vec4u;
var<private> walk_max_ball: f32;
var<private> walk_origin: vec3f;
var<private> walk_stack: array<CcWalkFrame, CC_WALK_STACK>;
var<private> walk_len: u32;
var<private> walk_overflow: bool;
// Set by walk_place: whether the node is cut, and the part inside in node coordinates.
var<private> walk_cut: bool;
var<private> walk_clip: vec4f;

// The lower-left corner of quadrant c in units of half the parent.
fn cc_quadrant_offset(c: u32) -> vec2u {
    return vec2u(select(0u, 1u, c == 1u || c == 2u), select(0u, 1u, c >= 2u));
}

fn cc_quadrant_sides(c: u32) -> u32 {
    switch c {
        case 0u: { return CC_SIDE_BOTTOM | CC_SIDE_LEFT; }
        case 1u: { return CC_SIDE_BOTTOM | CC_SIDE_RIGHT; }
        case 2u: { return CC_SIDE_RIGHT | CC_SIDE_TOP; }
        default: { return CC_SIDE_TOP | CC_SIDE_LEFT; }
    }
}

// Whether the square (x, y, size) in walk units overlaps the box.
fn walk_overlaps(x: u32, y: u32, size: u32) -> bool {
    let bx = walk_box;
    return max(bx.x, x) < min(bx.y, x + size) && max(bx.z, y) < min(bx.w, y + size);
}

// `Walk::place`: false if the node does not overlap the box.
fn walk_place(e: ptr<function, CcWalkEntry>) -> bool {
    walk_cut = false;
    if (*e).inside {
        return true;
    }
    let bx = walk_box;
    let ov = vec4u(max(bx.x, (*e).x), min(bx.y, (*e).x + (*e).size), max(bx.z, (*e).y),
        min(bx.w, (*e).y + (*e).size));
    if ov.x >= ov.y || ov.z >= ov.w {
        return false;
    }
    walk_cut = !all(ov == vec4u((*e).x, (*e).x + (*e).size, (*e).y, (*e).y + (*e).size));
    let s = f32((*e).size);
    walk_clip = vec4f(f32(ov.x - (*e).x) / s, f32(ov.y - (*e).x) / s, f32(ov.z - (*e).y) / s,
        f32(ov.w - (*e).y) / s);
    let bw = f32(bx.y - bx.x);
    let bh = f32(bx.w - bx.z);
    (*e).rect = vec4f(f32(ov.x - bx.x) / bw, f32(ov.y - bx.x) / bw, f32(ov.z - bx.z) / bh,
        f32(ov.w - bx.z) / bh);
    (*e).sides = select(0u, CC_SIDE_BOTTOM, ov.z == bx.z) | select(0u, CC_SIDE_RIGHT, ov.y == bx.y)
        | select(0u, CC_SIDE_TOP, ov.w == bx.w) | select(0u, CC_SIDE_LEFT, ov.x == bx.x);
    (*e).inside = true;
    return true;
}

fn cc_lerp(p: vec3f, q: vec3f, t: f32) -> vec3f {
    return p + (q - p) * t;
}

// de Casteljau split of the cubic a0..a3 at t: the left or right half.
fn cc_split_cubic(a: array<vec3f, 4>, t: f32, right: bool) -> array<vec3f, 4> {
    let a1 = array<vec3f, 3>(cc_lerp(a[0], a[1], t), cc_lerp(a[1], a[2], t), cc_lerp(a[2], a[3], t));
    let b1 = array<vec3f, 2>(cc_lerp(a1[0], a1[1], t), cc_lerp(a1[1], a1[2], t));
    let m = cc_lerp(b1[0], b1[1], t);
    if right {
        return array<vec3f, 4>(m, b1[1], a1[2], a[3]);
    }
    return array<vec3f, 4>(a[0], a1[0], b1[0], m);
}

// `bicubic::clip_cubic`: the cubic over [lo, hi] of [0, 1].
fn cc_clip_cubic(c: array<vec3f, 4>, lo: f32, hi: f32) -> array<vec3f, 4> {
    var left = c;
    if hi < 1.0 {
        left = cc_split_cubic(c, hi, false);
    }
    if lo > 0.0 {
        return cc_split_cubic(left, lo / hi, true);
    }
    return left;
}

// bs_net clipped to walk_clip (rows in u, then columns in v).
fn cc_clip_net() {
    for (var j = 0u; j < 4u; j++) {
        let r = cc_clip_cubic(array<vec3f, 4>(bs_net[4u * j], bs_net[4u * j + 1u],
            bs_net[4u * j + 2u], bs_net[4u * j + 3u]), walk_clip.x, walk_clip.y);
        for (var i = 0u; i < 4u; i++) {
            bs_net[4u * j + i] = r[i];
        }
    }
    for (var i = 0u; i < 4u; i++) {
        let c = cc_clip_cubic(array<vec3f, 4>(bs_net[i], bs_net[4u + i], bs_net[8u + i],
            bs_net[12u + i]), walk_clip.z, walk_clip.w);
        for (var j = 0u; j < 4u; j++) {
            bs_net[4u * j + i] = c[j];
        }
    }
}

// Net k into bs_net (shape) and bs_offset.
fn cc_load_net(k: u32) {
    // Constant indices throughout (see `cc_net_eval`).
    let p = cc_net_points(k);
    bs_offset = p[0] - walk_origin;
    bs_net = array<vec3f, 16>(vec3f(0.0), p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8],
        p[9], p[10], p[11], p[12], p[13], p[14], p[15]);
}

// `Walk::small`: a node of `level` is at most 1/64 of the box's shorter side.
fn walk_small(level: u32) -> bool {
    let bmin = min(walk_box.y - walk_box.x, walk_box.w - walk_box.z);
    return level >= 27u || (bmin >> (27u - level)) >= 105u;
}

// `Walk::push`: a split node (placed) onto the path, with the children to visit: those
// the box overlaps while the node is cut, all four once it is inside.
fn walk_push(e: CcWalkEntry, children: vec4u) {
    var todo = 15u;
    if walk_cut {
        // Below level 21 nodes are never cut by a box of the grid.
        if (e.size & 1u) != 0u {
            walk_overflow = true;
            return;
        }
        let h = e.size / 2u;
        todo = 0u;
        for (var c = 0u; c < 4u; c++) {
            let q = cc_quadrant_offset(c);
            if walk_overlaps(e.x + q.x * h, e.y + q.y * h, h) {
                todo |= 1u << c;
            }
        }
    }
    if walk_len < CC_WALK_STACK {
        walk_stack[walk_len] = CcWalkFrame(e, walk_cut, children, todo);
        walk_len += 1u;
    } else {
        walk_overflow = true;
    }
}

// `Walk::child`: child c of the frame on top of the path.
fn walk_child(c: u32) -> CcWalkEntry {
    let f = walk_stack[walk_len - 1u];
    let e = f.entry;
    let q = cc_quadrant_offset(c);
    if f.cut {
        let h = e.size / 2u;
        return CcWalkEntry(f.children[c], e.level + 1u, e.x + q.x * h, e.y + q.y * h, h, false,
            vec4f(0.0), 0u);
    }
    let r = e.rect;
    let hu = 0.5 * (r.y - r.x);
    let hv = 0.5 * (r.w - r.z);
    let u0 = r.x + f32(q.x) * hu;
    let v0 = r.z + f32(q.y) * hv;
    return CcWalkEntry(f.children[c], e.level + 1u, e.x, e.y, e.size, true,
        vec4f(u0, u0 + hu, v0, v0 + hv), e.sides & cc_quadrant_sides(c));
}

// `bound::box_bound`: the bound of box `bx` (walk units: u0, u1, v0, v1) of patch p with
// corner positions c.
fn cc_box_bound(p: u32, bx: vec4u, c: array<vec3f, 4>) -> f32 {
    bound_start(c);
    // A patch without a vertex is one Bézier piece.
    let root = cc_roots[p];
    bs_track_dev = (cc_nodes[root.node].kind & CC_NODE_KIND_MASK) != CC_NODE_BEZIER;
    bs_dev_everywhere = (root.flags & CC_ROOT_CREASED) != 0u;
    if !cc_walk_pieces(p, bx, c) {
        return CC_INFINITY;
    }
    return bound_finish();
}

// `bound::face_bound`: the bound of the quad control face whose patches are first ..
// first + 3, the limit points of its vertices at `corners`: CC_INFINITY where a walk ran
// out of stack. Only with CC_FACE_SINK.
fn cc_face_bound(first: u32, corners: array<vec3f, 4>) -> f32 {
    var scale_abs = 0.0;
    for (var k = 0u; k < 4u; k++) {
        scale_abs = max(scale_abs, cc_max_abs(corners[k]));
        bs_corners[k] = corners[k] - corners[0];
    }
    bs_scale_rel = 0.0;
    for (var k = 0u; k < 4u; k++) {
        bs_scale_rel = max(bs_scale_rel, cc_max_abs(bs_corners[k]));
    }
    bs_dev = 0.0;
    bs_dev_side = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let p = first + k;
        let one = CC_PARAM_ONE;
        let own = array<vec3f, 4>(cc_eval(CcPoint(p, 0u, 0u)).position, cc_eval(CcPoint(p, one, 0u)).position,
            cc_eval(CcPoint(p, one, one)).position, cc_eval(CcPoint(p, 0u, one)).position);
        fb_k = k;
        fb_shift = own[0] - corners[0];
        if !cc_walk_pieces(p, vec4u(0u, CC_WALK_ONE, 0u, CC_WALK_ONE), own) {
            return CC_INFINITY;
        }
    }
    let c = bs_corners;
    let twist = c[0] - c[1] + c[2] - c[3];
    return bs_dev + bs_dev_side + 0.25 * length(twist) + 64.0 * CC_F32_EPSILON * bs_scale_rel
        + 8.0 * CC_F32_EPSILON * scale_abs;
}

// `bound::walk_pieces`: every piece of box `bx` of patch p (corner positions c) fed to
// the sums, relative to c[0]; false where the walk ran out of stack.
fn cc_walk_pieces(p: u32, bx: vec4u, c: array<vec3f, 4>) -> bool {
    walk_box = bx;
    walk_max_ball = 1e-4 * max(length(c[2] - c[0]), length(c[3] - c[1]));
    walk_origin = c[0];
    walk_len = 0u;
    walk_overflow = false;
    // Patches alike share nodes: a node's net or corner counts from the patch's first.
    let root = cc_roots[p];
    var e = CcWalkEntry(root.node, 0u, 0u, 0u, CC_WALK_ONE, false, vec4f(0.0), 0u);
    // Bounded: every node is visited once, and trees are finite; the cap guards a
    // corrupt upload.
    for (var guard = 0u; guard < 65536u; guard++) {
        let nd = cc_nodes[e.node];
        let kind = nd.kind & CC_NODE_KIND_MASK;
        var piece = false;
        var vertex = false;
        var corner = root.corners + nd.index;
        if walk_place(&e) {
            if kind == CC_NODE_SPLIT {
                // A node whose ball is small enough enters as its vertex.
                let ball = nd.kind >> CC_NODE_BALL_SHIFT;
                if !walk_cut && ball != 0u && walk_small(e.level) {
                    corner = root.corners + ball - 1u;
                    vertex = cc_corners[corner].hull_radius <= walk_max_ball;
                }
                if !vertex {
                    walk_push(e, cc_splits[nd.index]);
                }
            } else {
                piece = kind == CC_NODE_BEZIER;
                vertex = !piece;
            }
        }
        if piece {
            cc_load_net(root.nets + nd.index);
            if walk_cut {
                cc_clip_net();
            }
            if CC_FACE_SINK != 0u {
                face_piece(e.rect, e.sides);
            } else {
                bound_piece(e.rect, e.sides);
            }
        }
        if vertex {
            let cv = cc_corners[corner];
            let limit = vec3f(cv.limit[0], cv.limit[1], cv.limit[2]) - walk_origin;
            if CC_FACE_SINK != 0u {
                face_vertex(limit, cv.hull_radius, e.rect, e.sides);
            } else {
                bound_vertex(limit, cv.hull_radius, e.rect, e.sides);
            }
        }
        // The next node: the next child of the innermost split node with one left.
        while walk_len > 0u && walk_stack[walk_len - 1u].todo == 0u {
            walk_len -= 1u;
        }
        if walk_len == 0u || walk_overflow {
            break;
        }
        let todo = walk_stack[walk_len - 1u].todo;
        let c = firstTrailingBit(todo);
        walk_stack[walk_len - 1u].todo = todo & (todo - 1u);
        e = walk_child(c);
    }
    return !walk_overflow && walk_len == 0u;
}
