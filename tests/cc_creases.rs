//! Creased surfaces (OpenSubdiv's semi-sharp and infinitely sharp creases, corners,
//! Chaikin's rule, smooth triangles): the guarantee holds when measured, the output is
//! watertight, and the creases shape the patches as OpenSubdiv's rules say.

use glam::DVec3;
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive, tessellate_uniform, CcParams, SurfaceModel,
};
use tessera_core::measure::measure_error;
use tessera_core::watertight::check_watertight;
use tessera_core::Tolerance;
use tessera_tests::{cc_model, control_mesh, open_boundary, surface_of};

/// Quads, triangles and a pentagon; boundaries of both rules; semi-sharp, fractional
/// and infinite creases; Chaikin's rule; corners; darts; smooth triangles.
const SHAPES: [&str; 12] = [
    "catmark_cube_creases0",
    "catmark_cube_creases2",
    "catmark_cube_corner3",
    "catmark_chaikin1",
    "catmark_dart_edgecorner",
    "catmark_dart_edgeonly",
    "catmark_inf_crease1",
    "catmark_pyramid_creases1",
    "catmark_tent_creases0",
    "catmark_smoothtris1",
    "catmark_torus_creases1",
    "catmark_edgeonly",
];

fn shape(name: &str) -> String {
    format!("opensubdiv/{name}.obj")
}

fn params(tolerance: f64) -> CcParams {
    CcParams {
        tolerance: Tolerance::Absolute(tolerance),
        max_depth: 10,
        first_split: Default::default(),
        leaf_bound: Default::default(),
    }
}

#[test]
fn measured_error_never_exceeds_the_tolerance_on_creased_surfaces() {
    for name in SHAPES {
        let control = control_mesh(&shape(name));
        assert!(control.has_creases() || control.smooth_triangles, "{name}");
        let model = cc_model(&shape(name));
        let size = control.bbox_diag();
        let samples = surface_samples(&model, 32);
        for rel in [1e-2, 3e-3, 1e-3] {
            let tol = rel * size;
            let out = tessellate_adaptive(&model, &params(tol)).unwrap();
            assert_eq!(out.unmet, 0, "{name} at {rel}");
            assert!(out.max_bound <= tol, "{name} at {rel}");
            let e = measure_error(&samples, &out.mesh, model.mesh.control_diag);
            assert!(
                e.max_error <= tol,
                "{name} at {rel}: measured {} > {tol}",
                e.max_error
            );
            assert!(
                e.max_error >= 0.05 * tol,
                "{name} at {rel}: {} ≪ {tol}",
                e.max_error
            );
        }
    }
}

#[test]
fn the_creases_change_the_surface_and_the_measure_sees_it() {
    // Test the tester: the smooth surface's tessellation, measured against the creased
    // surface, misses it by far more than the tolerance.
    let name = shape("catmark_cube_creases2");
    let creased = cc_model(&name);
    let mut control = control_mesh(&name);
    control.drop_creases("--no-creases");
    let smooth = surface_of(&control);
    let tol = 1e-3 * control.bbox_diag();
    let out = tessellate_adaptive(&smooth, &params(tol)).unwrap();
    let e = measure_error(
        &surface_samples(&creased, 16),
        &out.mesh,
        creased.mesh.control_diag,
    );
    assert!(e.max_error > 10.0 * tol, "{}", e.max_error);
}

#[test]
fn creased_output_is_watertight() {
    for name in SHAPES {
        let model = cc_model(&shape(name));
        let size = model.mesh.control_diag;
        let boundary = open_boundary(&model);
        for out in [
            tessellate_adaptive(&model, &params(2e-3 * size)).unwrap(),
            tessellate_uniform(&model, 4).unwrap(),
        ] {
            let positions: Vec<_> = out.mesh.positions().collect();
            let r = check_watertight(&positions, &out.mesh.indices, &boundary, 1e-6 * size);
            assert!(r.is_watertight(), "{name}: {r:?}");
        }
    }
}

