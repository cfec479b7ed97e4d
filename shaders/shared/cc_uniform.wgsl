// The numbering of the uniform Catmull-Clark vertices (a grid point in a chart), shared
// by the points and the cells kernels (bindings 70-71). Twin: `grid_vertex` in
// `tessera_core::catmull_clark::gpu_uniform` (`grid_place` is in `shared/cc_face.wgsl`).

#include "shared/types.wgsl"
#include "shared/cc_face.wgsl"

@group(0) @binding(70) var<uniform> uniform_params: CcUniformParams;
@group(0) @binding(71) var<storage, read> uniform_patches: array<CcUniformPatch>;

// The output vertex of grid point (i, j) of dense patch d in its chart, and whether d
// writes it.
struct GridVertex {
    index: u32,
    owned: bool,
}

fn grid_vertex(d: u32, i: u32, j: u32) -> GridVertex {
    let n = uniform_params.segments;
    let place = grid_place(i, j, n);
    let flags = uniform_patches[d].flags;
    if place.kind == GRID_CORNER {
        return GridVertex(uniform_patches[d].corners[place.k], (flags & (CC_OWNS_CORNER << place.k)) != 0u);
    }
    if place.kind == GRID_EDGE {
        let t = select(place.t, n - place.t, (flags & (CC_EDGE_REVERSED << place.k)) != 0u);
        let index = uniform_params.corner_count + uniform_patches[d].edges[place.k] * (n - 1u) + t - 1u;
        return GridVertex(index, (flags & (CC_OWNS_EDGE << place.k)) != 0u);
    }
    let first = uniform_params.corner_count + uniform_params.edge_count * (n - 1u);
    return GridVertex(first + (d * (n - 1u) + j - 1u) * (n - 1u) + i - 1u, true);
}

fn uniform_invocation(gid: vec3u, groups: vec3u) -> u32 {
    return gid.x + gid.y * groups.x * 64u;
}
