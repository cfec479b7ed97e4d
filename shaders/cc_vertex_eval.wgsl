// One invocation per point: position, normal, parameter and patch of each output vertex.
// Twin of `tessera_core::catmull_clark::gpu_model::vertex_eval`.

#include "shared/types.wgsl"
#include "shared/cc_patch.wgsl"

@group(0) @binding(30) var<storage, read> cc_points: array<CcPoint>;
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
    let s = cc_eval(point);
    let one = f32(CC_PARAM_ONE);
    out_vertices[v] = OutVertex(
        array<f32, 3>(s.position.x, s.position.y, s.position.z),
        array<f32, 3>(s.normal.x, s.normal.y, s.normal.z),
        array<f32, 2>(f32(point.u) / one, f32(point.v) / one),
        point.patch_id,
    );
}
