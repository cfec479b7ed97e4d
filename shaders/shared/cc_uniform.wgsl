// The numbering of the uniform Catmull-Clark grid points, shared by the points and the
// cells kernels (bindings 70-71). Twin: `grid_place` and `grid_vertex` in
// `tessera_core::catmull_clark::gpu_uniform`.

#include "shared/types.wgsl"

@group(0) @binding(70) var<uniform> uniform_params: CcUniformParams;
@group(0) @binding(71) var<storage, read> uniform_patches: array<CcUniformPatch>;

const GRID_CORNER: u32 = 0u;
const GRID_EDGE: u32 = 1u;
const GRID_INSIDE: u32 = 2u;

// Corner k, point t (from corner k) of edge k, or inside.
struct GridPlace {
    kind: u32,
    k: u32,
    t: u32,
}

fn grid_place(i: u32, j: u32, n: u32) -> GridPlace {
    if j == 0u {
        if i == 0u {
            return GridPlace(GRID_CORNER, 0u, 0u);
        }
        if i == n {
            return GridPlace(GRID_CORNER, 1u, 0u);
        }
        return GridPlace(GRID_EDGE, 0u, i);
    }
    if j == n {
        if i == n {
            return GridPlace(GRID_CORNER, 2u, 0u);
        }
        if i == 0u {
            return GridPlace(GRID_CORNER, 3u, 0u);
        }
        return GridPlace(GRID_EDGE, 2u, n - i);
    }
    if i == n {
        return GridPlace(GRID_EDGE, 1u, j);
    }
    if i == 0u {
        return GridPlace(GRID_EDGE, 3u, n - j);
    }
    return GridPlace(GRID_INSIDE, 0u, 0u);
}

// The output vertex of grid point (i, j) of dense patch d, and whether d evaluates it.
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
