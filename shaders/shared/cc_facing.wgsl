// Back-facing patches, for a view that culls them (`CC_VIEW_CULL_BACKFACES`): twin of
// `tessera_core::catmull_clark::facing` and `View::{facing, box_back_facing}`, whose docs
// prove the test. A patch faces away when `f(X)·n < 0` at the eight corners of its box
// for every generator `n` of the cone of its normals: the 144 products of each net's u-
// and v-differences, and the limit normal of each corner node.

#include "shared/cc_patch.wgsl"
#include "shared/cc_view.wgsl"

// `facing::FACING_STACK`: nodes the walk keeps pending at most; past it the patch is
// taken as facing the eye.
const CC_FACING_STACK: u32 = 128u;

// The facing field over a box: at its lowest corner, and its steps along the sides.
struct CcFacing {
    f0: vec3f,
    g: array<vec3f, 3>,
}

// `View::facing` at a point whose clip coordinates are `c`.
fn cc_facing_at(c: vec4f) -> vec3f {
    let r_x = cc_view_row(0u);
    let r_y = cc_view_row(1u);
    let r_w = cc_view_row(3u);
    return c.x * cross(r_y, r_w) + c.y * cross(r_w, r_x) + c.w * cross(r_x, r_y);
}

// Whether the generator `n` faces away over the whole box, from `f` at its lowest corner
// and the steps `g` along its sides (`View::box_back_facing`); a zero one spans nothing.
// Without short circuits: a CPU device runs every branch anyway.
fn cc_faces_away(f: CcFacing, n: vec3f) -> bool {
    let most = dot(f.f0, n) + max(dot(f.g[0], n), 0.0) + max(dot(f.g[1], n), 0.0)
        + max(dot(f.g[2], n), 0.0);
    return (most < 0.0) | all(n == vec3f(0.0));
}

// `facing::NEGLIGIBLE_SINE`, squared.
const CC_NEGLIGIBLE_SINE_SQ: f32 = 1e-10;

// The extent of the patch's box squared, as `facing::patch_back_facing` takes it, for
// the products' test.
var<private> cc_net_size_sq: f32;

// `facing::product_normal`, tested: `a × b` faces away, or `a` and `b` are parallel to
// within the negligible sine, or one is shorter than that fraction of the patch's box
// (their product is rounding noise and spans nothing).
fn cc_product_faces_away(f: CcFacing, a: vec3f, b: vec3f) -> bool {
    let n = cross(a, b);
    let a2 = dot(a, a);
    let b2 = dot(b, b);
    let l2 = CC_NEGLIGIBLE_SINE_SQ * cc_net_size_sq;
    let negligible = dot(n, n) <= CC_NEGLIGIBLE_SINE_SQ * a2 * b2 || a2 <= l2 || b2 <= l2;
    return cc_faces_away(f, n) | negligible;
}

// The twelve products of one u-difference `a` with the net's v-differences `b`.
fn cc_row_faces_away(f: CcFacing, a: vec3f, b: array<vec3f, 12>) -> bool {
    return cc_product_faces_away(f, a, b[0]) & cc_product_faces_away(f, a, b[1])
        & cc_product_faces_away(f, a, b[2]) & cc_product_faces_away(f, a, b[3])
        & cc_product_faces_away(f, a, b[4]) & cc_product_faces_away(f, a, b[5])
        & cc_product_faces_away(f, a, b[6]) & cc_product_faces_away(f, a, b[7])
        & cc_product_faces_away(f, a, b[8]) & cc_product_faces_away(f, a, b[9])
        & cc_product_faces_away(f, a, b[10]) & cc_product_faces_away(f, a, b[11]);
}

// `facing::net_normals` of net k, tested: point 0 is absolute and the rest offsets from
// it, so point 0 is taken as the origin (differences do not change). Written out, so
// that every index is a constant.
fn cc_net_faces_away(f: CcFacing, k: u32) -> bool {
    var q = cc_net_points(k);
    q[0] = vec3f(0.0);
    let dv = array<vec3f, 12>(
        q[4] - q[0], q[5] - q[1], q[6] - q[2], q[7] - q[3],
        q[8] - q[4], q[9] - q[5], q[10] - q[6], q[11] - q[7],
        q[12] - q[8], q[13] - q[9], q[14] - q[10], q[15] - q[11],
    );
    return cc_row_faces_away(f, q[1] - q[0], dv) & cc_row_faces_away(f, q[2] - q[1], dv)
        & cc_row_faces_away(f, q[3] - q[2], dv) & cc_row_faces_away(f, q[5] - q[4], dv)
        & cc_row_faces_away(f, q[6] - q[5], dv) & cc_row_faces_away(f, q[7] - q[6], dv)
        & cc_row_faces_away(f, q[9] - q[8], dv) & cc_row_faces_away(f, q[10] - q[9], dv)
        & cc_row_faces_away(f, q[11] - q[10], dv) & cc_row_faces_away(f, q[13] - q[12], dv)
        & cc_row_faces_away(f, q[14] - q[13], dv) & cc_row_faces_away(f, q[15] - q[14], dv);
}

// `facing::patch_back_facing`: whether patch p, whose surface lies in the box [lo, hi],
// faces away from the eye everywhere. Its quadtree is walked depth first from the root;
// the cap on steps only guards against a corrupt upload.
fn cc_patch_back_facing(p: u32, lo: vec3f, hi: vec3f) -> bool {
    let c = cc_view_corners(lo, hi);
    cc_net_size_sq = dot(hi - lo, hi - lo);
    let f0 = cc_facing_at(c[0]);
    let f = CcFacing(f0, array<vec3f, 3>(cc_facing_at(c[1]) - f0, cc_facing_at(c[2]) - f0,
        cc_facing_at(c[4]) - f0));
    let root = cc_roots[p];
    var stack: array<u32, CC_FACING_STACK>;
    stack[0] = root.node;
    var top = 1u;
    var away = true;
    for (var steps = 0u; top > 0u && away && steps < 4096u; steps++) {
        top -= 1u;
        let nd = cc_nodes[stack[top]];
        let kind = nd.kind & CC_NODE_KIND_MASK;
        if kind == CC_NODE_SPLIT {
            if top + 4u > CC_FACING_STACK {
                return false;
            }
            let s = cc_splits[nd.index];
            stack[top] = s[0];
            stack[top + 1u] = s[1];
            stack[top + 2u] = s[2];
            stack[top + 3u] = s[3];
            top += 4u;
        } else if kind == CC_NODE_BEZIER {
            away = cc_net_faces_away(f, root.nets + nd.index);
        } else if kind == CC_NODE_CORNER {
            let n = cc_corners[root.corners + nd.index].normal;
            away = cc_faces_away(f, vec3f(n[0], n[1], n[2]));
        }
    }
    return away && top == 0u;
}
