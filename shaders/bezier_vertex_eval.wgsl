// Stage 6, one invocation per output vertex (dispatched indirectly by `bezier_finish`):
// position, normal facing the patch's front, parameter and patch.
// Twin of `tessera_core::bezier::tessellate::vertex_eval`.

#include "shared/types.wgsl"
#include "shared/patch.wgsl"
#include "shared/topo.wgsl"
#include "shared/thresholds.wgsl"

@group(0) @binding(1) var nets: texture_storage_2d<rgba32float, read>;
@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(9) var<storage, read> records: array<VertexRecord>;
@group(0) @binding(10) var<storage, read_write> out_vertices: array<OutVertex>;
@group(0) @binding(13) var<storage, read> status: BezierStatus;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let v = gid.x + gid.y * groups.x * 64u;
    if v >= status.vertices || v >= arrayLength(&out_vertices) || v >= arrayLength(&records) {
        return;
    }
    let r = records[v];
    // Inside a culled patch no triangle uses the vertex (`vertex_eval_at`).
    if patch_culled(r.patch_id) && inside_patch(r.u, r.v) {
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
