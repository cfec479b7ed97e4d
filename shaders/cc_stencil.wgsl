// Every patch's quadtree from the control points, through stencil tables built once per
// topology (twin: `tessera_core::catmull_clark::stencil`, whose docs describe the
// tables). Two entries, a dispatch each:
// - `level1`, one invocation per level-1 point: its terms over the control points;
// - `pieces`, one invocation per record (a Bézier net, ball or corner of some patch): its
//   rows over the patch's one-ring of level-1 points, summed over the ring's offsets
//   from its first point, so that tiny pieces keep their shape in single precision.
// Both run only after the points moved: their dispatches are indirect, with arguments
// written through the queue with the points (`update_points`) and cleared to no
// workgroups after this step, so a run whose points did not move costs no invocation.
// Seven storage buffers at most per entry: the default limit is eight.

#include "shared/types.wgsl"

@group(0) @binding(70) var<storage, read> control: array<f32>;
@group(0) @binding(71) var<storage, read> level1_offsets: array<u32>;
@group(0) @binding(72) var<storage, read> level1_weights: array<CcWeight>;
@group(0) @binding(73) var<storage, read_write> level1_points: array<vec4f>;
@group(0) @binding(74) var<storage, read> rings: array<u32>;
@group(0) @binding(75) var<storage, read> patch_stencils: array<CcPatchStencil>;
@group(0) @binding(77) var<storage, read> tables: array<CcStencilTable>;
@group(0) @binding(78) var<storage, read> records: array<CcPieceRecord>;
@group(0) @binding(79) var<storage, read> weights: array<f32>;
// The nets' four pages (`cc_patch.wgsl` reads them).
@group(0) @binding(80) var nets_out_0: texture_storage_2d<rgba32float, write>;
@group(0) @binding(83) var nets_out_1: texture_storage_2d<rgba32float, write>;
@group(0) @binding(84) var nets_out_2: texture_storage_2d<rgba32float, write>;
@group(0) @binding(85) var nets_out_3: texture_storage_2d<rgba32float, write>;
@group(0) @binding(81) var<storage, read_write> corners_out: array<CcCorner>;
// [0, records of all patches, level-1 points, 0].
@group(0) @binding(82) var<uniform> step: vec4u;

fn stencil_invocation(gid: vec3u, groups: vec3u) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

fn control_point(i: u32) -> vec3f {
    return vec3f(control[3u * i], control[3u * i + 1u], control[3u * i + 2u]);
}

@compute @workgroup_size(64)
fn level1(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let q = stencil_invocation(gid, groups);
    if q >= step.z || q + 1u >= arrayLength(&level1_offsets)
        || q >= arrayLength(&level1_points) {
        return;
    }
    let end = min(level1_offsets[q + 1u], arrayLength(&level1_weights));
    var acc = vec3f(0.0);
    for (var t = level1_offsets[q]; t < end; t++) {
        let w = level1_weights[t];
        acc += control_point(w.point) * w.weight;
    }
    level1_points[q] = vec4f(acc, 0.0);
}

var<private> ring_base: u32;
var<private> columns: u32;
var<private> origin: vec3f;

fn ring_offset(i: u32) -> vec3f {
    return level1_points[rings[ring_base + i]].xyz - origin;
}

// Row k of the rows starting at weight w0.
fn stencil_row(w0: u32, k: u32) -> vec3f {
    let base = w0 + k * columns;
    var acc = vec3f(0.0);
    for (var i = 0u; i < columns; i++) {
        acc += ring_offset(i) * weights[base + i];
    }
    return acc;
}

