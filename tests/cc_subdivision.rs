//! The subdivision rules against meshes nobody here computed: OpenSubdiv's published
//! Hbr uniform refinements, and the refined Spot and Blub meshes of Keenan Crane.

use glam::DVec3;
use tessera_core::catmull_clark::refine::{refine_sharp, Scheme, Sharpness};
use tessera_core::catmull_clark::{BoundaryRule, ControlMesh};
use tessera_tests::control_mesh;

/// `steps` global Catmull-Clark steps, with the mesh's creases and options.
fn subdivide(mesh: &ControlMesh, steps: usize) -> (Vec<DVec3>, Vec<Vec<u32>>) {
    let scheme = Scheme {
        boundary: mesh.boundary,
        creasing: mesh.crease_method,
        smooth_triangles: mesh.smooth_triangles,
    };
    let mut sharp = Sharpness::from_tags(&mesh.creases, &mesh.corners);
    let (mut points, mut faces) = (mesh.positions.clone(), mesh.faces.clone());
    for _ in 0..steps {
        let (r, next) = refine_sharp(&points, &faces, &scheme, &sharp);
        points = r.points;
        faces = r.quads.iter().map(|q| q.to_vec()).collect();
        sharp = next;
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
fn matches_opensubdiv_hbr_uniform_baselines_with_creases_and_corners() {
    // Every creased shape Hbr's baselines cover: semi-sharp, fractional and infinite
    // creases, Chaikin's rule, darts and corners, boundaries of both rules.
    let shapes = [
        "catmark_cube_creases0",
        "catmark_cube_creases1",
        "catmark_cube_corner0",
        "catmark_cube_corner1",
        "catmark_cube_corner2",
        "catmark_cube_corner3",
        "catmark_cube_corner4",
        // Normal creasing; Hbr's Chaikin rule is not Far's (it averages in infinitely
        // sharp neighbours too, and lowers ¾ of a lone crease's sharpness), so the
        // Chaikin shape is compared with OpenSubdiv's Bfr instead (osd_compare.rs).
        "catmark_chaikin0",
        "catmark_dart_edgecorner",
        "catmark_dart_edgeonly",
        "catmark_pyramid_creases0",
        "catmark_pyramid_creases1",
        "catmark_tent_creases0",
        "catmark_tent_creases1",
        "catmark_edgeonly",
    ];
    for shape in shapes {
        let mesh = control_mesh(&format!("opensubdiv/{shape}.obj"));
        assert!(mesh.has_creases(), "{shape}");
        for level in 0..=2 {
            let path = format!("opensubdiv/reference_hbr_uniform/{shape}_level{level}.obj");
            if !tessera_tests::asset(&path).exists() {
                continue;
            }
            let reference = control_mesh(&path);
            let (points, faces) = subdivide(&mesh, level + 1);
            assert_eq!(faces.len(), reference.faces.len(), "{shape} level {level}");
            let d = point_set_distance(&used_points(&points, &faces), &reference.positions);
            assert!(d < 1e-6 * mesh.bbox_diag(), "{shape} level {level}: {d}");
        }
    }
}

#[test]
fn the_creases_matter_and_the_comparison_sees_them() {
    // Test the tester: the creased cube subdivided smooth misses Hbr's points.
    for shape in ["catmark_cube_creases1", "catmark_cube_corner3"] {
        let mut mesh = control_mesh(&format!("opensubdiv/{shape}.obj"));
        let reference = control_mesh(&format!(
            "opensubdiv/reference_hbr_uniform/{shape}_level1.obj"
        ));
        mesh.drop_creases("--no-creases");
        let (points, faces) = subdivide(&mesh, 2);
        let d = point_set_distance(&used_points(&points, &faces), &reference.positions);
        assert!(d > 1e-4 * mesh.bbox_diag(), "{shape}: {d}");
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
