// Stage 5c, one invocation per coarse triangle that is not plain (the first slots of the
// emit order, dispatched indirectly by `bezier_finish`): where its inner points are evaluated (in
// lattice order) and its indices. Twin of `tessera_core::bezier::tessellate::tri_emit`.

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
@group(0) @binding(7) var<storage, read> counts: array<u32>;
@group(0) @binding(8) var scratch: texture_storage_2d<r32uint, read>;
@group(0) @binding(9) var<storage, read_write> records: array<VertexRecord>;
@group(0) @binding(11) var<storage, read_write> out_indices: array<u32>;
@group(0) @binding(13) var<storage, read> status: BezierStatus;

// The writing sink.
var<private> next_index: u32;
var<private> inner_base: u32;

// Inner points before each word of the triangle's bit set (twin of `prefix` in `tri_emit`):
// one lookup per rank instead of a loop over the words before it.
const MAX_POINTS_WORDS: u32 = (((1u << ARRAY_DEPTH) + 1u) * ((1u << ARRAY_DEPTH) + 2u) / 2u + 31u) / 32u;
var<private> word_below: array<u32, MAX_POINTS_WORDS>;

fn inner_rank(c: TriCtx, i: u32) -> u32 {
    let mask = (1u << (i % 32u)) - 1u;
    return word_below[i / 32u] + countOneBits(scratch_word(c.points_base + i / 32u) & mask);
}

// The triangle's side edges and the first vertex of each, read once (see `main`).
var<private> side_edges: vec3u;
var<private> side_first: vec3u;

fn global_index(v: VRef) -> u32 {
    if v.kind == VREF_COARSE {
        return v.a;
    }
    if v.kind == VREF_EDGE {
        let first = select(select(side_first.z, side_first.y, v.a == side_edges.y), side_first.x, v.a == side_edges.x);
        return first + v.b;
    }
    return inner_base + v.a;
}

fn sink_triangle(a: VRef, b: VRef, c: VRef) {
    let ids = array<u32, 3>(global_index(a), global_index(b), global_index(c));
    for (var k = 0u; k < 3u; k++) {
        if next_index < arrayLength(&out_indices) {
            out_indices[next_index] = ids[k];
        }
        next_index += 1u;
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    // Dispatched indirectly for the first `general_triangles` slots of the emit order;
    // the plain triangles after them are `tri_emit_plain`'s.
    let slot = gid.x + gid.y * groups.x * 64u;
    if slot >= status.general_triangles || slot >= params.coarse_triangles || status.overflow != 0u {
        return;
    }
    // The coarse triangles in `tri_order`'s order: lanes side by side do alike work.
    let t = counts[order_base() + slot];
    let c = tri_ctx(t);
    if patch_culled(c.l.patch_id) {
        return;
    }
    let e = params.coarse_edges;
    let tris = params.coarse_triangles;
    inner_base = params.coarse_vertices + counts[e + t];
    side_edges = c.side_edges;
    side_first = params.coarse_vertices + vec3u(counts[side_edges.x], counts[side_edges.y], counts[side_edges.z]);
    // The records of the inner points in lattice order, reading only the groups of words
    // that hold points (most of a triangle's 68 words at depth 6 are empty).
    var next = inner_base;
    var rows = LatticeRows(0u, 0u);
    let shift = word_group_shift(params.points_words);
    var held = scratch_word(c.groups_index);
    while held != 0u {
        let g = firstTrailingBit(held);
        held &= held - 1u;
        let end = min((g + 1u) << shift, params.points_words);
        for (var w = g << shift; w < end; w++) {
            word_below[w] = next - inner_base;
            var bits = scratch_word(c.points_base + w);
            while bits != 0u {
                let i = 32u * w + firstTrailingBit(bits);
                bits &= bits - 1u;
                rows = rows_seek(c.l, rows, i);
                let uv = lattice_uv(c.l, rows_point(rows, i));
                if next < arrayLength(&records) {
                    records[next] = VertexRecord(c.l.patch_id, uv.x, uv.y);
                }
                next += 1u;
            }
        }
    }
    next_index = 3u * (counts[e + tris + t] - counts[e + tris]);
    tri_triangles(c);
}
