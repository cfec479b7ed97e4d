// Exact evaluation of a Catmull-Clark patch from its flattened quadtree: walk down in
// fixed point to the Bézier piece holding the point, evaluate the bicubic there.
// Twin of `tessera_core::catmull_clark::gpu_model::cc_eval`.

#include "shared/types.wgsl"

// Per patch, its root node and first net and corner (`CcRoot`): patches alike share
// their nodes, whose nets and corners count from the patch's first.
@group(0) @binding(20) var<storage, read> cc_roots: array<CcRoot>;
@group(0) @binding(21) var<storage, read> cc_nodes: array<CcNode>;
@group(0) @binding(22) var<storage, read> cc_splits: array<vec4u>;
// The Bézier nets as read-only storage textures, four pages of them
// (`tessera_core::gpu_types::CcNetLayout`: 12 rgba32float texels per net): a storage
// buffer read at per-lane addresses is a loop over the lanes on a CPU device, a texel
// fetch a plain load. Pages, because one texture of a large model's nets would be
// taller than a device allows, or larger than it can allocate at once.
@group(0) @binding(23) var cc_nets_0: texture_storage_2d<rgba32float, read>;
@group(0) @binding(25) var cc_nets_1: texture_storage_2d<rgba32float, read>;
@group(0) @binding(26) var cc_nets_2: texture_storage_2d<rgba32float, read>;
@group(0) @binding(27) var cc_nets_3: texture_storage_2d<rgba32float, read>;
@group(0) @binding(24) var<storage, read> cc_corners: array<CcCorner>;

struct CcSample {
    position: vec3f,
    normal: vec3f,
}

fn cc_bernstein(t: f32) -> vec4f {
    let s = 1.0 - t;
    return vec4f(s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t);
}

fn cc_bernstein_d(t: f32) -> vec4f {
    let s = 1.0 - t;
    return vec4f(-3.0 * s * s, 3.0 * s * s - 6.0 * s * t, 6.0 * s * t - 3.0 * t * t, 3.0 * t * t);
}

struct CcDerivs {
    p: vec3f,
    pu: vec3f,
    pv: vec3f,
}

// Net k's page, and its first texel there (twin: `CcNetLayout::texel_of`).
fn cc_net_page(k: u32) -> u32 {
    return k / (CC_NETS_PER_ROW * CC_NET_PAGE_ROWS);
}

fn cc_net_at(k: u32) -> vec2u {
    let i = k % (CC_NETS_PER_ROW * CC_NET_PAGE_ROWS);
    return vec2u((i % CC_NETS_PER_ROW) * 12u, i / CC_NETS_PER_ROW);
}

// The 16 points of the net at texel `at` of `page`, `x y z` each, from its 12 texels.
fn cc_page_net(page: texture_storage_2d<rgba32float, read>, at: vec2u) -> array<vec3f, 16> {
    let t0 = textureLoad(page, at);
    let t1 = textureLoad(page, at + vec2u(1u, 0u));
    let t2 = textureLoad(page, at + vec2u(2u, 0u));
    let t3 = textureLoad(page, at + vec2u(3u, 0u));
    let t4 = textureLoad(page, at + vec2u(4u, 0u));
    let t5 = textureLoad(page, at + vec2u(5u, 0u));
    let t6 = textureLoad(page, at + vec2u(6u, 0u));
    let t7 = textureLoad(page, at + vec2u(7u, 0u));
    let t8 = textureLoad(page, at + vec2u(8u, 0u));
    let t9 = textureLoad(page, at + vec2u(9u, 0u));
    let t10 = textureLoad(page, at + vec2u(10u, 0u));
    let t11 = textureLoad(page, at + vec2u(11u, 0u));
    return array<vec3f, 16>(
        t0.xyz, vec3f(t0.w, t1.xy), vec3f(t1.zw, t2.x), t2.yzw,
        t3.xyz, vec3f(t3.w, t4.xy), vec3f(t4.zw, t5.x), t5.yzw,
        t6.xyz, vec3f(t6.w, t7.xy), vec3f(t7.zw, t8.x), t8.yzw,
        t9.xyz, vec3f(t9.w, t10.xy), vec3f(t10.zw, t11.x), t11.yzw,
    );
}

// The 16 points of net k. A kernel compiled for one page reads it without a branch.
fn cc_net_points(k: u32) -> array<vec3f, 16> {
    let page = cc_net_page(k);
    let at = cc_net_at(k);
    if CC_NET_PAGES_USED == 1u || page == 0u {
        return cc_page_net(cc_nets_0, at);
    }
    if page == 1u {
        return cc_page_net(cc_nets_1, at);
    }
    if page == 2u {
        return cc_page_net(cc_nets_2, at);
    }
    return cc_page_net(cc_nets_3, at);
}

