// Stages 3a and 3b for the coarse triangles `bezier_tri_roots` did not decide (their
// root may split, or Euler's formula does not hold), one invocation each:
// mark the bisection tree as the lattice points it makes, then count the inner vertices
// and the triangles the replay will make (by Euler's formula, without the replay). Twin
// of `tri_mark`, `TriScratch::inner_count` and `tri_count` in `tessera_core::bezier`;
// `bezier_tri_roots.wgsl` takes the others.

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
@group(0) @binding(14) var<storage, read_write> tally: array<atomic<u32>>;
@group(0) @binding(8) var scratch: texture_storage_2d<r32uint, read_write>;

// The counting sink: any injective numbering of inner points will do.
var<private> triangles: u32;

fn sink_triangle(a: VRef, b: VRef, c: VRef) {
    triangles += 1u;
}

fn inner_rank(c: TriCtx, i: u32) -> u32 {
    return i;
}

fn scratch_store(w: u32, value: u32) {
    textureStore(scratch, scratch_texel(w), vec4u(value, 0u, 0u, 0u));
}

// Stage "mark": the bisection tree as the points it makes (twin of `tri_mark`), and
// the groups of words that hold them. The triangle's point and pole words must be zero
// (the stage clears them). Returns the inner points marked, each counted once as its
// bit turns on (no loop over the words after).
fn tri_mark(c: TriCtx) -> u32 {
    var inner = 0u;
    var groups = 0u;
    let shift = word_group_shift(params.points_words);
    var w = walk_start(lattice_root(c.l));
    loop {
        if splits(c, w.t, w.level) {
            let pl = place(c.l, lattice_mid(w.t.a, w.t.b));
            // One read-modify-write for either kind of mark, its word chosen by
            // `select`: a masked device would run both branches' texel accesses.
            let inside = pl.kind == PLACE_INSIDE;
            let pole = pl.kind == PLACE_SIDE && side_collapsed(c, pl.k);
            if inside || pole {
                let i = select(pole_index(c.l, pl.k, pl.f), pl.f, inside);
                let word = select(c.pole_base, c.points_base, inside) + i / 32u;
                let bit = 1u << (i % 32u);
                let old = scratch_word(word);
                scratch_store(word, old | bit);
                let new_inner = inside && (old & bit) == 0u;
                inner += u32(new_inner);
                groups |= select(0u, 1u << ((pl.f / 32u) >> shift), inside);
            }
            w = walk_down(w);
        } else {
            w = walk_advance(w);
            if w.done {
                break;
            }
        }
    }
    scratch_store(c.groups_index, groups);
    return inner;
}

// Dispatched indirectly over the coarse triangles `tri_roots` listed (their root may
// split), in the emit order's slots, which `tri_order` fills later.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let slot = gid.x + gid.y * groups.x * 64u;
    if slot >= atomicLoad(&tally[TALLY_MARKED]) || slot >= params.coarse_triangles {
        return;
    }
    let t = counts[order_base() + slot];
    let c = tri_ctx(t);
    let inner = tri_mark(c);
    if flat_evaluations > 0u {
        atomicAdd(&tally[TALLY_EVALUATIONS], flat_evaluations);
    }
    var made = euler_count(c, inner);
    if made == NO_COUNT {
        // A patch degenerate enough that the formula does not hold: replay.
        triangles = 0u;
        tri_triangles(c);
        made = triangles;
    }
    counts[params.coarse_edges + t] = inner;
    counts[params.coarse_edges + params.coarse_triangles + t] = made;
    // The emit order's buckets (`bezier_tri_order.wgsl`).
    let bucket = order_bucket(made, is_plain(c, inner, made));
    counts[order_keys_base() + t] = bucket;
    atomicAdd(&tally[TALLY_ORDER + bucket], 1u);
}
