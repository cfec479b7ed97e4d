//! The adaptive Catmull-Clark tessellation: the guaranteed bound holds when measured,
//! the output is watertight, and the bound of a cell is never below its true error.

use glam::DVec3;
use tessera_core::catmull_clark::adaptive::{flatness_bound, triangle_distance_bound};
use tessera_core::catmull_clark::bound::split_proof;
use tessera_core::catmull_clark::triangulate::{self, PolyVertex};
use tessera_core::catmull_clark::{
    surface_samples, tessellate_adaptive, tessellate_uniform, CcParams, CcTessellation, LeafBound,
    SurfaceModel,
};
use tessera_core::measure::{closest_point_on_triangle, measure_error};
use tessera_core::watertight::check_watertight;
use tessera_core::Tolerance;
use tessera_tests::{cc_model, control_mesh, fan, open_boundary};

fn diag(rel: &str) -> f64 {
    control_mesh(rel).bbox_diag()
}

fn adaptive(model: &SurfaceModel, tolerance: f64) -> CcTessellation {
    tessellate_adaptive(
        model,
        &CcParams {
            tolerance: Tolerance::Absolute(tolerance),
            max_depth: 10,
            first_split: Default::default(),
            leaf_bound: Default::default(),
        },
    )
    .unwrap()
}

#[test]
fn measured_error_never_exceeds_the_tolerance() {
    let meshes = [
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_torus.obj",
        "opensubdiv/catmark_edgecorner.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_nonquads.obj",
        "opensubdiv/catmark_hole_test1.obj",
        "opensubdiv/catmark_xord_boundary.obj",
        "opensubdiv/catmark_pole8.obj",
        "catmull_clark/blub_control_mesh.obj",
    ];
    let mut models: Vec<(String, SurfaceModel, f64)> = meshes
        .iter()
        .map(|name| (name.to_string(), cc_model(name), diag(name)))
        .collect();
    // Extraordinary vertices of high valence, interior and on the boundary.
    for (n, closed) in [(7, true), (12, true), (16, true), (5, false), (16, false)] {
        let mesh = fan(n, closed);
        let model = SurfaceModel::new(
            tessera_core::catmull_clark::PatchMesh::new(&mesh).unwrap(),
            tessera_core::catmull_clark::TREE_DEPTH,
        );
        models.push((format!("fan {n} {closed}"), model, mesh.bbox_diag()));
    }
    for (name, model, size) in &models {
        let samples = surface_samples(model, 32);
        for rel in [1e-2, 3e-3, 1e-3] {
            let tol = rel * size;
            let out = adaptive(model, tol);
            assert_eq!(out.unmet, 0, "{name} {rel}");
            assert!(out.max_bound <= tol, "{name} {rel}");
            let e = measure_error(&samples, &out.mesh, model.mesh.control_diag);
            assert!(
                e.max_error <= tol,
                "{name} at {rel}: measured {} > {tol}",
                e.max_error
            );
            // And the tolerance is used, not ignored by over-refining everything.
            assert!(
                e.max_error >= 0.1 * tol,
                "{name} at {rel}: {} ≪ {tol}",
                e.max_error
            );
        }
    }
}

