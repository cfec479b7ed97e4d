//! Decisions of Map2p, Map4p, Map8p and the flat test on hand-checked cases.

use tessera_core::bezier::edge_tests::{
    bit_positions, map_test, map_test_with, subdivide_segment, TestInputs,
};
use tessera_core::bezier::EdgeTest;
use tessera_core::gpu_types::{DisplacementMap, MAP_RES};
use tessera_tests::parabolic_cylinder;

/// A map sampled from `f(u, v)` at the 16×16 grid.
fn map_of(f: impl Fn(f32, f32) -> f32) -> DisplacementMap {
    let mut m = DisplacementMap {
        d: [0.0; MAP_RES * MAP_RES],
    };
    for j in 0..MAP_RES {
        for i in 0..MAP_RES {
            m.d[MAP_RES * j + i] = f(i as f32 / 15.0, j as f32 / 15.0);
        }
    }
    m
}

const MAPS: [EdgeTest; 3] = [EdgeTest::Map2p, EdgeTest::Map4p, EdgeTest::Map8p];

#[test]
fn map2p_compares_the_ends_with_the_midpoint() {
    // d = u: along u from 0 to 1, |d1 − d12| = 0.5.
    let m = map_of(|u, _| u);
    for t in MAPS {
        assert!(map_test(t, &m, 0.49, [0.0, 0.5], [1.0, 0.5]), "{t:?}");
        assert!(!map_test(t, &m, 0.51, [0.0, 0.5], [1.0, 0.5]), "{t:?}");
    }
    // Across: constant along the segment, so Map2p sees nothing.
    assert!(!map_test(EdgeTest::Map2p, &m, 0.01, [0.5, 0.0], [0.5, 1.0]));
}

#[test]
fn map4p_looks_across_the_edge() {
    // d = v; segment along u at v = 0.5 from u = 0.25 to 0.75: (ue, ve) = (−0.25, 0),
    // d3 at (0.5, 0.25), d4 at (0.5, 0.75): |d3 − d12| = 0.25.
    let m = map_of(|_, v| v);
    let (a, b) = ([0.25, 0.5], [0.75, 0.5]);
    assert!(!map_test(EdgeTest::Map2p, &m, 0.2, a, b));
    assert!(map_test(EdgeTest::Map4p, &m, 0.24, a, b));
    assert!(!map_test(EdgeTest::Map4p, &m, 0.26, a, b));
    assert!(map_test(EdgeTest::Map8p, &m, 0.24, a, b));
}

#[test]
fn map8p_looks_along_the_diagonals() {
    // d = (u − ½)(v − ½) vanishes on the axes through the centre, where Map2p and Map4p
    // read; Map8p reads at (½ ± ⅛, ½ ± ⅛) where |d| = 1/64. Bilinear reads of the map
    // are exact for this bilinear function.
    let m = map_of(|u, v| (u - 0.5) * (v - 0.5));
    let (a, b) = ([0.25, 0.5], [0.75, 0.5]);
    assert!(!map_test(EdgeTest::Map2p, &m, 1e-4, a, b));
    assert!(!map_test(EdgeTest::Map4p, &m, 1e-4, a, b));
    assert!(map_test(EdgeTest::Map8p, &m, 1.0 / 64.0 - 1e-4, a, b));
    assert!(!map_test(EdgeTest::Map8p, &m, 1.0 / 64.0 + 1e-4, a, b));
}

#[test]
fn flat_test_measures_the_chord_deviation() {
    // z = x²: from x = 0 to 1 the surface midpoint (½, y, ¼) is ¼ below the chord's.
    let model = parabolic_cylinder();
    let cp = model.patches[0].cp;
    let map = map_of(|_, _| 0.0);
    let inputs = |th| TestInputs {
        test: EdgeTest::Flat,
        threshold: th,
        max_depth: 1,
        map: &map,
        cp: &cp,
    };
    let (bits, evals) = subdivide_segment(&inputs(0.249), [0.0, 0.3], [1.0, 0.3]);
    assert_eq!(bit_positions(&bits).collect::<Vec<_>>(), vec![128]);
    assert_eq!(evals, 3, "two ends and one candidate");
    let (bits, _) = subdivide_segment(&inputs(0.251), [0.0, 0.3], [1.0, 0.3]);
    assert_eq!(bit_positions(&bits).count(), 0);
}

