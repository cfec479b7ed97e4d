// One invocation per grid point of every surface patch ((n + 1)² each): the vertex of
// `(patch, i/n, j/n)` in the patch's chart written where it goes, by the one patch that
// owns it, so each vertex is evaluated once (by `cc_vertex_eval` next), at its point's
// home, so that the copies of a point on a seam between charts get the same bits.
// Invocation 0 writes the vertex count that kernel reads. Twin: `uniform_point` in
// `tessera_core::catmull_clark::gpu_uniform`.

#include "shared/cc_uniform.wgsl"

@group(0) @binding(72) var<storage, read_write> uniform_points: array<CcVertexPoint>;
@group(0) @binding(73) var<storage, read_write> uniform_counts: array<u32>;

// i/n in fixed point (1 = 2^31), rounded down, without 64-bit arithmetic (`grid_param`).
fn grid_param(i: u32, n: u32) -> u32 {
    let q = CC_PARAM_ONE / n;
    let r = CC_PARAM_ONE % n;
    return i * q + i * r / n;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let g = uniform_invocation(gid, groups);
    let n = uniform_params.segments;
    let side = n + 1u;
    if g == 0u {
        let inner = n - 1u;
        uniform_counts[0] = uniform_params.corner_count + uniform_params.edge_count * inner
            + uniform_params.patch_count * inner * inner;
    }
    if g >= uniform_params.patch_count * side * side {
        return;
    }
    let d = g / (side * side);
    let i = g % side;
    let j = g / side % side;
    let v = grid_vertex(d, i, j);
    if v.owned && v.index < arrayLength(&uniform_points) {
        let place = grid_place(i, j, n);
        var home = vec3u(uniform_patches[d].patch_id, i, j);
        if place.kind == GRID_CORNER {
            home = cc_corner_home(uniform_patches[d].corner_homes[place.k], n);
        } else if place.kind == GRID_EDGE {
            let reversed = (uniform_patches[d].flags & (CC_EDGE_REVERSED << place.k)) != 0u;
            let t = select(place.t, n - place.t, reversed);
            home = cc_edge_home(uniform_patches[d].edge_homes[place.k], t, n);
        }
        let uv = cc_face_uv(uniform_patches[d].face_corner, i, j, n);
        uniform_points[v.index] = CcVertexPoint(home.x, grid_param(home.y, n),
            grid_param(home.z, n), uniform_patches[d].face, uv.x, uv.y);
    }
}