/// The guarantee on every shipped control mesh (the published refined meshes,
/// `*_triangulated` and `*_quadrangulated`, are reference data, not inputs): at two
/// tolerances the measured max error (32×32 exact samples per patch) is at or under
/// the tolerance. Meshes the reader or the topology check refuses (non-manifold, valence
/// beyond 64) must be refused with a message naming the file.
#[test]
fn every_shipped_control_mesh_meets_its_tolerance() {
    let mut files: Vec<std::path::PathBuf> = ["opensubdiv", "catmull_clark"]
        .iter()
        .flat_map(|dir| std::fs::read_dir(tessera_tests::asset(dir)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "obj"))
        .filter(|p| {
            let name = p.file_name().unwrap().to_string_lossy();
            !name.contains("_triangulated") && !name.contains("_quadrangulated")
        })
        .collect();
    files.sort();
    assert!(files.len() > 80, "{} meshes", files.len());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let (checked, refused) = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let (mut checked, mut refused) = (Vec::new(), Vec::new());
                    loop {
                        let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some(file) = files.get(i) else { break };
                        let name = file.file_name().unwrap().to_string_lossy().to_string();
                        let control = tessera_core::io::load_control_mesh(file).unwrap();
                        let mesh = match tessera_core::catmull_clark::PatchMesh::new(&control) {
                            Ok(m) => m,
                            Err(e) => {
                                let msg = e.to_string();
                                assert!(msg.contains(&name), "{msg}");
                                refused.push(name);
                                continue;
                            }
                        };
                        let model =
                            SurfaceModel::new(mesh, tessera_core::catmull_clark::TREE_DEPTH);
                        let samples = surface_samples(&model, 32);
                        for rel in [1e-2, 3e-3] {
                            let tol = rel * control.bbox_diag();
                            let out = adaptive(&model, tol);
                            assert_eq!(out.unmet, 0, "{name} at {rel}");
                            let e = measure_error(&samples, &out.mesh, model.mesh.control_diag);
                            assert!(
                                e.max_error <= tol,
                                "{name} at {rel}: measured {} > {tol}",
                                e.max_error
                            );
                        }
                        checked.push(name);
                    }
                    (checked, refused)
                })
            })
            .collect();
        workers
            .into_iter()
            .fold((Vec::new(), Vec::new()), |mut acc, w| {
                let (c, r) = w.join().unwrap();
                acc.0.extend(c);
                acc.1.extend(r);
                acc
            })
    });
    let mut refused = refused;
    refused.sort();
    // Exactly the meshes known to be outside what the topology supports: non-manifold
    // edges or vertices, interior valence 2, valence beyond 64.
    let expected = [
        "catmark_fan.obj",
        "catmark_gregory_test4.obj",
        "catmark_gregory_test8.obj",
        "catmark_nonman_edge100.obj",
        "catmark_nonman_edges.obj",
        "catmark_nonman_quadpole360.obj",
        "catmark_nonman_quadpole64.obj",
        "catmark_nonman_quadpole8.obj",
        "catmark_nonman_verts.obj",
        "catmark_pole360.obj",
        "catmark_val2_back2back.obj",
        "catmark_val2_foldover.obj",
        "catmark_val2_interior.obj",
        "catmark_val2_nonman.obj",
    ];
    assert_eq!(refused, expected, "checked: {checked:?}");
}

#[test]
fn the_bound_of_a_cell_is_above_its_true_error() {
    // Cells anywhere, the extraordinary corners included, triangulated three ways (both
    // diagonals, and a fan from a point in the middle of the first side as a finer
    // neighbour would add): the bound must exceed the distance of every sampled surface
    // point to each triangulation. The largest ratio true/bound shows the check has teeth:
    // a bound half as large would fail it.
    let mut tightest = 0f64;
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_pyramid.obj",
    ] {
        let model = cc_model(name);
        let mut checked = 0;
        for p in (0..model.mesh.patch_count()).step_by(7) {
            for (u0, v0, s) in [
                (0.0, 0.0, 1.0),
                (0.0, 0.0, 0.25),
                (0.5, 0.0, 0.5),
                (0.0, 0.0, 1.0 / 3.0),
                (0.25, 0.125, 0.125),
                (0.0, 0.0, 1.0 / 64.0),
            ] {
                let b = [u0, u0 + s, v0, v0 + s];
                let bound = flatness_bound(&model, p, b);
                let [c0, c1, c2, c3, m] = [
                    (b[0], b[2]),
                    (b[1], b[2]),
                    (b[1], b[3]),
                    (b[0], b[3]),
                    (0.5 * (b[0] + b[1]), b[2]),
                ]
                .map(|(u, v)| model.eval(p, u, v).position);
                let triangulations = [
                    vec![[c0, c1, c2], [c0, c2, c3]],
                    vec![[c0, c1, c3], [c1, c2, c3]],
                    vec![[m, c1, c2], [m, c2, c3], [m, c3, c0]],
                ];
                let mut worst = 0f64;
                for j in 0..=24 {
                    for i in 0..=24 {
                        let (u, v) = (u0 + s * i as f64 / 24.0, v0 + s * j as f64 / 24.0);
                        let x = model.eval(p, u, v).position;
                        for tris in &triangulations {
                            let d = tris
                                .iter()
                                .map(|t| {
                                    (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length()
                                })
                                .fold(f64::INFINITY, f64::min);
                            worst = worst.max(d);
                        }
                    }
                }
                assert!(
                    worst <= bound * (1.0 + 1e-9),
                    "{name} patch {p} {b:?}: {worst} > bound {bound}"
                );
                tightest = tightest.max(worst / bound);
                checked += 1;
            }
        }
        assert!(checked > 10, "{name}: {checked} cells");
    }
    eprintln!("tightest {tightest}");
    assert!(
        tightest > 0.5,
        "the bound is never within 2× of the truth: {tightest}"
    );
}

