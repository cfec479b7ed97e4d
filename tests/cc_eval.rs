//! Exact evaluation against facts from outside the code: limit masks at every vertex of
//! a refined mesh, the bicubic B-spline on regular patches, and continuity of the
//! pieces around extraordinary vertices and across patch edges.

use std::collections::HashMap;

use glam::DVec3;
use tessera_core::catmull_clark::bicubic;
use tessera_core::catmull_clark::patch::{Node, PatchSurface};
use tessera_core::catmull_clark::refine::{edge_key, refine};
use tessera_core::catmull_clark::{BoundaryRule, ControlMesh, PatchMesh, SurfaceModel, TREE_DEPTH};
use tessera_tests::{cc_model, control_mesh, fan};

fn model_of(mesh: &ControlMesh) -> SurfaceModel {
    SurfaceModel::new(PatchMesh::new(mesh).unwrap(), TREE_DEPTH)
}

#[test]
#[allow(clippy::approx_constant)] // the values as SOURCES.md prints them
fn cube_corner_limit_is_half_the_corner() {
    // SOURCES.md: with an all-quad cube the limit of a corner is half its position.
    let mesh = control_mesh("opensubdiv/catmark_cube.obj");
    let model = model_of(&mesh);
    let v = mesh
        .positions
        .iter()
        .position(|p| (*p - DVec3::new(0.0, -1.414214, 1.0)).length() < 1e-6)
        .unwrap() as u32;
    let mut seen = 0;
    for (f, face) in mesh.faces.iter().enumerate() {
        if let Some(k) = face.iter().position(|&w| w == v) {
            let p = model.mesh.first_patch[f] as usize + k;
            let s = model.eval(p, 0.0, 0.0).position;
            assert!((s - DVec3::new(0.0, -0.707107, 0.5)).length() < 1e-6, "{s}");
            seen += 1;
        }
    }
    assert_eq!(seen, 3);
}

/// Limit positions of every vertex of a quad mesh by the standard masks: interior
/// `(n²P + 4Σe + Σf)/(n(n+5))`, smooth boundary `(a + 4P + b)/6`, corner `P`.
fn limit_by_masks(points: &[DVec3], quads: &[Vec<u32>], rule: BoundaryRule) -> Vec<DVec3> {
    let mut edge_uses: HashMap<(u32, u32), u32> = HashMap::new();
    for q in quads {
        for k in 0..4 {
            *edge_uses.entry(edge_key(q[k], q[(k + 1) % 4])).or_default() += 1;
        }
    }
    let mut around: Vec<Vec<(usize, usize)>> = vec![Vec::new(); points.len()];
    for (f, q) in quads.iter().enumerate() {
        for k in 0..4 {
            around[q[k] as usize].push((f, k));
        }
    }
    (0..points.len())
        .filter(|&v| !around[v].is_empty())
        .map(|v| {
            let p = points[v];
            let boundary: Vec<u32> = around[v]
                .iter()
                .flat_map(|&(f, k)| [quads[f][(k + 1) % 4], quads[f][(k + 3) % 4]])
                .filter(|&w| edge_uses[&edge_key(v as u32, w)] == 1)
                .collect();
            if boundary.len() == 2 {
                if around[v].len() == 1 && rule == BoundaryRule::EdgeAndCorner {
                    return p;
                }
                return (points[boundary[0] as usize] + 4.0 * p + points[boundary[1] as usize])
                    / 6.0;
            }
            let n = around[v].len() as f64;
            let mut s = n * n * p;
            for &(f, k) in &around[v] {
                s += 4.0 * points[quads[f][(k + 1) % 4] as usize]
                    + points[quads[f][(k + 2) % 4] as usize];
            }
            s / (n * (n + 5.0))
        })
        .collect()
}

