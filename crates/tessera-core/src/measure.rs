//! Error against the true surface: the distance from a dense sampling of the
//! exact surface to the output triangles (one-sided Hausdorff), with exact point–triangle
//! distances found through a bounding-volume hierarchy. Double precision throughout.

use glam::DVec3;
use serde::Serialize;

use crate::bezier::model::BezierModel;
use crate::bezier::patch::eval_frame_f64;
use crate::mesh::Mesh;

/// Default samples per patch side (a 64×64 grid per patch, boundaries included).
pub const DEFAULT_SAMPLES_PER_SIDE: usize = 64;
/// The most samples per patch side `--measure-samples` accepts.
pub const MAX_SAMPLES_PER_SIDE: usize = 1024;
/// The most samples one measurement takes in all (24 bytes each: 1.5 GiB).
pub const MAX_SAMPLES: u64 = 1 << 26;

/// Refuses a sampling of `per_side`² points on each of `patches` patches that is
/// coarser than 32 per side or larger than the limits above.
pub fn check_sampling(per_side: usize, patches: usize) -> crate::Result<()> {
    if !(32..=MAX_SAMPLES_PER_SIDE).contains(&per_side) {
        return Err(crate::Error::Param(format!(
            "--measure-samples {per_side}: must be in 32..={MAX_SAMPLES_PER_SIDE}"
        )));
    }
    let total = (per_side as u64).pow(2) * patches as u64;
    if total > MAX_SAMPLES {
        return Err(crate::Error::Param(format!(
            "--measure-samples {per_side}: {per_side}² × {patches} patches = {total} samples, more than the {MAX_SAMPLES} allowed"
        )));
    }
    Ok(())
}

/// Summary of the distances from the surface samples to the mesh.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct ErrorStats {
    /// Largest distance from a sample to the mesh, model units.
    pub max_error: f64,
    /// Mean distance over the samples, model units.
    pub mean_error: f64,
    /// 99th percentile of the distances, model units.
    pub p99_error: f64,
    /// Diagonal of the bounding box of the input's control points: the box a relative
    /// tolerance is a fraction of ([`crate::Tolerance`]).
    pub bbox_diag: f64,
    /// `max_error / bbox_diag`.
    pub max_error_rel: f64,
    /// Diagonal of the bounding box of the surface samples (the measured surface's box,
    /// inside the control points' hull).
    pub surface_bbox_diag: f64,
    /// Surface samples measured.
    pub samples: usize,
    /// Index of the sample with the largest error.
    pub worst_sample: usize,
}

/// Points of every patch on an `n × n` parameter grid `(i/(n-1), j/(n-1))`.
pub fn bezier_surface_samples(model: &BezierModel, n: usize) -> Vec<DVec3> {
    let n = n.max(2);
    let mut out = Vec::with_capacity(model.patches.len() * n * n);
    for patch in &model.patches {
        let cp = patch.cp_f64();
        for j in 0..n {
            for i in 0..n {
                let (u, v) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                out.push(eval_frame_f64(&cp, u, v).pos);
            }
        }
    }
    out
}

/// Distance statistics from `samples` to `mesh`, relative to `bbox_diag` (the diagonal
/// of the control points' box). Runs on all cores.
pub fn measure_error(samples: &[DVec3], mesh: &Mesh, bbox_diag: f64) -> ErrorStats {
    let tris: Vec<[DVec3; 3]> = mesh
        .triangles()
        .map(|t| t.map(|i| DVec3::from(mesh.vertices[i as usize].position.map(f64::from))))
        .collect();
    if samples.is_empty() || tris.is_empty() {
        return ErrorStats {
            bbox_diag,
            ..Default::default()
        };
    }
    let bvh = TriangleBvh::new(tris);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(16);
    let chunk = samples.len().div_ceil(threads);
    let mut dist = vec![0f64; samples.len()];
    std::thread::scope(|s| {
        for (pts, out) in samples.chunks(chunk).zip(dist.chunks_mut(chunk)) {
            let bvh = &bvh;
            s.spawn(move || {
                let mut hint = 0;
                for (p, d) in pts.iter().zip(out) {
                    let (dd, t) = bvh.nearest(*p, hint);
                    hint = t;
                    *d = dd;
                }
            });
        }
    });
    let (lo, hi) = samples.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let surface_bbox_diag = (hi - lo).length();
    let mean = dist.iter().sum::<f64>() / dist.len() as f64;
    let mut sorted = dist.clone();
    sorted.sort_by(f64::total_cmp);
    let max = *sorted.last().unwrap_or(&0.0);
    let worst_sample = dist.iter().position(|&d| d == max).unwrap_or(0);
    let p99 = sorted[((sorted.len() as f64 * 0.99).ceil() as usize).clamp(1, sorted.len()) - 1];
    ErrorStats {
        max_error: max,
        mean_error: mean,
        p99_error: p99,
        bbox_diag,
        max_error_rel: if bbox_diag > 0.0 {
            max / bbox_diag
        } else {
            0.0
        },
        surface_bbox_diag,
        samples: samples.len(),
        worst_sample,
    }
}

