//! The Bézier path in a culling view: the patches out of view emit nothing and are not
//! evaluated inside, the rest keeps its shape, and the mesh stays free of T-junctions.

use glam::{DVec3, Vec3};
use tessera_core::bezier::tessellate::{culled, patch_thresholds, vertex_eval};
use tessera_core::bezier::{
    tessellate_adaptive_in_view, AdaptiveParams, BezierModel, BezierView, EdgeTest, PreparedBezier,
    Tessellation,
};
use tessera_core::gpu_types::VertexRecord;
use tessera_core::measure::{bezier_surface_samples, measure_error};
use tessera_core::watertight::check_watertight;
use tessera_core::View;
use tessera_tests::{bezier_close_view as close_view, teaset};

fn teapot() -> BezierModel {
    teaset()
        .into_iter()
        .find(|(n, _)| *n == "teapot")
        .expect("teapot")
        .1
}

fn diag(model: &BezierModel) -> f32 {
    let (lo, hi) = model.bounds();
    (hi - lo).length()
}

fn run(
    model: &BezierModel,
    prep: &PreparedBezier,
    test: EdgeTest,
    view: &BezierView,
) -> Tessellation {
    let params = AdaptiveParams {
        test,
        threshold: 0.05 * diag(model),
        max_depth: 6,
    };
    tessellate_adaptive_in_view(prep, &params, view).expect("tessellate")
}

#[test]
fn culled_patches_emit_nothing_and_the_rest_stays_whole() {
    let model = teapot();
    let prep = PreparedBezier::new(&model);
    let (near, far) = (close_view(&model, true), close_view(&model, false));
    let cps: Vec<[Vec3; 16]> = (0..prep.layout.patches)
        .map(|p| prep.control_points(p))
        .collect();
    let flipped: Vec<bool> = prep.topo.iter().map(|t| t.flipped()).collect();
    let th = patch_thresholds(&cps, &flipped, diag(&model), Some(&near)).expect("thresholds");
    let is_culled: Vec<bool> = th.iter().map(|&t| culled(t)).collect();
    let n_culled = is_culled.iter().filter(|&&c| c).count();
    assert!(
        n_culled > 0 && n_culled < model.patches.len(),
        "{n_culled} of {} patches culled",
        model.patches.len()
    );
    // Conservative: no sample of a culled patch lies in the frustum.
    let n = 12;
    let samples = bezier_surface_samples(&model, n);
    for (k, x) in samples.iter().enumerate() {
        if is_culled[k / (n * n)] {
            assert!(
                !near.view.contains(*x),
                "patch {} in view at {x}",
                k / (n * n)
            );
        }
    }
    for test in [EdgeTest::Map4p, EdgeTest::Flat] {
        let what = test.name();
        let out = run(&model, &prep, test, &near);
        let whole = run(&model, &prep, test, &far);
        eprintln!(
            "{what}: {n_culled} of {} patches culled, {} triangles against {}, {} evaluations against {}",
            model.patches.len(),
            out.mesh.triangle_count(),
            whole.mesh.triangle_count(),
            out.evaluations,
            whole.evaluations
        );
        assert_eq!(out.culled_patches, n_culled, "{what}");
        assert_eq!(whole.culled_patches, 0, "{what}");
        assert!(
            out.mesh.triangle_count() < whole.mesh.triangle_count(),
            "{what}"
        );
        // No triangle of a culled patch, and fewer evaluations: none inside the culled
        // patches.
        let faces = |t: [u32; 3]| t.map(|i| out.mesh.vertices[i as usize].face);
        assert!(
            out.mesh
                .triangles()
                .all(|t| faces(t).iter().any(|&f| !is_culled[f as usize])),
            "{what}: a culled patch's triangle"
        );
        assert!(out.evaluations < whole.evaluations, "{what}");
        // Exactly the vertices the triangles use are evaluated: the others keep no
        // normal, and the vertex evaluations (past the flat test's) count the used ones.
        let mut referenced = vec![false; out.mesh.vertices.len()];
        for &i in &out.mesh.indices {
            referenced[i as usize] = true;
        }
        let blank = |v: &tessera_core::gpu_types::OutVertex| v.normal == [0.0; 3];
        let blanks = out.mesh.vertices.iter().filter(|v| blank(v)).count();
        let used = referenced.iter().filter(|&&r| r).count();
        assert!(
            out.mesh
                .vertices
                .iter()
                .zip(&referenced)
                .all(|(v, &r)| r != blank(v)),
            "{what}: a used vertex left out, or an unused one evaluated"
        );
        assert!(blanks > 4 * n_culled, "{what}: {blanks} left out");
        eprintln!("{what}: {used} used vertices, {blanks} left out");
        if test == EdgeTest::Map4p {
            // The map tests evaluate nothing: every evaluation is a used vertex's.
            assert_eq!(out.evaluations as usize, used, "{what}");
        }
        let positions: Vec<Vec3> = out.mesh.positions().collect();
        let report = check_watertight(
            &positions,
            &out.mesh.indices,
            &[],
            1e-6 * diag(&model) as f64,
        );
        assert_eq!(
            (
                report.t_junctions,
                report.degenerate_triangles,
                report.non_manifold_edges
            ),
            (0, 0, 0),
            "{what}: {report:?}"
        );
        // What is in view is still covered: its samples lie as near the culled mesh as
        // the whole one.
        let inside: Vec<DVec3> = samples
            .iter()
            .copied()
            .filter(|&x| near.view.contains(x))
            .collect();
        let d = diag(&model) as f64;
        let (e_out, e_whole) = (
            measure_error(&inside, &out.mesh, d).max_error,
            measure_error(&inside, &whole.mesh, d).max_error,
        );
        assert!(
            e_out <= 1.5 * e_whole + 1e-6 * d,
            "{what}: {e_out} against {e_whole}"
        );
    }
}

