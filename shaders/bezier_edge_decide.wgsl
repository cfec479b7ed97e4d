// Stage 1, one invocation per coarse edge: recursive bisection of the edge by its own
// test and by the right triangles beside it. Writes the edge's bit set of inserted
// dyadic points and their count. Twin of `tessera_core::bezier::tessellate::edge_decide`.

#include "shared/types.wgsl"
#include "shared/patch.wgsl"
#include "shared/map.wgsl"
#include "shared/lattice.wgsl"
#include "shared/topo.wgsl"
#include "shared/coarse.wgsl"
#include "shared/need.wgsl"

@group(0) @binding(1) var nets: texture_storage_2d<rgba32float, read>;
@group(0) @binding(2) var maps: texture_storage_2d<rgba16float, read>;
@group(0) @binding(3) var topology: texture_storage_2d<rgba32uint, read>;
// The edges' bit sets go to the scratch (`edge_set_word`), where the triangle kernels read
// them with plain loads.
@group(0) @binding(8) var scratch: texture_storage_2d<r32uint, write>;
@group(0) @binding(7) var<storage, read_write> counts: array<u32>;
@group(0) @binding(14) var<storage, read_write> tally: array<atomic<u32>>;

// Whether a triangle beside the edge asks for piece [lo, hi] to be split.
fn side_need(side: EdgeSide, lo: u32, hi: u32) -> bool {
    let l = lattice_new(side.tri, params.max_depth);
    // Dividing by DYADIC_SCALE / l.n, a power of two: a shift, not an integer
    // division (a scalar loop over the lanes on a CPU device).
    let shift = countTrailingZeros(DYADIC_SCALE) - l.depth;
    var f0 = lo >> shift;
    var f1 = hi >> shift;
    if !side.forward {
        f0 = (DYADIC_SCALE - hi) >> shift;
        f1 = (DYADIC_SCALE - lo) >> shift;
    }
    return interior_need(l, triangle_on_side(l, side.k, f0, f1));
}

// Whether side k of the edge is there and its patch is not culled: the triangles of a
// culled patch emit nothing and ask for no points.
fn side_alive(sides: EdgeSides, k: u32) -> bool {
    return sides.count > k && !patch_culled(sides.s[k].tri / COARSE_TRIANGLES_PER_PATCH);
}

// Unrolled over the (at most two) sides: an array indexed by a loop counter is a memory
// access per lane on a CPU device.
fn sides_need(sides: EdgeSides, lo: u32, hi: u32) -> bool {
    return (side_alive(sides, 0u) && side_need(sides.s[0], lo, hi))
        || (side_alive(sides, 1u) && side_need(sides.s[1], lo, hi));
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let e = gid.x + gid.y * groups.x * 64u;
    if e >= params.coarse_edges {
        return;
    }
    var bits = EdgeSet(vec4u(0u), vec4u(0u));
    let depth = min(params.max_depth, MAX_DEPTH_LIMIT);
    let sides = coarse_edge_sides(e);
    // An edge between culled patches gets no points.
    let alive = sides.count == 0u || side_alive(sides, 0u) || side_alive(sides, 1u);
    if !edge_collapsed(e) && depth > 0u && alive {
        let ends = edge_endpoints(e);
        // A map test asks the owner's map about the whole coarse edge only (see
        // `edge_decide`): asked once here, not masked on every piece. The flat test
        // measures every piece itself.
        var whole = false;
        if EDGE_TEST != TEST_FLAT {
            whole = segment_test(EDGE_TEST, ends.patch_id, patch_threshold(ends.patch_id),
                lerp_uv(ends.uv0, ends.uv1, 0u), lerp_uv(ends.uv0, ends.uv1, DYADIC_SCALE));
        }
        // Depth-first over the dyadic pieces [lo, lo + width] without a stack (twin of
        // `subdivide_segment_with`): a piece is a second child when lo / width is odd.
        let log_scale = countTrailingZeros(DYADIC_SCALE);
        var lo = 0u;
        var level = 0u;
        loop {
            let width = DYADIC_SCALE >> level;
            let hi = lo + width;
            let mid = lo + width / 2u;
            var split: bool;
            if EDGE_TEST == TEST_FLAT {
                split = segment_test(EDGE_TEST, ends.patch_id, patch_threshold(ends.patch_id),
                    lerp_uv(ends.uv0, ends.uv1, lo), lerp_uv(ends.uv0, ends.uv1, hi));
            } else {
                split = level == 0u && whole;
            }
            split = split || sides_need(sides, lo, hi);
            if split {
                bits = set_insert(bits, mid);
                if level + 1u < depth {
                    level += 1u;
                    continue;
                }
            }
            while level > 0u && ((lo >> (log_scale - level)) & 1u) != 0u {
                lo -= DYADIC_SCALE >> level;
                level -= 1u;
            }
            if level == 0u {
                break;
            }
            lo += DYADIC_SCALE >> level;
        }
    }
    // Written out: a vector indexed by a loop counter can become memory per lane.
    let w = edge_set_word(e);
    textureStore(scratch, scratch_texel(w), vec4u(bits.lo.x));
    textureStore(scratch, scratch_texel(w + 1u), vec4u(bits.lo.y));
    textureStore(scratch, scratch_texel(w + 2u), vec4u(bits.lo.z));
    textureStore(scratch, scratch_texel(w + 3u), vec4u(bits.lo.w));
    textureStore(scratch, scratch_texel(w + 4u), vec4u(bits.hi.x));
    textureStore(scratch, scratch_texel(w + 5u), vec4u(bits.hi.y));
    textureStore(scratch, scratch_texel(w + 6u), vec4u(bits.hi.z));
    textureStore(scratch, scratch_texel(w + 7u), vec4u(bits.hi.w));
    counts[e] = set_count(bits);
    if flat_evaluations > 0u {
        atomicAdd(&tally[TALLY_EVALUATIONS], flat_evaluations);
    }
}
