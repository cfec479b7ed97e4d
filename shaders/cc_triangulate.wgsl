// One invocation per leaf: its polygon zipped into triangles between two opposite
// corners (no new vertices, no zero-area triangles; proof in
// `tessera_core::catmull_clark::triangulate`, the twin). A polygon of m vertices gives
// m - 2 triangles, so leaf l writes from index 3 · (poly_offsets[l] - 2 l), and
// invocation 0 the draw arguments. Nothing is written when the mesh does not fit
// (`finish_run` in cc_polygon.wgsl).

#include "shared/cc_tess.wgsl"
#include "shared/cc_poly.wgsl"

@group(0) @binding(55) var<storage, read> leaves: array<CcCell>;
@group(0) @binding(63) var<storage, read> poly_verts: array<vec4u>;
@group(0) @binding(64) var<storage, read> vertices: array<OutVertex>;
@group(0) @binding(65) var<storage, read_write> indices: array<u32>;
@group(0) @binding(66) var<storage, read_write> draw: DrawIndexedIndirectArgs;

const CC_DIAGONAL_MARGIN: f32 = 1e-4;

var<private> poly_base: u32;
var<private> poly_len: u32;
var<private> index_at: u32;

fn poly_vertex(k: u32) -> vec4u {
    return poly_verts[poly_base + k % poly_len];
}

fn vertex_position(id: u32) -> vec3f {
    let v = vertices[id];
    return vec3f(v.position[0], v.position[1], v.position[2]);
}

fn put_triangle(a: u32, b: u32, c: u32) {
    if index_at + 3u <= arrayLength(&indices) && index_at + 3u <= cc_params.index_capacity {
        indices[index_at] = a;
        indices[index_at + 1u] = b;
        indices[index_at + 2u] = c;
    }
    index_at += 3u;
}

fn cc_gcd(a: u32, b: u32) -> u32 {
    var x = a;
    var y = b;
    while y != 0u {
        let r = x % y;
        x = y;
        y = r;
    }
    return x;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let l = cc_invocation(gid, groups);
    let n = min(cc_state.leaves, cc_params.leaf_capacity);
    // `finish_run` (cc_polygon.wgsl) found that the mesh does not fit.
    if atomicLoad(&cc_state.overflow) != 0u {
        return;
    }
    // The leaf dispatch always has invocation 0.
    if l == 0u {
        draw.index_count = cc_state.need_indices;
        draw.instance_count = 1u;
        draw.first_index = 0u;
        draw.base_vertex = 0;
        draw.first_instance = 0u;
    }
    if l >= n || l >= arrayLength(&leaves) || l + 1u >= arrayLength(&poly_offsets) {
        return;
    }
    poly_base = poly_offsets[l];
    poly_len = poly_offsets[l + 1u] - poly_base;
    // Nothing is read past the polygons written.
    if poly_base + poly_len > cc_params.poly_capacity || poly_base + poly_len > arrayLength(&poly_verts) {
        return;
    }
    index_at = 3u * (poly_base - 2u * l);
    // A culled leaf (`cc_polygon`'s two-vertex polygon): no triangles.
    if poly_len < 4u {
        return;
    }
    if cc_side_base(l) + 4u > arrayLength(&poly_offsets) {
        return;
    }
    let sc = cc_side_counts(l);
    let corners = vec4u(0u, 1u + sc.x, 2u + sc.x + sc.y, 3u + sc.x + sc.y + sc.z);
    let c0 = poly_vertex(corners.x);
    let c2 = poly_vertex(corners.z);
    let d02 = dot(vertex_position(c0.x) - vertex_position(c2.x), vertex_position(c0.x) - vertex_position(c2.x));
    let c1 = poly_vertex(corners.y);
    let c3 = poly_vertex(corners.w);
    let d13 = dot(vertex_position(c1.x) - vertex_position(c3.x), vertex_position(c1.x) - vertex_position(c3.x));
    // `zip_start`: corner 1 unless diagonal 1-3 is shorter by more than the margin.
    let s = select(0u, 1u, d02 <= d13 * (1.0 + CC_DIAGONAL_MARGIN));
    let start = corners[s];
    let end = corners[s + 2u];
    // Progress toward the end corner, x·h + y·w in the cell's units, scaled by the gcd
    // of w and h so that it fits in 32 bits.
    let w = c2.y - c0.y;
    let h = c2.z - c0.z;
    let g = cc_gcd(w, h);
    let wr = w / g;
    let hr = h / g;
    let m = poly_len;
    let len_l = (end + m - start) % m - 1u;
    let len_r = (start + m - end) % m - 1u;
    put_triangle(poly_vertex(start + m - 1u).x, poly_vertex(start).x, poly_vertex(start + 1u).x);
    var a = 0u;
    var b = 0u;
    for (var guard = 0u; guard < m && (a + 1u < len_l || b + 1u < len_r); guard++) {
        var advance_l = b + 1u == len_r;
        if !advance_l && a + 1u < len_l {
            let fl = poly_vertex(start + 2u + a);
            let fr = poly_vertex(start + m - 2u - b);
            let xl = select(c2.y - fl.y, fl.y - c0.y, s == 0u);
            let xr = select(c2.y - fr.y, fr.y - c0.y, s == 0u);
            advance_l = xl * hr + (fl.z - c0.z) * wr <= xr * hr + (fr.z - c0.z) * wr;
        }
        if advance_l {
            put_triangle(poly_vertex(start + m - 1u - b).x, poly_vertex(start + 1u + a).x,
                poly_vertex(start + 2u + a).x);
            a += 1u;
        } else {
            put_triangle(poly_vertex(start + m - 2u - b).x, poly_vertex(start + m - 1u - b).x,
                poly_vertex(start + 1u + a).x);
            b += 1u;
        }
    }
    put_triangle(poly_vertex(start + 1u + a).x, poly_vertex(end).x, poly_vertex(start + m - 1u - b).x);
}