#[test]
fn the_bound_of_a_whole_face_is_above_its_true_error() {
    // Quad control faces taken whole, extraordinary and creased ones included, through
    // the limit points of their vertices: both diagonals, a fan from the edge point of
    // the first side (a face across that is not a face leaf) and one from a point a
    // quarter along it (finer leaves across). Every sampled surface point of the face
    // must be within the bound of each.
    let mut tightest = 0f64;
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_cube_creases1.obj",
        "opensubdiv/catmark_car.obj",
        "opensubdiv/catmark_edgeonly.obj",
    ] {
        let model = cc_model(name);
        let mut checked = 0;
        let faces = model.mesh.control_faces.len();
        for f in (0..faces).step_by((faces / 40).max(1)) {
            let bound = model.face_bound(f);
            if model.mesh.control_faces[f].len() != 4 {
                assert!(bound.is_infinite(), "{name} face {f}");
                continue;
            }
            let at = |s: f64, t: f64| {
                model
                    .eval_face(f as u32, s, t)
                    .expect("on the face")
                    .position
            };
            let [c0, c1, c2, c3, e, q] = [
                (0.0, 0.0),
                (1.0, 0.0),
                (1.0, 1.0),
                (0.0, 1.0),
                (0.5, 0.0),
                (0.25, 0.0),
            ]
            .map(|(s, t)| at(s, t));
            let triangulations = [
                vec![[c0, c1, c2], [c0, c2, c3]],
                vec![[c0, c1, c3], [c1, c2, c3]],
                vec![[e, c1, c2], [e, c2, c3], [e, c3, c0]],
                vec![[q, c1, c2], [q, c2, c3], [q, c3, c0]],
            ];
            let mut worst = 0f64;
            for j in 0..=24 {
                for i in 0..=24 {
                    let x = at(i as f64 / 24.0, j as f64 / 24.0);
                    for tris in &triangulations {
                        let d = tris
                            .iter()
                            .map(|t| (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length())
                            .fold(f64::INFINITY, f64::min);
                        worst = worst.max(d);
                    }
                }
            }
            assert!(
                worst <= bound * (1.0 + 1e-9),
                "{name} face {f}: {worst} > bound {bound}"
            );
            assert!(bound.is_finite() && bound > 0.0, "{name} face {f}: {bound}");
            tightest = tightest.max(worst / bound);
            checked += 1;
        }
        assert!(checked >= 6, "{name}: {checked} faces");
    }
    eprintln!("tightest {tightest}");
    assert!(
        tightest > 0.5,
        "the face bound is never within 2× of the truth: {tightest}"
    );
}

