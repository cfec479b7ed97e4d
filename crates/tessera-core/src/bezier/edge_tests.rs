//! Edge tests (paper §2.2, SPEC §1) and the recursive bisection they drive.
//! CPU twin of `shaders/shared/edge_tests.wgsl`.
//!
//! A segment from `(u1, v1)` to `(u2, v2)` in a patch's parameter space is split at its
//! midpoint `(u12, v12)` when its test is positive; the halves are tested again, down to
//! `max_depth` levels. Inserted points are dyadic fractions `k / 256` of the segment,
//! returned as a bit set, so that the same decisions can be replayed by any later stage.

use glam::Vec3;

use super::patch::eval_frame_f32;
use super::prepare::map_read;
use crate::gpu_types::{DisplacementMap, EDGE_BIT_WORDS, MAX_DEPTH_LIMIT};

/// Which test decides whether an edge is split.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EdgeTest {
    /// `|d1 − d12| > th or |d2 − d12| > th` on the displacement map.
    Map2p,
    /// Map2p plus `d3`, `d4` across the edge at `(u12 ∓ ve, v12 ± ue)`.
    Map4p,
    /// Map4p plus `d5..d8` at `(u12, v12) + ½(±(ue, ve) ± (−ve, ue))`.
    Map8p,
    /// The vector test: `|S(u12, v12) − (S1 + S2)/2| > th`. Evaluates the surface.
    Flat,
}

impl EdgeTest {
    pub fn name(self) -> &'static str {
        match self {
            EdgeTest::Map2p => "map2p",
            EdgeTest::Map4p => "map4p",
            EdgeTest::Map8p => "map8p",
            EdgeTest::Flat => "flat",
        }
    }

    /// Index used by the shaders' `test` uniform.
    pub fn index(self) -> u32 {
        self as u32
    }
}

/// Denominator of the dyadic positions of inserted points.
pub const DYADIC_SCALE: u32 = 1 << MAX_DEPTH_LIMIT;

/// Inserted points of one segment: bit `k` set means a vertex at fraction `k / 256`.
pub type EdgeBits = [u32; EDGE_BIT_WORDS];

/// Whether `k` is set.
pub fn bit_is_set(bits: &EdgeBits, k: u32) -> bool {
    bits[(k / 32) as usize] >> (k % 32) & 1 != 0
}

/// The set positions in increasing order.
pub fn bit_positions(bits: &EdgeBits) -> impl Iterator<Item = u32> + '_ {
    (1..DYADIC_SCALE).filter(move |&k| bit_is_set(bits, k))
}

/// Number of inserted points.
pub fn bit_count(bits: &EdgeBits) -> u32 {
    bits.iter().map(|w| w.count_ones()).sum()
}

/// What one patch's tests read.
#[derive(Clone, Copy)]
pub struct TestInputs<'a> {
    pub test: EdgeTest,
    pub threshold: f32,
    pub max_depth: u32,
    pub map: &'a DisplacementMap,
    pub cp: &'a [Vec3; 16],
}

/// Point at fraction `k / 256` of the segment `a → b`.
#[inline]
pub fn lerp_uv(a: [f32; 2], b: [f32; 2], k: u32) -> [f32; 2] {
    let f = k as f32 / DYADIC_SCALE as f32;
    [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]
}

/// The map test on the segment `uv1 → uv2` (Map2p, Map4p or Map8p).
pub fn map_test(
    test: EdgeTest,
    map: &DisplacementMap,
    th: f32,
    uv1: [f32; 2],
    uv2: [f32; 2],
) -> bool {
    let m = [(uv1[0] + uv2[0]) * 0.5, (uv1[1] + uv2[1]) * 0.5];
    let d12 = map_read(map, m[0], m[1]);
    let differs = |u: f32, v: f32| (map_read(map, u, v) - d12).abs() > th;
    if differs(uv1[0], uv1[1]) || differs(uv2[0], uv2[1]) {
        return true;
    }
    if test == EdgeTest::Map2p {
        return false;
    }
    let (ue, ve) = (uv1[0] - m[0], uv1[1] - m[1]);
    if differs(m[0] - ve, m[1] + ue) || differs(m[0] + ve, m[1] - ue) {
        return true;
    }
    if test == EdgeTest::Map4p {
        return false;
    }
    for (a, b) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        let du = 0.5 * (a * ue - b * ve);
        let dv = 0.5 * (a * ve + b * ue);
        if differs(m[0] + du, m[1] + dv) {
            return true;
        }
    }
    false
}

/// Recursive bisection of the segment `uv0 → uv1` in one patch. Returns the inserted
/// points and the number of surface evaluations made (zero for the map tests).
pub fn subdivide_segment(inp: &TestInputs, uv0: [f32; 2], uv1: [f32; 2]) -> (EdgeBits, u32) {
    let mut bits = [0u32; EDGE_BIT_WORDS];
    let evals = subdivide_interval(inp, uv0, uv1, 0, DYADIC_SCALE, inp.max_depth, &mut bits);
    (bits, evals)
}

/// Recursive bisection of the piece `[lo, hi]` (in 1/256ths) of the segment `uv0 → uv1`,
/// at most `depth` levels and never below one unit. Sets the inserted points in `bits`;
/// returns the surface evaluations made.
pub fn subdivide_interval(
    inp: &TestInputs,
    uv0: [f32; 2],
    uv1: [f32; 2],
    lo: u32,
    hi: u32,
    depth: u32,
    bits: &mut EdgeBits,
) -> u32 {
    let mut evals = 0;
    let depth = depth.min(MAX_DEPTH_LIMIT);
    let flat = inp.test == EdgeTest::Flat;
    let eval = |k: u32, evals: &mut u32| {
        *evals += 1;
        let [u, v] = lerp_uv(uv0, uv1, k);
        eval_frame_f32(inp.cp, u, v).pos
    };
    // Explicit stack (the shader has no recursion): a piece [lo, hi] at its level, and
    // for the flat test the surface points at its ends.
    let mut stack: Vec<(u32, u32, u32, Vec3, Vec3)> =
        Vec::with_capacity(MAX_DEPTH_LIMIT as usize + 1);
    if depth > 0 && hi - lo >= 2 {
        let (p0, p1) = if flat {
            (eval(lo, &mut evals), eval(hi, &mut evals))
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        stack.push((lo, hi, 0, p0, p1));
    }
    while let Some((lo, hi, level, p_lo, p_hi)) = stack.pop() {
        let mid = (lo + hi) / 2;
        let mut p_mid = Vec3::ZERO;
        let split = if flat {
            p_mid = eval(mid, &mut evals);
            (p_mid - (p_lo + p_hi) * 0.5).length() > inp.threshold
        } else {
            map_test(
                inp.test,
                inp.map,
                inp.threshold,
                lerp_uv(uv0, uv1, lo),
                lerp_uv(uv0, uv1, hi),
            )
        };
        if split {
            bits[(mid / 32) as usize] |= 1 << (mid % 32);
            if level + 1 < depth && mid - lo >= 2 {
                stack.push((mid, hi, level + 1, p_mid, p_hi));
                stack.push((lo, mid, level + 1, p_lo, p_mid));
            }
        }
    }
    evals
}
