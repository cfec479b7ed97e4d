// The first slot probed for a key (twin: `vertex_hash::home_slot`).

fn cc_home_slot(key: vec2u, capacity: u32) -> u32 {
    var h = (key.y * 0x9E3779B1u) ^ (key.x * 0x85EBCA77u);
    h ^= h >> 15u;
    h = h * 0x2C1B3C6Du;
    h ^= h >> 12u;
    return h & (capacity - 1u);
}
