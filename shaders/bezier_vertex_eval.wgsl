// Stage 6, one invocation per output vertex (dispatched indirectly by `bezier_finish`):
// position, normal facing the patch's front, parameter and patch.
// Twin of `tessera_core::bezier::tessellate::vertex_eval`.

#include "shared/types.wgsl"
#include "shared/patch.wgsl"
#include "shared/topo.wgsl"

@group(0) @binding(1) var nets: texture_storage_2d<rgba32float, read>;
@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(9) var<storage, read> records: array<VertexRecord>;
@group(0) @binding(10) var<storage, read_write> out_vertices: array<OutVertex>;
@group(0) @binding(13) var<storage, read> status: BezierStatus;
@group(0) @binding(14) var<storage, read> tally: array<u32>;

// A coarse vertex no triangle in view has as a corner (all the others are made for
// one): no triangle uses it.
fn unused(v: u32) -> bool {
    return v < params.coarse_vertices
        && (tally[TALLY_USED_BITS + v / 32u] & (1u << (v & 31u))) == 0u;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let v = gid.x + gid.y * groups.x * 64u;
    if v >= status.vertices || v >= arrayLength(&out_vertices) || v >= arrayLength(&records) {
        return;
    }
    let r = records[v];
    // Not evaluated (`vertex_eval_at`).
    if unused(v) {
        out_vertices[v] = OutVertex(array<f32, 3>(0.0, 0.0, 0.0), array<f32, 3>(0.0, 0.0, 0.0),
            array<f32, 2>(r.u, r.v), r.patch_id);
        return;
    }
    let f = eval_frame(r.patch_id, r.u, r.v);
    var n = frame_normal(f, r.u, r.v);
    if patch_flipped(r.patch_id) {
        n = -n;
    }
    out_vertices[v] = OutVertex(
        array<f32, 3>(f.pos.x, f.pos.y, f.pos.z),
        array<f32, 3>(n.x, n.y, n.z),
        array<f32, 2>(r.u, r.v),
        r.patch_id,
    );
}
