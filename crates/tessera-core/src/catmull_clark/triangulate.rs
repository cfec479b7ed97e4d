//! Triangulation of a leaf's polygon (its corners plus the marked vertices on its
//! sides) without new vertices, T-junctions or zero-area triangles.
//!
//! The polygon is convex in the parameter square, with runs of collinear ("flat")
//! vertices along the sides. An ear at a strictly convex vertex is never degenerate,
//! and clipping one next to a flat vertex makes that vertex strictly convex, so the
//! number of strictly convex vertices never drops while flat ones remain: the polygon
//! never collapses to a segment. Without flat vertices the rest is a convex polygon;
//! a quad is split along its shorter diagonal in space.

use glam::DVec3;

/// A polygon vertex: integer parameter coordinates and the output vertex id.
#[derive(Clone, Copy, Debug)]
pub struct PolyVertex {
    pub i: i64,
    pub j: i64,
    pub id: u32,
}

fn cross(a: PolyVertex, b: PolyVertex, c: PolyVertex) -> i64 {
    (b.i - a.i) * (c.j - a.j) - (b.j - a.j) * (c.i - a.i)
}

/// Appends counter-clockwise triangles of the polygon `poly` (counter-clockwise in the
/// parameter plane) to `out`; `position` gives the space position of an output vertex.
pub fn triangulate(mut poly: Vec<PolyVertex>, position: impl Fn(u32) -> DVec3, out: &mut Vec<u32>) {
    let convex = |p: &[PolyVertex], k: usize| {
        let n = p.len();
        cross(p[(k + n - 1) % n], p[k], p[(k + 1) % n]) > 0
    };
    while poly.len() > 3 {
        let n = poly.len();
        let flat: Vec<bool> = (0..n).map(|k| !convex(&poly, k)).collect();
        let ear = if flat.iter().any(|&f| f) {
            (0..n)
                .find(|&k| !flat[k] && (flat[(k + n - 1) % n] || flat[(k + 1) % n]))
                .expect("a flat run ends at a strictly convex vertex")
        } else if n == 4 {
            // Shorter diagonal: 0–2 (ears at 1 and 3) or 1–3 (ears at 0 and 2).
            let d02 = (position(poly[0].id) - position(poly[2].id)).length_squared();
            let d13 = (position(poly[1].id) - position(poly[3].id)).length_squared();
            if d02 <= d13 {
                1
            } else {
                0
            }
        } else {
            0
        };
        let (a, b, c) = (poly[(ear + n - 1) % n], poly[ear], poly[(ear + 1) % n]);
        out.extend([a.id, b.id, c.id]);
        poly.remove(ear);
    }
    if poly.len() == 3 {
        out.extend([poly[0].id, poly[1].id, poly[2].id]);
    }
}
