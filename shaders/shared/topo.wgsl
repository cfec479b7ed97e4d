// Patch topology and boundary curves. Twin of `tessera_core::gpu_types::TopologyTexture`.
// The kernel declares `topology`, an rgba32uint storage texture: patch p's
// `GpuPatchTopo` in texels TOPO_TEXELS·p .. + 2 (corners, sides, flags), then curve c's
// `GpuCurve` in texel TOPO_TEXELS·patches + c, texel i at (i mod width, i / width). A
// storage buffer read at per-lane addresses is a loop over the lanes on a CPU device, a
// texel fetch a plain load.
fn topology_texel(i: u32) -> vec4u {
    return textureLoad(topology, vec2u(i % TOPOLOGY_TEXTURE_WIDTH, i / TOPOLOGY_TEXTURE_WIDTH));
}

// Component k of v, by select (a vector indexed per lane is a memory access per lane).
fn pick4(v: vec4u, k: u32) -> u32 {
    return select(select(select(v.w, v.z, k == 2u), v.y, k == 1u), v.x, k == 0u);
}

fn topo_corner(p: u32, slot: u32) -> u32 {
    return pick4(topology_texel(TOPO_TEXELS * p), slot);
}

fn topo_side(p: u32, side: u32) -> u32 {
    return pick4(topology_texel(TOPO_TEXELS * p + 1u), side);
}

fn side_curve(p: u32, side: u32) -> u32 {
    return topo_side(p, side) >> 1u;
}

fn side_reversed(p: u32, side: u32) -> bool {
    return (topo_side(p, side) & 1u) != 0u;
}

fn patch_flipped(p: u32) -> bool {
    return (topology_texel(TOPO_TEXELS * p + 2u).x & 1u) != 0u;
}

fn curve_at(c: u32) -> GpuCurve {
    let t = topology_texel(TOPO_TEXELS * params.patches + c);
    return GpuCurve(t.x, t.y, t.z, t.w);
}