fn nearest(p: DVec3, set: &[DVec3]) -> f64 {
    set.iter()
        .map(|q| (p - *q).length())
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn evaluation_equals_limit_masks_at_every_refined_vertex() {
    // Every vertex of the mesh after 1 + m steps is the point (i, j)/2^m of a patch.
    let mut meshes: Vec<(String, ControlMesh, usize)> = Vec::new();
    // Interior valences 3..=16 and boundary valences 2..=17 (every size the issue names).
    for n in 3..=16 {
        meshes.push((format!("closed fan of {n}"), fan(n, true), 2));
        meshes.push((format!("open fan of {n}"), fan(n, false), 2));
    }
    meshes.push(("open fan of 1".into(), fan(1, false), 2));
    for (name, rule, m) in [
        ("catmull_clark/spot_control_mesh.obj", None, 1),
        ("catmull_clark/blub_control_mesh.obj", None, 2),
        ("opensubdiv/catmark_edgecorner.obj", None, 2),
        ("opensubdiv/catmark_edgeonly.obj", None, 2),
        ("opensubdiv/catmark_nonquads.obj", None, 2),
        (
            "opensubdiv/catmark_flap.obj",
            Some(BoundaryRule::EdgeOnly),
            2,
        ),
        ("opensubdiv/catmark_pole64.obj", None, 1),
    ] {
        let mut mesh = control_mesh(name);
        if let Some(r) = rule {
            mesh.boundary = r;
        }
        // The smooth masks: creased limits are compared with OpenSubdiv's own.
        mesh.drop_creases("--no-creases");
        meshes.push((name.to_string(), mesh, m));
    }
    for (name, mesh, m) in meshes {
        let model = model_of(&mesh);
        let (mut points, mut faces) = (mesh.positions.clone(), mesh.faces.clone());
        for _ in 0..=m {
            let r = refine(&points, &faces, mesh.boundary);
            points = r.points;
            faces = r.quads.iter().map(|q| q.to_vec()).collect();
        }
        let masks = limit_by_masks(&points, &faces, mesh.boundary);
        let g = 1u32 << m;
        let mut evaluated = Vec::new();
        for p in 0..model.mesh.patch_count() {
            for j in 0..=g {
                for i in 0..=g {
                    evaluated.push(
                        model
                            .eval(p, i as f64 / g as f64, j as f64 / g as f64)
                            .position,
                    );
                }
            }
        }
        let size = mesh.bbox_diag();
        let worst = masks
            .iter()
            .map(|&s| nearest(s, &evaluated))
            .fold(0.0, f64::max);
        assert!(worst < 1e-9 * size, "{name}: {worst}");
        let back = evaluated
            .iter()
            .map(|&s| nearest(s, &masks))
            .fold(0.0, f64::max);
        assert!(back < 1e-9 * size, "{name}: {back}");
    }
}

/// Uniform cubic B-spline basis (the textbook definition, not the code under test).
fn bspline(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ]
}

#[test]
fn regular_patches_are_bicubic_b_splines() {
    // A 7×7 grid of vertices with bumpy heights; face (2, 2) has a regular one-ring.
    let at = |i: usize, j: usize| 7 * j + i;
    let positions: Vec<DVec3> = (0..49)
        .map(|k| {
            let (i, j) = ((k % 7) as f64, (k / 7) as f64);
            DVec3::new(
                i + 0.1 * (j * 1.3).sin(),
                j,
                (i * 0.7).sin() * (j * 0.9).cos() + 0.05 * i * j,
            )
        })
        .collect();
    let mut faces = Vec::new();
    for j in 0..6 {
        for i in 0..6 {
            faces.push(vec![
                at(i, j) as u32,
                at(i + 1, j) as u32,
                at(i + 1, j + 1) as u32,
                at(i, j + 1) as u32,
            ]);
        }
    }
    let face = 6 * 2 + 2;
    let model = model_of(&ControlMesh::new(positions.clone(), faces));
    let b = |s: f64, t: f64| {
        let (bs, bt) = (bspline(s), bspline(t));
        let mut p = DVec3::ZERO;
        for (jj, wt) in bt.iter().enumerate() {
            for (ii, ws) in bs.iter().enumerate() {
                p += ws * wt * positions[at(1 + ii, 1 + jj)];
            }
        }
        p
    };
    for k in 0..4 {
        let p = model.mesh.first_patch[face] as usize + k;
        assert!(model.patches[p].is_regular());
        for (u, v) in [
            (0.0, 0.0),
            (0.3, 0.7),
            (1.0, 0.5),
            (0.123, 0.987),
            (1.0, 1.0),
        ] {
            // Patch k of a quad face at face coordinates (s, t) (topology docs).
            let (s, t) = match k {
                0 => (u / 2.0, v / 2.0),
                1 => (1.0 - v / 2.0, u / 2.0),
                2 => (1.0 - u / 2.0, 1.0 - v / 2.0),
                _ => (v / 2.0, 1.0 - u / 2.0),
            };
            let d = (model.eval(p, u, v).position - b(s, t)).length();
            assert!(d < 1e-12, "patch corner {k} at ({u}, {v}): {d}");
        }
    }
}