#[test]
fn the_split_proof_never_exceeds_the_bound() {
    // The proof skips the walk of a cell its centre and side midpoints already show to be
    // too far from flat; it must never be above the bound, or it would split cells the
    // bound passes. Cells of every size, at extraordinary corners too. The largest ratio
    // proof/bound shows the check has teeth (a proof twice as large would fail it), and
    // the share of cells it proves that it is worth its evaluations.
    let (mut tightest, mut cells, mut useful) = (0f64, 0, 0);
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_car.obj",
        "opensubdiv/catmark_pyramid.obj",
    ] {
        let model = cc_model(name);
        for p in (0..model.mesh.patch_count()).step_by(13) {
            for (u0, v0, s) in [
                (0.0, 0.0, 1.0),
                (0.0, 0.0, 0.5),
                (0.5, 0.5, 0.5),
                (0.0, 0.0, 0.125),
                (0.25, 0.125, 0.125),
                (0.0, 0.0, 1.0 / 3.0),
            ] {
                let b = [u0, u0 + s, v0, v0 + s];
                let bound = flatness_bound(&model, p, b);
                let at = |u: f64, v: f64| model.eval(p, u0 + s * u, v0 + s * v).position;
                let corners = [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)];
                let mids = [at(0.5, 0.0), at(1.0, 0.5), at(0.5, 1.0), at(0.0, 0.5)];
                let proof = split_proof(corners, at(0.5, 0.5), mids);
                assert!(
                    proof <= bound,
                    "{name} patch {p} {b:?}: proof {proof} > bound {bound}"
                );
                tightest = tightest.max(proof / bound);
                cells += 1;
                useful += usize::from(proof > 0.5 * bound);
            }
        }
    }
    eprintln!("tightest {tightest}, {useful} of {cells} within 2x");
    assert!(
        tightest > 0.5,
        "the proof is never within 2× of the bound: {tightest}"
    );
    assert!(
        4 * useful > cells,
        "the proof is within 2× of the bound on {useful} of {cells}"
    );
}

#[test]
fn output_is_watertight_and_the_check_catches_planted_cracks() {
    for (name, rel) in [
        ("opensubdiv/catmark_cube.obj", 1e-3),
        ("catmull_clark/spot_control_mesh.obj", 2e-3),
        ("opensubdiv/catmark_torus.obj", 1e-3),
        ("opensubdiv/catmark_edgecorner.obj", 1e-3),
        ("opensubdiv/catmark_hole_test1.obj", 1e-3),
        ("opensubdiv/catmark_nonquads.obj", 3e-3),
    ] {
        let model = cc_model(name);
        let tol = 1e-6 * diag(name);
        let boundary = open_boundary(&model);
        for out in [
            adaptive(&model, rel * diag(name)),
            tessellate_uniform(&model, 5).unwrap(),
        ] {
            let positions: Vec<_> = out.mesh.positions().collect();
            let r = check_watertight(&positions, &out.mesh.indices, &boundary, tol);
            assert!(r.is_watertight(), "{name}: {r:?}");
            assert_eq!(r.boundary_edges > 0, !boundary.is_empty(), "{name}");
            // Every model has edges between control faces: their points are copied.
            assert!(r.seam_copies > 0, "{name}: {r:?}");
        }
    }
    // Test the tester. A copy of a vertex with the same position bits is shared, as the
    // seam copies are; one bit off, a crack by index (and a duplicate), though welding
    // closes it; a removed triangle is a hole.
    let model = cc_model("opensubdiv/catmark_cube.obj");
    let out = adaptive(&model, 1e-3 * diag("opensubdiv/catmark_cube.obj"));
    let positions: Vec<_> = out.mesh.positions().collect();
    let clean = check_watertight(&positions, &out.mesh.indices, &[], 1e-6);
    assert!(clean.is_watertight(), "{clean:?}");
    let planted = |bump: u32| {
        let mut positions = positions.clone();
        let mut indices = out.mesh.indices.clone();
        let mut p = positions[indices[0] as usize];
        p.x = f32::from_bits(p.x.to_bits() + bump);
        positions.push(p);
        indices[0] = positions.len() as u32 - 1;
        check_watertight(&positions, &indices, &[], 1e-6)
    };
    let r = planted(0);
    assert!(r.is_watertight(), "{r:?}");
    assert_eq!(r.seam_copies, clean.seam_copies + 1, "{r:?}");
    let r = planted(1);
    assert!(r.cracks_by_index > 0 && r.duplicate_vertices > 0, "{r:?}");
    assert_eq!(r.cracks_by_position, 0, "{r:?}");
    let mut indices = out.mesh.indices.clone();
    indices.truncate(indices.len() - 3);
    let r = check_watertight(&positions, &indices, &[], 1e-6);
    assert!(r.cracks_by_position > 0, "{r:?}");
}

