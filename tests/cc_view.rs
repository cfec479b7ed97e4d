//! The Catmull-Clark reference in a view: a tolerance in pixels that holds when measured
//! (every sampled surface point inside the frustum projects within p pixels of its
//! nearest mesh point), culling, and no T-junction whatever the level of detail.

use glam::{DVec3, Vec3};
use tessera_core::catmull_clark::faces::check_faces;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive_in_view, CcParams, CcTessellation, SurfaceModel,
    ViewTolerance,
};
use tessera_core::measure::{max_error_px, measure_error};
use tessera_core::watertight::check_watertight;
use tessera_core::{Tolerance, View};
use tessera_tests::{assert_crack_free, cc_model, open_boundary, view, Stand};

fn params() -> CcParams {
    CcParams {
        // The world tolerance only caps: the pixels decide.
        tolerance: Tolerance::Relative(1.0),
        max_depth: 10,
        first_split: Default::default(),
        leaf_bound: Default::default(),
    }
}

fn run(model: &SurfaceModel, view: View, pixels: Option<f64>, cull: bool) -> CcTessellation {
    run_with(model, view, pixels, cull, false)
}

fn run_with(
    model: &SurfaceModel,
    view: View,
    pixels: Option<f64>,
    cull: bool,
    face_leaves: bool,
) -> CcTessellation {
    let vt = ViewTolerance {
        view,
        pixels,
        cull,
        cull_backfaces: false,
        max_triangles: None,
        face_leaves,
    };
    tessellate_adaptive_in_view(model, &params(), &vt).unwrap()
}

fn positions(t: &CcTessellation) -> Vec<Vec3> {
    t.mesh
        .vertices
        .iter()
        .map(|v| Vec3::from(v.position))
        .collect()
}

#[test]
fn the_pixel_tolerance_holds_near_far_off_screen_and_behind_the_eye() {
    let names = [
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_torus.obj",
        "opensubdiv/catmark_cube_creases1.obj",
        "opensubdiv/catmark_car.obj",
        "catmull_clark/spot_control_mesh.obj",
    ];
    // The models side by side: one thread each.
    std::thread::scope(|s| {
        for name in names {
            s.spawn(move || pixel_tolerance_holds(name));
        }
    });
}

fn pixel_tolerance_holds(name: &str) {
    let model = cc_model(name);
    let samples = surface_samples(&model, 8);
    let small = model.mesh.surface_patches().count() < 200;
    let finer = small.then_some((Stand::Far, 0.5));
    // At 24 pixels from far away whole faces are within the tolerance.
    let views = [
        (Stand::Far, 1.0),
        (Stand::Close, 1.0),
        (Stand::Beside, 2.0),
        (Stand::Far, 24.0),
    ];
    let mut merged = false;
    for (stand, px) in views.into_iter().chain(finer) {
        let v = view(&model, stand);
        if matches!(stand, Stand::Beside) {
            assert!(
                samples.iter().any(|&p| v.pixel(p).is_none()),
                "{name}: nothing behind the eye"
            );
        }
        let out = run(&model, v, Some(px), true);
        holds(name, stand, px, &model, &samples, &out);
        if matches!(stand, Stand::Close) {
            // Culling removes what is out of view, and the kept part still holds.
            let all = run(&model, v, Some(px), false);
            assert!(
                out.mesh.triangle_count() < all.mesh.triangle_count(),
                "{name} {stand:?}"
            );
            assert!(out.culled_leaves > 0, "{name} {stand:?}");
        }
        // Faces taken whole where they can be: the same guarantee, fewer leaves.
        let faces = run_with(&model, v, Some(px), true, true);
        holds(name, stand, px, &model, &samples, &faces);
        assert!(
            faces.mesh.triangle_count() <= out.mesh.triangle_count() && faces.leaves <= out.leaves,
            "{name} {stand:?}: {} triangles with face leaves, {} without",
            faces.mesh.triangle_count(),
            out.mesh.triangle_count()
        );
        let report = check_faces(&model, &faces.mesh, params().grid());
        assert!(
            report.is_consistent(1e-5 * model.mesh.bbox_diag()),
            "{name} {stand:?}: {report:?}"
        );
        merged |= faces.mesh.triangle_count() < out.mesh.triangle_count();
    }
    // The cube's six faces are each a sixth of a rounded blob: none is flat enough.
    if !name.ends_with("catmark_cube.obj") {
        assert!(merged, "{name}: no face is ever a leaf");
    }
}