#[test]
fn recursion_refines_where_the_test_fires_and_stops_at_max_depth() {
    // The chord deviation of z = x² on a piece of length h is h²/4 everywhere: with
    // th between 1/64 (h = ¼) and 1/16 (h = ½), exactly two levels split.
    let model = parabolic_cylinder();
    let cp = model.patches[0].cp;
    let map = map_of(|_, _| 0.0);
    let run = |th, depth| {
        let inputs = TestInputs {
            test: EdgeTest::Flat,
            threshold: th,
            max_depth: depth,
            map: &map,
            cp: &cp,
        };
        bit_positions(&subdivide_segment(&inputs, [0.0, 0.5], [1.0, 0.5]).0).collect::<Vec<_>>()
    };
    assert_eq!(run(0.02, 6), vec![64, 128, 192]);
    assert_eq!(
        run(1e-9, 2),
        vec![64, 128, 192],
        "depth 2 allows two levels"
    );
    assert_eq!(run(1e-9, 3).len(), 7);
    // Map tests read the map only: no evaluations.
    let m = map_of(|u, _| u * u);
    let inputs = TestInputs {
        test: EdgeTest::Map4p,
        threshold: 0.01,
        max_depth: 6,
        map: &m,
        cp: &cp,
    };
    let (bits, evals) = subdivide_segment(&inputs, [0.0, 0.5], [1.0, 0.5]);
    assert!(bit_positions(&bits).count() > 3);
    assert_eq!(evals, 0);
}

/// Whether `p` is in triangle `t` with `slack` (in barycentric units), as
/// `refine::TrianglePlane` decides it.
fn in_triangle(t: [[f32; 2]; 3], p: [f32; 2], slack: f32) -> bool {
    let (e1, e2) = (
        [t[1][0] - t[0][0], t[1][1] - t[0][1]],
        [t[2][0] - t[0][0], t[2][1] - t[0][1]],
    );
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    let (du, dv) = (p[0] - t[0][0], p[1] - t[0][1]);
    let s = (du * e2[1] - dv * e2[0]) / det;
    let r = (e1[0] * dv - e1[1] * du) / det;
    s >= -slack && r >= -slack && s + r <= 1.0 + slack
}

/// Counts the sides of right triangles where reading one point of each mirrored pair
/// (`one_inside`) decides differently from reading both, with a displacement defined
/// inside the triangle (with `slack`).
fn one_inside_disagreements(slack: f32) -> (usize, usize) {
    let m = map_of(|u, v| (7.0 * u).sin() * (5.0 * v).cos() + 0.3 * u * v);
    let (mut differ, mut positive) = (0, 0);
    for size in [0.02f32, 0.07, 0.2] {
        for k in 0..24 {
            // Right angle at r, legs of length `size`, turned by k · 15°.
            let angle = k as f32 * std::f32::consts::PI / 12.0;
            let (c, s) = (angle.cos() * size, angle.sin() * size);
            let r = [0.4 + 0.01 * k as f32, 0.3 + 0.013 * k as f32];
            let t = [r, [r[0] + c, r[1] + s], [r[0] - s, r[1] + c]];
            let d = |u: f32, v: f32| {
                in_triangle(t, [u, v], slack)
                    .then(|| tessera_core::bezier::prepare::map_read(&m, u, v))
            };
            for (a, b) in [(t[1], t[2]), (t[0], t[1]), (t[2], t[0])] {
                for test in [EdgeTest::Map4p, EdgeTest::Map8p] {
                    for th in [0.001, 0.01, 0.05] {
                        let ends = [d(a[0], a[1]), d(b[0], b[1])];
                        let one = map_test_with(test, th, [a, b], ends, true, d);
                        let both = map_test_with(test, th, [a, b], ends, false, d);
                        differ += usize::from(one != both);
                        positive += usize::from(both);
                    }
                }
            }
        }
    }
    (differ, positive)
}

#[test]
fn reading_one_point_of_a_mirrored_pair_decides_as_reading_both_on_a_side() {
    // The slack `interior_need` uses: the outer point of a pair is half a side away.
    let (differ, positive) = one_inside_disagreements(1e-4);
    assert!(
        positive > 100,
        "the cases must not all be negative ({positive})"
    );
    assert_eq!(differ, 0);
    // Test of the test: a region reaching past the sides (slack 1, so both points of a
    // pair have values) makes the shortcut miss some.
    assert!(one_inside_disagreements(1.0).0 > 0);
}
