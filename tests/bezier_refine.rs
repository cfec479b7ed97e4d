//! The refinement inside coarse triangles: what it guarantees about the mesh it makes.

use tessera_core::bezier::refine::{tri_mark, TriContext, TriScratch};
use tessera_core::bezier::tessellate::{
    edge_decide, euler_count, replay_count, tri_context, tri_count,
};
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
            let e = measure_error(&samples, &t.mesh, model.bbox_diag());
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
            let e = measure_error(&samples, &t.mesh, model.bbox_diag());
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

/// The CPU twins' first stages on every coarse triangle: the coarse edges' decisions,
/// then each triangle's marks, handed to `visit` with the triangle's context.
fn for_each_marked_triangle(
    prep: &PreparedBezier,
    p: &AdaptiveParams,
    mut visit: impl FnMut(u32, &TriContext, &TriScratch),
) {
    let l = prep.layout;
    let cps: Vec<_> = (0..l.patches).map(|k| prep.control_points(k)).collect();
    let bits: Vec<_> = (0..l.coarse_edges)
        .map(|e| edge_decide(prep, &cps, p, e).0)
        .collect();
    for t in 0..l.coarse_triangles {
        let ctx = tri_context(prep, &cps, &bits, p, t);
        let mut scratch = TriScratch::new(p.max_depth);
        tri_mark(&ctx, &mut scratch);
        visit(t, &ctx, &scratch);
    }
}

/// The triangle count the mark stage reports without replaying the bisection (Euler's
/// formula, `euler_count`) equals the count of the replay that emits the triangles, on
/// every coarse triangle of the teaset, for every test and several thresholds; and the
/// formula covers the triangles at the collapsed poles too. A count off by one would
/// shift every later triangle's indices.
#[test]
fn triangle_count_by_euler_formula_equals_the_replay() {
    let mut at_poles = 0;
    for (name, model) in teaset() {
        let prep = PreparedBezier::new(&model);
        for test in EdgeTest::ALL {
            for th in [0.05f32, 0.01, 0.002] {
                for_each_marked_triangle(&prep, &params(test, th), |t, ctx, scratch| {
                    assert_eq!(
                        euler_count(ctx, scratch),
                        Some(replay_count(ctx, scratch)),
                        "{name} {test:?} th={th} coarse triangle {t}"
                    );
                    at_poles += ctx.sides.iter().any(|s| s.2) as usize;
                });
            }
        }
    }
    assert!(
        at_poles > 0,
        "no coarse triangle on a collapsed side was checked"
    );
}

/// A patch whose bottom row and right column both collapse to one point (the teaset
/// loader refuses it; `BezierModel::from_nets` does not check): the coarse triangle in
/// that corner has two collapsed sides, where Euler's formula does not apply; the count
/// falls back to the replay and still equals it.
#[test]
fn a_patch_with_two_collapsed_sides_falls_back_to_the_replay_count() {
    let prep = PreparedBezier::new(&tessera_tests::two_collapsed_sides());
    let p = params(EdgeTest::Map4p, 0.01);
    let mut fallbacks = 0;
    for_each_marked_triangle(&prep, &p, |t, ctx, scratch| {
        fallbacks += euler_count(ctx, scratch).is_none() as usize;
        assert_eq!(
            tri_count(ctx, scratch),
            replay_count(ctx, scratch),
            "coarse triangle {t}"
        );
    });
    assert!(fallbacks > 0, "no coarse triangle needed the replay");
    let mesh = tessellate_adaptive(&prep, &p).unwrap().mesh;
    assert!(mesh.triangle_count() > 0);
}
