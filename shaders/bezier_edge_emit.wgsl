// Stage 5b, one invocation per coarse edge: where its inserted points are evaluated.
// Twin of `tessera_core::bezier::tessellate::edge_emit`.

#include "shared/types.wgsl"
#include "shared/lattice.wgsl"
#include "shared/topo.wgsl"
#include "shared/coarse.wgsl"

@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
// The edges' bit sets, in the scratch (`edge_set_word`).
@group(0) @binding(8) var scratch: texture_storage_2d<r32uint, read>;
@group(0) @binding(7) var<storage, read> counts: array<u32>;
@group(0) @binding(9) var<storage, read_write> records: array<VertexRecord>;
@group(0) @binding(13) var<storage, read> status: BezierStatus;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let e = gid.x + gid.y * groups.x * 64u;
    if e >= params.coarse_edges || status.overflow != 0u {
        return;
    }
    let ends = edge_endpoints(e);
    // One exclusive scan runs over the edges and then the triangles, so the next slot
    // says how many points this edge has.
    var next = params.coarse_vertices + counts[e];
    let end = params.coarse_vertices + counts[e + 1u];
    // Words are read only while points remain: most coarse edges have none, and each
    // read is a loop over the lanes on a CPU device.
    for (var w = 0u; w < EDGE_BIT_WORDS && next < end; w++) {
        var bits = textureLoad(scratch, scratch_texel(edge_set_word(e) + w)).x;
        while bits != 0u {
            let k = 32u * w + firstTrailingBit(bits);
            bits &= bits - 1u;
            let uv = lerp_uv(ends.uv0, ends.uv1, k);
            if next < arrayLength(&records) {
                records[next] = VertexRecord(ends.patch_id, uv.x, uv.y);
            }
            next += 1u;
        }
    }
}
