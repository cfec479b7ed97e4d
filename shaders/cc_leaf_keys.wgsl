// One invocation per leaf: eight items for the vertex hash, the keys and the vertices
// they stand for; invocation 0 tells the hash how many items there are. Item 8·leaf + k
// is corner k in the leaf's chart; item 8·leaf + 4 + k the same point in the chart
// across, when corner k lies inside a seam edge of the patch (the polygons there look
// the point up in their own chart), else no key. A level-1 point needs no such item: it
// is a corner of a leaf in every chart around it. Each vertex is evaluated at its
// point's home, the same for all its copies. A face leaf has items of its own
// (`face_items`).
// Twin: `tessera_core::catmull_clark::gpu_model::leaf_items`.

#include "shared/cc_tess.wgsl"

@group(0) @binding(40) var<storage, read_write> keys_out: array<vec2u>;
@group(0) @binding(43) var<storage, read_write> hash_status: CcHashStatusView;
@group(0) @binding(55) var<storage, read> leaves: array<CcCell>;
@group(0) @binding(59) var<storage, read> topo: array<CcPatchTopo>;
@group(0) @binding(60) var<storage, read_write> item_points: array<CcVertexPoint>;
// Homes of the level-1 points, then of the level-1 edges (from `cc_params.points`).
@group(0) @binding(67) var<storage, read> homes: array<u32>;
// Marking's words (`shared/cc_tess.wgsl`): here the trial each patch chose, marked for
// the patches of face leaves.
@group(0) @binding(57) var<storage, read> marks: array<u32>;

// `gpu_model::home_point`: where every chart's vertex of grid point q of patch p is
// evaluated, as (patch, i, j).
fn home_point(tp: CcPatchTopo, p: u32, q: vec2u) -> vec3u {
    let n = cc_params.grid;
    let place = grid_place(q.x, q.y, n);
    if place.kind == GRID_CORNER {
        return cc_corner_home(homes[tp.quad[place.k]], n);
    }
    if place.kind == GRID_EDGE {
        let t = cc_edge_canonical(tp, place.k, place.t);
        return cc_edge_home(homes[cc_params.points + tp.edges[place.k]], t, n);
    }
    return vec3u(p, q);
}

// The vertex of grid point q of the patch with topology tp, evaluated at `home`.
fn vertex_point(home: vec3u, tp: CcPatchTopo, q: vec2u) -> CcVertexPoint {
    let uv = cc_face_uv(tp.face_corner, q.x, q.y, cc_params.grid);
    return CcVertexPoint(home.x, cc_grid_fixed(home.y), cc_grid_fixed(home.z), tp.face, uv.x, uv.y);
}

// A face leaf of the quad face whose first patch is `first`: item k is vertex k (corner
// (0, 0) of patch first + k), item 4 + k the level-1 edge point at the end of that
// patch's side v = 0 (its corner (n, 0)), in its chart, where the face across is not a
// face leaf too (its leaves have the point as a corner; with a face leaf across, neither
// polygon has it), else no key.
fn face_items(l: u32, first: u32) {
    let n = cc_params.grid;
    for (var k = 0u; k < 4u; k++) {
        let p = first + k;
        let tp = topo[p];
        let at = 8u * l + k;
        let across = tp.across[0];
        let needed = across != CC_NO_NEIGHBOUR
            && (marks[cc_chosen_at(across >> 2u)] & CC_CHOSEN_FACE_LEAF) == 0u;
        var edge_key = CC_NO_KEY;
        var edge_point = CcVertexPoint(0u, 0u, 0u, 0u, 0.0, 0.0);
        if needed {
            let q = vec2u(n, 0u);
            edge_key = cc_chart_key(tp, p, q.x, q.y);
            edge_point = vertex_point(home_point(tp, p, q), tp, q);
        }
        if at + 4u < arrayLength(&keys_out) && at + 4u < arrayLength(&item_points) {
            let q = vec2u(0u, 0u);
            keys_out[at] = cc_chart_key(tp, p, q.x, q.y);
            item_points[at] = vertex_point(home_point(tp, p, q), tp, q);
            keys_out[at + 4u] = edge_key;
            item_points[at + 4u] = edge_point;
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    if l == 0u {
        hash_status.items = 8u * n;
    }
    if l >= n || l >= arrayLength(&leaves) {
        return;
    }
    let grid = cc_params.grid;
    let cell = leaves[l];
    // A leaf of a patch wholly out of view has no vertices, and puts no points on its
    // neighbours' sides (a culled leaf of a patch partly in view still marks its
    // corners: the polygons' side walk halves a side only where its midpoint is marked).
    if (cell.trial_depth & CC_CELL_PATCH_CULLED) != 0u {
        for (var k = 0u; k < 8u; k++) {
            if 8u * l + k < arrayLength(&keys_out) {
                keys_out[8u * l + k] = CC_NO_KEY;
            }
        }
        return;
    }
    if (cell.trial_depth & CC_CELL_FACE) != 0u {
        face_items(l, cell.patch_id);
        return;
    }
    let tp = topo[cell.patch_id];
    for (var k = 0u; k < 4u; k++) {
        let at = 8u * l + k;
        let q = cc_cell_corner(cell, k);
        let home = home_point(tp, cell.patch_id, q);
        var across_key = CC_NO_KEY;
        var across_point = CcVertexPoint(0u, 0u, 0u, 0u, 0.0, 0.0);
        let place = grid_place(q.x, q.y, grid);
        if place.kind == GRID_EDGE && cc_seam(tp.face_corner, place.k)
            && tp.across[place.k] != CC_NO_NEIGHBOUR {
            // The patch across runs the edge the other way.
            let a = tp.across[place.k];
            let tq = topo[a >> 2u];
            let qq = cc_edge_point(a & 3u, grid - place.t, grid);
            across_key = cc_chart_key(tq, a >> 2u, qq.x, qq.y);
            across_point = vertex_point(home, tq, qq);
        }
        if at + 4u < arrayLength(&keys_out) && at + 4u < arrayLength(&item_points) {
            keys_out[at] = cc_chart_key(tp, cell.patch_id, q.x, q.y);
            item_points[at] = vertex_point(home, tp, q);
            keys_out[at + 4u] = across_key;
            item_points[at + 4u] = across_point;
        }
    }
}
