// The polygons of the leaves (cc_polygon writes them, cc_triangulate reads them).

#include "shared/cc_tess.wgsl"

// The polygon sizes (scanned into offsets by the host) for leaf_capacity + 1 entries,
// then four side counts per leaf.
@group(0) @binding(62) var<storage, read_write> poly_offsets: array<u32>;

fn cc_side_base(l: u32) -> u32 {
    return cc_params.leaf_capacity + 1u + 4u * l;
}

fn cc_side_counts(l: u32) -> vec4u {
    let b = cc_side_base(l);
    return vec4u(poly_offsets[b], poly_offsets[b + 1u], poly_offsets[b + 2u], poly_offsets[b + 3u]);
}
