//! Bicubic Bézier patches in double precision: evaluation, quadrant split, and the two
//! guaranteed bounds the flatness test uses. Nets are row-major, `b[4*j + i]`, `i` along u.

use glam::DVec3;

/// The 16 control points of a bicubic Bézier patch, `b[4*j + i]`.
pub type Net = [DVec3; 16];

fn bernstein(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t]
}

fn bernstein_d(t: f64) -> [f64; 4] {
    let s = 1.0 - t;
    [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * s * t,
        6.0 * s * t - 3.0 * t * t,
        3.0 * t * t,
    ]
}

/// Position and the two first derivatives at `(u, v)`.
pub fn eval(b: &Net, u: f64, v: f64) -> (DVec3, DVec3, DVec3) {
    let (bu, bv, du, dv) = (bernstein(u), bernstein(v), bernstein_d(u), bernstein_d(v));
    let (mut p, mut pu, mut pv) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
    for j in 0..4 {
        for i in 0..4 {
            let c = b[4 * j + i];
            p += bu[i] * bv[j] * c;
            pu += du[i] * bv[j] * c;
            pv += bu[i] * dv[j] * c;
        }
    }
    (p, pu, pv)
}

/// de Casteljau halves of a cubic: `[left, right]` control points.
fn halve(c: [DVec3; 4]) -> ([DVec3; 4], [DVec3; 4]) {
    let a = [
        (c[0] + c[1]) * 0.5,
        (c[1] + c[2]) * 0.5,
        (c[2] + c[3]) * 0.5,
    ];
    let b = [(a[0] + a[1]) * 0.5, (a[1] + a[2]) * 0.5];
    let m = (b[0] + b[1]) * 0.5;
    ([c[0], a[0], b[0], m], [m, b[1], a[2], c[3]])
}

/// The four quadrants, in the order `[0,½]², [½,1]×[0,½], [½,1]², [0,½]×[½,1]`.
pub fn split4(b: &Net) -> [Net; 4] {
    // Split every row in u, then every column of each half in v.
    let mut lo = [DVec3::ZERO; 16];
    let mut hi = [DVec3::ZERO; 16];
    for j in 0..4 {
        let (l, r) = halve([b[4 * j], b[4 * j + 1], b[4 * j + 2], b[4 * j + 3]]);
        lo[4 * j..4 * j + 4].copy_from_slice(&l);
        hi[4 * j..4 * j + 4].copy_from_slice(&r);
    }
    let split_v = |n: &Net| {
        let mut bottom = [DVec3::ZERO; 16];
        let mut top = [DVec3::ZERO; 16];
        for i in 0..4 {
            let (l, r) = halve([n[i], n[4 + i], n[8 + i], n[12 + i]]);
            for j in 0..4 {
                bottom[4 * j + i] = l[j];
                top[4 * j + i] = r[j];
            }
        }
        (bottom, top)
    };
    let (q0, q3) = split_v(&lo);
    let (q1, q2) = split_v(&hi);
    [q0, q1, q2, q3]
}

/// Bounds `(A, B, C)` on `|S_uu|`, `|S_vv|`, `|S_uv|` over the patch, from the Bézier
/// nets of the second derivatives (convex hull property).
pub fn second_derivatives(b: &Net) -> (f64, f64, f64) {
    let (mut a, mut bb, mut c) = (0f64, 0f64, 0f64);
    for j in 0..4 {
        for i in 0..2 {
            let d = b[4 * j + i] - 2.0 * b[4 * j + i + 1] + b[4 * j + i + 2];
            a = a.max(6.0 * d.length());
        }
    }
    for j in 0..2 {
        for i in 0..4 {
            let d = b[4 * j + i] - 2.0 * b[4 * (j + 1) + i] + b[4 * (j + 2) + i];
            bb = bb.max(6.0 * d.length());
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            let d = b[4 * j + i] - b[4 * j + i + 1] - b[4 * (j + 1) + i] + b[4 * (j + 1) + i + 1];
            c = c.max(9.0 * d.length());
        }
    }
    (a, bb, c)
}

/// Upper bound on `|D²S(h, h)|` for unit `h`, given `(A, B, C)` from
/// [`second_derivatives`]: `hᵤ²A + 2|hᵤhᵥ|C + hᵥ²B ≤ λmax([[A, C], [C, B]])`.
pub fn hessian_bound((a, b, c): (f64, f64, f64)) -> f64 {
    0.5 * (a + b) + (0.25 * (a - b) * (a - b) + c * c).sqrt()
}

/// The cubic over `[a, b] ⊂ [0, 1]` (de Casteljau at `b`, then at `a/b`).
fn clip_cubic(c: [DVec3; 4], a: f64, b: f64) -> [DVec3; 4] {
    let split = |c: [DVec3; 4], t: f64| {
        let l = |p: DVec3, q: DVec3| p + (q - p) * t;
        let a1 = [l(c[0], c[1]), l(c[1], c[2]), l(c[2], c[3])];
        let b1 = [l(a1[0], a1[1]), l(a1[1], a1[2])];
        let m = l(b1[0], b1[1]);
        ([c[0], a1[0], b1[0], m], [m, b1[1], a1[2], c[3]])
    };
    let left = if b < 1.0 { split(c, b).0 } else { c };
    if a > 0.0 {
        split(left, a / b).1
    } else {
        left
    }
}

/// The net of the same surface over the box `[u0, u1] × [v0, v1] ⊂ [0, 1]²`.
pub fn clip(b: &Net, (u0, u1): (f64, f64), (v0, v1): (f64, f64)) -> Net {
    let mut rows = [DVec3::ZERO; 16];
    for j in 0..4 {
        let r = clip_cubic([b[4 * j], b[4 * j + 1], b[4 * j + 2], b[4 * j + 3]], u0, u1);
        rows[4 * j..4 * j + 4].copy_from_slice(&r);
    }
    let mut out = [DVec3::ZERO; 16];
    for i in 0..4 {
        let c = clip_cubic([rows[i], rows[4 + i], rows[8 + i], rows[12 + i]], v0, v1);
        for j in 0..4 {
            out[4 * j + i] = c[j];
        }
    }
    out
}

/// The bilinear interpolant of four corner points (at `(0,0), (1,0), (1,1), (0,1)`).
pub fn bilinear(c: &[DVec3; 4], u: f64, v: f64) -> DVec3 {
    (1.0 - v) * ((1.0 - u) * c[0] + u * c[1]) + v * ((1.0 - u) * c[3] + u * c[2])
}

/// Upper bound on `|S(x) - B(x)|` over the part `[o, o + s]` (in the coordinates of
/// `B`) covered by the net `b`: the bilinear `B` is a bicubic whose Bézier points are
/// its values at `(i/3, j/3)`, so the difference is bounded by its control points.
pub fn deviation_from_bilinear(b: &Net, corners: &[DVec3; 4], o: (f64, f64), s: f64) -> f64 {
    let mut d = 0f64;
    for j in 0..4 {
        for i in 0..4 {
            let (u, v) = (o.0 + s * i as f64 / 3.0, o.1 + s * j as f64 / 3.0);
            d = d.max((b[4 * j + i] - bilinear(corners, u, v)).length());
        }
    }
    d
}
