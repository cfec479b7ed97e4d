// Stage 3, one invocation per coarse triangle, before the mark kernel: a triangle whose
// root is known to be a leaf without the interior test (its hypotenuse, the cell's
// diagonal, has no midpoint point) marks nothing, and its counts follow from Euler's
// formula; this kernel writes them. The others it lists for `bezier_tri_mark`,
// dispatched indirectly over them. A triangle in view also marks its corners as used:
// the vertex kernel evaluates no other coarse vertex. Twin of the root branch of the mark
// loop in `tessera_core::bezier::tessellate_adaptive` (`root_known_leaf`, `mark_used`).
//
// A CPU device runs all of the mark kernel's walk, interior test and texel fetches
// included, for every triangle, whether a lane needs it or not: at coarse thresholds
// most roots are leaves, and this kernel has none of that code.

#include "shared/types.wgsl"
#include "shared/patch.wgsl"
#include "shared/map.wgsl"
#include "shared/lattice.wgsl"
#include "shared/topo.wgsl"
#include "shared/coarse.wgsl"
#include "shared/need.wgsl"
#include "shared/refine.wgsl"

@group(0) @binding(1) var nets: texture_storage_2d<rgba32float, read>;
@group(0) @binding(2) var maps: texture_storage_2d<rgba16float, read>;
@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
@group(0) @binding(7) var<storage, read_write> counts: array<u32>;
@group(0) @binding(8) var scratch: texture_storage_2d<r32uint, read>;
// The status as words, for the mark kernel's dispatch (STATUS_MARK_DISPATCH).
@group(0) @binding(13) var<storage, read_write> status_words: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> tally: array<atomic<u32>>;

// The shared refinement code's sink (not called here).
fn sink_triangle(a: VRef, b: VRef, c: VRef) {}

fn inner_rank(c: TriCtx, i: u32) -> u32 {
    return i;
}

// Coarse vertex v is a corner of a triangle in view: it is evaluated (the first to mark
// it counts it).
fn mark_used(v: u32) {
    let bit = 1u << (v & 31u);
    if (atomicOr(&tally[TALLY_USED_BITS + v / 32u], bit) & bit) == 0u {
        atomicAdd(&tally[TALLY_USED], 1u);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let t = gid.x + gid.y * groups.x * 64u;
    if t >= params.coarse_triangles {
        return;
    }
    let c = tri_ctx(t);
    var made = NO_COUNT;
    let culled = patch_culled(c.l.patch_id);
    if !culled {
        mark_used(c.corner_ids.x);
        mark_used(c.corner_ids.y);
        mark_used(c.corner_ids.z);
    }
    if culled {
        // A culled patch's triangles make nothing; its first one counts it.
        made = 0u;
        if t % COARSE_TRIANGLES_PER_PATCH == 0u {
            atomicAdd(&tally[TALLY_CULLED], 1u);
        }
    } else if root_known_leaf(c) {
        made = euler_count(c, 0u);
    }
    if made == NO_COUNT {
        // The mark kernel's: a slot in its list, and its dispatch raised to cover it
        // (x capped as the other kernels', y the rest; zeroed before each run). Only the
        // first slot of each workgroup raises it: the others need no more groups, and
        // each atomic is a loop over the lanes on a CPU device.
        let slot = atomicAdd(&tally[TALLY_MARKED], 1u);
        counts[order_base() + slot] = t;
        if slot % 64u == 0u {
            let needed = slot / 64u + 1u;
            atomicMax(&status_words[STATUS_MARK_DISPATCH], min(needed, MAX_GROUPS_X));
            atomicMax(&status_words[STATUS_MARK_DISPATCH + 1u], (needed + MAX_GROUPS_X - 1u) / MAX_GROUPS_X);
            atomicMax(&status_words[STATUS_MARK_DISPATCH + 2u], 1u);
        }
        return;
    }
    counts[params.coarse_edges + t] = 0u;
    counts[params.coarse_edges + params.coarse_triangles + t] = made;
    let bucket = order_bucket(made, is_plain(c, 0u, made));
    counts[order_keys_base() + t] = bucket;
    atomicAdd(&tally[TALLY_ORDER + bucket], 1u);
}