/// Bézier pieces of a patch quadtree with their squares `(u0, v0, size)`.
fn pieces(s: &PatchSurface) -> Vec<(bicubic::Net, f64, f64, f64)> {
    let mut out = Vec::new();
    let mut stack = vec![(0usize, 0.0, 0.0, 1.0)];
    while let Some((n, u, v, size)) = stack.pop() {
        match &s.nodes[n] {
            Node::Bezier(net) => out.push((**net, u, v, size)),
            Node::Split(ch) => {
                let h = size / 2.0;
                for (c, &(du, dv)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
                    .iter()
                    .enumerate()
                {
                    stack.push((ch[c] as usize, u + du * h, v + dv * h, h));
                }
            }
            Node::Corner(_) => {}
        }
    }
    out
}

/// Position and derivatives in patch coordinates of a piece at patch point (u, v).
fn piece_eval(piece: &(bicubic::Net, f64, f64, f64), u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let (net, u0, v0, s) = piece;
    let (p, pu, pv) = bicubic::eval(net, (u - u0) / s, (v - v0) / s);
    (p, pu / *s, pv / *s)
}

#[test]
fn pieces_around_extraordinary_vertices_join_continuously() {
    for name in [
        "catmull_clark/spot_control_mesh.obj",
        "opensubdiv/catmark_edgeonly.obj",
        "opensubdiv/catmark_nonquads.obj",
        "opensubdiv/catmark_xord_boundary.obj",
    ] {
        let model = cc_model(name);
        let size = model
            .mesh
            .points
            .iter()
            .fold(0.0f64, |m, p| m.max(p.length()));
        let mut checked = 0;
        for s in model.patches.iter().filter(|s| !s.is_regular()).take(40) {
            let pcs = pieces(s);
            // Pieces whose squares share a side: sample along the shared segment.
            for a in &pcs {
                for b in &pcs {
                    let (ua, va, sa) = (a.1, a.2, a.3);
                    let (ub, vb, sb) = (b.1, b.2, b.3);
                    // b right of a (sharing u = ua + sa), overlapping in v.
                    if (ub - (ua + sa)).abs() < 1e-15 {
                        let (lo, hi) = (va.max(vb), (va + sa).min(vb + sb));
                        if hi > lo {
                            for t in [0.0, 0.3, 0.77, 1.0] {
                                let v = lo + (hi - lo) * t;
                                let (pa, dua, dva) = piece_eval(a, ub, v);
                                let (pb, dub, dvb) = piece_eval(b, ub, v);
                                assert!(
                                    (pa - pb).length() < 1e-12 * size,
                                    "{name}: C0 {}",
                                    (pa - pb).length()
                                );
                                // C1 in the parameters (the surface is C2 away from the vertex),
                                // up to the rounding of coordinates of size `size` divided by
                                // the piece's width (pieces go 21 levels deep).
                                let tol = 1e-7 * dua.length().max(dva.length())
                                    + 1e-13 * size / sa.min(sb);
                                assert!((dua - dub).length() < tol, "{name}: C1 u");
                                assert!((dva - dvb).length() < tol, "{name}: C1 v");
                                checked += 1;
                            }
                        }
                    }
                    // b above a.
                    if (vb - (va + sa)).abs() < 1e-15 {
                        let (lo, hi) = (ua.max(ub), (ua + sa).min(ub + sb));
                        if hi > lo {
                            for t in [0.0, 0.4, 1.0] {
                                let u = lo + (hi - lo) * t;
                                let (pa, dua, dva) = piece_eval(a, u, vb);
                                let (pb, dub, dvb) = piece_eval(b, u, vb);
                                assert!((pa - pb).length() < 1e-12 * size, "{name}: C0");
                                let tol = 1e-7 * dua.length().max(dva.length())
                                    + 1e-13 * size / sa.min(sb);
                                assert!(
                                    (dua - dub).length() < tol && (dva - dvb).length() < tol,
                                    "{name}: C1"
                                );
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 100, "{name}: only {checked} joins");
    }
}

#[test]
fn patches_agree_along_shared_edges_and_normals_converge_at_vertices() {
    let model = cc_model("catmull_clark/spot_control_mesh.obj");
    let mesh = &model.mesh;
    // Each level-1 edge seen from its two patches: same points, same normals.
    let mut by_edge: HashMap<u32, Vec<(usize, usize)>> = HashMap::new();
    for p in 0..mesh.patch_count() {
        for k in 0..4 {
            by_edge
                .entry(mesh.quad_edges[p][k])
                .or_default()
                .push((p, k));
        }
    }
    let on_edge = |k: usize, t: f64| match k {
        0 => (t, 0.0),
        1 => (1.0, t),
        2 => (1.0 - t, 1.0),
        _ => (0.0, 1.0 - t),
    };
    let mut shared = 0;
    for users in by_edge.values().filter(|u| u.len() == 2) {
        // (patch, edge) pairs: the two patches that share this level-1 edge.
        let ((p, k), (q, l)) = (users[0], users[1]);
        for t in [0.0, 0.1, 0.37, 0.5, 0.9, 1.0] {
            // The edge runs in opposite directions in the two patches.
            let (u, v) = on_edge(k, t);
            let (s, w) = on_edge(l, 1.0 - t);
            let (a, b) = (model.eval(p, u, v), model.eval(q, s, w));
            assert!(
                (a.position - b.position).length() < 1e-12,
                "{}",
                (a.position - b.position).length()
            );
            assert!(
                a.normal.dot(b.normal) > 1.0 - 1e-9,
                "normals {} {}",
                a.normal,
                b.normal
            );
        }
        shared += 1;
    }
    assert!(shared > 1000);
    // At an extraordinary vertex the stored normal is the limit of the nearby normals:
    // their distance to it shrinks geometrically (by the eigenvalue ratio per level)
    // instead of levelling off, as it would for a wrong normal.
    let mut vertices = 0;
    for p in (0..mesh.patch_count()).filter(|&p| !model.patches[p].is_regular()) {
        for (cu, cv) in [(0.0, 0.0), (1.0, 1.0)] {
            let at = model.eval(p, cu, cv).normal;
            let gap = |k: i32| {
                let d = 2f64.powi(-k);
                let n = model.eval(p, (cu - d).abs(), (cv - d).abs()).normal;
                (1.0 - n.dot(at)).max(0.0).sqrt()
            };
            let (g6, g12) = (gap(6), gap(12));
            assert!(
                g12 < 0.2 * g6 + 1e-9 && g12 < 0.02,
                "patch {p} at ({cu}, {cv}): {g6} then {g12}"
            );
            vertices += 1;
        }
    }
    assert!(vertices > 100);
}