/// The pixels hold on the samples in view, no leaf is unmet, and there is no
/// T-junction.
fn holds(
    name: &str,
    stand: Stand,
    px: f64,
    model: &SurfaceModel,
    samples: &[DVec3],
    out: &CcTessellation,
) {
    let v = view(model, stand);
    assert_eq!(out.unmet, 0, "{name} {stand:?}");
    let err = max_error_px(samples, &out.mesh, &v)
        .unwrap_or_else(|| panic!("{name} {stand:?}: no sample in view"));
    assert!(err <= px, "{name} {stand:?}: {err} px > {px}");
    // The tolerance is used, not met by refining everything (where the whole model,
    // curved somewhere, is in view).
    if matches!(stand, Stand::Far) && px <= 1.0 {
        assert!(err >= 0.05 * px, "{name} {stand:?}: {err} px ≪ {px}");
    }
    assert_crack_free(model, &out.mesh, &format!("{name} {stand:?}"));
}

#[test]
fn detail_follows_the_distance_and_reruns_give_the_same_mesh_on_a_kept_model_or_a_fresh_one() {
    let model = cc_model("opensubdiv/catmark_car.obj");
    let far = run(&model, view(&model, Stand::Far), Some(1.0), true);
    let close = run(&model, view(&model, Stand::Close), Some(1.0), false);
    assert!(close.mesh.triangle_count() > far.mesh.triangle_count());
    let again = run(&model, view(&model, Stand::Far), Some(1.0), true);
    assert_eq!(far.mesh.indices, again.mesh.indices);
    assert_eq!(positions(&far), positions(&again));
    // The patches' root bounds the model kept from those runs change nothing: a fresh
    // model gives the same mesh, after the same bounds.
    let fresh = cc_model("opensubdiv/catmark_car.obj");
    let first = run(&fresh, view(&fresh, Stand::Close), Some(1.0), false);
    assert_eq!(first.mesh.indices, close.mesh.indices);
    assert_eq!(positions(&first), positions(&close));
    assert_eq!(first.bounds, close.bounds);
    // The whole model in view and none culled: watertight, with its levels of detail.
    let report = check_watertight(
        &positions(&far),
        &far.mesh.indices,
        &open_boundary(&model),
        1e-5 * model.mesh.control_diag,
    );
    assert!(report.is_watertight(), "{report:?}");
    assert_eq!(far.culled_leaves, 0);
}

#[test]
fn a_view_looking_away_gives_an_empty_mesh() {
    let model = cc_model("opensubdiv/catmark_torus.obj");
    let out = run(&model, view(&model, Stand::Away), Some(1.0), true);
    assert_eq!(out.mesh.triangle_count(), 0);
    assert_eq!(out.culled_patches, model.mesh.surface_patches().count());
    // With a world tolerance, culling applies as well.
    let world = run(&model, view(&model, Stand::Away), None, true);
    assert_eq!(world.mesh.triangle_count(), 0);
    // And with faces taken whole.
    let faces = run_with(&model, view(&model, Stand::Away), Some(24.0), true, true);
    assert_eq!(faces.mesh.triangle_count(), 0);
    assert_eq!(faces.culled_patches, model.mesh.surface_patches().count());
}

#[test]
fn the_t_junction_check_catches_a_planted_one() {
    let model = cc_model("opensubdiv/catmark_torus.obj");
    let out = run(&model, view(&model, Stand::Far), Some(1.0), true);
    let mut pos = positions(&out);
    let mut idx = out.mesh.indices.clone();
    // Split one triangle at the midpoint of its first edge, and not its neighbour.
    let (a, b, c) = (idx[0], idx[1], idx[2]);
    pos.push((pos[a as usize] + pos[b as usize]) / 2.0);
    let m = pos.len() as u32 - 1;
    idx[..3].copy_from_slice(&[a, m, c]);
    idx.extend_from_slice(&[m, b, c]);
    let report = check_watertight(
        &pos,
        &idx,
        &open_boundary(&model),
        1e-5 * model.mesh.control_diag,
    );
    assert!(report.t_junctions > 0, "{report:?}");
}

