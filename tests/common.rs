//! Shared helpers for the integration tests: shipped assets and small analytic patches.

use std::path::PathBuf;

use tessera_core::bezier::BezierModel;

pub mod fuzz;
pub mod osd;

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

/// A degenerate patch, bent in both directions, whose bottom row and right column are
/// one control point: two sides collapsed to one point, meeting at a corner.
pub fn two_collapsed_sides() -> BezierModel {
    let curved = single_patch(|x, y| [x, y, 0.5 * (x - 0.5) * (y - 0.3)]);
    let mut net: [u32; 16] = std::array::from_fn(|i| i as u32);
    for k in [0, 1, 2, 7, 11, 15] {
        net[k] = 3;
    }
    BezierModel::from_nets(curved.points.clone(), vec![net])
}

/// A shipped Catmull-Clark control mesh.
pub fn control_mesh(rel: &str) -> tessera_core::catmull_clark::ControlMesh {
    tessera_core::io::load_control_mesh(&asset(rel)).expect("shipped mesh loads")
}

/// A shipped Catmull-Clark mesh with its patches built.
pub fn cc_model(rel: &str) -> tessera_core::catmull_clark::SurfaceModel {
    surface_of(&control_mesh(rel))
}

/// The smooth surface of a shipped Catmull-Clark mesh (creases and corners dropped, as
/// `--no-creases` does): what the GPU stages take.
pub fn smooth_cc_model(rel: &str) -> tessera_core::catmull_clark::SurfaceModel {
    let mut control = control_mesh(rel);
    control.drop_creases("--no-creases");
    surface_of(&control)
}

/// A control mesh's patches, built.
pub fn surface_of(
    control: &tessera_core::catmull_clark::ControlMesh,
) -> tessera_core::catmull_clark::SurfaceModel {
    use tessera_core::catmull_clark::{PatchMesh, SurfaceModel, TREE_DEPTH};
    SurfaceModel::new(PatchMesh::new(control).expect("valid"), TREE_DEPTH)
}

