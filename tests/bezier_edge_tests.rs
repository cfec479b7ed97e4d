//! Decisions of Map2p, Map4p, Map8p and the flat test on hand-checked cases.

use tessera_core::bezier::edge_tests::{bit_positions, map_test, subdivide_segment, TestInputs};
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