#[test]
fn output_is_deterministic_and_faces_outwards() {
    let model = cc_model("catmull_clark/spot_control_mesh.obj");
    let tol = 3e-3 * diag("catmull_clark/spot_control_mesh.obj");
    let (a, b) = (adaptive(&model, tol), adaptive(&model, tol));
    assert_eq!(a.mesh, b.mesh);
    // Triangles wind counter-clockwise around the evaluated normals.
    let v = &a.mesh.vertices;
    let mut agree = 0;
    for t in a.mesh.triangles() {
        let [p, q, r] = t.map(|i| DVec3::from(v[i as usize].position.map(f64::from)));
        let n: DVec3 = t
            .iter()
            .map(|&i| DVec3::from(v[i as usize].normal.map(f64::from)))
            .sum();
        if (q - p).cross(r - p).dot(n) > 0.0 {
            agree += 1;
        }
    }
    assert_eq!(agree, a.mesh.triangle_count());
}

#[test]
fn polygons_with_points_on_every_side_triangulate_without_slivers() {
    // A 4×4 square with every combination of 0..=3 points on each side, zipped from
    // either corner (the space positions are sheared one way or the other so that each
    // diagonal is the shorter in turn): every triangle counter-clockwise with positive
    // area, together tiling the square.
    let mut zips = [0usize; 2];
    for code in 0..4usize.pow(4) {
        let counts: [usize; 4] = std::array::from_fn(|s| (code >> (2 * s)) & 3);
        let corner = [(0i64, 0i64), (4, 0), (4, 4), (0, 4)];
        let mut pts = Vec::new();
        let mut corners = [0; 4];
        for s in 0..4 {
            corners[s] = pts.len();
            let (a, b) = (corner[s], corner[(s + 1) % 4]);
            pts.push(a);
            // Points at distinct integer steps along the side.
            for k in 1..=counts[s] as i64 {
                pts.push((a.0 + (b.0 - a.0) * k / 4, a.1 + (b.1 - a.1) * k / 4));
            }
        }
        let poly: Vec<PolyVertex> = pts
            .iter()
            .enumerate()
            .map(|(k, &(i, j))| PolyVertex { i, j, id: k as u32 })
            .collect();
        for shear in [-0.5, 0.5] {
            let position = |id: u32| {
                let (i, j) = pts[id as usize];
                DVec3::new(i as f64 + shear * j as f64, j as f64, 0.0)
            };
            let d02 = (position(corners[0] as u32) - position(corners[2] as u32)).length_squared();
            let d13 = (position(corners[1] as u32) - position(corners[3] as u32)).length_squared();
            zips[triangulate::zip_start(d02, d13)] += 1;
            let mut out = Vec::new();
            triangulate::triangulate(&poly, corners, position, &mut out);
            assert_eq!(out.len() / 3, pts.len() - 2, "{counts:?}");
            let mut area = 0;
            for t in out.chunks(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|k| pts[k as usize]);
                let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
                assert!(cross > 0, "{counts:?}: degenerate or flipped {t:?}");
                area += cross;
            }
            assert_eq!(area, 2 * 16, "{counts:?}: the triangles tile the square");
        }
    }
    assert!(zips[0] > 0 && zips[1] > 0, "both diagonals tried: {zips:?}");
}

