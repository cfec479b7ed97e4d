//! The subdivision rules against meshes nobody here computed: OpenSubdiv's published
//! Hbr uniform refinements, and the refined Spot and Blub meshes of Keenan Crane.

use glam::DVec3;
use tessera_core::catmull_clark::refine::refine;
use tessera_core::catmull_clark::{BoundaryRule, ControlMesh};
use tessera_tests::control_mesh;

/// `steps` global Catmull-Clark steps.
fn subdivide(mesh: &ControlMesh, steps: usize) -> (Vec<DVec3>, Vec<Vec<u32>>) {
    let (mut points, mut faces) = (mesh.positions.clone(), mesh.faces.clone());
    for _ in 0..steps {
        let r = refine(&points, &faces, mesh.boundary);
        points = r.points;
        faces = r.quads.iter().map(|q| q.to_vec()).collect();
    }
    (points, faces)
}

/// Largest distance from each reference point to the nearest of `ours` (and back).
fn point_set_distance(ours: &[DVec3], reference: &[DVec3]) -> f64 {
    let nearest = |p: DVec3, set: &[DVec3]| {
        set.iter()
            .map(|q| (p - *q).length())
            .fold(f64::INFINITY, f64::min)
    };
    let a = reference
        .iter()
        .map(|&p| nearest(p, ours))
        .fold(0.0, f64::max);
    let b = ours
        .iter()
        .map(|&p| nearest(p, reference))
        .fold(0.0, f64::max);
    a.max(b)
}

/// Points used by faces (OpenSubdiv's files list no unused ones; ours keep the
/// control mesh's unused vertices in place).
fn used_points(points: &[DVec3], faces: &[Vec<u32>]) -> Vec<DVec3> {
    let mut used = vec![false; points.len()];
    for &v in faces.iter().flatten() {
        used[v as usize] = true;
    }
    points
        .iter()
        .zip(used)
        .filter(|(_, u)| *u)
        .map(|(p, _)| *p)
        .collect()
}

#[test]
fn matches_opensubdiv_hbr_uniform_baselines() {
    // Shapes without creases or corners. Hbr's harness uses edge-only boundaries
    // unless the shape is tagged (the flaps are untagged).
    let shapes = [
        ("catmark_cube", 2),
        ("catmark_pyramid", 2),
        ("catmark_tent", 2),
        ("catmark_flap", 2),
        ("catmark_flap2", 1),
        ("catmark_edgecorner", 1),
    ];
    for (shape, max_level) in shapes {
        let mut mesh = control_mesh(&format!("opensubdiv/{shape}.obj"));
        if shape.starts_with("catmark_flap") {
            mesh.boundary = BoundaryRule::EdgeOnly;
        }
        for level in 0..=max_level {
            let reference = control_mesh(&format!(
                "opensubdiv/reference_hbr_uniform/{shape}_level{level}.obj"
            ));
            let (points, faces) = subdivide(&mesh, level + 1);
            assert_eq!(
                faces.len(),
                reference.faces.len(),
                "{shape} level {level}: face count"
            );
            let ours = used_points(&points, &faces);
            assert_eq!(
                ours.len(),
                reference.positions.len(),
                "{shape} level {level}: vertex count"
            );
            let d = point_set_distance(&ours, &reference.positions);
            assert!(d < 1e-6, "{shape} level {level}: {d}");
        }
    }
}

#[test]
fn the_boundary_rule_matters_and_the_comparison_sees_it() {
    // Test the tester: edge-and-corner on the flap does not match Hbr's edge-only file.
    let mesh = control_mesh("opensubdiv/catmark_flap.obj");
    assert_eq!(mesh.boundary, BoundaryRule::EdgeAndCorner);
    let reference = control_mesh("opensubdiv/reference_hbr_uniform/catmark_flap_level0.obj");
    let (points, faces) = subdivide(&mesh, 1);
    let d = point_set_distance(&used_points(&points, &faces), &reference.positions);
    assert!(d > 1e-3, "{d}");
}

#[test]
fn matches_crane_refined_spot_and_blub() {
    // spot_triangulated: 2 steps, then each quad split into two triangles (same points).
    let spot = control_mesh("catmull_clark/spot_control_mesh.obj");
    let reference = control_mesh("catmull_clark/spot_triangulated.obj");
    let (points, faces) = subdivide(&spot, 2);
    assert_eq!(2 * faces.len(), reference.faces.len());
    let d = point_set_distance(&used_points(&points, &faces), &reference.positions);
    assert!(d < 2e-5, "spot: {d}"); // the file has 6 significant digits
                                    // blub_quadrangulated: 3 steps.
    let blub = control_mesh("catmull_clark/blub_control_mesh.obj");
    let reference = control_mesh("catmull_clark/blub_quadrangulated.obj");
    let (points, faces) = subdivide(&blub, 3);
    assert_eq!(faces.len(), reference.faces.len());
    let d = point_set_distance(&used_points(&points, &faces), &reference.positions);
    assert!(d < 2e-5, "blub: {d}");
}
