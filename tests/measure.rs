//! Error measurement on cases with known answers, and against an independent brute force.

use glam::DVec3;
use tessera_core::bezier::{tessellate_uniform, PreparedBezier};
use tessera_core::measure::{bezier_surface_samples, closest_point_on_triangle, measure_error};
use tessera_tests::{parabolic_cylinder, plane_patch, teaset};

#[test]
fn a_plane_is_measured_exactly() {
    let model = plane_patch();
    let prep = PreparedBezier::new(&model);
    let t = tessellate_uniform(&model, &prep, 2).unwrap();
    let samples = bezier_surface_samples(&model, 33);
    let e = measure_error(&samples, &t.mesh, model.bbox_diag());
    assert!(e.max_error < 1e-6, "{e:?}");
    // The same mesh lifted by δ: every sample is δ away.
    let mut lifted = t.mesh.clone();
    lifted
        .vertices
        .iter_mut()
        .for_each(|v| v.position[2] += 0.125);
    let e = measure_error(&samples, &lifted, model.bbox_diag());
    for x in [e.max_error, e.mean_error, e.p99_error] {
        assert!((x - 0.125).abs() < 1e-6, "{e:?}");
    }
    // The control box and the sampled surface's box, reported apart.
    assert!((e.bbox_diag - 2f64.sqrt()).abs() < 1e-6, "{e:?}");
    assert!((e.surface_bbox_diag - 2f64.sqrt()).abs() < 1e-9, "{e:?}");
    assert!(
        (e.max_error_rel - 0.125 / e.bbox_diag).abs() < 1e-9,
        "{e:?}"
    );
}

#[test]
fn parabolic_cylinder_error_is_the_analytic_sagitta() {
    // z = x² cut into chords of width h: the largest distance is at the middle of the
    // flattest chord [0, h], the gap h²/4 along z seen along the chord's normal, whose
    // slope is h: h² / (4 √(1 + h²)). Samples at i/64 contain every chord middle.
    let model = parabolic_cylinder();
    let prep = PreparedBezier::new(&model);
    for n in [2u32, 4, 8] {
        let t = tessellate_uniform(&model, &prep, n).unwrap();
        let e = measure_error(
            &bezier_surface_samples(&model, 65),
            &t.mesh,
            model.bbox_diag(),
        );
        let h = 1.0 / n as f64;
        let expected = h * h / (4.0 * (1.0 + h * h).sqrt());
        assert!(
            (e.max_error - expected).abs() < 1e-6 * (1.0 + expected),
            "n = {n}: {} vs {expected}",
            e.max_error
        );
    }
}

/// Distance to a triangle by a different route: the plane foot if it is inside (by
/// barycentric coordinates), else the nearest of the three edges.
fn brute_distance(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let seg = |x: DVec3, y: DVec3| {
        let d = y - x;
        let t = ((p - x).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        (x + d * t - p).length()
    };
    let n = (b - a).cross(c - a);
    if n.length_squared() > 0.0 {
        let n = n.normalize();
        let foot = p - n * (p - a).dot(n);
        let area = |x: DVec3, y: DVec3, z: DVec3| (y - x).cross(z - x).dot(n);
        let total = area(a, b, c);
        let (wa, wb, wc) = (
            area(foot, b, c) / total,
            area(a, foot, c) / total,
            area(a, b, foot) / total,
        );
        if wa >= 0.0 && wb >= 0.0 && wc >= 0.0 {
            return (p - foot).length();
        }
    }
    seg(a, b).min(seg(b, c)).min(seg(c, a))
}

#[test]
fn bvh_agrees_with_brute_force_on_the_teapot() {
    let (_, model) = teaset().into_iter().next().unwrap();
    let prep = PreparedBezier::new(&model);
    let t = tessellate_uniform(&model, &prep, 5).unwrap();
    let samples: Vec<DVec3> = bezier_surface_samples(&model, 12)
        .into_iter()
        .step_by(7)
        .collect();
    let tris: Vec<[DVec3; 3]> = t
        .mesh
        .triangles()
        .map(|tr| tr.map(|i| DVec3::from(t.mesh.vertices[i as usize].position.map(f64::from))))
        .collect();
    let mut brute = Vec::new();
    for &p in &samples {
        let d = tris
            .iter()
            .map(|[a, b, c]| brute_distance(p, *a, *b, *c))
            .fold(f64::INFINITY, f64::min);
        let ericson = tris
            .iter()
            .map(|[a, b, c]| (closest_point_on_triangle(p, *a, *b, *c) - p).length())
            .fold(f64::INFINITY, f64::min);
        assert!(
            (d - ericson).abs() < 1e-9,
            "closest-point routines disagree: {d} vs {ericson}"
        );
        brute.push(d);
    }
    let e = measure_error(&samples, &t.mesh, model.bbox_diag());
    let max = brute.iter().cloned().fold(0.0, f64::max);
    let mean = brute.iter().sum::<f64>() / brute.len() as f64;
    assert!(
        (e.max_error - max).abs() < 1e-9 && (e.mean_error - mean).abs() < 1e-9,
        "{e:?} vs {max} {mean}"
    );
    assert!(max > 1e-3, "the check must see real error");
    // p99: the smallest distance with at least 99% of the samples at or under it.
    let mut sorted = brute.clone();
    sorted.sort_by(f64::total_cmp);
    let p99 = sorted
        .iter()
        .copied()
        .find(|&d| brute.iter().filter(|&&x| x <= d).count() * 100 >= 99 * brute.len())
        .unwrap();
    assert!(
        (e.p99_error - p99).abs() < 1e-9,
        "p99 {} vs {p99}",
        e.p99_error
    );
    assert!(p99 < max, "p99 must differ from the max to test anything");
}
