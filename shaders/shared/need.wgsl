// The tests that ask a right triangle of a coarse triangle's lattice to be bisected;
// shared by the coarse-edge stage and the triangle stage, so both decide alike.
// Twin of `lattice_edge_test` and `interior_need` in `tessera_core::bezier::refine`.

// The edge test (TEST_MAP2P .. TEST_FLAT), fixed when the pipeline is created: a CPU
// device runs both sides of every branch under a mask, so choosing the test at run time
// made every decision pay for all four (edge_decide took 2.3x as long on lavapipe).
override EDGE_TEST: u32;

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
    return segment_test(EDGE_TEST, l.patch_id, params.threshold, lattice_uv(l, ab[0]), lattice_uv(l, ab[1]));
}

// Whether right triangle t asks to be bisected (twin of `interior_need`).
fn interior_need(l: Lattice, t: Tri) -> bool {
    let m = lattice_mid(t.a, t.b);
    var seg = array<vec2u, 8>(t.a, t.b, t.r, t.a, t.b, t.r, t.r, m);
    let use_map = EDGE_TEST != TEST_FLAT;
    var pl: TrianglePlane;
    if use_map {
        pl = triangle_plane(l.patch_id, lattice_uv(l, t.r), lattice_uv(l, t.a), lattice_uv(l, t.b));
    }
    for (var s = 0u; s < 4u; s++) {
        let a = seg[2u * s];
        let b = seg[2u * s + 1u];
        var yes: bool;
        if use_map {
            let ab = canonical_order(l, a, b);
            yes = map_test_with(EDGE_TEST, params.threshold, lattice_uv(l, ab[0]), lattice_uv(l, ab[1]), pl, true);
        } else {
            yes = lattice_edge_test(l, a, b);
        }
        if yes {
            return true;
        }
    }
    return false;
}