// `stencil::record_patch`: the last patch whose first record is at most r.
fn record_patch(r: u32) -> u32 {
    var lo = 0u;
    var hi = arrayLength(&patch_stencils);
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if patch_stencils[mid].records <= r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

// A texel of a page (a storage texture is stored to through its global only).
fn store_texel(page: u32, at: vec2u, texel: vec4f) {
    if CC_NET_PAGES_USED == 1u || page == 0u {
        textureStore(nets_out_0, at, texel);
    } else if page == 1u {
        textureStore(nets_out_1, at, texel);
    } else if page == 2u {
        textureStore(nets_out_2, at, texel);
    } else {
        textureStore(nets_out_3, at, texel);
    }
}

// Net k into its page (`CcNetLayout::texel_of`, as `cc_net_page` and `cc_net_at`), in
// the texel order of `cc_page_net`.
fn store_net(k: u32, a: array<vec3f, 16>) {
    let per_page = CC_NETS_PER_ROW * CC_NET_PAGE_ROWS;
    let page = k / per_page;
    let i = k % per_page;
    let at = vec2u((i % CC_NETS_PER_ROW) * 12u, i / CC_NETS_PER_ROW);
    for (var j = 0u; j < 4u; j++) {
        let p0 = a[4u * j];
        let p1 = a[4u * j + 1u];
        let p2 = a[4u * j + 2u];
        let p3 = a[4u * j + 3u];
        let t = at + vec2u(3u * j, 0u);
        store_texel(page, t, vec4f(p0, p1.x));
        store_texel(page, t + vec2u(1u, 0u), vec4f(p1.yz, p2.xy));
        store_texel(page, t + vec2u(2u, 0u), vec4f(p2.z, p3));
    }
}

// A net's 16 rows in one pass over the ring (each point read once).
fn net_rows(w0: u32) -> array<vec3f, 16> {
    var a = array<vec3f, 16>();
    let m = columns;
    for (var i = 0u; i < m; i++) {
        let d = ring_offset(i);
        let w = w0 + i;
        a[0] += d * weights[w];
        a[1] += d * weights[w + m];
        a[2] += d * weights[w + 2u * m];
        a[3] += d * weights[w + 3u * m];
        a[4] += d * weights[w + 4u * m];
        a[5] += d * weights[w + 5u * m];
        a[6] += d * weights[w + 6u * m];
        a[7] += d * weights[w + 7u * m];
        a[8] += d * weights[w + 8u * m];
        a[9] += d * weights[w + 9u * m];
        a[10] += d * weights[w + 10u * m];
        a[11] += d * weights[w + 11u * m];
        a[12] += d * weights[w + 12u * m];
        a[13] += d * weights[w + 13u * m];
        a[14] += d * weights[w + 14u * m];
        a[15] += d * weights[w + 15u * m];
    }
    a[0] += origin;
    return a;
}

// glam's `normalize_or_zero`.
fn stencil_normalize(n: vec3f) -> vec3f {
    let r = 1.0 / length(n);
    if r > 0.0 && r < 3.4e38 {
        return n * r;
    }
    return vec3f(0.0);
}

@compute @workgroup_size(64)
fn pieces(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let r = stencil_invocation(gid, groups);
    if r >= step.y {
        return;
    }
    let p = record_patch(r);
    let ps = patch_stencils[p];
    let table = tables[ps.table];
    let rec = records[table.records + r - ps.records];
    ring_base = ps.ring;
    columns = table.columns;
    origin = level1_points[rings[ring_base]].xyz;
    if (rec.kind & 0xffu) == CC_RECORD_NET {
        store_net(ps.nets + rec.out, net_rows(rec.weights));
        return;
    }
    let ring_rows = rec.counts & 0xffffu;
    let pairs = rec.counts >> 16u;
    let limit = origin + stencil_row(rec.weights, 0u);
    var radius = 0.0;
    for (var k = 1u; k <= ring_rows; k++) {
        radius = max(radius, length(stencil_row(rec.weights, k)));
    }
    var normal = vec3f(0.0);
    for (var j = 0u; j < pairs; j++) {
        let a = stencil_row(rec.weights, 1u + ring_rows + 2u * j);
        let b = stencil_row(rec.weights, 2u + ring_rows + 2u * j);
        normal += cross(a, b);
    }
    let n = stencil_normalize(normal);
    let corner = select(0u, (rec.kind >> 8u) & 0xffu, (rec.kind & 0xffu) == CC_RECORD_CORNER);
    let at = ps.corners + rec.out;
    if at < arrayLength(&corners_out) {
        corners_out[at] = CcCorner(array<f32, 3>(limit.x, limit.y, limit.z), corner,
            array<f32, 3>(n.x, n.y, n.z), radius);
    }
}
