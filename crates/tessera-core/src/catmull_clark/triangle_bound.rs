//! The distance bound for a known triangulation: a guaranteed upper bound on the
//! distance from every surface point of a box to the nearest of the triangles given.
//!
//! Distance to a convex set is a convex function, and a point of a Bézier piece is a
//! convex combination of its control points (Bernstein weights are non-negative and sum
//! to one); so the distance from any point of the piece to a triangle is at most the
//! largest distance of the piece's control points to it, and the distance to the
//! nearest triangle at most the smallest of those over the triangles. Where that is
//! above the target the piece is split in four (de Casteljau) and each quarter bounded
//! alone: the control points close in on the surface and each quarter picks its own
//! triangle, so the bound tends to the true largest distance. The innermost square at
//! an extraordinary vertex enters as its ball: the distance of its limit point plus its
//! radius.
//!
//! Unlike the flatness bound ([`super::bound`]) it needs no slab, no projection and no
//! orientation condition, and it sees how the triangles actually lie (a saddle pays
//! the larger of its rise and its fall, not their sum); but it holds only for those
//! triangles, so a leaf accepted by it must be checked again when finer neighbours put
//! points on its sides ([`super::adaptive`]).

use glam::{DVec2, DVec3};

use super::bicubic::{self, Net};
use super::bound::{walk_pieces, PieceSink};
use super::patch::PatchSurface;
use crate::measure::closest_point_on_triangle;

/// How many times a piece is split in four, at most, while its bound is above the
/// target.
pub const REFINE_DEPTH: u32 = 6;

/// The bound on the distance from the surface over the box `bx` (walk units) of a patch
/// with corner positions `corners` to the nearest of `triangles`; `f64::INFINITY` once
/// it is known to be above `target` (the rest is then not bounded).
pub fn triangles_bound(
    surface: &PatchSurface,
    bx: [u32; 4],
    corners: [DVec3; 4],
    triangles: &[[DVec3; 3]],
    target: f64,
) -> f64 {
    let origin = corners[0];
    let mut sum = TriangleDistance {
        triangles: triangles
            .iter()
            .map(|t| Triangle::new(t.map(|p| p - origin)))
            .collect(),
        target2: target * target,
        max2: 0.0,
    };
    if !walk_pieces(surface, bx, corners, &mut sum) || sum.max2 > sum.target2 {
        return f64::INFINITY;
    }
    sum.max2.sqrt()
}

/// A triangle in its own plane's frame: distances are a height and a distance in the
/// plane, which costs a few dot products where the point lies over the triangle.
struct Triangle {
    a: DVec3,
    normal: DVec3,
    axes: (DVec3, DVec3),
    /// The corners in the plane: `(0, 0)`, `(b, 0)`, `c` with `c.y > 0`.
    b: f64,
    c: DVec2,
    /// The corners, for a triangle too thin to have a frame.
    corners: [DVec3; 3],
    thin: bool,
}

impl Triangle {
    fn new(t: [DVec3; 3]) -> Self {
        let (ab, ac) = (t[1] - t[0], t[2] - t[0]);
        let cross = ab.cross(ac);
        let (len, blen) = (cross.length(), ab.length());
        let thin = blen == 0.0
            || len.is_nan()
            || len <= 1e-12 * ab.length_squared().max(ac.length_squared());
        let normal = if thin { DVec3::Z } else { cross / len };
        let x = if thin { DVec3::X } else { ab / blen };
        let y = normal.cross(x);
        Triangle {
            a: t[0],
            normal,
            axes: (x, y),
            b: blen,
            c: DVec2::new(ac.dot(x), ac.dot(y)),
            corners: t,
            thin,
        }
    }

    /// The squared distance from `p`.
    fn distance2(&self, p: DVec3) -> f64 {
        if self.thin {
            let t = &self.corners;
            return (p - closest_point_on_triangle(p, t[0], t[1], t[2])).length_squared();
        }
        let d = p - self.a;
        let h = self.normal.dot(d);
        let q = DVec2::new(d.dot(self.axes.0), d.dot(self.axes.1));
        let (a, b, c) = (DVec2::ZERO, DVec2::new(self.b, 0.0), self.c);
        // Edge functions, positive inside (the corners run counter-clockwise).
        let edges = [(a, b), (b, c), (c, a)];
        let mut flat = f64::INFINITY;
        let mut inside = true;
        for (s, e) in edges {
            if (e - s).perp_dot(q - s) < 0.0 {
                inside = false;
                // Outside a convex polygon, the nearest point lies on an edge that faces
                // the point.
                let dir = e - s;
                let t = ((q - s).dot(dir) / dir.length_squared()).clamp(0.0, 1.0);
                flat = flat.min((q - s - dir * t).length_squared());
            }
        }
        if inside {
            flat = 0.0;
        }
        h * h + flat
    }
}

/// The running maximum over the pieces of a box, squared.
struct TriangleDistance {
    /// Relative to the box's first corner, as the pieces are.
    triangles: Vec<Triangle>,
    target2: f64,
    max2: f64,
}

impl TriangleDistance {
    /// The squared bound over one net, split while above the target;
    /// `f64::INFINITY` once the box is known to fail.
    fn net_bound(&self, net: &Net, depth: u32) -> f64 {
        let mut best = f64::INFINITY;
        for t in &self.triangles {
            let mut worst = 0f64;
            for p in net {
                worst = worst.max(t.distance2(*p));
                if worst >= best {
                    break;
                }
            }
            best = best.min(worst);
        }
        if best <= self.target2 {
            return best;
        }
        // A net's corners lie on the surface: one farther than the target from every
        // triangle fails the box at once; at the finest split, any net above it does.
        let on_surface_far = [0, 3, 12, 15].iter().any(|&k| {
            self.triangles
                .iter()
                .all(|t| t.distance2(net[k]) > self.target2)
        });
        if depth == 0 || on_surface_far {
            return f64::INFINITY;
        }
        let mut max = 0f64;
        for q in &bicubic::split4(net) {
            max = max.max(self.net_bound(q, depth - 1));
            if max > self.target2 {
                return f64::INFINITY;
            }
        }
        max
    }
}

impl PieceSink for TriangleDistance {
    fn piece(&mut self, shape: &Net, offset: DVec3, _rect: [f64; 4], _sides: u32) {
        if self.max2 > self.target2 {
            return;
        }
        let net = shape.map(|p| p + offset);
        self.max2 = self.max2.max(self.net_bound(&net, REFINE_DEPTH));
    }

    fn vertex(&mut self, limit: DVec3, radius: f64, _rect: [f64; 4], _sides: u32) {
        let d2 = self
            .triangles
            .iter()
            .map(|t| t.distance2(limit))
            .fold(f64::INFINITY, f64::min);
        let d = d2.sqrt() + radius;
        self.max2 = self.max2.max(d * d);
    }
}
