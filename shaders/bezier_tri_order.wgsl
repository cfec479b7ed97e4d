// Stage 4b, one invocation per coarse triangle: its place in the order `tri_emit` takes
// them in, those that make the most triangles first and the plain ones last (for
// `tri_emit_plain`), from the bucket `tri_roots` or `tri_mark` chose. Twin of `emit_order` in
// `tessera_core::bezier::tessellate`.
//
// A CPU device runs a workgroup's lanes in lockstep, each loop as long as its longest
// lane: in index order, neighbouring coarse triangles make very different numbers of
// triangles. Bucketed by that number, lanes side by side do about the same work, and the
// heaviest go first, so the device's threads finish together. The mesh does not
// depend on the order (each triangle writes where the scan says), so the atomic slots
// need not be deterministic.

#include "shared/types.wgsl"

@group(0) @binding(7) var<storage, read_write> counts: array<u32>;
@group(0) @binding(14) var<storage, read_write> tally: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let t = gid.x + gid.y * groups.x * 64u;
    if t >= params.coarse_triangles {
        return;
    }
    let slot = atomicAdd(&tally[TALLY_ORDER + counts[order_keys_base() + t]], 1u);
    counts[order_base() + slot] = t;
}