/// The uniform pipeline of the GPU (its CPU twin, `gpu_uniform`) makes the reference's
/// uniform mesh: the same vertices (matched by face and face coordinates, positions
/// within 1e-5 of the diagonal), the same triangles in the same order.
#[test]
fn gpu_uniform_twin_makes_the_uniform_reference_mesh() {
    use tessera_core::catmull_clark::gpu_model::CcGpuModel;
    use tessera_core::catmull_clark::gpu_uniform::{tessellate_uniform_gpu_twin, uniform_patches};
    let cases = [
        ("opensubdiv/catmark_cube.obj", 3),
        ("opensubdiv/catmark_cube.obj", 1),
        ("opensubdiv/catmark_hole_test1.obj", 4),
        ("opensubdiv/catmark_edgecorner.obj", 5),
        ("catmull_clark/spot_control_mesh.obj", 2),
    ];
    for (name, n) in cases {
        let model = cc_model(name);
        let reference = tessellate_uniform(&model, n).unwrap().mesh;
        let layout = uniform_patches(&model.mesh);
        let twin = tessellate_uniform_gpu_twin(&CcGpuModel::new(&model), &layout, n).unwrap();
        assert_eq!(
            twin.vertices.len(),
            reference.vertices.len(),
            "{name} n={n}"
        );
        assert_eq!(twin.indices.len(), reference.indices.len(), "{name} n={n}");
        // A vertex is a point of a face at its exact coordinates (units of 1/(2n)): one
        // per chart, as both number them.
        let grid = |v: &tessera_core::gpu_types::OutVertex| {
            let g = |x: f32| (x as f64 * 2.0 * n as f64).round() as u32;
            (v.face, g(v.uv[0]), g(v.uv[1]))
        };
        let by_point: std::collections::HashMap<_, _> = reference
            .vertices
            .iter()
            .enumerate()
            .map(|(id, v)| (grid(v), id as u32))
            .collect();
        let tol = 1e-5 * diag(name) as f32;
        let to_reference: Vec<u32> = twin
            .vertices
            .iter()
            .map(|v| {
                let id = by_point[&grid(v)];
                let r = &reference.vertices[id as usize];
                let d = glam::Vec3::from(v.position).distance(glam::Vec3::from(r.position));
                assert!(d <= tol, "{name} n={n}: vertex {:?} off by {d}", grid(v));
                id
            })
            .collect();
        let mut distinct = to_reference.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(
            distinct.len(),
            to_reference.len(),
            "{name} n={n}: one vertex twice"
        );
        let mapped: Vec<u32> = twin
            .indices
            .iter()
            .map(|&i| to_reference[i as usize])
            .collect();
        assert_eq!(mapped, reference.indices, "{name} n={n}");
    }
}

#[test]
fn the_triangle_bound_is_above_the_true_distance_and_tends_to_it() {
    // Cells anywhere, the extraordinary corners and the boundary included, under three
    // triangulations (both diagonals, and a fan from the middle of the first side). The
    // bound must never be below the sampled distance to the nearest triangle: unrefined
    // (target infinite: the control points' distances) and refined toward 1.5 × the
    // sampled truth, which it must reach on 80% of the cells (so that a bound looser
    // than that on more than a fifth of them would fail this test). Pieces that straddle
    // a triangle edge close in only linearly (a quarter is half as far across), so small
    // cells, whose true distance is small against their size, need more splits than
    // the depth allows: 84% reach 1.5×, 72% 1.1×.
    let (mut cells, mut certified) = (0, 0);
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_pyramid.obj",
    ] {
        let model = cc_model(name);
        for p in (0..model.mesh.patch_count()).step_by(11) {
            for (u0, v0, s) in [
                (0.0, 0.0, 1.0),
                (0.5, 0.0, 0.5),
                (0.0, 0.0, 0.125),
                (0.25, 0.125, 0.125),
            ] {
                let b = [u0, u0 + s, v0, v0 + s];
                let [c0, c1, c2, c3, m] = [
                    (b[0], b[2]),
                    (b[1], b[2]),
                    (b[1], b[3]),
                    (b[0], b[3]),
                    (0.5 * (b[0] + b[1]), b[2]),
                ]
                .map(|(u, v)| model.eval(p, u, v).position);
                for tris in [
                    vec![[c0, c1, c2], [c0, c2, c3]],
                    vec![[c0, c1, c3], [c1, c2, c3]],
                    vec![[m, c1, c2], [m, c2, c3], [m, c3, c0]],
                ] {
                    let mut truth = 0f64;
                    for j in 0..=32 {
                        for i in 0..=32 {
                            let (u, v) = (u0 + s * i as f64 / 32.0, v0 + s * j as f64 / 32.0);
                            let x = model.eval(p, u, v).position;
                            let d = tris
                                .iter()
                                .map(|t| {
                                    (x - closest_point_on_triangle(x, t[0], t[1], t[2])).length()
                                })
                                .fold(f64::INFINITY, f64::min);
                            truth = truth.max(d);
                        }
                    }
                    let coarse = triangle_distance_bound(&model, p, b, &tris, f64::INFINITY);
                    assert!(
                        coarse >= truth * (1.0 - 1e-9),
                        "{name} {p} {b:?}: {coarse} < {truth}"
                    );
                    let fine = triangle_distance_bound(&model, p, b, &tris, 1.5 * truth);
                    assert!(
                        fine >= truth * (1.0 - 1e-9),
                        "{name} {p} {b:?}: {fine} < {truth}"
                    );
                    cells += 1;
                    if fine.is_finite() {
                        certified += 1;
                    }
                }
            }
        }
    }
    eprintln!("{certified} of {cells} cells bounded within 1.5× the sampled truth");
    assert!(
        cells > 100 && certified * 10 >= cells * 8,
        "{certified} of {cells}"
    );
}

