//! Bicubic Bézier patch evaluation: position, partial derivatives and a normal that
//! stays finite where a boundary row of the control net collapses to a point.
//!
//! Control points are row-major: `cp[4 * row + col]`, with `u` running along a row
//! (the column index) and `v` along a column (the row index):
//! `S(u, v) = Σ_row Σ_col B_row(v) B_col(u) cp[4 * row + col]`.
//! The front side is the side of `∂S/∂u × ∂S/∂v`.
//!
//! There are two copies of the evaluator: `f32` (the CPU twin of the WGSL evaluator,
//! `shaders/shared/patch.wgsl`) and `f64` (the "true surface" for error measurement).

use glam::{DVec3, Vec3};

/// Cubic Bernstein basis and its derivative at `t`.
macro_rules! bernstein {
    ($name:ident, $t:ty) => {
        #[inline]
        fn $name(t: $t) -> ([$t; 4], [$t; 4]) {
            let s = 1.0 - t;
            let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
            let d = [
                -3.0 * s * s,
                3.0 * s * s - 6.0 * t * s,
                6.0 * t * s - 3.0 * t * t,
                3.0 * t * t,
            ];
            (b, d)
        }
    };
}
bernstein!(bernstein_f32, f32);
bernstein!(bernstein_f64, f64);

/// Point, first derivatives and the mixed derivative of a patch at one parameter.
#[derive(Clone, Copy, Debug)]
pub struct Frame<V> {
    /// The surface point `S(u, v)`.
    pub pos: V,
    /// `∂S/∂u`.
    pub du: V,
    /// `∂S/∂v`.
    pub dv: V,
    /// `∂²S/∂u∂v`.
    pub duv: V,
}

macro_rules! eval_frame {
    ($name:ident, $v:ty, $t:ty, $basis:ident) => {
        /// Position, `∂S/∂u`, `∂S/∂v` and `∂²S/∂u∂v` at `(u, v)`.
        pub fn $name(cp: &[$v; 16], u: $t, v: $t) -> Frame<$v> {
            let (bu, du) = $basis(u);
            let (bv, dv) = $basis(v);
            let mut f = Frame {
                pos: <$v>::ZERO,
                du: <$v>::ZERO,
                dv: <$v>::ZERO,
                duv: <$v>::ZERO,
            };
            for row in 0..4 {
                let mut p = <$v>::ZERO;
                let mut pu = <$v>::ZERO;
                for col in 0..4 {
                    let c = cp[4 * row + col];
                    p += c * bu[col];
                    pu += c * du[col];
                }
                f.pos += p * bv[row];
                f.du += pu * bv[row];
                f.dv += p * dv[row];
                f.duv += pu * dv[row];
            }
            f
        }
    };
}
eval_frame!(eval_frame_f32, Vec3, f32, bernstein_f32);
eval_frame!(eval_frame_f64, DVec3, f64, bernstein_f64);

macro_rules! frame_normal {
    ($name:ident, $v:ty, $t:ty) => {
        /// Unit normal `∂S/∂u × ∂S/∂v`. Where a boundary row or column of the net has
        /// collapsed to a point (the teapot's lid and bottom), one derivative vanishes
        /// along that boundary; the normal is then the limit from inside the patch, with
        /// the mixed derivative standing in for the vanished one. Never NaN.
        pub fn $name(f: &Frame<$v>, u: $t, v: $t) -> $v {
            let scale = f.du.length() + f.dv.length() + f.duv.length();
            let tiny = scale * 1e-5;
            let mut du = f.du;
            let mut dv = f.dv;
            if du.length() <= tiny {
                // S_u(u, v) ≈ (v - v_edge) S_uv near a collapsed row at v_edge.
                du = if v < 0.5 { f.duv } else { -f.duv };
            }
            if dv.length() <= tiny {
                dv = if u < 0.5 { f.duv } else { -f.duv };
            }
            let n = du.cross(dv);
            let len = n.length();
            if len > 0.0 && len.is_finite() {
                n / len
            } else {
                <$v>::Z
            }
        }
    };
}
frame_normal!(frame_normal_f32, Vec3, f32);
frame_normal!(frame_normal_f64, DVec3, f64);

/// One bicubic Bézier patch (single precision, as uploaded to the GPU).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BezierPatch {
    /// Control points, row-major `b[4j + i]` (`i` along u).
    pub cp: [Vec3; 16],
}

impl BezierPatch {
    /// Surface point at `(u, v)`.
    pub fn point(&self, u: f32, v: f32) -> Vec3 {
        eval_frame_f32(&self.cp, u, v).pos
    }

    /// Surface point and unit normal at `(u, v)`.
    pub fn point_normal(&self, u: f32, v: f32) -> (Vec3, Vec3) {
        let f = eval_frame_f32(&self.cp, u, v);
        (f.pos, frame_normal_f32(&f, u, v))
    }

    /// Control points in double precision, for exact evaluation in measurements.
    pub fn cp_f64(&self) -> [DVec3; 16] {
        self.cp.map(|c| c.as_dvec3())
    }

    /// Surface point at `(u, v)` evaluated in double precision.
    pub fn point_f64(&self, u: f64, v: f64) -> DVec3 {
        eval_frame_f64(&self.cp_f64(), u, v).pos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane() -> BezierPatch {
        let mut cp = [Vec3::ZERO; 16];
        for row in 0..4 {
            for col in 0..4 {
                cp[4 * row + col] = Vec3::new(col as f32, row as f32, 0.0);
            }
        }
        BezierPatch { cp }
    }

    #[test]
    fn planar_patch_is_linear_with_unit_z_normal() {
        let p = plane();
        let (x, n) = p.point_normal(0.25, 0.75);
        assert!((x - Vec3::new(0.75, 2.25, 0.0)).length() < 1e-6);
        assert!((n - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let mut p = plane();
        p.cp[5].z = 1.0;
        p.cp[10].z = -0.5;
        p.cp[3].z = 0.7;
        let cp = p.cp_f64();
        let (u, v, h) = (0.3, 0.6, 1e-6);
        let f = eval_frame_f64(&cp, u, v);
        let du =
            (eval_frame_f64(&cp, u + h, v).pos - eval_frame_f64(&cp, u - h, v).pos) / (2.0 * h);
        let dv =
            (eval_frame_f64(&cp, u, v + h).pos - eval_frame_f64(&cp, u, v - h).pos) / (2.0 * h);
        let duv = (eval_frame_f64(&cp, u + h, v).dv - eval_frame_f64(&cp, u - h, v).dv) / (2.0 * h);
        assert!((f.du - du).length() < 1e-6);
        assert!((f.dv - dv).length() < 1e-6);
        assert!((f.duv - duv).length() < 1e-6);
    }

    #[test]
    fn collapsed_row_gives_the_limit_normal_not_nan() {
        // A cone-like patch: row 0 collapsed to the apex.
        let mut p = plane();
        for col in 0..4 {
            p.cp[col] = Vec3::new(1.5, 0.0, 1.0);
        }
        let (_, n_edge) = p.point_normal(0.4, 0.0);
        let (_, n_near) = p.point_normal(0.4, 1e-4);
        assert!(n_edge.is_finite());
        assert!((n_edge.length() - 1.0).abs() < 1e-5);
        assert!(n_edge.dot(n_near) > 0.99, "{n_edge} vs {n_near}");
    }
}
