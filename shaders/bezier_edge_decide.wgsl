// Stage 1, one invocation per coarse edge: recursive bisection of the edge by its own
// test and by the right triangles beside it. Writes the edge's bit set of inserted
// dyadic points and their count. Twin of `tessera_core::bezier::tessellate::edge_decide`.

#include "shared/types.wgsl"
#include "shared/patch.wgsl"
#include "shared/map.wgsl"
#include "shared/lattice.wgsl"
#include "shared/coarse.wgsl"
#include "shared/need.wgsl"

@group(0) @binding(1) var<storage, read> patches: array<GpuPatch>;
@group(0) @binding(2) var maps: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> topo: array<GpuPatchTopo>;
@group(0) @binding(4) var<storage, read> curves: array<GpuCurve>;
@group(0) @binding(6) var<storage, read_write> edge_bits: array<u32>;
@group(0) @binding(7) var<storage, read_write> counts: array<u32>;
@group(0) @binding(14) var<storage, read_write> evaluations: atomic<u32>;

struct Piece {
    lo: u32,
    hi: u32,
    level: u32,
}

// Whether a triangle beside the edge asks for piece [lo, hi] to be split.
fn sides_need(sides: EdgeSides, lo: u32, hi: u32) -> bool {
    for (var s = 0u; s < sides.count; s++) {
        let side = sides.s[s];
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
        if interior_need(l, triangle_on_side(l, side.k, f0, f1)) {
            return true;
        }
    }
    return false;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let e = gid.x + gid.y * groups.x * 64u;
    if e >= params.coarse_edges {
        return;
    }
    var bits: array<u32, EDGE_BIT_WORDS>;
    let depth = min(params.max_depth, MAX_DEPTH_LIMIT);
    if !edge_collapsed(e) && depth > 0u {
        let ends = edge_endpoints(e);
        let sides = coarse_edge_sides(e);
        // The flat test measures every chord itself; a map test asks the owner's map
        // about the whole coarse edge only (see `edge_decide`).
        let own_test_levels = select(1u, 0xffffffffu, EDGE_TEST == TEST_FLAT);
        var stack: array<Piece, 12>;
        var top = 1u;
        stack[0] = Piece(0u, DYADIC_SCALE, 0u);
        while top > 0u {
            top -= 1u;
            let piece = stack[top];
            let mid = (piece.lo + piece.hi) / 2u;
            var split = false;
            if piece.level < own_test_levels {
                split = segment_test(EDGE_TEST, ends.patch_id, params.threshold,
                    lerp_uv(ends.uv0, ends.uv1, piece.lo), lerp_uv(ends.uv0, ends.uv1, piece.hi));
            }
            if !split {
                split = sides_need(sides, piece.lo, piece.hi);
            }
            if split {
                bits[mid / 32u] |= 1u << (mid % 32u);
                if piece.level + 1u < depth {
                    stack[top] = Piece(mid, piece.hi, piece.level + 1u);
                    stack[top + 1u] = Piece(piece.lo, mid, piece.level + 1u);
                    top += 2u;
                }
            }
        }
    }
    var count = 0u;
    for (var w = 0u; w < EDGE_BIT_WORDS; w++) {
        edge_bits[e * EDGE_BIT_WORDS + w] = bits[w];
        count += countOneBits(bits[w]);
    }
    counts[e] = count;
    if flat_evaluations > 0u {
        atomicAdd(&evaluations, flat_evaluations);
    }
}