/// The largest distance in pixels between the projection of a sample inside the view's
/// frustum and the projection of its nearest 3D point on `mesh`; `None` when no sample is
/// inside (infinite when some are and the mesh is empty). Runs on all cores.
pub fn max_error_px(samples: &[DVec3], mesh: &Mesh, view: &crate::View) -> Option<f64> {
    let inside: Vec<DVec3> = samples
        .iter()
        .copied()
        .filter(|&p| view.contains(p))
        .collect();
    if inside.is_empty() {
        return None;
    }
    let tris: Vec<[DVec3; 3]> = mesh
        .triangles()
        .map(|t| t.map(|i| DVec3::from(mesh.vertices[i as usize].position.map(f64::from))))
        .collect();
    if tris.is_empty() {
        return Some(f64::INFINITY);
    }
    let bvh = TriangleBvh::new(tris);
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(16);
    let chunk = inside.len().div_ceil(threads);
    let worst = std::thread::scope(|s| {
        let jobs: Vec<_> = inside
            .chunks(chunk)
            .map(|pts| {
                let bvh = &bvh;
                s.spawn(move || {
                    let mut hint = 0;
                    let mut worst: f64 = 0.0;
                    for &p in pts {
                        let (_, t) = bvh.nearest(p, hint);
                        hint = t;
                        let [a, b, c] = bvh.tris[t];
                        let q = closest_point_on_triangle(p, a, b, c);
                        // A nearest point behind the eye cannot be drawn near `p`.
                        let px = match (view.pixel(p), view.pixel(q)) {
                            (Some(sp), Some(sq)) => (sp - sq).length(),
                            _ => f64::INFINITY,
                        };
                        worst = worst.max(px);
                    }
                    worst
                })
            })
            .collect();
        jobs.into_iter()
            .map(|j| j.join().expect("a measuring thread"))
            .fold(0.0, f64::max)
    });
    Some(worst)
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection §5.1.5).
pub fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // Degenerate triangle: nearest of its edges.
        let seg = |x: DVec3, y: DVec3| {
            let d = y - x;
            let t = if d.length_squared() > 0.0 {
                ((p - x).dot(d) / d.length_squared()).clamp(0.0, 1.0)
            } else {
                0.0
            };
            x + d * t
        };
        return [seg(a, b), seg(b, c), seg(c, a)]
            .into_iter()
            .min_by(|x, y| {
                (*x - p)
                    .length_squared()
                    .total_cmp(&(*y - p).length_squared())
            })
            .unwrap_or(a);
    }
    let (v, w) = (vb / denom, vc / denom);
    a + ab * v + ac * w
}

#[derive(Clone, Copy)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle; inner node: index of the left child (right is +1).
    first: u32,
    /// Leaf: triangle count (> 0); inner node: 0.
    count: u32,
}

/// A bounding-volume hierarchy over triangles for nearest-point queries.
pub struct TriangleBvh {
    nodes: Vec<Node>,
    tris: Vec<[DVec3; 3]>,
}

impl TriangleBvh {
    /// Builds the hierarchy over `tris` (the triangles' corner positions).
    pub fn new(mut tris: Vec<[DVec3; 3]>) -> Self {
        let mut nodes = Vec::with_capacity(2 * tris.len() / 2 + 1);
        nodes.push(Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
        });
        let n = tris.len();
        Self::build(&mut nodes, &mut tris, 0, 0, n);
        TriangleBvh { nodes, tris }
    }

    fn build(
        nodes: &mut Vec<Node>,
        tris: &mut [[DVec3; 3]],
        node: usize,
        start: usize,
        end: usize,
    ) {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let (mut clo, mut chi) = (lo, hi);
        for t in &tris[start..end] {
            for v in t {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
            let c = (t[0] + t[1] + t[2]) / 3.0;
            clo = clo.min(c);
            chi = chi.max(c);
        }
        nodes[node] = Node {
            lo,
            hi,
            first: start as u32,
            count: (end - start) as u32,
        };
        if end - start <= 4 {
            return;
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (start + end) / 2;
        tris[start..end].select_nth_unstable_by(mid - start, |a, b| {
            let ca = (a[0] + a[1] + a[2])[axis];
            let cb = (b[0] + b[1] + b[2])[axis];
            ca.total_cmp(&cb)
        });
        let left = nodes.len();
        nodes.push(nodes[node]);
        nodes.push(nodes[node]);
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        Self::build(nodes, tris, left, start, mid);
        Self::build(nodes, tris, left + 1, mid, end);
    }

    fn box_dist_sq(n: &Node, p: DVec3) -> f64 {
        let d = (n.lo - p).max(p - n.hi).max(DVec3::ZERO);
        d.length_squared()
    }

    /// Distance from `p` to the nearest triangle, and that triangle's index. `hint` is a
    /// triangle likely to be near (the previous answer), used as the first bound.
    pub fn nearest(&self, p: DVec3, hint: usize) -> (f64, usize) {
        let dist_sq = |i: usize| {
            let [a, b, c] = self.tris[i];
            (closest_point_on_triangle(p, a, b, c) - p).length_squared()
        };
        let mut best_i = hint.min(self.tris.len() - 1);
        let mut best = dist_sq(best_i);
        let mut stack = Vec::with_capacity(64);
        stack.push(0usize);
        while let Some(ni) = stack.pop() {
            let n = &self.nodes[ni];
            if Self::box_dist_sq(n, p) >= best {
                continue;
            }
            if n.count > 0 {
                for i in n.first as usize..(n.first + n.count) as usize {
                    let d = dist_sq(i);
                    if d < best {
                        best = d;
                        best_i = i;
                    }
                }
            } else {
                let (l, r) = (n.first as usize, n.first as usize + 1);
                let (dl, dr) = (
                    Self::box_dist_sq(&self.nodes[l], p),
                    Self::box_dist_sq(&self.nodes[r], p),
                );
                // Push the farther child first so the nearer one is searched first.
                if dl < dr {
                    stack.push(r);
                    stack.push(l);
                } else {
                    stack.push(l);
                    stack.push(r);
                }
            }
        }
        (best.sqrt(), best_i)
    }
}