#[test]
fn own_triangles_leaf_bound_meets_the_tolerance_with_fewer_triangles() {
    // `LeafBound::Triangles` keeps a leaf by its actual triangles, checked again with the
    // points its neighbours add. The measured error must stay under the tolerance, the
    // output watertight, and the triangles no more than the flatness bound's (fewer on
    // the curved meshes).
    let (mut fewer, mut cases, mut triangle_bounds) = (0, 0, 0);
    let mut models: Vec<(String, SurfaceModel, f64)> = [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_cube.obj",
        "opensubdiv/catmark_edgecorner.obj",
        "opensubdiv/catmark_hole_test1.obj",
        "opensubdiv/catmark_nonquads.obj",
        "opensubdiv/catmark_xord_boundary.obj",
    ]
    .iter()
    .map(|name| (name.to_string(), cc_model(name), diag(name)))
    .collect();
    let mesh = fan(12, true);
    models.push((
        "fan 12".into(),
        SurfaceModel::new(
            tessera_core::catmull_clark::PatchMesh::new(&mesh).unwrap(),
            tessera_core::catmull_clark::TREE_DEPTH,
        ),
        mesh.bbox_diag(),
    ));
    for (name, model, size) in &models {
        let samples = surface_samples(model, 32);
        let boundary = open_boundary(model);
        for rel in [1e-2, 3e-3] {
            let tol = rel * size;
            let params = |leaf_bound| CcParams {
                tolerance: Tolerance::Absolute(tol),
                max_depth: 10,
                first_split: Default::default(),
                leaf_bound,
            };
            let flat = tessellate_adaptive(model, &params(LeafBound::Flatness)).unwrap();
            let own = tessellate_adaptive(model, &params(LeafBound::Triangles)).unwrap();
            assert_eq!(own.unmet, 0, "{name} {rel}");
            assert!(own.max_bound <= tol, "{name} {rel}");
            triangle_bounds += own.triangle_bounds;
            let e = measure_error(&samples, &own.mesh, model.mesh.control_diag);
            assert!(
                e.max_error <= tol,
                "{name} at {rel}: measured {} > {tol}",
                e.max_error
            );
            let positions: Vec<_> = own.mesh.positions().collect();
            let r = check_watertight(&positions, &own.mesh.indices, &boundary, 1e-6 * size);
            assert!(r.is_watertight(), "{name} {rel}: {r:?}");
            let (a, b) = (own.mesh.triangle_count(), flat.mesh.triangle_count());
            assert!(a <= b, "{name} {rel}: {a} > {b} triangles");
            cases += 1;
            if a < b {
                fewer += 1;
            }
        }
    }
    assert!(
        fewer * 2 > cases,
        "fewer triangles on only {fewer} of {cases}"
    );
    assert!(triangle_bounds > 0, "the triangle bound was never tried");
}

