// What the kernels of the adaptive Catmull-Clark pipeline share (bindings 50-58): the
// parameters, the counters, the first-split trials, grid parameters and point keys.
// Twins: `tessera_core::gpu_types::cc_trial_split`,
// `tessera_core::catmull_clark::keys::topo_chart_key`.

#include "shared/types.wgsl"
#include "shared/cc_patch.wgsl"
#include "shared/cc_face.wgsl"

// `tessera_core::gpu_types::CcState`.
struct CcCounters {
    drawn_vertices: u32,
    leaves: u32,
    overflow: atomic<u32>,
    need_poly: u32,
    need_indices: u32,
    unmet: atomic<u32>,
    max_bound_bits: atomic<u32>,
    vertices: u32,
    bounds: atomic<u32>,
    proven: atomic<u32>,
    decision_blocks: atomic<u32>,
    culled_leaves: atomic<u32>,
    culled_patches: atomic<u32>,
}

// `tessera_core::gpu_types::CcHashStatus` as the kernels around the hash read and set it
// (the hash's own kernels use the atomic `CcHashStatus` of `shared/cc_hash.wgsl`).
struct CcHashStatusView {
    items: u32,
    overflow: u32,
    unique: u32,
    pad: u32,
}

@group(0) @binding(50) var<uniform> cc_params: CcTessParams;
@group(0) @binding(51) var<storage, read_write> cc_state: CcCounters;
// Marking's words (binding 57, `stage::marks_words`, see cc_traverse.wgsl), P patches
// and T trials:
// - [0, P]: per patch the key of its best trial, !(leaves << 5 | trial), then its first
//   leaf (scanned in place, the total at P);
// - [P + 1, 2P + 1): the same key, kept; [2P + 1, 3P + 1): the key of the best trial
//   the device cut short; [3P + 1, 4P + 1): the trial chosen;
// - [4P + 1, 5P + 1): per patch the flatness bound of its whole square, plus one in its
//   bits (0 for none yet): kept from run to run, cleared when the control points move;
// - [5P + 1, 6P + 1): at the first patch of each quad face, the bound of the face taken
//   whole (`cc_face_bound.wgsl`), kept likewise;
// - per patch and trial, what its leaves guarantee: the largest bound, the leaves over
//   their tolerance, the leaves culled;
// - blocks of 32 decisions, `[bits, next]`: one per patch and trial, then a pool.
// Declared by the kernels that use it (atomic where marking writes it).

// Indirect dispatch arguments: [3..6] the leaves, [6..9] the hash items (eight per leaf:
// `cc_leaf_keys`).
@group(0) @binding(58) var<storage, read_write> args: array<u32>;

fn cc_best_at(p: u32) -> u32 {
    return cc_params.patch_count + 1u + p;
}

fn cc_cut_at(p: u32) -> u32 {
    return 2u * cc_params.patch_count + 1u + p;
}

fn cc_chosen_at(p: u32) -> u32 {
    return 3u * cc_params.patch_count + 1u + p;
}

fn cc_root_bound_at(p: u32) -> u32 {
    return 4u * cc_params.patch_count + 1u + p;
}

fn cc_face_bound_at(first: u32) -> u32 {
    return 5u * cc_params.patch_count + 1u + first;
}

fn cc_stats_at(p: u32, t: u32) -> u32 {
    return 6u * cc_params.patch_count + 1u + 3u * (p * cc_params.trials + t);
}

fn cc_bits_at(block: u32) -> u32 {
    return cc_stats_at(cc_params.patch_count, 0u) + 2u * block;
}

fn cc_invocation(gid: vec3u, groups: vec3u) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}

// `cc_trial_split`: (ku, kv) of trial t.
fn cc_trial_split(t: u32) -> vec2u {
    if t < 4u {
        return vec2u(2u * t + 1u);
    }
    let k = (t - 4u) / 2u + 1u;
    return select(vec2u(k + 1u, k), vec2u(k, k + 1u), t % 2u == 0u);
}

// Width and height of a cell in grid units.
fn cc_cell_size(cell: CcCell) -> vec2u {
    let s = cc_trial_split(cell.trial_depth & 0xffu);
    let depth = (cell.trial_depth & ~(CC_CELL_CULLED | CC_CELL_PATCH_CULLED | CC_CELL_FACE)) >> 8u;
    return vec2u((cc_params.grid / s.x) >> depth, (cc_params.grid / s.y) >> depth);
}

// Corner k of a cell, counter-clockwise from its lower-left.
fn cc_cell_corner(cell: CcCell, k: u32) -> vec2u {
    let size = cc_cell_size(cell);
    let o = vec2u(select(0u, 1u, k == 1u || k == 2u), select(0u, 1u, k >= 2u));
    return vec2u(cell.i, cell.j) + o * size;
}

// A grid coordinate as a fixed-point parameter: round(i · 2^31 / grid), grid =
// 105 · 2^(max_depth + 3), without 64-bit integers (none in WGSL): the remainder of
// i / 105 shifted by s = 28 - max_depth in two steps that stay below 2^32. No loop: a
// CPU device stops every loop of an invocation after 65 535 iterations in all, and this
// runs for every surface point.
fn cc_grid_fixed(i: u32) -> u32 {
    let s = 28u - cc_params.max_depth;
    let a = min(s, 16u);
    let b = s - a;
    let q = i / 105u;
    let x1 = (i % 105u) << a;
    let x2 = (x1 % 105u) << b;
    var r = (q << s) + ((x1 / 105u) << b) + x2 / 105u;
    if 2u * (x2 % 105u) >= 105u {
        r += 1u;
    }
    return r;
}

// `keys::topo_chart_key` as `[hi, lo]` words: the same point in the same chart gets the
// same key from every patch. A level-1 point's key holds its chart, an edge point's key
// the side of a seam it is on (bit 31: the patch runs the edge from its smaller end).
fn cc_chart_key(topo: CcPatchTopo, p: u32, i: u32, j: u32) -> vec2u {
    let n = cc_params.grid;
    let place = grid_place(i, j, n);
    if place.kind == GRID_CORNER {
        return vec2u(cc_chart(topo.face_corner, p), topo.quad[place.k]);
    }
    if place.kind == GRID_EDGE {
        let k = place.k;
        let forward = topo.quad[k] < topo.quad[(k + 1u) % 4u];
        let side = select(0u, 1u << 31u, forward && cc_seam(topo.face_corner, k));
        return vec2u((1u << 30u) | topo.edges[k], side | cc_edge_canonical(topo, k, place.t));
    }
    return vec2u((2u << 30u) | (p << 8u) | (i >> 12u), ((i & 0xfffu) << 20u) | j);
}

// Distance from corner k along edge k, counted from the edge's smaller end point.
fn cc_edge_canonical(topo: CcPatchTopo, k: u32, t: u32) -> u32 {
    return select(cc_params.grid - t, t, topo.quad[k] < topo.quad[(k + 1u) % 4u]);
}

// Indirect dispatch arguments for `items` invocations of 64 (as `kernel::groups_2d`), at
// word `base`: 3 the leaves, 6 the hash items.
fn cc_write_args(base: u32, items: u32) {
    let g = (items + 63u) / 64u;
    args[base] = min(g, 32768u);
    args[base + 1u] = select((g + 32767u) / 32768u, 1u, g == 0u);
    args[base + 2u] = 1u;
}
