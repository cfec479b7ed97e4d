// Stage 5d, one invocation per plain coarse triangle (no point inside or on its sides,
// none collapsed; the last slots of the emit order, dispatched indirectly by
// `bezier_finish`): its one triangle, the corners of its lattice's root as the
// bisection walk would emit them. Twin of `tri_emit_plain` in
// `tessera_core::bezier::tessellate`.
//
// A CPU device runs all of `tri_emit`'s code for every triangle, whether a lane needs
// it or not: at coarse thresholds most coarse triangles are plain, and this kernel has
// none of that code.

#include "shared/types.wgsl"
#include "shared/lattice.wgsl"
#include "shared/topo.wgsl"
#include "shared/coarse.wgsl"

@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(7) var<storage, read> counts: array<u32>;
@group(0) @binding(11) var<storage, read_write> out_indices: array<u32>;
@group(0) @binding(13) var<storage, read> status: BezierStatus;

// Component k of ids, by select: a vector indexed per lane is a memory access per lane
// on a CPU device.
fn corner_vertex(ids: vec3u, k: u32) -> u32 {
    return select(select(ids.z, ids.y, k == 1u), ids.x, k == 0u);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let slot = status.general_triangles + gid.x + gid.y * groups.x * 64u;
    if slot >= params.coarse_triangles || status.overflow != 0u {
        return;
    }
    let t = counts[order_base() + slot];
    let l = lattice_new(t, params.max_depth);
    let p = l.patch_id;
    let ids = vec3u(coarse_vertex(p, l.g0), coarse_vertex(p, l.g1), coarse_vertex(p, l.g2));
    let root = lattice_root(l);
    // Each root corner is a lattice corner k, whose vertex is the coarse vertex ids[k].
    var tri = vec3u(corner_vertex(ids, place(l, root.r).k), corner_vertex(ids, place(l, root.a).k), corner_vertex(ids, place(l, root.b).k));
    if patch_flipped(p) {
        tri = tri.xzy;
    }
    let e = params.coarse_edges;
    let tris = params.coarse_triangles;
    let first = 3u * (counts[e + tris + t] - counts[e + tris]);
    for (var k = 0u; k < 3u; k++) {
        if first + k < arrayLength(&out_indices) {
            out_indices[first + k] = tri[k];
        }
    }
}
