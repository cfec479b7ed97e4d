// One invocation per grid cell of every surface patch (n² each): its two triangles,
// cut along the shorter diagonal in space as `triangulate` cuts a plain quad. Invocation
// 0 writes the draw arguments. Twin: `uniform_cell` and `quad_triangles` in
// `tessera_core::catmull_clark::gpu_uniform`.

#include "shared/cc_uniform.wgsl"

@group(0) @binding(74) var<storage, read> uniform_vertices: array<OutVertex>;
@group(0) @binding(75) var<storage, read_write> uniform_indices: array<u32>;
@group(0) @binding(76) var<storage, read_write> uniform_draw: DrawIndexedIndirectArgs;

// `tessera_core::catmull_clark::triangulate::DIAGONAL_MARGIN`.
const DIAGONAL_MARGIN: f32 = 1e-4;

fn position(id: u32) -> vec3f {
    if id >= arrayLength(&uniform_vertices) {
        return vec3f(0.0);
    }
    let v = uniform_vertices[id];
    return vec3f(v.position[0], v.position[1], v.position[2]);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let c = uniform_invocation(gid, groups);
    let n = uniform_params.segments;
    let cells = uniform_params.patch_count * n * n;
    if c == 0u {
        uniform_draw = DrawIndexedIndirectArgs(6u * cells, 1u, 0u, 0, 0u);
    }
    if c >= cells {
        return;
    }
    let d = c / (n * n);
    let i = c % n;
    let j = c / n % n;
    let a = grid_vertex(d, i, j).index;
    let b = grid_vertex(d, i + 1u, j).index;
    let e = grid_vertex(d, i + 1u, j + 1u).index;
    let f = grid_vertex(d, i, j + 1u).index;
    let d02 = dot(position(a) - position(e), position(a) - position(e));
    let d13 = dot(position(b) - position(f), position(b) - position(f));
    var tri: array<u32, 6>;
    if d02 <= d13 * (1.0 + DIAGONAL_MARGIN) {
        tri = array<u32, 6>(a, b, e, e, f, a);
    } else {
        tri = array<u32, 6>(f, a, b, b, e, f);
    }
    if 6u * c + 6u <= arrayLength(&uniform_indices) {
        for (var k = 0u; k < 6u; k++) {
            uniform_indices[6u * c + k] = tri[k];
        }
    }
}