/// Each vertex's `(face, u, v)`, evaluated through `SurfaceModel::eval_face` (which
/// shares nothing with the tessellators but the patches), is where the vertex is: within
/// 1e-5 of the model's diagonal, seams included; every triangle lies in one chart; the
/// copies of a seam point agree bit for bit. Quads, triangles and pentagons, adaptive
/// and uniform. Then the checker is shown to catch each planted defect.
#[test]
fn every_vertex_lies_at_its_face_coordinates_and_seam_copies_agree() {
    use tessera_core::catmull_clark::faces::check_faces;
    for (name, rel, n) in [
        ("opensubdiv/catmark_nonquads.obj", 3e-3, 5),
        ("opensubdiv/catmark_pyramid.obj", 1e-3, 4),
        ("opensubdiv/catmark_cube.obj", 1e-3, 3),
        ("catmull_clark/spot_control_mesh.obj", 3e-3, 2),
    ] {
        let model = cc_model(name);
        let tol = 1e-5 * model.mesh.bbox_diag();
        let params = CcParams {
            tolerance: Tolerance::Absolute(rel * diag(name)),
            max_depth: 6,
            first_split: Default::default(),
            leaf_bound: Default::default(),
        };
        let not_quads = model.mesh.control_faces.iter().any(|f| f.len() != 4);
        let adaptive = tessellate_adaptive(&model, &params).unwrap().mesh;
        let uniform = tessellate_uniform(&model, n).unwrap().mesh;
        for (what, mesh, grid) in [
            ("adaptive", &adaptive, params.grid()),
            ("uniform", &uniform, n),
        ] {
            let r = check_faces(&model, mesh, grid);
            eprintln!("{name} {what}: {r:?}");
            assert!(r.is_consistent(tol), "{name} {what}: {r:?}");
            assert_eq!(r.vertices, mesh.vertices.len(), "{name} {what}");
            assert!(r.seam_points > 0, "{name} {what}");
            assert_eq!(r.inner_seam_points > 0, not_quads, "{name} {what}");
        }
    }
    // Test the tester, on the pentagons' and triangles' mesh.
    let model = cc_model("opensubdiv/catmark_nonquads.obj");
    let tol = 1e-5 * model.mesh.bbox_diag();
    let grid = 6;
    let mesh = tessellate_uniform(&model, grid).unwrap().mesh;
    let clean = check_faces(&model, &mesh, grid);
    assert!(clean.is_consistent(tol), "{clean:?}");
    // A vertex with its u and v swapped is off the surface (away from the diagonal).
    let mut swapped = mesh.clone();
    let k = swapped
        .vertices
        .iter()
        .position(|v| (v.uv[0] - v.uv[1]).abs() > 0.2 && v.uv[0] < 1.0 && v.uv[1] < 1.0)
        .unwrap();
    let v = &mut swapped.vertices[k];
    v.uv = [v.uv[1], v.uv[0]];
    assert!(check_faces(&model, &swapped, grid).max_distance > tol);
    // Copies: one a bit off; a triangle using the copy of another chart; two vertices for
    // one point in one chart.
    let copies = {
        let mut by_position: std::collections::HashMap<[u32; 3], Vec<usize>> = Default::default();
        for (k, v) in mesh.vertices.iter().enumerate() {
            by_position
                .entry(v.position.map(f32::to_bits))
                .or_default()
                .push(k);
        }
        by_position
            .into_values()
            .find(|c| c.len() > 1 && mesh.vertices[c[0]].face != mesh.vertices[c[1]].face)
            .unwrap()
    };
    let mut off = mesh.clone();
    let x = &mut off.vertices[copies[1]].position[0];
    *x = f32::from_bits(x.to_bits() + 1);
    let r = check_faces(&model, &off, grid);
    assert!(r.unequal_copies == 1 && r.max_distance <= tol, "{r:?}");
    let mut mixed = mesh.clone();
    let at = mixed
        .indices
        .iter()
        .position(|&i| i as usize == copies[0])
        .unwrap();
    mixed.indices[at] = copies[1] as u32;
    assert!(check_faces(&model, &mixed, grid).mixed_triangles > 0);
    let mut repeated = mesh.clone();
    repeated.vertices.push(mesh.vertices[copies[0]]);
    repeated.indices[at] = mesh.vertices.len() as u32;
    assert_eq!(check_faces(&model, &repeated, grid).repeated, 1);
}