// One offset's terms of the sums (point `c` weighted by bu_i bv_j, du_i bv_j, bu_i dv_j).
fn cc_net_term(d: CcDerivs, c: vec3f, bui: f32, dui: f32, bvj: f32, dvj: f32) -> CcDerivs {
    return CcDerivs(d.p + (bui * bvj) * c, d.pu + (dui * bvj) * c, d.pv + (bui * dvj) * c);
}

// Point 0 of a net is absolute, points 1..16 offsets from it (exact shape in f32 for the
// tiny pieces at extraordinary vertices): the offsets' Bézier sum, then the origin added.
fn cc_net_eval(k: u32, u: f32, v: f32) -> CcDerivs {
    let p = cc_net_points(k);
    let bu = cc_bernstein(u);
    let bv = cc_bernstein(v);
    let du = cc_bernstein_d(u);
    let dv = cc_bernstein_d(v);
    // Written out, row by row (the twin's order), so that every index is a constant: a
    // private array indexed by a loop counter is a memory access per lane on a CPU device.
    var d = CcDerivs(vec3f(0.0), vec3f(0.0), vec3f(0.0));
    d = cc_net_term(d, p[1], bu.y, du.y, bv.x, dv.x);
    d = cc_net_term(d, p[2], bu.z, du.z, bv.x, dv.x);
    d = cc_net_term(d, p[3], bu.w, du.w, bv.x, dv.x);
    d = cc_net_term(d, p[4], bu.x, du.x, bv.y, dv.y);
    d = cc_net_term(d, p[5], bu.y, du.y, bv.y, dv.y);
    d = cc_net_term(d, p[6], bu.z, du.z, bv.y, dv.y);
    d = cc_net_term(d, p[7], bu.w, du.w, bv.y, dv.y);
    d = cc_net_term(d, p[8], bu.x, du.x, bv.z, dv.z);
    d = cc_net_term(d, p[9], bu.y, du.y, bv.z, dv.z);
    d = cc_net_term(d, p[10], bu.z, du.z, bv.z, dv.z);
    d = cc_net_term(d, p[11], bu.w, du.w, bv.z, dv.z);
    d = cc_net_term(d, p[12], bu.x, du.x, bv.w, dv.w);
    d = cc_net_term(d, p[13], bu.y, du.y, bv.w, dv.w);
    d = cc_net_term(d, p[14], bu.z, du.z, bv.w, dv.w);
    d = cc_net_term(d, p[15], bu.w, du.w, bv.w, dv.w);
    d.p += p[0];
    return d;
}

fn cc_normalize_or_zero(n: vec3f) -> vec3f {
    let l = length(n);
    if l > 0.0 {
        return n / l;
    }
    return vec3f(0.0);
}

// Position and unit normal on a net; where the derivatives are parallel (a collapsed
// edge) the normal is taken a little inside.
fn cc_net_point(k: u32, u: f32, v: f32) -> CcSample {
    let d = cc_net_eval(k, u, v);
    var n = cross(d.pu, d.pv);
    if dot(n, n) <= 1e-12 * dot(d.pu, d.pu) * dot(d.pv, d.pv) {
        let e = cc_net_eval(k, u + (0.5 - u) * 1e-4, v + (0.5 - v) * 1e-4);
        n = cross(e.pu, e.pv);
    }
    return CcSample(d.p, cc_normalize_or_zero(n));
}

fn cc_eval(point: CcPoint) -> CcSample {
    let root = cc_roots[point.patch_id];
    var nd = cc_nodes[root.node];
    var x = point.u;
    var y = point.v;
    var size = CC_PARAM_ONE;
    // Down to the node holding the point, then one evaluation after the loop: on a
    // SIMD device that masks rather than branches, an evaluation inside the loop would
    // run on every level. The stored depth bounds the walk; the cap only guards against
    // a corrupt upload.
    for (var level = 0u; level < 64u && (nd.kind & CC_NODE_KIND_MASK) == CC_NODE_SPLIT; level++) {
        // Past 2^-31 (the chains at extraordinary vertices) the point is a corner of
        // the node and stays that corner of the child.
        let half = size >> 1u;
        let right = select(x >= half, x >= 1u, size == 1u);
        let top = select(y >= half, y >= 1u, size == 1u);
        var c = 0u;
        if right && !top {
            c = 1u;
        } else if right && top {
            c = 2u;
        } else if top {
            c = 3u;
        }
        if size > 1u {
            if right {
                x -= half;
            }
            if top {
                y -= half;
            }
            size = half;
        }
        nd = cc_nodes[cc_splits[nd.index][c]];
    }
    let kind = nd.kind & CC_NODE_KIND_MASK;
    if kind == CC_NODE_BEZIER {
        return cc_net_point(root.nets + nd.index, f32(x) / f32(size), f32(y) / f32(size));
    }
    if kind == CC_NODE_CORNER {
        let c = cc_corners[root.corners + nd.index];
        return CcSample(
            vec3f(c.limit[0], c.limit[1], c.limit[2]),
            vec3f(c.normal[0], c.normal[1], c.normal[2]),
        );
    }
    return CcSample(vec3f(0.0), vec3f(0.0));
}
