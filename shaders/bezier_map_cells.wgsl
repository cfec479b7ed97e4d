// Once per stage, one invocation per texel of the map atlas: the four corners of one
// map cell, from the maps as uploaded (16 × 16 halves a patch, two to a word). The
// atlas holds every value four times so that a bilinear read is one texel fetch; built
// here, only the maps themselves cross the bus. Twin of
// `tessera_core::gpu_types::MapAtlas::from_halves`.

#include "shared/types.wgsl"

@group(0) @binding(16) var<storage, read> map_halves: array<u32>;
@group(0) @binding(17) var map_cells: texture_storage_2d<rgba16float, write>;

const MAP_CELLS: u32 = MAP_RES - 1u;

// A finite half's bits as f32, exactly: sign, exponent rebiased from 15 to 127, mantissa
// widened. Zero for a zero or subnormal exponent (the CPU keeps no subnormal halves:
// `quantize_maps`). By bits, where `unpack2x16float` needs a capability not every naga
// backend has.
fn half_to_f32(h: u32) -> f32 {
    let sign = (h & 0x8000u) << 16u;
    let exponent = (h >> 10u) & 0x1fu;
    let mantissa = h & 0x3ffu;
    let bits = sign | ((exponent + 112u) << 23u) | (mantissa << 13u);
    return select(bitcast<f32>(bits), 0.0, exponent == 0u);
}

// Value k = MAP_RES · j + i of patch p; stored back as a half, exactly.
fn map_value(p: u32, k: u32) -> f32 {
    let word = map_halves[p * (MAP_RES * MAP_RES / 2u) + k / 2u];
    return half_to_f32((word >> (16u * (k % 2u))) & 0xffffu);
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u, @builtin(num_workgroups) groups: vec3u) {
    let item = gid.x + gid.y * groups.x * 64u;
    let cells = MAP_CELLS * MAP_CELLS;
    if item >= params.patches * cells {
        return;
    }
    let p = item / cells;
    let cell = item % cells;
    let i = cell % MAP_CELLS;
    let j = cell / MAP_CELLS;
    let k = MAP_RES * j + i;
    let below = k + MAP_RES;
    let tile = vec2u(p % MAP_ATLAS_TILES_PER_ROW, p / MAP_ATLAS_TILES_PER_ROW) * MAP_CELLS;
    let corners = vec4f(map_value(p, k), map_value(p, k + 1u), map_value(p, below), map_value(p, below + 1u));
    textureStore(map_cells, tile + vec2u(i, j), corners);
}
