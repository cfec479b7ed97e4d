// One invocation per vertex: position and normal evaluated at its point's home (so that
// every chart's copy of a point gets the same bits), and the face and face (u, v) it
// carries. Twin of `tessera_core::catmull_clark::gpu_model::vertex_eval`.

#include "shared/types.wgsl"
#include "shared/cc_patch.wgsl"

@group(0) @binding(30) var<storage, read> cc_points: array<CcVertexPoint>;
@group(0) @binding(31) var<storage, read_write> out_vertices: array<OutVertex>;
// [0]: how many points (written by the GPU in the adaptive pipeline).
@group(0) @binding(32) var<storage, read> cc_counts: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let v = gid.x + gid.y * groups.x * 64u;
    if v >= cc_counts[0] || v >= arrayLength(&out_vertices) || v >= arrayLength(&cc_points) {
        return;
    }
    let point = cc_points[v];
    let s = cc_eval(CcPoint(point.patch_id, point.u, point.v));
    out_vertices[v] = OutVertex(
        array<f32, 3>(s.position.x, s.position.y, s.position.z),
        array<f32, 3>(s.normal.x, s.normal.y, s.normal.z),
        array<f32, 2>(point.face_u, point.face_v),
        point.face,
    );
}
