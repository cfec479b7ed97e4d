//! The refinement inside coarse triangles: what it guarantees about the mesh it makes.

use tessera_core::bezier::{tessellate_adaptive, AdaptiveParams, EdgeTest, PreparedBezier};
use tessera_core::measure::{bezier_surface_samples, measure_error};
use tessera_tests::teaset;

fn params(test: EdgeTest, threshold: f32) -> AdaptiveParams {
    AdaptiveParams {
        test,
        threshold,
        max_depth: AdaptiveParams::DEFAULT_MAX_DEPTH,
    }
}

/// The flat test asks whether the surface midpoint of a side lies within `th` of the chord
/// midpoint; with every side of every leaf tested, the whole mesh should lie within about
/// `th` of the surface. (Measured: 0.29–1.06 × th over the teaset at 0.005–0.05.)
#[test]
fn flat_test_keeps_the_error_near_its_threshold() {
    for (name, model) in teaset() {
        let prep = PreparedBezier::new(&model);
        let samples = bezier_surface_samples(&model, 24);
        for th in [0.04f32, 0.01] {
            let t = tessellate_adaptive(&prep, &params(EdgeTest::Flat, th)).unwrap();
            let e = measure_error(&samples, &t.mesh);
            assert!(
                e.max_error <= 1.25 * th as f64,
                "{name} th={th}: max error {} ({} triangles)",
                e.max_error,
                t.mesh.triangle_count()
            );
        }
    }
}

/// A lower threshold never makes the mesh coarser: triangles grow and max error does not
/// (more than measurement noise) when the threshold halves.
#[test]
fn refinement_is_monotone_in_the_threshold() {
    let (_, model) = teaset().into_iter().next().unwrap();
    let prep = PreparedBezier::new(&model);
    let samples = bezier_surface_samples(&model, 16);
    for test in [EdgeTest::Map2p, EdgeTest::Map4p, EdgeTest::Flat] {
        let mut last: Option<(usize, f64)> = None;
        for th in [0.08f32, 0.04, 0.02] {
            let t = tessellate_adaptive(&prep, &params(test, th)).unwrap();
            let e = measure_error(&samples, &t.mesh);
            if let Some((tris, err)) = last {
                assert!(t.mesh.triangle_count() > tris, "{test:?} th={th}");
                assert!(
                    e.max_error <= err * 1.05,
                    "{test:?} th={th}: {} > {err}",
                    e.max_error
                );
            }
            last = Some((t.mesh.triangle_count(), e.max_error));
        }
    }
}
