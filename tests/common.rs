//! Shared helpers for the integration tests: shipped assets and small analytic patches.

use std::path::PathBuf;

use tessera_core::bezier::BezierModel;

/// Path of a shipped asset (never `../shared`).
pub fn asset(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../assets")
        .join(rel)
}

/// The shipped Newell teaset models.
pub fn teaset() -> Vec<(&'static str, BezierModel)> {
    ["teapot", "teacup", "teaspoon"]
        .into_iter()
        .map(|n| {
            (
                n,
                BezierModel::load(&asset(&format!("teaset/{n}"))).expect("shipped model loads"),
            )
        })
        .collect()
}

/// A single patch from a function of the control-grid position `(col/3, row/3)`.
pub fn single_patch(f: impl Fn(f32, f32) -> [f32; 3]) -> BezierModel {
    let mut points = Vec::new();
    for row in 0..4 {
        for col in 0..4 {
            points.push(glam::Vec3::from_array(f(
                col as f32 / 3.0,
                row as f32 / 3.0,
            )));
        }
    }
    BezierModel::from_nets(points, vec![std::array::from_fn(|i| i as u32)])
}

/// The plane z = 0 over the unit square.
pub fn plane_patch() -> BezierModel {
    single_patch(|x, y| [x, y, 0.0])
}

/// The parabolic cylinder `z = x²` over the unit square, exactly: x(u) = u, y(v) = v, and
/// the Bernstein coefficients of u² are (0, 0, 1/3, 1).
pub fn parabolic_cylinder() -> BezierModel {
    single_patch(|x, y| {
        let zc = [0.0, 0.0, 1.0 / 3.0, 1.0];
        [x, y, zc[(x * 3.0).round() as usize]]
    })
}

/// A shipped Catmull-Clark control mesh.
pub fn control_mesh(rel: &str) -> tessera_core::catmull_clark::ControlMesh {
    tessera_core::io::load_control_mesh(&asset(rel)).expect("shipped mesh loads")
}

/// A shipped Catmull-Clark mesh with its patches built.
pub fn cc_model(rel: &str) -> tessera_core::catmull_clark::SurfaceModel {
    use tessera_core::catmull_clark::{PatchMesh, SurfaceModel, TREE_DEPTH};
    SurfaceModel::new(
        PatchMesh::new(&control_mesh(rel)).expect("valid"),
        TREE_DEPTH,
    )
}