#[test]
fn a_bezier_view_looking_away_draws_nothing() {
    let model = teapot();
    let prep = PreparedBezier::new(&model);
    let mut v = close_view(&model, true);
    let (lo, hi) = model.bounds();
    let c = ((lo + hi) / 2.0).as_dvec3();
    v.view = View::look_at(
        c + DVec3::new(0.0, -2.0, 0.0) * diag(&model) as f64,
        c + DVec3::new(0.0, -3.0, 0.0) * diag(&model) as f64,
        DVec3::Z,
        30f64.to_radians(),
        (640, 480),
        0.01,
    )
    .expect("view");
    for test in [EdgeTest::Map4p, EdgeTest::Flat] {
        let out = run(&model, &prep, test, &v);
        assert_eq!(out.mesh.triangle_count(), 0);
        assert_eq!(out.culled_patches, model.patches.len());
        // Not even the coarse grid's corners and sides are evaluated.
        assert_eq!(out.evaluations, 0, "{}", test.name());
    }
}

#[test]
fn culling_back_faces_drops_only_patches_facing_away() {
    // The teapot framed from above one side: with back faces culled, more patches go,
    // each facing away at every sample (its drawn normal, the winding's), fewer
    // triangles are left, and the drawn normals face out of the teapot, so what goes is
    // what a closed surface hides.
    let model = teapot();
    let prep = PreparedBezier::new(&model);
    let (lo, hi) = model.bounds();
    let c = ((lo + hi) / 2.0).as_dvec3();
    let d = diag(&model) as f64;
    let eye = c + DVec3::new(0.6, -0.9, 0.7) * d;
    let view = |cull_backfaces| BezierView {
        view: View::look_at(eye, c, DVec3::Z, 40f64.to_radians(), (640, 480), 0.01 * d)
            .expect("view"),
        pixels: 1.0,
        cull: true,
        cull_backfaces,
    };
    let cps: Vec<[Vec3; 16]> = (0..prep.layout.patches)
        .map(|p| prep.control_points(p))
        .collect();
    let flipped: Vec<bool> = prep.topo.iter().map(|t| t.flipped()).collect();
    let th = patch_thresholds(&cps, &flipped, diag(&model), Some(&view(true))).expect("th");
    let front = run(&model, &prep, EdgeTest::Map4p, &view(false));
    let culled_run = run(&model, &prep, EdgeTest::Map4p, &view(true));
    eprintln!(
        "{} patches culled facing away ({} without), {} triangles against {}",
        culled_run.culled_patches,
        front.culled_patches,
        culled_run.mesh.triangle_count(),
        front.mesh.triangle_count()
    );
    assert!(culled_run.culled_patches > front.culled_patches);
    assert!(culled_run.mesh.triangle_count() < front.mesh.triangle_count());
    let n = 8;
    let (mut outward, mut samples) = (0, 0);
    for p in 0..prep.layout.patches {
        for k in 0..n * n {
            let (u, v) = ((k % n) as f32 / 7.0, (k / n) as f32 / 7.0);
            let r = VertexRecord { patch: p, u, v };
            let s = vertex_eval(&prep, &cps, &r);
            let (x, nrm) = (
                Vec3::from(s.position).as_dvec3(),
                Vec3::from(s.normal).as_dvec3(),
            );
            if nrm == DVec3::ZERO {
                continue;
            }
            samples += 1;
            outward += usize::from(nrm.dot(x - c) > 0.0);
            if culled(th[p as usize]) && view(false).view.contains(x) {
                assert!(
                    nrm.dot(eye - x) < 0.0,
                    "patch {p} faces the eye at ({u}, {v})"
                );
            }
        }
    }
    assert!(
        outward * 10 > samples * 7,
        "{outward} of {samples} face out"
    );
}
