// A view's tolerance in pixels and its frustum cull, for the adaptive Catmull-Clark
// kernels: twin of `tessera_core::View::{gain, cell_tolerance, box_outside}`, whose
// module docs prove the bound, here in single precision (`cc_params.view`).

#include "shared/cc_tess.wgsl"
#include "shared/cc_bound.wgsl"

// The clip coordinates of the eight corners of the box [lo, hi]: `c(lo)` plus the
// matrix's columns scaled by the box's sides (the map is affine).
fn cc_view_corners(lo: vec3f, hi: vec3f) -> array<vec4f, 8> {
    let m = cc_params.view.clip;
    let d = hi - lo;
    let c0 = m * vec4f(lo, 1.0);
    var c: array<vec4f, 8>;
    for (var k = 0u; k < 8u; k++) {
        c[k] = c0 + m[0] * select(0.0, d.x, (k & 1u) != 0u) + m[1] * select(0.0, d.y, (k & 2u) != 0u)
            + m[2] * select(0.0, d.z, (k & 4u) != 0u);
    }
    return c;
}

// Row r of the matrix's linear part (WGSL matrices are column-major).
fn cc_view_row(r: u32) -> vec3f {
    let m = cc_params.view.clip;
    return vec3f(m[0][r], m[1][r], m[2][r]);
}

// `View::gain`: the pixels a model-space distance can become on a segment in the box
// [lo, hi], one of whose ends lies in the frustum, at most `reach` long; infinite where
// no positive w bounds it.
fn cc_view_gain(lo: vec3f, hi: vec3f, reach: f32) -> f32 {
    let a_x = cc_view_row(0u);
    let a_y = cc_view_row(1u);
    let a_w = cc_view_row(3u);
    let c = cc_view_corners(lo, hi);
    var w_box = c[0].w;
    var x_hi = 0.0;
    var y_hi = 0.0;
    for (var k = 0u; k < 8u; k++) {
        w_box = min(w_box, c[k].w);
        x_hi = max(x_hi, abs(c[k].x));
        y_hi = max(y_hi, abs(c[k].y));
    }
    let w_lo = max(w_box, cc_params.view.near_w - length(a_w) * reach);
    if !(w_lo > 0.0) {
        return CC_INFINITY;
    }
    let half = 0.5 * cc_params.view.viewport;
    let alpha = half / w_lo;
    let beta = half * vec2f(x_hi, y_hi) / (w_lo * w_lo);
    let kx = alpha.x * length(a_x) + beta.x * length(a_w);
    let ky = alpha.y * length(a_y) + beta.y * length(a_w);
    let g12 = alpha.x * alpha.y * abs(dot(a_x, a_y)) + alpha.x * beta.y * abs(dot(a_x, a_w))
        + beta.x * alpha.y * abs(dot(a_y, a_w)) + beta.x * beta.y * dot(a_w, a_w);
    // The largest eigenvalue of the Jacobian rows' Gram matrix: its squared norm.
    let mean = 0.5 * (kx * kx + ky * ky);
    let half_gap = 0.5 * (kx * kx - ky * ky);
    return sqrt(mean + length(vec2f(half_gap, g12)));
}

// g(δ) of `View::cell_tolerance`: the pixels over the gain of the box grown by 2δ.
fn cc_view_g(lo: vec3f, hi: vec3f, delta: f32) -> f32 {
    let grow = vec3f(2.0 * delta);
    return cc_params.view.pixels / cc_view_gain(lo - grow, hi + grow, delta);
}

// `ToleranceSearch`: `View::cell_tolerance`'s bisection for the largest δ ≤ g(δ) between
// g(g(0)) and g(0), run only as far as each question needs. The steps never depend on
// the questions, so each answer is the whole search's.
struct CcViewSearch {
    lo: vec3f,
    hi: vec3f,
    valid: f32,
    invalid: f32,
    // `CELL_TOLERANCE_STEPS` at first.
    steps_left: u32,
}

fn cc_view_search(lo: vec3f, hi: vec3f) -> CcViewSearch {
    let upper = cc_view_g(lo, hi, 0.0);
    let valid = cc_view_g(lo, hi, upper);
    return CcViewSearch(lo, hi, valid, upper, select(10u, 0u, valid >= upper));
}

// `ToleranceSearch::admits`: whether `bound` ≤ the tolerance.
fn cc_view_admits(s: ptr<function, CcViewSearch>, bound: f32) -> bool {
    while (*s).steps_left > 0u && !(bound <= (*s).valid || bound > (*s).invalid) {
        let mid = 0.5 * ((*s).valid + (*s).invalid);
        if mid <= cc_view_g((*s).lo, (*s).hi, mid) {
            (*s).valid = mid;
        } else {
            (*s).invalid = mid;
        }
        (*s).steps_left -= 1u;
    }
    return bound <= (*s).valid;
}

// `View::box_outside`: the box [lo, hi] lies wholly outside one plane of the frustum.
fn cc_view_box_outside(lo: vec3f, hi: vec3f) -> bool {
    let c = cc_view_corners(lo, hi);
    var inside = vec3<bool>(false);
    var inside_z = vec3<bool>(false);
    for (var k = 0u; k < 8u; k++) {
        let v = c[k];
        // Some corner on the inner side of each plane: x ≤ w, −w ≤ x, y ≤ w, −w ≤ y,
        // 0 ≤ z, z ≤ w.
        inside = inside | !(vec3f(v.w - v.x, v.w + v.x, v.w - v.y) < vec3f(0.0));
        inside_z = inside_z | !(vec3f(v.w + v.y, v.z, v.w - v.z) < vec3f(0.0));
    }
    return !all(inside) || !all(inside_z);
}

// The box of a cell's four corners.
fn cc_corners_lo(c: array<vec3f, 4>) -> vec3f {
    return min(min(c[0], c[1]), min(c[2], c[3]));
}

fn cc_corners_hi(c: array<vec3f, 4>) -> vec3f {
    return max(max(c[0], c[1]), max(c[2], c[3]));
}
