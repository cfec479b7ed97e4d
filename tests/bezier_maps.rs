//! Displacement maps and coarse tessellation on patches with known answers.

use tessera_core::bezier::prepare::{displacement_map, map_read};
use tessera_core::bezier::{tessellate_adaptive, AdaptiveParams, EdgeTest, PreparedBezier};
use tessera_core::gpu_types::MAP_RES;
use tessera_tests::{parabolic_cylinder, plane_patch};

#[test]
fn planar_patch_gives_a_zero_map_and_no_refinement() {
    let model = plane_patch();
    let prep = PreparedBezier::new(&model);
    assert!(
        prep.maps[0].d.iter().all(|d| d.abs() < 1e-6),
        "{:?}",
        prep.maps[0].d
    );
    for test in [
        EdgeTest::Map2p,
        EdgeTest::Map4p,
        EdgeTest::Map8p,
        EdgeTest::Flat,
    ] {
        let out = tessellate_adaptive(
            &prep,
            &AdaptiveParams {
                test,
                threshold: 1e-4,
                max_depth: 6,
            },
        )
        .unwrap();
        assert_eq!(out.mesh.triangle_count(), 18, "{test:?} refined a plane");
        assert_eq!(out.mesh.vertices.len(), 16);
    }
}

#[test]
fn parabolic_cylinder_map_matches_the_analytic_distance() {
    // z = x² against the chord planes of the coarse grid x ∈ {0, 1/3, 2/3, 1}: in the
    // strip [x0, x1] the coarse plane is z = (x0 + x1) x − x0 x1 and the surface lies
    // below it by (x − x0)(x1 − x), measured along the plane's unit normal.
    let model = parabolic_cylinder();
    let map = displacement_map(&model.patches[0].cp_f64());
    for j in 0..MAP_RES {
        for i in 0..MAP_RES {
            let x = i as f64 / (MAP_RES - 1) as f64;
            let k = ((x * 3.0).floor() as usize).min(2);
            let (x0, x1) = (k as f64 / 3.0, (k + 1) as f64 / 3.0);
            let m = x0 + x1;
            let expected = -(x - x0) * (x1 - x) / (1.0 + m * m).sqrt();
            let got = map.d[MAP_RES * j + i] as f64;
            // On a coarse grid line the neighbouring strip's plane is as near; both are 0.
            assert!(
                (got - expected).abs() < 1e-6,
                "map({i},{j}) = {got}, expected {expected}"
            );
        }
    }
    // Bilinear reads interpolate the samples.
    let (a, b) = (map.d[3], map.d[4]);
    let mid = map_read(&map, 3.5 / 15.0, 0.0);
    assert!((mid - 0.5 * (a + b)).abs() < 1e-6);
}

#[test]
fn upload_stays_under_two_kilobytes_per_patch() {
    for (name, model) in tessera_tests::teaset() {
        let prep = PreparedBezier::new(&model);
        let per_patch = prep.upload_bytes() as f64 / model.patches.len() as f64;
        assert!(per_patch < 2048.0, "{name}: {per_patch} B/patch");
    }
}
