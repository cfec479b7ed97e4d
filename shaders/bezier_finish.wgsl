// After the scan, one invocation: totals, the capacity check, the indirect draw
// arguments, the emit order's bucket slots and the indirect dispatches of the emit and
// vertex kernels. Nothing is read back to draw. Twin of the totals in
// `tessera_core::bezier::tessellate_adaptive` and of the first half of `emit_order`.

#include "shared/types.wgsl"

@group(0) @binding(7) var<storage, read> counts: array<u32>;
@group(0) @binding(12) var<storage, read_write> draw_args: DrawIndexedIndirectArgs;
@group(0) @binding(13) var<storage, read_write> status: BezierStatus;
@group(0) @binding(14) var<storage, read_write> tally: array<u32>;

// The workgroup size of the kernels it dispatches (vertex_eval, tri_emit, tri_emit_plain).
const VERTEX_WORKGROUP: u32 = 64u;

// An indirect dispatch of `items` invocations (none on overflow), spilling into y.
fn dispatch_of(items: u32, overflow: u32) -> vec3u {
    let groups = select((items + VERTEX_WORKGROUP - 1u) / VERTEX_WORKGROUP, 0u, overflow != 0u);
    return vec3u(min(groups, MAX_GROUPS_X), (groups + MAX_GROUPS_X - 1u) / MAX_GROUPS_X, 1u);
}

@compute @workgroup_size(1)
fn main() {
    let e = params.coarse_edges;
    let t = params.coarse_triangles;
    // Exclusive scan of [edge vertices | inner vertices | triangles | 0].
    let edge_vertices = counts[e];
    let vertices = params.coarse_vertices + counts[e + t];
    let triangles = counts[e + 2u * t] - counts[e + t];
    let indices = 3u * triangles;
    var overflow = 0u;
    if vertices > params.vertex_capacity {
        overflow |= 1u;
    }
    // 3 × triangles must not wrap past u32 (the check would pass a wrapped count).
    if indices > params.index_capacity || triangles > 0x55555555u {
        overflow |= 2u;
    }
    status.vertices = vertices;
    status.indices = indices;
    status.overflow = overflow;
    status.edge_vertices = edge_vertices;
    // Of the coarse vertices only those a triangle in view uses are evaluated.
    status.culled_patches = tally[TALLY_CULLED];
    status.evaluations = tally[TALLY_EVALUATIONS] + vertices - params.coarse_vertices + tally[TALLY_USED];
    let vertex_dispatch = dispatch_of(vertices, overflow);
    status.dispatch_x = vertex_dispatch.x;
    status.dispatch_y = vertex_dispatch.y;
    status.dispatch_z = vertex_dispatch.z;
    draw_args.index_count = select(indices, 0u, overflow != 0u);
    draw_args.instance_count = 1u;
    draw_args.first_index = 0u;
    draw_args.base_vertex = 0;
    draw_args.first_instance = 0u;
    // Each emit-order bucket's first slot: the exclusive scan of its triangle counts.
    var slot = 0u;
    for (var b = 0u; b < ORDER_BUCKETS; b++) {
        let n = tally[TALLY_ORDER + b];
        tally[TALLY_ORDER + b] = slot;
        slot += n;
    }
    // The plain triangles, last, go to their own kernel; no emit kernel runs on overflow.
    let general = tally[TALLY_ORDER + PLAIN_BUCKET];
    status.general_triangles = general;
    let emit = dispatch_of(general, overflow);
    status.emit_dispatch_x = emit.x;
    status.emit_dispatch_y = emit.y;
    status.emit_dispatch_z = emit.z;
    let plain = dispatch_of(t - general, overflow);
    status.plain_dispatch_x = plain.x;
    status.plain_dispatch_y = plain.y;
    status.plain_dispatch_z = plain.z;
}
