// Where a Catmull-Clark vertex lies on its control face: the patch's place in the
// face's chart, the face's own (u, v) (OpenSubdiv Bfr's parameterisation, Ptex's for
// quads), and the homes where every chart's copy of a point is evaluated, so that the
// copies get the same bits. Twins: `tessera_core::catmull_clark::topology::{face_coords,
// sub_face_tiles}`, `keys::{chart_of, seam, face_uv}`, `gpu_uniform::grid_place`,
// `gpu_model::{edge_point, corner_home, edge_home}`.

#include "shared/types.wgsl"

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

// The grid point at distance t from corner k along edge k (`edge_point`).
fn cc_edge_point(k: u32, t: u32, n: u32) -> vec2u {
    switch k {
        case 0u: { return vec2u(t, 0u); }
        case 1u: { return vec2u(n, t); }
        case 2u: { return vec2u(n - t, n); }
        default: { return vec2u(0u, n - t); }
    }
}

// The chart of patch p (`chart_of`): for a quad face its first patch, else p itself.
// `face_corner` is the patch's corner in its face | the face's sides << 8.
fn cc_chart(face_corner: u32, p: u32) -> u32 {
    return select(p, p - (face_corner & 0xffu), (face_corner >> 8u) == 4u);
}

// Whether edge k of a patch is a seam between charts (`seam`): the halves of control
// edges always, the edges to the face point in a face that is not a quad.
fn cc_seam(face_corner: u32, k: u32) -> bool {
    return k == 0u || k == 3u || (face_corner >> 8u) != 4u;
}

// Sub-face tiles per row of a face of `sides` != 4 sides (`sub_face_tiles`).
fn cc_sub_face_tiles(sides: u32) -> u32 {
    if sides < 10u {
        return select(2u, 3u, sides > 4u);
    }
    var r = 1u;
    while (r + 1u) * (r + 1u) < sides {
        r += 1u;
    }
    return 1u + r;
}

// Grid point (i, j)/scale of the patch at corner k of a face of `sides` sides in the
// face's coordinates, units of 1/(2·scale) (`face_coords`).
fn cc_face_coords(k: u32, sides: u32, i: u32, j: u32, scale: u32) -> vec2u {
    let m = 2u * scale;
    if sides == 4u {
        switch k {
            case 0u: { return vec2u(i, j); }
            case 1u: { return vec2u(m - j, i); }
            case 2u: { return vec2u(m - i, m - j); }
            default: { return vec2u(j, m - i); }
        }
    }
    let d = cc_sub_face_tiles(sides);
    return vec2u((k % d) * m + i, (k / d) * m + j);
}

// The face's (u, v) of that point as a vertex carries it (`face_uv`): integers below
// 2^24 divided once, so every patch of a face gives a shared point the same bits.
fn cc_face_uv(face_corner: u32, i: u32, j: u32, scale: u32) -> vec2f {
    let c = cc_face_coords(face_corner & 0xffu, face_corner >> 8u, i, j, scale);
    let m = f32(2u * scale);
    return vec2f(f32(c.x) / m, f32(c.y) / m);
}

// Homes are `patch << 3 | reversed << 2 | k`: the smallest surface patch at a level-1
// point (k its corner there) or edge (k its index there, reversed if the patch runs it
// from its larger end point). (patch, i, j) of a point's home (`corner_home`).
fn cc_corner_home(home: u32, n: u32) -> vec3u {
    let c = home & 3u;
    return vec3u(home >> 3u, select(0u, n, c == 1u || c == 2u), select(0u, n, c >= 2u));
}

// (patch, i, j) of the point at canonical t (from the smaller end point) of an edge
// with this home (`edge_home`).
fn cc_edge_home(home: u32, t: u32, n: u32) -> vec3u {
    let local = select(t, n - t, (home & 4u) != 0u);
    return vec3u(home >> 3u, cc_edge_point(home & 3u, local, n));
}