#[test]
fn a_triangle_cap_coarsens_the_pixels_until_the_mesh_fits() {
    let model = cc_model("opensubdiv/catmark_car.obj");
    let v = view(&model, Stand::Close);
    let free = run(&model, v, Some(0.5), true);
    assert_eq!(free.tolerance_px, Some(0.5));
    // Halfway between the mesh at 0.5 px and the coarsest there is in this view.
    let coarsest = run(&model, v, Some(1e4), true);
    let cap = (free.mesh.triangle_count() + coarsest.mesh.triangle_count()) / 2;
    let capped = tessellate_adaptive_in_view(
        &model,
        &params(),
        &ViewTolerance {
            view: v,
            pixels: Some(0.5),
            cull: true,
            cull_backfaces: false,
            max_triangles: Some(cap),
            face_leaves: false,
        },
    )
    .unwrap();
    assert!(
        capped.mesh.triangle_count() <= cap,
        "{} > {cap}",
        capped.mesh.triangle_count()
    );
    let achieved = capped.tolerance_px.unwrap();
    assert!(achieved > 0.5, "{achieved}");
    // One step finer would not have fitted, and what it reports holds when measured.
    let finer = run(&model, v, Some(achieved / std::f64::consts::SQRT_2), true);
    assert!(finer.mesh.triangle_count() > cap);
    let err = max_error_px(&surface_samples(&model, 8), &capped.mesh, &v).unwrap();
    assert!(err <= achieved, "{err} px > {achieved}");
    // A cap that the mesh meets changes nothing.
    let roomy = ViewTolerance {
        view: v,
        pixels: Some(0.5),
        cull: true,
        cull_backfaces: false,
        max_triangles: Some(free.mesh.triangle_count()),
        face_leaves: false,
    };
    let same = tessellate_adaptive_in_view(&model, &params(), &roomy).unwrap();
    assert_eq!(same.mesh.indices, free.mesh.indices);
    assert_eq!(same.tolerance_px, Some(0.5));
    // A cap below the coarsest mesh is an error, not a loop.
    let tight = ViewTolerance {
        max_triangles: Some(coarsest.mesh.triangle_count() - 1),
        ..roomy
    };
    let err = tessellate_adaptive_in_view(&model, &params(), &tight).unwrap_err();
    assert!(err.to_string().contains("triangles"), "{err}");
}

/// Surface samples of every patch with their limit normals.
fn samples_with_normals(model: &SurfaceModel, n: usize) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for p in model.mesh.surface_patches() {
        for j in 0..n {
            for i in 0..n {
                let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                let s = model.eval(p, u, v);
                out.push((s.position, s.normal));
            }
        }
    }
    out
}

#[test]
fn back_face_culling_drops_only_what_faces_away() {
    for (name, stand) in [
        ("catmull_clark/spot_control_mesh.obj", Stand::Close),
        ("opensubdiv/catmark_car.obj", Stand::Far),
        ("opensubdiv/catmark_cube_creases1.obj", Stand::Far),
    ] {
        let model = cc_model(name);
        let v = view(&model, stand);
        let px = 1.0;
        let front = run(&model, v, Some(px), true);
        let culled = tessellate_adaptive_in_view(
            &model,
            &params(),
            &ViewTolerance {
                view: v,
                pixels: Some(px),
                cull: true,
                cull_backfaces: true,
                max_triangles: None,
                face_leaves: false,
            },
        )
        .unwrap();
        assert!(
            culled.culled_patches > front.culled_patches,
            "{name}: {} patches culled, {} without back faces",
            culled.culled_patches,
            front.culled_patches
        );
        assert!(
            culled.mesh.triangle_count() < front.mesh.triangle_count(),
            "{name}"
        );
        // The triangles wind counter-clockwise about the surface's normal, the winding
        // the cull takes as the front.
        let m = &front.mesh;
        let wound = m
            .triangles()
            .filter(|t| {
                let [a, b, c] = t.map(|i| Vec3::from(m.vertices[i as usize].position));
                let n = t.map(|i| Vec3::from(m.vertices[i as usize].normal));
                (b - a).cross(c - a).dot(n[0] + n[1] + n[2]) > 0.0
            })
            .count();
        assert!(
            wound * 100 >= m.triangle_count() * 99,
            "{name}: {wound} of {}",
            m.triangle_count()
        );
        // Samples facing the eye keep the pixel guarantee; samples facing away lost
        // their triangles, so the cull did remove surface.
        let eye = v.eye();
        let samples = samples_with_normals(&model, 8);
        let facing: Vec<DVec3> = samples
            .iter()
            .filter(|(x, n)| (eye - *x).dot(*n) > 0.0)
            .map(|s| s.0)
            .collect();
        let away: Vec<DVec3> = samples
            .iter()
            .filter(|(x, n)| v.contains(*x) && (eye - *x).dot(*n) < -0.5 * (eye - *x).length())
            .map(|s| s.0)
            .collect();
        let err = max_error_px(&facing, &culled.mesh, &v).unwrap();
        assert!(err <= px, "{name}: front-facing {err} px > {px}");
        // In projection other surface may lie near a culled point, so the loss is
        // measured in world units: a culled point lies far from what is left, and close
        // to the mesh that kept it.
        let diag = model.mesh.bbox_diag();
        let kept = measure_error(&away, &front.mesh, diag).max_error;
        let lost = measure_error(&away, &culled.mesh, diag).max_error;
        assert!(
            lost > 10.0 * kept && lost > 0.01 * diag,
            "{name}: back-facing samples within {lost} of the culled mesh, {kept} of the whole"
        );
    }
}
