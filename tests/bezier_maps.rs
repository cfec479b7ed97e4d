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

/// Paper §2.1 on the shipped models, checked by an independent route: every map sample
/// is, in magnitude, the distance from the surface point to the nearest point of the
/// coarse mesh (Ericson's closest point on each of the 18 triangles). All three cases
/// occur and are counted: the normal of exactly one triangle passes through the point,
/// of several (the nearest counts), of none (the nearest edge counts).
#[test]
fn map_samples_are_distances_to_the_coarse_mesh_in_all_three_cases() {
    use glam::DVec3;
    use tessera_core::bezier::patch::eval_frame_f64;
    use tessera_core::bezier::prepare::coarse_triangle_grid;
    use tessera_core::gpu_types::{COARSE_SEGMENTS, COARSE_TRIANGLES_PER_PATCH};
    use tessera_core::measure::closest_point_on_triangle;

    let (mut one, mut several, mut none) = (0, 0, 0);
    for (name, model) in tessera_tests::teaset() {
        let size = {
            let (lo, hi) = model.bounds();
            (hi - lo).length() as f64
        };
        for patch in &model.patches {
            let cp = patch.cp_f64();
            let map = displacement_map(&cp);
            let n = COARSE_SEGMENTS as f64;
            let at = |ij: [u32; 2]| eval_frame_f64(&cp, ij[0] as f64 / n, ij[1] as f64 / n).pos;
            let tris: Vec<[DVec3; 3]> = (0..COARSE_TRIANGLES_PER_PATCH as u32)
                .map(|t| coarse_triangle_grid(t).map(at))
                .collect();
            for j in 0..MAP_RES {
                for i in 0..MAP_RES {
                    let last = (MAP_RES - 1) as f64;
                    let s = eval_frame_f64(&cp, i as f64 / last, j as f64 / last).pos;
                    let dists: Vec<f64> = tris
                        .iter()
                        .map(|[a, b, c]| (closest_point_on_triangle(s, *a, *b, *c) - s).length())
                        .collect();
                    let nearest = dists.iter().copied().fold(f64::INFINITY, f64::min);
                    let got = map.d[MAP_RES * j + i] as f64;
                    assert!(
                        (got.abs() - nearest).abs() <= 1e-6 * size,
                        "{name}: map {got} vs nearest {nearest}"
                    );
                    // Which triangles' normals pass through s: the closest point is the
                    // foot of the perpendicular, strictly inside.
                    let containing = tris
                        .iter()
                        .zip(&dists)
                        .filter(|([a, b, c], &d)| {
                            let nrm = (*b - *a).cross(*c - *a);
                            nrm.length() > 0.0
                                && ((s - *a).dot(nrm.normalize()).abs() - d).abs() <= 1e-9 * size
                        })
                        .count();
                    match containing {
                        0 => none += 1,
                        1 => one += 1,
                        _ => several += 1,
                    }
                }
            }
        }
    }
    assert!(
        one > 0 && several > 0 && none > 0,
        "cases: one {one}, several {several}, none {none}"
    );
}