/// Asserts that a tessellation of `model` has no T-junction, degenerate triangle or
/// edge of more than two triangles (its open boundary excepted).
pub fn assert_crack_free(
    model: &tessera_core::catmull_clark::SurfaceModel,
    mesh: &tessera_core::mesh::Mesh,
    what: &str,
) {
    let positions: Vec<glam::Vec3> = mesh
        .vertices
        .iter()
        .map(|v| glam::Vec3::from(v.position))
        .collect();
    let report = tessera_core::watertight::check_watertight(
        &positions,
        &mesh.indices,
        &open_boundary(model),
        1e-5 * model.mesh.control_diag,
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
}

/// The open boundary curves of a surface (patch sides no other patch shares, and sides
/// against a hole), densely sampled: where a watertight mesh may have boundary edges.
pub fn open_boundary(model: &tessera_core::catmull_clark::SurfaceModel) -> Vec<Vec<glam::DVec3>> {
    let mesh = &model.mesh;
    let mut lines = Vec::new();
    for p in mesh.surface_patches() {
        for k in 0..4 {
            let e = mesh.quad_edges[p][k] as usize;
            let across_hole = mesh.edge_uses[e] == 2
                && (0..mesh.patch_count())
                    .any(|q| q != p && mesh.hole[q] && mesh.quad_edges[q].contains(&(e as u32)));
            if mesh.edge_uses[e] == 1 || across_hole {
                lines.push(
                    (0..=256)
                        .map(|i| {
                            let t = i as f64 / 256.0;
                            let (u, v) = [(t, 0.0), (1.0, t), (1.0 - t, 1.0), (0.0, 1.0 - t)][k];
                            model.eval(p, u, v).position
                        })
                        .collect(),
                );
            }
        }
    }
    lines
}

/// A fan of `quads` quads around a centre vertex, wavy so that nothing is planar: closed
/// (`quads` = the valence, an interior vertex) or open (`quads` + 1 = the valence, a
/// boundary vertex).
pub fn fan(quads: usize, closed: bool) -> tessera_core::catmull_clark::ControlMesh {
    let n = quads;
    let spokes = if closed { n } else { n + 1 };
    let span = if closed {
        std::f64::consts::TAU
    } else {
        1.5 * std::f64::consts::PI
    };
    let step = span / n as f64;
    let at = |r: f64, a: f64| glam::DVec3::new(r * a.cos(), r * a.sin(), 0.3 * (3.0 * a).cos() * r);
    let mut positions = vec![glam::DVec3::new(0.0, 0.0, 0.2)];
    for k in 0..spokes {
        positions.push(at(1.0, k as f64 * step));
    }
    for k in 0..n {
        positions.push(at(1.5, (k as f64 + 0.5) * step));
    }
    let faces = (0..n as u32)
        .map(|k| {
            let next = (k + 1) % spokes as u32;
            vec![0, 1 + k, 1 + spokes as u32 + k, 1 + next]
        })
        .collect();
    tessera_core::catmull_clark::ControlMesh::new(positions, faces)
}

/// A torus of `around × across` grid quads, each cut into two triangles (every vertex of
/// valence 6), with a ripple so that nothing is a surface of revolution: a triangle mesh
/// of any size, `2 · around · across` faces.
pub fn triangle_torus(around: usize, across: usize) -> tessera_core::catmull_clark::ControlMesh {
    use std::f64::consts::TAU;
    let at = |i: usize, j: usize| {
        let (a, b) = (
            TAU * i as f64 / around as f64,
            TAU * j as f64 / across as f64,
        );
        let r = 0.4 + 0.03 * (5.0 * a + 2.0 * b).sin();
        glam::DVec3::new(
            (1.0 + r * b.cos()) * a.cos(),
            (1.0 + r * b.cos()) * a.sin(),
            r * b.sin(),
        )
    };
    let mut positions = Vec::with_capacity(around * across);
    for i in 0..around {
        for j in 0..across {
            positions.push(at(i, j));
        }
    }
    let id = |i: usize, j: usize| ((i % around) * across + j % across) as u32;
    let mut faces = Vec::with_capacity(2 * around * across);
    for i in 0..around {
        for j in 0..across {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            faces.push(vec![a, b, c]);
            faces.push(vec![a, c, d]);
        }
    }
    tessera_core::catmull_clark::ControlMesh::new(positions, faces)
}

/// Where a test view stands relative to a model ([`view`]).
#[derive(Clone, Copy, Debug)]
pub enum Stand {
    /// The whole model on screen.
    Far,
    /// Close, looking past the centre: part of the model off screen.
    Close,
    /// Among the model, looking out: part of it behind the eye.
    Beside,
    /// Looking away from the model.
    Away,
}

/// The centre and diagonal of the box of the model's surface samples.
pub fn model_box(model: &tessera_core::catmull_clark::SurfaceModel) -> (glam::DVec3, f64) {
    let samples = tessera_core::catmull_clark::surface_samples(model, 2);
    let lo = samples.iter().fold(glam::DVec3::INFINITY, |a, &p| a.min(p));
    let hi = samples
        .iter()
        .fold(glam::DVec3::NEG_INFINITY, |a, &p| a.max(p));
    ((lo + hi) / 2.0, (hi - lo).length())
}

/// A 320 × 240 view of `model` from `stand`, 40° vertical field, near plane at 0.02 of
/// the model's size.
pub fn view(model: &tessera_core::catmull_clark::SurfaceModel, stand: Stand) -> tessera_core::View {
    let (c, d) = model_box(model);
    let dir = glam::DVec3::new(0.5, -1.0, 0.45).normalize();
    let side = dir.cross(glam::DVec3::Z).normalize();
    let (eye, target) = match stand {
        Stand::Far => (c + dir * 2.5 * d, c),
        Stand::Close => (c + dir * 0.9 * d, c + side * 0.3 * d),
        Stand::Beside => {
            // Inside the model's box, looking out: the surface around and behind the eye.
            let eye = c + side * 0.05 * d;
            let nearest = tessera_core::catmull_clark::surface_samples(model, 2)
                .into_iter()
                .min_by(|a, b| (*a - eye).length().total_cmp(&(*b - eye).length()))
                .unwrap();
            (eye, nearest)
        }
        Stand::Away => (c + dir * 2.0 * d, c + dir * 3.0 * d),
    };
    tessera_core::View::look_at(
        eye,
        target,
        glam::DVec3::Z,
        40f64.to_radians(),
        (320, 240),
        0.02 * d,
    )
    .unwrap()
}

/// Close to the spout and looking along the body: the handle and part of the lid are
/// out of view.
pub fn bezier_close_view(model: &BezierModel, cull: bool) -> tessera_core::bezier::BezierView {
    let (lo, hi) = model.bounds();
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let (c, d) = ((lo + hi) / 2.0, (hi - lo).length());
    tessera_core::bezier::BezierView {
        view: tessera_core::View::look_at(
            c + glam::DVec3::new(0.5, -0.45, 0.1) * d,
            c + glam::DVec3::new(0.3, 0.0, 0.0) * d,
            glam::DVec3::Z,
            30f64.to_radians(),
            (640, 480),
            0.01 * d,
        )
        .expect("view"),
        pixels: 1.0,
        cull,
        cull_backfaces: false,
    }
}
