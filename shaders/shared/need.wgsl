// The tests that ask a right triangle of a coarse triangle's lattice to be bisected;
// shared by the coarse-edge stage and the triangle stage, so both decide alike.
// Twin of `lattice_edge_test` and `interior_need` in `tessera_core::bezier::refine`.

// The edge test (TEST_MAP2P .. TEST_FLAT), fixed when the pipeline is created: a CPU
// device runs both sides of every branch under a mask, so choosing the test at run time
// would make every decision pay for all four.
override EDGE_TEST: u32;

#include "shared/thresholds.wgsl"

fn canonical_order(l: Lattice, a: vec2u, b: vec2u) -> array<vec2u, 2> {
    let pa = patch_coords(l, a);
    let pb = patch_coords(l, b);
    if pa.x < pb.x || (pa.x == pb.x && pa.y <= pb.y) {
        return array<vec2u, 2>(a, b);
    }
    return array<vec2u, 2>(b, a);
}

fn lattice_edge_test(l: Lattice, a: vec2u, b: vec2u) -> bool {
    let ab = canonical_order(l, a, b);
    return segment_test(EDGE_TEST, l.patch_id, patch_threshold(l.patch_id), lattice_uv(l, ab[0]), lattice_uv(l, ab[1]));
}

// One segment of `interior_need` with the displacements at its ends, in canonical order.
fn segment_need(l: Lattice, pl: TrianglePlane, a: vec2u, b: vec2u, ua: vec2f, ub: vec2f, da: MaybeF32, db: MaybeF32, one_inside: bool) -> bool {
    let pa = patch_coords(l, a);
    let pb = patch_coords(l, b);
    let keep = pa.x < pb.x || (pa.x == pb.x && pa.y <= pb.y);
    let d1 = MaybeF32(select(db.valid, da.valid, keep), select(db.value, da.value, keep));
    let d2 = MaybeF32(select(da.valid, db.valid, keep), select(da.value, db.value, keep));
    return map_test_with(EDGE_TEST, patch_threshold(l.patch_id), select(ub, ua, keep), select(ua, ub, keep), d1, d2, pl, true, one_inside);
}

// Whether right triangle t asks to be bisected (twin of `interior_need`). The map is
// read once per corner and at the hypotenuse midpoint (each the end of two segments, and
// the corners also fix the plane), where testing segment by segment read them again.
fn interior_need(l: Lattice, t: Tri) -> bool {
    let m = lattice_mid(t.a, t.b);
    if EDGE_TEST == TEST_FLAT {
        return lattice_edge_test(l, t.a, t.b) || lattice_edge_test(l, t.r, t.a)
            || lattice_edge_test(l, t.b, t.r) || lattice_edge_test(l, t.r, m);
    }
    let p = l.patch_id;
    let ur = lattice_uv(l, t.r);
    let ua = lattice_uv(l, t.a);
    let ub = lattice_uv(l, t.b);
    let um = lattice_uv(l, m);
    let raw_r = map_read(p, ur.x, ur.y);
    let raw_a = map_read(p, ua.x, ua.y);
    let raw_b = map_read(p, ub.x, ub.y);
    let pl = triangle_plane(p, ur, ua, ub, raw_r, raw_a, raw_b);
    let dr = plane_value(pl, ur, raw_r);
    let da = plane_value(pl, ua, raw_a);
    let db = plane_value(pl, ub, raw_b);
    let dm = plane_value(pl, um, map_read(p, um.x, um.y));
    // The hypotenuse and the legs are sides of t; the median r – m is not.
    return segment_need(l, pl, t.a, t.b, ua, ub, da, db, true)
        || segment_need(l, pl, t.r, t.a, ur, ua, dr, da, true)
        || segment_need(l, pl, t.b, t.r, ub, ur, db, dr, true)
        || segment_need(l, pl, t.r, m, ur, um, dr, dm, false);
}