#[test]
fn a_regular_patch_beside_an_infinitely_sharp_crease_is_one_bspline() {
    // The cube with its 12 edges infinitely sharp: every corner of every patch is a
    // cube vertex (three sharp edges: a corner whose two patch edges are sharp), an
    // edge point (a crease vertex with two faces on each side) or a face point (smooth,
    // valence 4). So every patch is one bicubic, the face of the cube is exactly flat
    // and its edges are straight.
    let mut control = control_mesh(&shape("catmark_cube"));
    let edges: Vec<[u32; 2]> = {
        let mut e: Vec<[u32; 2]> = control
            .faces
            .iter()
            .flat_map(|f| (0..4).map(move |k| [f[k].min(f[(k + 1) % 4]), f[k].max(f[(k + 1) % 4])]))
            .collect();
        e.sort_unstable();
        e.dedup();
        e
    };
    assert_eq!(edges.len(), 12);
    control.creases = edges.into_iter().map(|e| (e, 10.0)).collect();
    let model = surface_of(&control);
    assert!(model.patches.iter().all(|p| p.is_regular()));
    for p in model.mesh.surface_patches() {
        // In the plane of its control face.
        let face = &control.faces[model.mesh.face_of[p].0 as usize];
        let at = |k: usize| control.positions[face[k] as usize];
        let normal = (at(1) - at(0)).cross(at(3) - at(0)).normalize();
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (1.0, 0.5), (0.5, 1.0)] {
            let x = model.eval(p, u, v).position;
            let off = (x - at(0)).dot(normal);
            assert!(off.abs() < 1e-12, "patch {p} at ({u}, {v}): {off}");
        }
    }
    // Semi-sharp instead: not flat, and its patches are split until the sharpness decays.
    control.creases.iter_mut().for_each(|c| c.1 = 2.5);
    let model = surface_of(&control);
    assert!(model.patches.iter().all(|p| !p.is_regular()));
}

/// A roof: two planes of control points meeting at a ridge along `x = 0`, seven columns
/// by four rows, with the ridge's edges given `sharpness` (none when 0).
fn roof(sharpness: f32) -> tessera_core::catmull_clark::ControlMesh {
    let (cols, rows) = (7u32, 4u32);
    let positions = (0..rows)
        .flat_map(|j| {
            (0..cols).map(move |i| {
                let x = i as f64 - 3.0;
                DVec3::new(x, j as f64, 1.0 - 0.5 * x.abs())
            })
        })
        .collect();
    let at = |i: u32, j: u32| j * cols + i;
    let faces = (0..rows - 1)
        .flat_map(|j| {
            (0..cols - 1).map(move |i| vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])
        })
        .collect();
    let mut mesh = tessera_core::catmull_clark::ControlMesh::new(positions, faces);
    if sharpness > 0.0 {
        mesh.creases = (0..rows - 1)
            .map(|j| ([at(3, j), at(3, j + 1)], sharpness))
            .collect();
    }
    mesh
}

#[test]
fn detail_goes_along_the_crease_and_nowhere_else() {
    // Away from the ridge every one-ring lies in one plane, so the surface there is flat
    // and needs one leaf (two triangles) per patch; at the ridge a semi-sharp crease
    // bends it in a band that needs more. Infinitely sharp, the ridge cuts the surface
    // into two flat halves: no detail anywhere.
    let count = |sharpness: f32| {
        let control = roof(sharpness);
        let model = SurfaceModel::new(
            tessera_core::catmull_clark::PatchMesh::new(&control).unwrap(),
            tessera_core::catmull_clark::TREE_DEPTH,
        );
        let tol = 1e-3 * control.bbox_diag();
        let out = tessellate_adaptive(&model, &params(tol)).unwrap();
        let e = measure_error(
            &surface_samples(&model, 16),
            &out.mesh,
            model.mesh.control_diag,
        );
        assert!(e.max_error <= tol, "sharpness {sharpness}: {}", e.max_error);
        let positions: Vec<DVec3> = out.mesh.positions().map(|p| p.as_dvec3()).collect();
        let (mut near, mut far) = (0, 0);
        for t in out.mesh.indices.chunks(3) {
            let x =
                (positions[t[0] as usize] + positions[t[1] as usize] + positions[t[2] as usize]).x
                    / 3.0;
            if x.abs() < 1.0 {
                near += 1;
            } else {
                far += 1;
            }
        }
        (near, far)
    };
    // 18 faces, 72 patches; 24 patches on faces beside the ridge, 48 away from it.
    let (near, far) = count(2.5);
    assert_eq!(far, 2 * 48, "semi-sharp: away from the ridge");
    assert!(
        near > 4 * 2 * 24,
        "semi-sharp: {near} triangles beside the ridge"
    );
    let (near, far) = count(10.0);
    assert_eq!(
        (near, far),
        (2 * 24, 2 * 48),
        "infinitely sharp: two flat halves"
    );
    let (smooth_near, smooth_far) = count(0.0);
    assert_eq!(smooth_far, 2 * 48, "smooth: away from the ridge");
    assert!(smooth_near > 2 * 24, "smooth: {smooth_near}");
}
